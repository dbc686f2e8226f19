"""Report section 'Seed 002, sec. IV: the DeLorenzo IM, matrix (13), G_M,min (19)'
(Amezquita-Brooks et al. sec. IV).

Matrix (13) against (1) with the Appendix parameters and with the parameters inverted from
(13); G_M,min of (19) and the sign of its value in dB; gamma(j w_r) of (14) and |gamma(j w_r)|
of (18) against the state space; k_1 ... k_5 of (16) and the limit (17); the positive-real-axis
crossings of gamma over w_r against G_M,min; figure: Fig. 3.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from acdrive._figures import save_figure
from acdrive._report import icad_targets as targets
from acdrive._report.icad.common import (
    EXACT_REL_TOL,
    FREQRESP_REL_TOL,
    SPEEDS_002,
    W_NYQ,
    W_R,
    gamma_real_axis_crossing,
    printed_digits,
    within_rel,
)
from acdrive._report.icad.rounding import rounding_reach, rounding_rows
from acdrive._report.icad.stator_matrix import entries_with_verdict, matrix_entry_rows
from acdrive._report.icad_figures import nyquist_family
from acdrive._report.markdown import Row, Section, db, fmt
from acdrive._verdicts import at_most, relative_difference, within_abs
from acdrive.analysis._freqresp import LTI, evaluate_ss
from acdrive.analysis._icad_closed_forms import (
    gm_min,
    im_msf_at_rotor_speed,
    im_msf_magnitude_at_rotor_speed,
)
from acdrive.analysis._icad_frequency import icad_response
from acdrive.analysis._plants import plant_from_params
from acdrive.machines._induction import DELORENZO_IM, DELORENZO_IM_13

#: arg gamma(j w_r) at w_r = 1e6 rad/s against its limit 0 deg of Amezquita-Brooks (17).
ARG_LIMIT_TOL_DEG = 0.01


def gm_min_note(gm: float, label: str) -> str:
    """G_M,min of (19) against the printed 0.75 (-2.47 dB); for the Appendix set, where it
    differs, whether L_s of (13) in place of the Appendix's alone gives the printed value."""
    linear = printed_digits(targets.GM_MIN_PRINTED.as_printed, gm)
    in_db = printed_digits(targets.GM_MIN_DB_PRINTED.as_printed, db(gm))
    note = f"{linear}; in dB {in_db}"
    if not (linear.holds and in_db.holds) and label == "App.":
        swapped = gm_min(dataclasses.replace(DELORENZO_IM, L_s=DELORENZO_IM_13.L_s))
        with_ls = printed_digits(targets.GM_MIN_PRINTED.as_printed, swapped)
        note += (
            f"; with L_s of (13) ({fmt(DELORENZO_IM_13.L_s, 5)} H) and the other Appendix "
            f"values, G_M,min = {fmt(swapped)}: {with_ls}"
            + (" (the Appendix L_s, through sigma, makes the difference)" if with_ls.holds else "")
        )
    return note


