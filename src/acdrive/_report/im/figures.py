"""The figures of the IM time-domain report: each experiment's run figures
(``drives.cage_im._outputs``) copied under report names, and the coupling figure (measured beside
(10)).
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import matplotlib

from acdrive._report.im.settings import PMSG_BANDWIDTH

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from acdrive._figures import save_figure
from acdrive._report import icad_targets as targets
from acdrive._report.markdown import fmt
from acdrive.analysis._coupling import CouplingResult, icad_coupling
from acdrive.drives.cage_im._outcome import IMOutcome
from acdrive.drives.cage_im._outputs import (
    step_comparison,
    write_comparison_figures,
    write_run_figures,
)

#: figures copied from each experiment's run folder into the report's (source -> file name)
FIGURES = {
    "fig11": [("compare_currents.png", "Fig. 11: i_alpha of (20) and the stationary PI")],
    "fig13": [
        ("speed.png", "Fig. 13(a): speed"),
        ("load_torque.png", "Fig. 13(b): load torque"),
        ("currents_closeup.png", "Fig. 13(c): currents at the load change"),
        ("modulation_a.png", "Fig. 13(d): phase-a modulation signal"),
    ],
    "fig14": [
        ("position.png", "Fig. 14(a): position"),
        ("load_torque.png", "Fig. 14(b): load torque"),
        ("currents_closeup.png", "Fig. 14(c): currents at the load change"),
    ],
    "fig16": [
        ("compare_speed.png", "Fig. 16(a): speed of each controller and the ideal ramp"),
        ("compare_current_alpha.png", "Fig. 16(b): i_alpha of each controller"),
    ],
    "fig18_20": [("step_responses.png", "Figs. 18 and 20: alpha step responses")],
    "fig23": [("currents.png", "Fig. 23: stator currents of the perturbed plant")],
}


def write_figures(outcomes: dict[str, IMOutcome], fig_dir: Path) -> dict[str, list]:
    """Draw every run's figures (``drives.cage_im._outputs``) in a scratch folder and copy those of
    ``FIGURES`` into ``fig_dir`` as ``<experiment>_<name>``; returns experiment -> [(file,
    caption)]."""
    out: dict[str, list] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for key, outcome in outcomes.items():
            folder = Path(tmp) / key
            folder.mkdir()
            write_run_figures(outcome.main, folder)
            if len(outcome.results) > 1 or step_comparison(outcome.main) is not None:
                write_comparison_figures(outcome, folder)
            for name, caption in FIGURES.get(key, []):
                if (folder / name).exists():
                    target = f"{key}_{name}"
                    shutil.copy(folder / name, fig_dir / target)
                    out.setdefault(key, []).append((target, caption))
    return out


def coupling_figure(couplings: dict[str, CouplingResult], path: Path) -> None:
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    w = np.logspace(1, 4, 400)
    for key, style in (("im", "C0"), ("im_5khz", "C1")):
        if key not in couplings:
            continue
        r = couplings[key]
        s = r.setup
        axes[0].semilogx(
            w, 20 * np.log10(np.abs(icad_coupling(s.params, s.w_e, s.controller, w, s.delay))),
            color=style, lw=1,
            label=f"(10), delay {fmt(1e6 * s.delay)} us" if s.delay else "(10)",
        )  # fmt: skip
        axes[0].semilogx(
            r.frequencies, r.db(), "o", color=style, label=f"simulated, hold {s.hold_samples} T_s"
        )
    if "im" in couplings:
        s = couplings["im"].setup
        axes[0].semilogx(
            w, 20 * np.log10(np.abs(icad_coupling(s.params, s.w_e, s.controller, w))), "k--",
            lw=0.8, label="(10), continuous",
        )  # fmt: skip
    axes[0].axhline(targets.SPEC_COUPLING.value, color="r", ls=":", lw=0.8, label="-15 dB spec")
    axes[0].set(
        xlabel="injection frequency (rad/s)",
        ylabel="|i_beta / r_alpha| (dB)",
        title=f"DeLorenzo IM, (20), w_r = {fmt(targets.W_R_MAX)} rad/s",
    )
    if "pmsg" in couplings:
        r = couplings["pmsg"]
        s = r.setup
        axes[1].semilogx(
            w, 20 * np.log10(np.abs(icad_coupling(s.params, s.w_e, s.controller, w))), lw=1,
            label="(10)",
        )  # fmt: skip
        axes[1].semilogx(r.frequencies, r.db(), "o", label="simulated")
        axes[1].set(
            xlabel="injection frequency (rad/s)",
            ylabel="|i_q / r_d| (dB)",
            title=f"2 MW PMSG, dq PI a = {fmt(PMSG_BANDWIDTH)} rad/s, w_e = {fmt(s.w_e)} rad/s",
        )
    for ax in axes:
        ax.grid(True, which="both", lw=0.3)
        ax.legend(fontsize=7)
    save_figure(path, fig)
