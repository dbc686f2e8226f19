"""Report section 'Seed 002, sec. V-C/V-D: controller (20), Table I, Figs. 5-8'
(Amezquita-Brooks et al. secs. V-C and V-D).

Controller (20) on both channels at w_r = 375 rad/s with both parameter sets: crossover
(the paper's 'bandwidth') and -3 dB bandwidth, phase and gain margins of c_i and of k_i g_ii
against the values quoted in the text and the sec. V-B specifications, the structural margins
of gamma h_j (Table I) and of gamma (bound (19)), the gains at the resonance, the coupling (10)
and conditions (b.1), (b.2); then the same over w_r; figures: Figs. 5-8.
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from acdrive._figures import save_figure
from acdrive._report import icad_targets as targets
from acdrive._report.icad.common import (
    BANDWIDTH_REL_TOL,
    APPROX_GAIN_TOL_DB,
    PM_TOL_DEG,
    SPEEDS_002,
    W_BODE,
    W_R,
    channel_response,
    within_rel,
)
from acdrive._report.icad_figures import bode_family, coupling_family, nyquist_family
from acdrive._report.markdown import Row, Section, db, fmt
from acdrive._verdicts import at_least, at_most, within_abs
from acdrive.analysis._freqresp import LTI
from acdrive.analysis._icad import analyse
from acdrive.analysis._icad_frequency import icad_response
from acdrive.analysis._plants import plant_from_params
from acdrive.machines._induction import DELORENZO_IM, DELORENZO_IM_13, IMParams

#: Structural gain margin of gamma h_j quoted with one decimal (3.4 dB, sec. V-C).
GM_GAMMA_H_TOL_DB = 0.1


def _speed_family(p: IMParams, k: LTI, speeds=SPEEDS_002, w=W_BODE, verify: bool = False):
    """ICAD analyses of machine ``p`` with ``k`` on both channels at each of ``speeds``, and the
    frequency responses of the family over ``w``."""
    plants = [plant_from_params(p, s) for s in speeds]
    analyses = [analyse(pl, k, k, w, verify=verify) for pl in plants]
    return analyses, icad_response(plants, k, k, w)


def section_controller_20(fig_dir: Path, k20: LTI) -> Section:
    """The section on controller ``k20`` = (20); Figs. 5-8 are written into ``fig_dir``."""
    s = Section("Seed 002, sec. V-C/V-D: controller (20), Table I, Figs. 5-8")
    results = {}
    for label, p in (("(13)", DELORENZO_IM_13), ("App.", DELORENZO_IM)):
        a = analyse(plant_from_params(p, W_R), k20, k20, verify=True)
        results[label] = a
    n = targets.NOMINAL_20
    r13 = results["(13)"]

    def both(fn, digits=4):
        return " / ".join(fmt(fn(results[lb]), digits) for lb in ("(13)", "App."))

    ch = lambda a: a.channels[0]  # channels are symmetric
    m13 = ch(r13).margins
    s.text = (
        "Controller (20) = 326.5 (s + 1000)/s x (s + 400)^2/(s^2 + 100 s + 42500) on both "
        "channels, w_r = 375 rad/s unless stated. acdrive's definitions: crossover = highest "
        "|c_i| = 1 frequency; bandwidth = -3 dB frequency of c_i/(1 + c_i); gain margin of a "
        "conditionally stable loop = its gain-reduction margin (with (13), the phase of c_i "
        "crosses -180 deg at "
        + ", ".join(f"{fmt(x)} rad/s" for x in m13.phase_crossovers_rad_s)
        + "; upward gain margin: "
        + ("none" if math.isinf(m13.gm_db) else f"{fmt(m13.gm_db, 3)} dB")
        + "). Table I itself is an image missing from the text; the values quoted in the text "
        "are compared, verdicts with the (13) parameters unless stated."
    )
    s.rows.append(
        Row(
            "'bandwidth' = crossover of c_i [rad/s] ((13) / App.)",
            "sec. V-C",
            fmt(n["bandwidth"].value),
            both(lambda a: ch(a).margins.crossover_rad_s),
            f"{within_rel(m13.crossover_rad_s, n['bandwidth'].value, BANDWIDTH_REL_TOL)} "
            "with (13): the paper's 'bandwidth' is read as the open-loop crossover of c_i",
        )
    )
    bw = ch(r13).bandwidth_rad_s
    s.rows.append(
        Row(
            "-3 dB closed-loop bandwidth of c_i/(1+c_i) [rad/s]",
            "-",
            "-",
            both(lambda a: ch(a).bandwidth_rad_s),
            f"{'larger' if bw > m13.crossover_rad_s else 'not larger'} than the crossover "
            f"(ratio {fmt(bw / m13.crossover_rad_s, 3)} with (13), PM {fmt(m13.pm_deg, 2)} deg)",
        )
    )
    s.rows.append(
        Row(
            "phase margin of c_i [deg]",
            "sec. VII (Fig. 19)",
            fmt(n["pm_full"].value),
            both(lambda a: ch(a).margins.pm_deg, 3),
            str(within_abs(m13.pm_deg, n["pm_full"].value, PM_TOL_DEG, " deg")),
        )
    )
    worst_gm = min(-ch(a).margins.gm_reduction_db for a in results.values())
    s.rows.append(
        Row(
            "gain margin of c_i [dB]",
            "spec > 12 dB",
            f"> {fmt(targets.SPEC_GM.value)}",
            both(lambda a: -ch(a).margins.gm_reduction_db, 3),
            f"gain-reduction margin; worse of the two {at_least(worst_gm, targets.SPEC_GM.value, ' dB')}",
        )
    )
    worst_kg_pm = min(ch(a).kg_margins.pm_deg for a in results.values())
    worst_kg_gm = min(-ch(a).kg_margins.gm_reduction_db for a in results.values())
    s.rows.append(
        Row(
            "margins of k_i g_ii: PM [deg] / GM [dB]",
            "Fig. 6, Table I",
            "robust",
            both(lambda a: ch(a).kg_margins.pm_deg, 3)
            + " ; "
            + both(lambda a: -ch(a).kg_margins.gm_reduction_db, 3),
            "against the sec. V-B specifications, worse of the two: PM "
            f"{at_least(worst_kg_pm, targets.SPEC_PM.value, ' deg')}, GM "
            f"{at_least(worst_kg_gm, targets.SPEC_GM.value, ' dB')}",
        )
    )
    s.rows.append(
        Row(
            "structural GM of gamma h_j [dB]",
            "sec. V-C, Table I",
            fmt(n["gm_gamma_h"].value),
            both(lambda a: ch(a).structural.gm_db, 3),
            f"{within_abs(ch(r13).structural.gm_db, n['gm_gamma_h'].value, GM_GAMMA_H_TOL_DB, ' dB')}"
            " with (13)",
        )
    )
    bound = -targets.GM_MIN_DB_PRINTED.value  # the printed G_M,min of (19) as a margin
    s.rows.append(
        Row(
            "structural GM of gamma [dB]",
            "(19)",
            f">= {fmt(bound)} (bound)",
            both(lambda a: a.structural.gm_db, 3),
            f"worse of the two {at_least(min(a.structural.gm_db for a in results.values()), bound, ' dB')}",
        )
    )
    w375 = np.array([W_R])
    kg = {lb: abs(channel_response(a.plant, k20, w375)["kg"][0, 0]) for lb, a in results.items()}
    cc = {lb: abs(channel_response(a.plant, k20, w375)["c"][0, 0]) for lb, a in results.items()}
    s.rows.append(
        Row(
            "|k_i g_ii(j375)| [dB]",
            "sec. V-C (Fig. 6)",
            f"> {fmt(n['kg_at_375'].value)}",
            " / ".join(fmt(db(kg[lb]), 3) for lb in ("(13)", "App.")),
            f"worse of the two {at_least(db(min(kg.values())), n['kg_at_375'].value, ' dB')}",
        )
    )
    s.rows.append(
        Row(
            "|c_i(j375)| (gain at the resonance) [dB]",
            "sec. VII",
            f"approx {fmt(n['lag_gain_at_peak'].value)}",
            " / ".join(fmt(db(cc[lb]), 3) for lb in ("(13)", "App.")),
            str(within_abs(db(cc["(13)"]), n["lag_gain_at_peak"].value, APPROX_GAIN_TOL_DB, " dB")),
        )
    )
    s.rows.append(
        Row(
            "coupling peak |y_i/r_j| (10) [dB]",
            "sec. V-D, Fig. 8",
            f"<= {fmt(n['coupling_peak'].value)}",
            both(lambda a: a.coupling_peak_db, 3),
            "printed maximum (read from a figure): "
            + str(
                at_most(
                    r13.coupling_peak_db,
                    n["coupling_peak"].value,
                    " dB",
                    yes="within it",
                    no="above it",
                )
            )
            + "; the "
            + targets.SPEC_COUPLING.text
            + " specification: "
            + str(at_most(r13.coupling_peak_db, targets.SPEC_COUPLING.value, " dB")),
        )
    )
    s.rows.append(
        Row(
            "(b.1), (b.2), closed-loop stable",
            "sec. V-C",
            "satisfied",
            " / ".join(
                "yes" if (a.b1 and a.b2 and a.closed_loop_stable) else "NO"
                for a in results.values()
            ),
            "exact counts, contour-verified",
        )
    )
    # speed families for Figs. 5-8
    analyses, resp = _speed_family(DELORENZO_IM_13, k20)
    peaks = [a.coupling_peak_db for a in analyses]
    worst_cp = max(peaks)
    s.rows.append(
        Row(
            "worst coupling peak over w_r in [0, 375] [dB]",
            "sec. V-D",
            f"<= {fmt(n['coupling_peak'].value)}",
            fmt(worst_cp, 3),
            f"at w_r = {fmt(SPEEDS_002[int(np.argmax(peaks))])}; printed maximum: "
            + str(
                at_most(worst_cp, n["coupling_peak"].value, " dB", yes="within it", no="above it")
            ),
        )
    )
    for key, name, cap in (
        (
            "c",
            "s002_bode_channels.png",
            "Amezquita-Brooks Fig. 5: Bode of the channels c_i with (20) over w_r.",
        ),
        (
            "kg",
            "s002_bode_kg.png",
            (
                "Amezquita-Brooks Fig. 6: Bode of k_i g_ii over w_r; |k g(j375)| at w_r = 375 "
                f"is {fmt(db(kg['(13)']), 3)} dB "
                f"({'above' if db(kg['(13)']) > n['kg_at_375'].value else 'NOT above'} "
                f"{fmt(n['kg_at_375'].value)} dB)."
            ),
        ),
    ):
        fig, axes = plt.subplots(2, 1, figsize=(8, 6.5), sharex=True)
        bode_family(resp, axes, key)
        save_figure(fig_dir / name, fig)
        s.figures.append((name, cap))
    min_gm_gamma = min(a.structural.gm_db for a in analyses)
    min_gm_gamma_h = min(c.structural.gm_db for a in analyses for c in a.channels)
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    nyquist_family(resp, axes[0], "gamma", zoom=((-0.3, 1.1), (-0.7, 0.7)))
    nyquist_family(resp, axes[1], "gamma_h", zoom=((-0.3, 1.1), (-0.7, 0.7)))
    save_figure(fig_dir / "s002_nyquist_gamma_h.png", fig)
    s.figures.append(
        (
            "s002_nyquist_gamma_h.png",
            (
                "Amezquita-Brooks Fig. 7: gamma and gamma h_j over w_r (zoom near (1, 0)); "
                f"smallest structural margins {fmt(min_gm_gamma, 3)} dB (gamma) and "
                f"{fmt(min_gm_gamma_h, 3)} dB (gamma h_j): "
                + (
                    "every trajectory stays left of the critical point."
                    if min(min_gm_gamma, min_gm_gamma_h) > 0.0
                    else "some trajectory reaches the critical point or passes right of it."
                )
            ),
        )
    )
    fig, ax = plt.subplots(figsize=(8, 4.2))
    coupling_family(resp, ax)
    ax.axhline(targets.SPEC_COUPLING.value, color="r", ls=":", lw=0.8)
    ax.set_ylim(-120, 0)
    save_figure(fig_dir / "s002_coupling.png", fig)
    s.figures.append(
        (
            "s002_coupling.png",
            "Amezquita-Brooks Fig. 8: coupling |y_1/r_2| over w_r (dotted: -15 dB specification).",
        )
    )
    return s