def section_delorenzo_model(fig_dir: Path) -> Section:
    """The DeLorenzo IM section; Fig. 3 is written into ``fig_dir``."""
    s = Section("Seed 002, sec. IV: the DeLorenzo IM, matrix (13), G_M,min (19)")
    rows_app, verdicts_app = matrix_entry_rows(
        "Appendix parameters", targets.DELORENZO_MATRIX_13, DELORENZO_IM
    )
    rows_13, _ = matrix_entry_rows(
        "parameters of (13)", targets.DELORENZO_MATRIX_13, DELORENZO_IM_13
    )
    s.rows += rows_app + rows_13
    reach = rounding_reach(targets.DELORENZO_APPENDIX_PRINTED, targets.DELORENZO_MATRIX_13)
    s.rows += rounding_rows(reach, "Appendix", "Amezquita-Brooks (13)")
    inverted = {
        k: printed_digits(v.as_printed, getattr(DELORENZO_IM_13, k))
        for k, v in targets.DELORENZO_APPENDIX_PRINTED.items()
        if k != "P"
    }
    beyond = [k for k, v in inverted.items() if not v.holds]
    b13 = 1.0 / (DELORENZO_IM_13.sigma * DELORENZO_IM_13.L_s)
    b_app = 1.0 / (DELORENZO_IM.sigma * DELORENZO_IM.L_s)
    n_off = sum(not v.holds for v in verdicts_app.values())
    s.text = (
        f"With the Appendix parameters, {n_off} of the {len(verdicts_app)} entries of matrix (13) "
        f"differ from (1) beyond the printed digits ({entries_with_verdict(verdicts_app, False)}; rows "
        "below). Inverting (13) (`params_from_stationary_matrix`, machine `delorenzo-im-13`) "
        "gives "
        + ", ".join(
            f"{k} = {fmt(getattr(DELORENZO_IM_13, k))} "
            f"({100 * relative_difference(getattr(DELORENZO_IM_13, k), targets.DELORENZO_APPENDIX_PRINTED[k].value):+.2g} % "
            "from the Appendix)"
            for k in inverted
        )
        + "; beyond half a unit of the Appendix's last printed digit: "
        + (", ".join(beyond) if beyond else "none")
        + ". sigma L_s = L_s - L_m^2/L_r is a small difference of large numbers, so the "
        f"{100 * relative_difference(DELORENZO_IM_13.L_s, DELORENZO_IM.L_s):+.2g} % change of L_s "
        f"moves 1/(sigma L_s) by {100 * relative_difference(b13, b_app):+.2g} %. Both parameter sets "
        "are checked below, each against the printed values: **(13)** = `delorenzo-im-13`, "
        "**App.** = `delorenzo-im`. "
        + (
            "Within the rounding of the Appendix parameters (each printed value +/- half a unit "
            "of its last digit) one parameter set gives all six entries of (13) to the printed "
            f"digits (largest deviation {fmt(reach.best_ratio, 2)} of a half unit; rows 'over "
            "the rounding box'): the differences above need no misprint in (13); the rounding "
            "of the printed parameters, amplified through sigma L_s, accounts for them."
            if reach.reachable
            else "No parameter set found within the rounding of the Appendix parameters gives "
            f"all six entries of (13) (smallest largest deviation {fmt(reach.best_ratio, 3)} "
            "half units; rows 'over the rounding box')."
        )
    )
    for label, p in (("(13)", DELORENZO_IM_13), ("App.", DELORENZO_IM)):
        gm = gm_min(p)
        s.rows.append(
            Row(
                f"G_M,min (19), {label}",
                "(19), after (20)",
                f"{targets.GM_MIN_PRINTED.as_printed} ({targets.GM_MIN_DB_PRINTED.as_printed} dB)",
                f"{fmt(gm)} ({fmt(db(gm))} dB)",
                gm_min_note(gm, label),
            )
        )
    margin13 = -db(gm_min(DELORENZO_IM_13))
    s.rows.append(
        Row(
            "sign of G_M,min in dB",
            "after (20)",
            f"{targets.GM_MIN_DB_PRINTED.as_printed} dB",
            f"{margin13:+.3g} dB as a margin",
            "the paper quotes 20 log10 G_M,min; as a gain margin (factor that would put "
            f"gamma on +1) it is {margin13:+.3g} dB with (13). acdrive reports structural margins "
            "as positive dB when the plot stays left of (1, 0).",
        )
    )
    p = DELORENZO_IM_13
    # (14) and (18) against the state space; (16)-(17) limit of the argument
    for w_r in (100.0, W_R, 5000.0):
        plant = plant_from_params(p, w_r)
        G = evaluate_ss(plant.A, plant.B, plant.C, plant.D, np.array([1j * w_r]))[0]
        gam = G[0, 1] * G[1, 0] / (G[0, 0] * G[1, 1])
        cf = im_msf_at_rotor_speed(p, w_r)
        s.rows.append(
            Row(
                f"gamma(j w_r) at w_r = {fmt(w_r)}",
                "(14), (18)",
                "closed form",
                f"{fmt(gam, 4)}; |.| = {fmt(abs(gam))}",
                f"(14) {within_rel(cf, gam, FREQRESP_REL_TOL)}, (18) "
                f"{within_rel(im_msf_magnitude_at_rotor_speed(p, w_r), abs(gam), FREQRESP_REL_TOL)}",
            )
        )
    # (16): re_wr = a w_r^2 - b, im_wr = -c w_r, so 2 re im = -2ac w_r^3 + 2bc w_r and
    # re^2 - im^2 = a^2 w_r^4 - (2ab + c^2) w_r^2 + b^2: k_1..k_5 = 2ac, 2bc, a^2, 2ab + c^2, b^2
    sg, Ls, Lr, Lm, Rs, Rr = p.sigma, p.L_s, p.L_r, p.L_m, p.R_s, p.R_r
    a_ = 2 * sg * Ls * Lr**2 + Lr * Lm**2
    b_ = Lr * Rs * Rr
    c_ = sg * Ls * Lr * Rr + 2 * Lr**2 * Rs + Lm**2 * Rr
    ks = (2 * a_ * c_, 2 * b_ * c_, a_**2, 2 * a_ * b_ + c_**2, b_**2)
    wt = 250.0
    re_t = a_ * wt**2 - b_
    im_t = -c_ * wt
    lhs = 2 * re_t * im_t / (re_t**2 - im_t**2)
    rhs = (-ks[0] * wt**3 + ks[1] * wt) / (ks[2] * wt**4 - ks[3] * wt**2 + ks[4])
    s.rows.append(
        Row(
            "k_1 ... k_5 of (16)",
            "(16)",
            "real positive constants",
            ", ".join(fmt(k, 4) for k in ks),
            f"{'all positive' if min(ks) > 0 else 'NOT all positive'}; identity checked at "
            f"w_r = {fmt(wt)}: {within_rel(lhs, rhs, EXACT_REL_TOL)}",
        )
    )
    big = 1e6
    arg = math.degrees(np.angle(im_msf_at_rotor_speed(p, big)))
    s.rows.append(
        Row(
            "arg gamma(j w_r) as w_r -> inf",
            "(17)",
            "0 deg",
            f"{fmt(arg, 3)} deg at w_r = {fmt(big)} rad/s",
            str(within_abs(arg, 0.0, ARG_LIMIT_TOL_DEG, " deg")),
        )
    )
    rows_cross = []
    for w_r in SPEEDS_002[1:]:
        x, wx = gamma_real_axis_crossing(plant_from_params(p, w_r))
        rows_cross.append((w_r, x, wx, im_msf_magnitude_at_rotor_speed(p, w_r)))
    gm = gm_min(p)
    xs = [x for _, x, _, _ in rows_cross]
    lowest = rows_cross[int(np.argmax(xs))][0]  # largest crossing x = smallest margin
    gaps = [d - x for _, x, _, d in rows_cross]
    w_top, x_top, wx_top, _ = rows_cross[-1]
    s.rows.append(
        Row(
            f"structural GM of gamma at w_r = {fmt(w_top)}",
            "Fig. 3, text",
            "lowest at top speed, bounded by G_M,min",
            f"crossing x = {fmt(x_top)} at {fmt(wx_top)} rad/s = {fmt(-db(x_top))} dB",
            f"smallest margin at w_r = {fmt(lowest)} "
            f"({'the top speed' if lowest == w_top else 'NOT the top speed'}); largest crossing "
            f"{at_most(max(xs), gm, yes='bounded by G_M,min', no='NOT bounded by G_M,min')}; the "
            f"crossing is at w = F(3), {100 * relative_difference(wx_top, w_top):+.2g} % from w_r; "
            f"|gamma(j w_r)| (18) exceeds the crossing x by {fmt(gaps[0], 3)} at w_r = "
            f"{fmt(rows_cross[0][0])} and {fmt(gaps[-1], 3)} at {fmt(w_top)} rad/s",
        )
    )
    max_gamma = float(
        np.max(
            np.abs(icad_response(plant_from_params(p, W_R), LTI.gain(1), LTI.gain(1), W_NYQ).gamma)
        )
    )
    s.after = (
        "Positive-real-axis crossings of gamma (delorenzo-im-13):\n\n"
        "| w_r [rad/s] | crossing x | at w [rad/s] | margin -20 log10 x [dB] | |gamma(j w_r)| (18) |\n"
        "|---|---|---|---|---|\n"
        + "\n".join(
            f"| {fmt(a)} | {fmt(b)} | {fmt(c, 5)} | {fmt(-db(b))} | {fmt(d)} |"
            for a, b, c, d in rows_cross
        )
        + f"\n\nG_M,min = {fmt(gm)}: "
        + (
            "every crossing above stays below it"
            if max(xs) < gm
            else "some crossing above reaches it"
        )
        + (
            ", and the crossings grow with w_r"
            if all(b > a for a, b in itertools.pairwise(xs))
            else ", but the crossings do not grow steadily with w_r"
        )
        + " (G_M,min as the limit at high w_r: tests/test_icad_robustness.py). The largest "
        f"|gamma(j w)| at w_r = {fmt(W_R)} rad/s is {fmt(max_gamma)} "
        f"({'above' if max_gamma > 1 else 'not above'} 1), while every positive-real-axis "
        f"crossing is {'below 1' if max(xs) < 1 else 'NOT below 1'}."
    )
    plants = [plant_from_params(p, w) for w in SPEEDS_002]
    resp = icad_response(plants, LTI.gain(1.0), LTI.gain(1.0), W_NYQ)
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    nyquist_family(resp, axes[0])
    nyquist_family(resp, axes[1], zoom=((0.0, 1.1), (-0.6, 0.6)))
    th = np.linspace(-0.6, 0.6, 2)
    axes[1].plot([gm_min(p)] * 2, th, "k:", lw=0.8, label="G_M,min")
    axes[1].legend(fontsize=6)
    save_figure(fig_dir / "s002_nyquist_gamma.png", fig)
    s.figures.append(
        (
            "s002_nyquist_gamma.png",
            (
                "Amezquita-Brooks Fig. 3: Nyquist of gamma of the "
                "DeLorenzo IM ((13) parameters) for w_r = 0 ... 375 rad/s; right: zoom with "
                "G_M,min (dotted)."
            ),
        )
    )
    return s
