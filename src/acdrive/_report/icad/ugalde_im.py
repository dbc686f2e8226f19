"""Report section 'Seed 001, sec. 4: the 300 W IM, matrix (80) and the printed closed forms'
(Ugalde-Loo et al. sec. 4, the IM stator-current subsystem).

Matrix (80) against (41) with the parameters of sec. 4.5, and (80) against Amezquita-Brooks
et al. (13). The printed closed forms of the proof of conditions i-iv in sec. 4.4 ((44)-(48),
(53), (56), F(2), F(3) of (73), (75), (78)) are evaluated here exactly as printed, only to be
compared with the same quantities computed numerically from the state-space model (41); they
are not used by the analysis code. Also gamma(j w) of (60)-(61) against the state space, the
positive-real-axis crossing (58)-(59) and conditions i-iv over w_r; figures: Figs. 6-8.
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import scipy.signal
from scipy.optimize import brentq

from acdrive._figures import save_figure
from acdrive._report import icad_targets as targets
from acdrive._report.icad.common import (
    EXACT_REL_TOL,
    FREQRESP_REL_TOL,
    ROOT_REL_TOL,
    SPEEDS_001_IM,
    W_NYQ,
    error_within,
    fmt_rel,
    gamma_real_axis_crossing,
    within_rel,
)
from acdrive._report.icad.rounding import rounding_reach, rounding_rows
from acdrive._report.icad.stator_matrix import entries_with_verdict, matrix_entry_rows
from acdrive._report.icad_figures import nyquist_family
from acdrive._report.markdown import Row, Section, fmt
from acdrive._verdicts import at_most
from acdrive.analysis._freqresp import LTI, evaluate_ss
from acdrive.analysis._icad_closed_forms import im_dgamma_re_im, im_msf_closed_form
from acdrive.analysis._icad_conditions import structure_conditions
from acdrive.analysis._icad_frequency import icad_response
from acdrive.analysis._plants import plant_from_params
from acdrive.machines._induction import UGALDE_IM_300W, IMParams, stator_current_ss

#: A closed form of the proofs evaluated as printed against the same quantity computed
#: numerically from the state space (ss2tf polynomial coefficients, brentq roots).
CLOSED_FORM_REL_TOL = 1e-7


def _printed_closed_forms(p: IMParams, w_r: float) -> dict[str, float]:
    """The expressions of Ugalde-Loo et al. (44)-(48), (53), (56), (73), (75), (78) as printed."""
    Rs, Rr, Ls, Lr, Lm, sg = p.R_s, p.R_r, p.L_s, p.L_r, p.L_m, p.sigma
    wr = w_r
    k = 1.0 / (sg**2 * Ls**2 * Lr**4)
    mu = Ls * Lr - Lm**2
    out = {
        "n11_2": (2 * sg * Ls * Lr**2 * Rr + Lm**2 * Rr * Lr + Lr**3 * Rs) / (sg * Ls * Lr**3),
        "n11_1": (sg * Ls * Lr * (Lr**2 * wr**2 + Rr**2) + 2 * Lr**2 * Rs * Rr + Lm**2 * Rr**2)
        / (sg * Ls * Lr**3),
        "n11_0": (Lr**3 * Rs * wr**2 + Lr * Rs * Rr**2) / (sg * Ls * Lr**3),
        "n12_1": -(Lm**2) * Rr * wr / (sg**2 * Ls**2 * Lr**2),
        "d1": k * (2 * sg * Ls * Lr**2) * (Lm**2 * Rr + sg * Ls * Lr * Rr + Lr**2 * Rs),
        "d2": k * (Lm**4 * Rr**2 + Lr**4 * Rs**2 + sg**2 * Ls**2 * Lr**2 * (Rr**2 + Lr**2 * wr**2))
        + k * (2 * Lr**2 * Lm**2 * Rs * Rr + 2 * sg * Ls * Lr * Rr * (2 * Lr**2 * Rs + Lm**2 * Rr)),
        "d3": 2 * k * Lr * Rs * Rr * (Lr**2 * Rs + Lm**2 * Rr)
        + 2 * k * sg * Ls * Lr**2 * Rs * (Rr**2 + Lr**2 * wr**2),
        "d4": k * (Lr**4 * Rs**2 * wr**2 + Lr**2 * Rs**2 * Rr**2),
        "h2": 2 * (Lr * Rs + Ls * Rr) ** 3 / mu**3
        + 2 * Ls * Rr * wr**2 / mu
        + 2 * Rr * Rs * (Lr * Rs + Ls * Rr) / mu**2,
        "h3": 4
        * Rr
        * Rs
        * (wr**2 * mu**2 + (Lr * Rs + Ls * Rr) ** 2)
        * mu**-5
        * (mu * Ls * Lr * wr**2 + (Lr * Rs + Ls * Rr) ** 2),
    }
    beta = 1.0 / (sg**4 * Ls**4 * Lr**5)
    out["eta"] = (
        beta * (3 * Lr**2 * Lm**2 * Rs * Rr**2 + Lm**4 * Rr**3)
        + beta
        * (
            4 * sg * Ls * Lr**3 * Rs * Rr**2
            + 3 * sg * Ls * Lr * Lm**2 * Rr**3
            + 2 * Lr**4 * Rs**2 * Rr
        )
        + beta
        * (
            wr**2 * sg * Ls * Lr**3 * Rr * (2 * sg * Ls * Lr + Lm**2)
            + 2 * sg**2 * Ls**2 * Lr**2 * Rr**3
        )
    )
    Om = 2 * sg * Ls * Lr * Rr + Lr**2 * Rs + Lm**2 * Rr
    Psi = sg * Ls * Lr
    Ups = 2 * Lr * Rs * Rr + Lm**2 * Rr**2
    out["F2"] = math.sqrt(Om * (Rr**2 + wr**2 * Lr**2) * Rs) / Om
    out["F3"] = math.sqrt(Psi * (Psi * (wr**2 * Lr**2 + Rr**2) + Ups)) / Psi**2
    out["F3_consistent"] = math.sqrt(
        (Psi * (wr**2 * Lr**2 + Rr**2) + 2 * Lr**2 * Rs * Rr + Lm**2 * Rr**2) / (Psi * Lr**2)
    )
    c1a = (
        Lm**4 * Rr**2
        + 3 * sg * Ls * Lr * Lm**2 * Rr**2
        + 3 * Lr**2 * Lm**2 * Rs * Rr
        + Ls * Lr**3 * Lm**2 * sg * wr**2
        + 2 * (sg * Ls * Lr * Rr) ** 2
        + 2 * Lr**4 * Rs**2
        + 4 * sg * Ls * Lr**3 * Rs * Rr
        + 2 * Lr**4 * (sg * Ls * wr) ** 2
    ) ** 2
    out["c1_F2"] = -Rs * (Rr**4 + (Rr * wr * Lr) ** 2) / Om**3 * c1a
    out["c1_F3"] = Rr**2 / (sg**2 * Ls**2 * Lr**4) * c1a
    return out


def _gamma_60_as_printed(p: IMParams, w_r: float, w: np.ndarray) -> np.ndarray:
    """gamma(j w) of Ugalde-Loo (60) with d_gamma_w as printed there: its term
    -j w sigma L_s L_s^3 w_r^2 where (61) has -j w sigma L_s L_r^3 w_r^2 (the rest of d_gamma_w
    as (61), ``im_dgamma_re_im``)."""
    re, im = im_dgamma_re_im(p, w_r, w)
    extra = -w * p.sigma * p.L_s * (p.L_s**3 - p.L_r**3) * w_r**2
    num = p.L_r**2 * p.L_m**4 * p.R_r**2 * w_r**2 * w**2
    return num / (re + 1j * (im + extra)) ** 2


def c_of_80_row(p: IMParams) -> Row:
    """C of (80) as printed (``targets.UGALDE_IM_C_80_ROWS``) against C of (41) built by
    ``stator_current_ss``: the shape of each printed row and which row of (41)'s C it matches."""
    C = stator_current_ss(p, 0.0)[2]
    printed = targets.UGALDE_IM_C_80_ROWS
    lengths = [len(r) for r in printed]
    identity = np.array_equal(C, np.eye(2, 4))

    def matches(row) -> list[int]:
        # rows of (41)'s C equal to the printed row, or to it padded with trailing zeros
        padded = np.array(list(row) + [0] * (C.shape[1] - len(row)), dtype=float)
        return [i + 1 for i in range(C.shape[0]) if np.array_equal(C[i], padded)]

    found = [matches(r) for r in printed]
    covered = sorted({i for m in found for i in m})
    note = (
        f"printed with {len(printed)} rows of {', '.join(str(n) for n in lengths)} entries; "
        f"(41) has {C.shape[0]} outputs and {C.shape[1]} states. Printed row -> row of (41)'s C "
        "(a short row padded with zeros): "
        + "; ".join(
            f"{i + 1} -> {', '.join(str(j) for j in m) if m else 'none'}"
            for i, m in enumerate(found)
        )
        + ". "
    )
    if covered == list(range(1, C.shape[0] + 1)) and all(found):
        note += (
            "Every printed row is a row of (41)'s C and every row of it is printed: a "
            "typesetting misprint of C = [I_2 0]"
        )
    else:
        note += "The printed rows do not reduce to (41)'s C: the difference is open"
    note += f"; acdrive's C {'equals' if identity else 'differs from'} [I_2 0]"
    return Row(
        "C of (80)",
        "(80)",
        "; ".join(" ".join(str(x) for x in r) for r in printed),
        "; ".join(" ".join(f"{x:g}" for x in r) for r in C),
        note,
    )


