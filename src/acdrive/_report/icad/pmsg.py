"""Report section 'Seed 001, sec. 3: the 2 MW PMSG' (Ugalde-Loo et al. sec. 3).

The entries of A and B of the PMSG model (11) (sec. 3.5); the numerators (34) and the
denominator (35) of G from the state space; the MSF (36), whose printed numerator and
denominator are scaled differently; the closed form (18) of gamma against the state space; the
double pole of gamma (sec. 3.5); conditions i-iv over w_gen (secs. 3.4-3.5) and gamma(j0) of
(31)-(32); figure: Fig. 4. The paper writes the model with the mechanical speed w_gen,
acdrive's plants take the electrical speed w_r = n_P w_gen.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import scipy.signal

from acdrive._figures import save_figure
from acdrive._report import icad_targets as targets
from acdrive._report.icad.common import (
    EXACT_REL_TOL,
    FREQRESP_REL_TOL,
    SPEEDS_PMSG,
    error_within,
    fmt_rel,
    gamma_real_axis_crossing,
    printed_digits,
    within_rel,
)
from acdrive._report.icad_figures import nyquist_family
from acdrive._report.markdown import Row, Section, fmt
from acdrive._verdicts import at_most
from acdrive.analysis._freqresp import LTI, evaluate_ss
from acdrive.analysis._icad_closed_forms import pmsg_msf
from acdrive.analysis._icad_conditions import structure_conditions
from acdrive.analysis._icad_frequency import icad_response
from acdrive.analysis._plants import plant_from_params
from acdrive.machines._pmsm import PMSG_2MW


def section_pmsg(fig_dir: Path) -> Section:
    """The PMSG section; Fig. 4 is written into ``fig_dir``."""
    p = PMSG_2MW
    s = Section("Seed 001, sec. 3: the 2 MW PMSG")
    s.text = (
        "Ugalde-Loo et al. write the PMSG model (11) with the *mechanical* speed w_gen "
        "(n_P = 2, so the off-diagonal entries are 2 w_gen); acdrive's plants take the "
        "electrical speed w_r = n_P w_gen. Values below are per unit of w_gen where the paper's are."
    )
    one = plant_from_params(p, p.n_p * 1.0)  # w_gen = 1 rad/s
    rows = s.rows
    rows.append(
        Row(
            "A_11 = -R_s/L_d",
            "sec. 3.5",
            fmt(targets.PMSG_A_DIAG.value, 6),
            fmt(one.A[0, 0], 6),
            str(printed_digits(targets.PMSG_A_DIAG.as_printed, one.A[0, 0])),
        )
    )
    rows.append(
        Row(
            "A_12 per w_gen",
            "sec. 3.5",
            "2",
            fmt(one.A[0, 1], 6),
            str(within_rel(one.A[0, 1], targets.PMSG_A_OFFDIAG_PER_WGEN.value, EXACT_REL_TOL)),
        )
    )
    rows.append(
        Row(
            "B_11 = 1/L_d",
            "sec. 3.5",
            fmt(targets.PMSG_B.value, 6),
            fmt(one.B[0, 0], 6),
            str(printed_digits(targets.PMSG_B.as_printed, one.B[0, 0])),
        )
    )
    # (34)-(35) from the state space: numerator and denominator polynomials of G at w_gen = 1
    num, den = scipy.signal.ss2tf(one.A, one.B, one.C, one.D, input=0)
    num12 = scipy.signal.ss2tf(one.A, one.B, one.C, one.D, input=1)[0][0]
    for key, val, what in (
        ("n11_s", num[0][-2], "n_11: coefficient of s"),
        ("n11_0", num[0][-1], "n_11: constant"),
        ("n12_per_wgen", num12[-1], "n_12 per w_gen"),
    ):
        pr = targets.PMSG_G34[key]
        rows.append(
            Row(what, "(34)", pr.as_printed, fmt(val, 5), str(printed_digits(pr.as_printed, val)))
        )
    for key, val, what in (
        ("d_s", den[1], "d: coefficient of s"),
        ("d_0", den[2] - 4.0, "d: constant (w_gen = 0)"),
    ):
        pr = targets.PMSG_D35[key]
        rows.append(
            Row(what, "(35)", pr.as_printed, fmt(val, 6), str(printed_digits(pr.as_printed, val)))
        )
    two = plant_from_params(p, p.n_p * 2.0)
    d4 = scipy.signal.ss2tf(two.A, two.B, two.C, two.D, input=0)[1][2] - den[2]
    rows.append(
        Row(
            "d: coefficient of w_gen^2",
            "(35)",
            targets.PMSG_D35["d_wgen2"].as_printed,
            fmt(d4 / 3.0, 6),
            str(within_rel(d4 / 3.0, targets.PMSG_D35["d_wgen2"].value, EXACT_REL_TOL)),
        )
    )
    # (36): the MSF coefficient
    coef = -(p.L_d * p.L_q) * p.n_p**2  # gamma = coef w_gen^2 / ((L_q s + R_s)(L_d s + R_s))
    pr36 = targets.PMSG_MSF36["numerator_per_wgen2"]
    den_s, den_0 = targets.PMSG_MSF36["den_root_s"].value, targets.PMSG_MSF36["den_root_0"].value
    scale = den_s / p.L_d  # the printed (den_s s + den_0) = scale (L_d s + R_s) if uniform
    uniform = within_rel(den_0 / p.R_s, scale, EXACT_REL_TOL)
    numerator = printed_digits(pr36.as_printed, coef)
    if numerator.holds and uniform.holds and abs(scale - 1.0) > EXACT_REL_TOL:
        note36 = (
            f"the printed numerator equals -L_d L_q n_P^2 unscaled ({numerator}) while the printed "
            f"denominator is (L_d s + R_s)^2 scaled by {fmt(scale)}^2 (both roots scaled alike: "
            f"{uniform}): as printed, gamma is {fmt(scale**2)} times too small. Consistent form: "
            f"{fmt(coef * scale**2, 6)} w_gen^2 / ({fmt(den_s)} s + {fmt(den_0)})^2."
        )
    else:
        note36 = f"numerator {numerator}; denominator scale {fmt(scale)} ({uniform})"
    rows.append(
        Row(
            "gamma numerator per w_gen^2 over (322e-6 s + 4.523e-3)^2",
            "(36)",
            f"{pr36.as_printed} over ({fmt(den_s)} s + {fmt(den_0)})^2",
            fmt(coef, 6),
            note36,
        )
    )
    sv = np.array([1j * 3.0, 10.0 + 5j])
    G = evaluate_ss(two.A, two.B, two.C, two.D, sv)
    gam = G[:, 0, 1] * G[:, 1, 0] / (G[:, 0, 0] * G[:, 1, 1])
    err = np.max(np.abs(gam - pmsg_msf(p, 2.0 * p.n_p, sv)) / np.abs(gam))
    rows.append(
        Row(
            "gamma(s) of (18) vs state space",
            "(18)",
            "closed form",
            f"max rel. diff {fmt_rel(err)}",
            str(error_within(err, FREQRESP_REL_TOL)),
        )
    )
    rows.append(
        Row(
            "double pole of gamma",
            "sec. 3.5",
            targets.PMSG_MSF36["double_pole"].as_printed,
            fmt(-p.R_s / p.L_d, 6),
            str(printed_digits(targets.PMSG_MSF36["double_pole"].as_printed, -p.R_s / p.L_d)),
        )
    )
    # conditions over speed, and the only real-axis crossing at w = 0 (28)-(32)
    conds = [structure_conditions(plant_from_params(p, w)) for w in SPEEDS_PMSG]
    ok = all(c.i and c.ii and c.iii and c.iv for c in conds)
    rows.append(
        Row(
            "conditions i-iv, w_gen in [0, 157] rad/s",
            "sec. 3.4-3.5, Fig. 4",
            "hold",
            "hold" if ok else "FAIL",
            "exact Nyquist counts (encirclements of +1)",
        )
    )
    top = SPEEDS_PMSG[-1]
    g0 = complex(pmsg_msf(p, top, np.array([0.0]))[0])
    plants = [plant_from_params(p, w) for w in SPEEDS_PMSG]
    crossings = [
        gamma_real_axis_crossing(pl)[0] for pl in plants
    ]  # 0: no positive-real-axis crossing
    real0 = abs(g0.imag) <= EXACT_REL_TOL * abs(g0)
    rows.append(
        Row(
            "gamma(j0) at w_gen = 157 rad/s",
            "(31)-(32)",
            "< 1 (negative real)",
            fmt(g0, 5),
            ("real" if real0 else "not real")
            + ", "
            + str(at_most(g0.real, 0.0, yes="negative", no="not negative"))
            + "; positive-real-axis crossings over w = 0.1 ... 1e5 rad/s at any speed: "
            + (
                "none"
                if max(crossings) == 0.0
                else f"largest x = {fmt(max(crossings))} ({at_most(max(crossings), 1.0, yes='left of (1, 0)', no='NOT left of (1, 0)')})"
            ),
        )
    )
    resp = icad_response(plants, LTI.gain(1.0), LTI.gain(1.0), np.logspace(-1, 5, 2000))
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    nyquist_family(resp, axes[0])
    nyquist_family(resp, axes[1], zoom=((-2.0, 1.2), (-1.5, 1.5)))
    for ax in axes:
        for line in ax.get_lines()[: len(SPEEDS_PMSG)]:
            line.set_label(line.get_label().replace("w_r", "w_e"))
        ax.legend(fontsize=6)
    axes[0].set_title("gamma, PMSG 2 MW (w_e = 2 w_gen)")
    save_figure(fig_dir / "s001_pmsg_nyquist.png", fig)
    s.figures.append(
        (
            "s001_pmsg_nyquist.png",
            (
                "Ugalde-Loo Fig. 4: Nyquist of gamma of the 2 MW PMSG for w_gen = 0 ... "
                "157 rad/s (electrical 0 ... 314 rad/s); "
                + (
                    "no encirclement of (1, 0) and no positive-real-axis crossing right of it at "
                    "any speed."
                    if ok and max(crossings) < 1.0
                    else "(1, 0) is encircled or crossed at some speed: see the table."
                )
            ),
        )
    )
    return s