def section_ugalde_im(fig_dir: Path) -> Section:
    """The 300 W IM section; Figs. 6-8 are written into ``fig_dir``."""
    p = UGALDE_IM_300W
    s = Section("Seed 001, sec. 4: the 300 W IM, matrix (80) and the printed closed forms")
    s.text = (
        "Matrix (80) against (41) with the parameters of sec. 4.5; then every closed form of "
        "the proof of conditions i-iv, evaluated as printed at w_r = 300 rad/s and compared with "
        "the same quantity computed numerically from the state-space model (transfer-function "
        "coefficients with scipy.signal.ss2tf, roots with brentq)."
    )
    rows80, verdicts80 = matrix_entry_rows("sec. 4.5 parameters", targets.UGALDE_IM_MATRIX_80, p)
    s.rows += rows80
    s.rows += rounding_rows(
        rounding_reach(targets.UGALDE_IM_PRINTED, targets.UGALDE_IM_MATRIX_80),
        "sec. 4.5",
        "Ugalde-Loo (80)",
    )
    m80, m13 = targets.UGALDE_IM_MATRIX_80, targets.DELORENZO_MATRIX_13
    same = (
        within_rel(m80.a11, m13.a11, EXACT_REL_TOL).holds
        and within_rel(m80.b, m13.b, EXACT_REL_TOL).holds
    )
    s.rows.append(
        Row(
            "a_11 and b_11 of (80)",
            "(80) vs seed 002 (13)",
            f"{targets.printed_text(m80.a11)}, {targets.printed_text(m80.b)}",
            f"{fmt(stator_current_ss(p, 0.0)[0][0, 0], 5)}, {fmt(stator_current_ss(p, 0.0)[1][0, 0], 4)}",
            f"(80) prints {'the same' if same else 'a different'} a_11 and b_11 as seed 002's (13) "
            f"({targets.printed_text(m13.a11)}, {targets.printed_text(m13.b)}) for the same 300 W motor. With "
            f"sec. 4.5's parameters, entries that agree to the printed digits: "
            f"{entries_with_verdict(verdicts80, True)}; that differ: {entries_with_verdict(verdicts80, False)} (rows above). "
            "acdrive uses the parameters (machine ugalde-im-300w).",
        )
    )
    s.rows.append(c_of_80_row(p))
    w_r = 300.0
    pr = _printed_closed_forms(p, w_r)
    plant = plant_from_params(p, w_r)
    num, den = scipy.signal.ss2tf(plant.A, plant.B, plant.C, plant.D, input=0)
    num12 = scipy.signal.ss2tf(plant.A, plant.B, plant.C, plant.D, input=1)[0][0]
    lead = num[0][1]  # 1/(sigma L_s)
    checks = [
        ("n_11 coefficient of s^2 / n_11 leading", "(44)", pr["n11_2"], num[0][2] / lead),
        ("n_11 coefficient of s / leading", "(44)", pr["n11_1"], num[0][3] / lead),
        ("n_11 constant / leading", "(44)", pr["n11_0"], num[0][4] / lead),
    ]
    for i, key in enumerate(("d1", "d2", "d3", "d4")):
        checks.append((f"d_w{i + 1}", "(45)", pr[key], den[i + 1]))
    d1, d2, d3, d4 = den[1:]
    checks.append(("d_w1 d_w2 - d_w3", "(48)", pr["h2"], d1 * d2 - d3))
    checks.append(
        (
            "d_w1 d_w2 d_w3 - d_w3^2 - d_w1^2 d_w4",
            "(48)",
            pr["h3"],
            d1 * d2 * d3 - d3**2 - d1**2 * d4,
        )
    )
    eta = num[0][1:]
    checks.append(
        ("eta_2 eta_3 - eta_1 eta_4", "(56)", pr["eta"], eta[1] * eta[2] - eta[0] * eta[3])
    )
    for name, where, printed, numeric in checks:
        s.rows.append(
            Row(
                name,
                where,
                fmt(printed, 7),
                fmt(numeric, 7),
                str(within_rel(printed, numeric, CLOSED_FORM_REL_TOL)),
            )
        )
    magnitude = within_rel(abs(pr["n12_1"]), abs(num12[3]), CLOSED_FORM_REL_TOL)
    s.rows.append(
        Row(
            "n_12 coefficient of s",
            "(44)",
            fmt(pr["n12_1"], 7),
            fmt(num12[3], 7),
            f"magnitude {magnitude}, opposite sign: with A of (41), g_12 = +L_m^2 R_r w_r s/(...) "
            "and g_21 the negative; (44) swaps the signs. gamma = g_12 g_21/(g_11 g_22) is "
            "unaffected."
            if magnitude.holds and pr["n12_1"] * num12[3] < 0
            else str(within_rel(pr["n12_1"], num12[3], CLOSED_FORM_REL_TOL)),
        )
    )
    wv = np.array([50.0, 313.0, 2000.0])
    G = evaluate_ss(plant.A, plant.B, plant.C, plant.D, 1j * wv)
    gam = G[:, 0, 1] * G[:, 1, 0] / (G[:, 0, 0] * G[:, 1, 1])
    err = float(np.max(np.abs(im_msf_closed_form(p, w_r, wv) - gam) / np.abs(gam)))
    err60 = float(np.max(np.abs(_gamma_60_as_printed(p, w_r, wv) - gam) / np.abs(gam)))
    as_printed_60 = error_within(err60, FREQRESP_REL_TOL)
    s.rows.append(
        Row(
            "gamma(j w) of (60)-(61) vs state space",
            "(60)-(61)",
            "closed form",
            f"max rel. diff {fmt_rel(err)}",
            f"{error_within(err, FREQRESP_REL_TOL)} with the closed form written from (61); (60) "
            "as printed, with the term -j w sigma L_s L_s^3 w_r^2 in d_gamma_w where (61) has "
            f"sigma L_s L_r^3 w_r^2: {as_printed_60}"
            + (
                " (a misprint of L_r^3 in (60))"
                if not as_printed_60.holds and error_within(err, FREQRESP_REL_TOL).holds
                else ""
            ),
        )
    )
    f2 = brentq(lambda x: im_dgamma_re_im(p, w_r, x)[0], 1e-6, 1e6)
    f3 = brentq(lambda x: im_dgamma_re_im(p, w_r, x)[1], 1e-3, 1e6)
    s.rows.append(
        Row(
            "F(2): root of re_dgamma",
            "(73)",
            fmt(pr["F2"], 7),
            fmt(f2, 7),
            str(within_rel(pr["F2"], f2, CLOSED_FORM_REL_TOL)),
        )
    )
    as_printed = within_rel(pr["F3"], f3, CLOSED_FORM_REL_TOL)
    consistent = within_rel(pr["F3_consistent"], f3, CLOSED_FORM_REL_TOL)
    s.rows.append(
        Row(
            "F(3): root of im_dgamma",
            "(73)",
            fmt(pr["F3"], 7),
            fmt(f3, 7),
            f"as printed: {as_printed}"
            + (
                "; the paper prints F(3) = +/- sqrt(Psi [Psi (w_r^2 L_r^2 + R_r^2) + Upsilon]) "
                "/ Psi^2 with Psi = sigma L_s L_r and Upsilon = 2 L_r R_s R_r + L_m^2 R_r^2: in "
                "units, Psi [Psi (...)] is H^4 ohm^2, so the square root over Psi^2 (H^4) is "
                "ohm/H^2, not 1/s, and Upsilon adds H ohm^2 to H^2 ohm^2. The dimensionally "
                "consistent sqrt((Psi (w_r^2 L_r^2 + R_r^2) + 2 L_r^2 R_s R_r + L_m^2 R_r^2) / "
                f"(Psi L_r^2)) = {fmt(pr['F3_consistent'], 7)} {consistent} with the root of (61)"
                if not as_printed.holds
                else ""
            ),
        )
    )
    xmax, wx = gamma_real_axis_crossing(plant)
    s.rows.append(
        Row(
            "positive-real-axis crossing of gamma at w = F(3)",
            "(58)-(59)",
            "Re gamma(jF(3)) < 1",
            f"x = {fmt(xmax, 4)} at w = {fmt(wx, 6)}",
            f"x {at_most(xmax, 1.0, yes='below 1', no='NOT below 1')}; crossing frequency "
            f"{within_rel(wx, f3, ROOT_REL_TOL)} with the root F(3) of (61)",
        )
    )
    for key, wx_, where in (("c1_F2", f2, "(75)"), ("c1_F3", f3, "(78)")):
        re, im = im_dgamma_re_im(p, w_r, wx_)
        s.rows.append(
            Row(
                f"c_1 = re^2 - im^2 at F({key[-1]})",
                where,
                fmt(pr[key], 7),
                fmt(re**2 - im**2, 7),
                str(within_rel(pr[key], re**2 - im**2, CLOSED_FORM_REL_TOL)),
            )
        )
    # figures 6, 7, 8
    plants = [plant_from_params(p, w) for w in SPEEDS_001_IM]
    conds = [structure_conditions(pl) for pl in plants]
    ok = all(c.i and c.ii and c.iii and c.iv for c in conds)
    s.rows.append(
        Row(
            "conditions i-iv over w_r in [0, 375]",
            "sec. 4.5, Figs. 6-8",
            "hold",
            "hold" if ok else "FAIL",
            "exact counts",
        )
    )
    top_re = max(
        float(np.max(np.concatenate([c.plant_poles.real, c.gamma_poles.real]))) for c in conds
    )
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    cols = plt.cm.viridis(np.linspace(0, 0.9, len(plants)))
    for c, w, col in zip(conds, SPEEDS_001_IM, cols):
        axes[0].plot(c.plant_poles.real, c.plant_poles.imag, "x", color=col, label=f"w_r = {w:g}")
        axes[1].plot(
            c.gamma_poles.real, c.gamma_poles.imag, "o", mfc="none", color=col, label=f"w_r = {w:g}"
        )
    axes[0].set_title("Fig. 6: poles of G (eigenvalues of A)")
    axes[1].set_title("Fig. 7: poles of gamma (zeros of g_11 g_22)")
    for ax in axes:
        ax.axvline(0, color="0.7", lw=0.5)
        ax.set_xlabel("Re [1/s]")
        ax.set_ylabel("Im [rad/s]")
        ax.legend(fontsize=6)
    save_figure(fig_dir / "s001_im_poles.png", fig)
    s.figures.append(
        (
            "s001_im_poles.png",
            (
                "Ugalde-Loo Figs. 6-7: poles of G and of gamma of the 300 W IM over w_r "
                f"(largest real part {fmt(top_re, 4)} 1/s: "
                f"{'all in' if top_re < 0 else 'NOT all in'} the open left half-plane)."
            ),
        )
    )
    resp = icad_response(plants, LTI.gain(1.0), LTI.gain(1.0), W_NYQ)
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    nyquist_family(resp, axes[0])
    nyquist_family(resp, axes[1], zoom=((-0.2, 1.2), (-0.8, 0.8)))
    save_figure(fig_dir / "s001_im_nyquist.png", fig)
    s.figures.append(
        (
            "s001_im_nyquist.png",
            (
                "Ugalde-Loo Fig. 8: Nyquist of gamma of the 300 W IM (w > 0); "
                + (
                    "no encirclement of (1, 0) at any speed (exact counts)."
                    if all(c.iv for c in conds)
                    else "(1, 0) is encircled at some speed (exact counts)."
                )
            ),
        )
    )
    return s
