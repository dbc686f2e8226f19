"""The files of one cage-IM drive run (``drives.cage_im._drive``): data (Parquet, CSV or .mat, with
columns.md), figures and summary.json, the simulated current steps drawn beside the linear
closed loop's (``drives.cage_im._step_comparison``).

Layout as the DFIM drive's (``drives.dfim._outputs``): one run writes into the folder itself;
several runs (compared controllers) each into ``<folder>/<label>/``, with the comparison figures
and the one summary.json in the folder. Figures follow Amezquita-Brooks et al.: currents with
references (Figs. 11, 13(c), 14(c), 23), speed (13(a)), load torque (13(b), 14(b)), the phase-a
modulation signal (13(d)), position (14(a)), the speed ramps against the ideal constant-torque
ramp and the superimposed alpha currents (16(a), (b)), step responses (18, 20). Their titles and
labels are built from the scenario and the computed numbers. Space vectors are drawn in the
paper's amplitude-invariant alpha-beta scaling (peak phase amperes: acdrive's power-invariant
vector over sqrt(3/2), Bodson (8)). Time traces are drawn as their min/max envelope, every peak
kept (``_figures``).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from acdrive._figures import new_figure, plot_trace, save_figure
from acdrive._output import strict_json
from acdrive.drives.cage_im._outcome import IMOutcome
from acdrive.drives.cage_im._result import IMDriveResult, ideal_ramp
# the step comparison's names, also reachable here (reports and tests import them from here)
from acdrive.drives.cage_im._step_comparison import RINGING_AFTER_S as RINGING_AFTER_S
from acdrive.drives.cage_im._step_comparison import (
    closed_loop_reference_ss as closed_loop_reference_ss,
)
from acdrive.drives.cage_im._step_comparison import (
    delayed_linear_step_response as delayed_linear_step_response,
)
from acdrive.drives.cage_im._step_comparison import linear_step_response as linear_step_response
from acdrive.drives.cage_im._step_comparison import ringing as ringing
from acdrive.drives.cage_im._step_comparison import step_comparison
from acdrive.drives.cage_im._step_comparison import step_summary as step_summary


def _save(fig, path: Path) -> Path:
    save_figure(path, fig)
    return path


# --- figures of one run ----------------------------------------------------------------------


def _title(result: IMDriveResult, what: str) -> str:
    s = result.setup
    name = s.current_control.controller
    who = name if result.label == name else f"{result.label}: {name}"
    return f"{s.name} [{who}]: {what}"


def _current_axes(ax, result: IMDriveResult, window=None):
    t = result.t
    mask = np.ones(t.size, dtype=bool) if window is None else (t >= window[0]) & (t <= window[1])
    i_s, i_ref = result.phase_peak("i_s")[mask], result.phase_peak("i_ref")[mask]
    plot_trace(ax, t[mask], i_s.real, lw=0.8, label="i_alpha")
    plot_trace(ax, t[mask], i_s.imag, lw=0.8, label="i_beta")
    plot_trace(ax, t[mask], i_ref.real, "k--", lw=0.8, label="i_alpha reference")
    plot_trace(ax, t[mask], i_ref.imag, "k:", lw=0.8, label="i_beta reference")
    ax.set(xlabel="time (s)", ylabel="current (A, phase peak)")
    ax.legend(fontsize=7, loc="upper right")


def _currents_figure(result: IMDriveResult, path: Path, window=None, what="stator currents"):
    fig, ax = new_figure((8, 3.6))
    _current_axes(ax, result, window)
    err = result.current_rms_error()
    ax.set_title(
        _title(result, f"{what}; RMS phase error {err:.3g} A from {result.setup.metrics_from:g} s"),
        fontsize=9,
    )
    return _save(fig, path)


def _closeup_window(result: IMDriveResult, t_change: float) -> tuple[float, float]:
    """Three periods of the stator current on either side of ``t_change`` (from the field's
    electrical speed then), within the run."""
    s = result.setup
    at = int(np.searchsorted(result.t, t_change))
    w_e = abs(s.plant.n_p * result.signal("w")[min(at, result.t.size - 1)])
    if "theta_f" in result.signals:
        theta = np.unwrap(result.signal("theta_f"))
        lo, hi = max(at - 20, 0), min(at + 20, theta.size - 1)
        if hi > lo:
            w_e = abs((theta[hi] - theta[lo]) / (result.t[hi] - result.t[lo]))
    half = 3.0 * 2.0 * math.pi / w_e if w_e > 1.0 else 0.05
    return max(t_change - half, result.t[0]), min(t_change + half, result.t[-1])


def write_run_figures(result: IMDriveResult, folder: Path) -> list[Path]:
    """The figures of one run (module docstring), by mode."""
    folder, s, t = Path(folder), result.setup, result.t
    paths = [_currents_figure(result, folder / "currents.png")]
    changes = result.load_changes()
    if changes:
        window = _closeup_window(result, changes[0])
        paths.append(
            _currents_figure(
                result,
                folder / "currents_closeup.png",
                window,
                f"currents around the load change at {changes[0]:g} s",
            )
        )
    if s.mode in ("speed-p", "speed-pi"):
        fig, ax = new_figure((8, 3.6))
        plot_trace(ax, t, result.signal("w_ref"), "k--", lw=1, label="reference")
        plot_trace(ax, t, result.signal("w"), lw=1, label="speed")
        ramp = result.ramp_metrics()
        if ramp is not None:
            plot_trace(
                ax,
                t,
                _ideal(result),
                ":",
                lw=1,
                label=f"ideal ramp tau_max/J = {ramp['ideal_slope_rad_s2']:.0f} rad/s^2",
            )
        m = result.speed_metrics()
        ax.set(xlabel="time (s)", ylabel="speed (rad/s)")
        ax.set_title(
            _title(
                result,
                f"speed; final {m['speed_final_rad_s']:.1f} rad/s for "
                f"{m['speed_reference_final_rad_s']:.1f} rad/s",
            ),
            fontsize=9,
        )
        ax.legend(fontsize=8)
        paths.append(_save(fig, folder / "speed.png"))
    elif s.mode == "current" and s.mechanics.free:  # imposed currents run the motor
        fig, ax = new_figure((8, 3.2))
        plot_trace(ax, t, result.signal("w"), lw=1)
        ax.set(xlabel="time (s)", ylabel="speed (rad/s)")
        ax.set_title(
            _title(
                result,
                f"speed under the imposed currents, {result.signal('w')[-1]:.1f} rad/s at the end",
            ),
            fontsize=9,
        )
        paths.append(_save(fig, folder / "speed.png"))
    if s.mode == "position":
        fig, ax = new_figure((8, 3.6))
        theta = result.signal("theta") + s.sensors.offset
        plot_trace(ax, t, result.signal("theta_ref"), "k--", lw=1, label="reference")
        plot_trace(ax, t, theta, lw=1, label="position")
        m = result.position_metrics()
        ax.set(xlabel="time (s)", ylabel="position (rad)")
        ax.set_title(
            _title(result, f"position; final error {m['position_final_error_rad']:.2g} rad"),
            fontsize=9,
        )
        ax.legend(fontsize=8)
        paths.append(_save(fig, folder / "position.png"))
    if s.mechanics.free:
        fig, ax = new_figure((8, 3.6))
        plot_trace(ax, t, result.signal("tau_load"), lw=1, label="load (active + brake)")
        plot_trace(ax, t, result.signal("tau_e"), lw=0.6, alpha=0.8, label="electromagnetic torque")
        plot_trace(ax, t, result.signal("tau_friction"), lw=1, label="friction")
        ax.set(xlabel="time (s)", ylabel="torque (N m)")
        ax.set_title(_title(result, "load torque"), fontsize=9)
        ax.legend(fontsize=8)
        paths.append(_save(fig, folder / "load_torque.png"))
    fig, ax = new_figure((8, 3.2))
    plot_trace(ax, t, result.signal("m_a"), lw=0.6)
    ax.axhline(1.0, color="k", ls=":", lw=0.8)
    ax.axhline(-1.0, color="k", ls=":", lw=0.8)
    peak = float(np.max(np.abs(result.signal("m_a"))))
    ax.set(xlabel="time (s)", ylabel="m_a")
    ax.set_title(
        _title(result, f"phase-a modulation signal ({s.inverter.model}), peak |m_a| {peak:.3f}"),
        fontsize=9,
    )
    paths.append(_save(fig, folder / "modulation_a.png"))
    return paths


def _ideal(result: IMDriveResult) -> np.ndarray:
    ramp = result.ramp_metrics()
    s = result.setup
    w0 = float(result.signal("w")[np.searchsorted(result.t, ramp["t_step_s"])])
    target = float(s.speed_reference[1][-1])
    return ideal_ramp(
        result.t, ramp["t_step_s"], w0, target, s.speed_p.k_p, s.speed_p.tau_max, s.mechanics.J
    )


def _comparison_window(result: IMDriveResult) -> tuple[float, float]:
    """Where Fig. 16(b)'s currents are compared: three electrical periods ending at 80 % of the
    ideal saturated ramp (high speed, full torque in every run), or the last 50 ms."""
    ramp = result.ramp_metrics()
    t = result.t
    if ramp is None:
        return max(t[0], t[-1] - 0.05), t[-1]
    end = min(ramp["t_step_s"] + 0.8 * (ramp["t_saturated_end_s"] - ramp["t_step_s"]), t[-1])
    w = abs(result.setup.plant.n_p * result.signal("w")[np.searchsorted(t, end) - 1])
    span = 3.0 * 2.0 * math.pi / w if w > 1.0 else 0.05
    return max(t[0], end - span), end


# --- comparison figures ------------------------------------------------------------------------


def write_comparison_figures(outcome: IMOutcome, folder: Path) -> list[Path]:
    folder, s = Path(folder), outcome.setup
    results = outcome.results
    first = outcome.main
    paths = []
    steps = {label: step_comparison(r) for label, r in results.items()}
    if any(v is not None for v in steps.values()):
        fig, axes = new_figure((11, 4), 1, 2)
        for label, c in steps.items():
            line = plot_trace(
                axes[0],
                1e3 * c["t"],
                c["simulated"].real,
                lw=1,
                label=f"{label} simulated ({c['overshoot_simulated']:.1%})",
            )
            plot_trace(
                axes[0],
                1e3 * c["t"],
                c["linear"][:, 0],
                "--",
                color=line.get_color(),
                lw=1,
                label=f"{label} linear ({c['overshoot_linear']:.1%})",
            )
            plot_trace(
                axes[1],
                1e3 * c["t"],
                c["simulated"].imag,
                lw=1,
                color=line.get_color(),
                label=f"{label} simulated",
            )
            plot_trace(axes[1], 1e3 * c["t"], c["linear"][:, 1], "--", color=line.get_color(), lw=1)
        w = next(v for v in steps.values() if v is not None)["speed_rad_s"]
        axes[0].set(
            xlabel="time after the step (ms)",
            ylabel="i_alpha / step",
            title=f"{s.name}: alpha step at {w:g} rad/s (overshoot)",
        )
        axes[1].set(
            xlabel="time after the step (ms)", ylabel="i_beta / step", title="coupling into i_beta"
        )
        for ax in axes:
            ax.legend(fontsize=7)
        paths.append(_save(fig, folder / "step_responses.png"))
        return paths
    if s.mode == "current":
        fig, ax = new_figure((8, 3.6))
        lo = s.metrics_from
        hi = min(
            first.t[-1], lo + 3.0 * 2.0 * math.pi / max(abs(s.current_reference.frequency), 1.0)
        )
        mask = (first.t >= lo) & (first.t <= hi)
        plot_trace(
            ax, first.t[mask], first.phase_peak("i_ref")[mask].real, "k--", lw=1, label="reference"
        )
        for label, r in results.items():
            plot_trace(
                ax,
                r.t[mask],
                r.phase_peak("i_s")[mask].real,
                lw=0.8,
                label=(
                    f"{label} ({r.setup.current_control.controller}): RMS error "
                    f"{r.current_rms_error():.3g} A"
                ),
            )
        ax.set(
            xlabel="time (s)",
            ylabel="i_alpha (A, phase peak)",
            title=f"{s.name}: i_alpha of each controller",
        )
        ax.legend(fontsize=7)
        paths.append(_save(fig, folder / "compare_currents.png"))
    if s.mode in ("speed-p", "speed-pi"):
        fig, ax = new_figure((8, 3.8))
        plot_trace(ax, first.t, first.signal("w_ref"), "k--", lw=1, label="reference")
        if first.ramp_metrics() is not None:
            ramp = first.ramp_metrics()
            plot_trace(
                ax,
                first.t,
                _ideal(first),
                "k:",
                lw=1,
                label=f"ideal ramp ({ramp['ideal_slope_rad_s2']:.0f} rad/s^2)",
            )
        for label, r in results.items():
            ramp = r.ramp_metrics()
            extra = (
                ""
                if ramp is None
                else (
                    f": slope {ramp['ramp_slope_rad_s2']:.0f} rad/s^2, ramp error "
                    f"{ramp['speed_ramp_error_rad_s']:.3g} rad/s"
                )
            )
            plot_trace(ax, r.t, r.signal("w"), lw=1, label=f"{label}{extra}")
        ax.set(
            xlabel="time (s)", ylabel="speed (rad/s)", title=f"{s.name}: speed of each controller"
        )
        ax.legend(fontsize=7)
        paths.append(_save(fig, folder / "compare_speed.png"))
        fig, ax = new_figure((8, 3.6))
        lo, hi = _comparison_window(first)
        mask = (first.t >= lo) & (first.t <= hi)
        for label, r in results.items():
            err = r.current_rms_error(mask)
            plot_trace(
                ax, r.t[mask], r.phase_peak("i_s")[mask].real, lw=0.8, label=f"{label} i_alpha"
            )
            plot_trace(
                ax,
                r.t[mask],
                r.phase_peak("i_ref")[mask].real,
                "--",
                lw=0.8,
                label=f"{label} reference (RMS phase error here {err:.3g} A)",
            )
        ax.set(
            xlabel="time (s)",
            ylabel="i_alpha (A, phase peak)",
            title=f"{s.name}: i_alpha of each controller, {lo:.3g} s to {hi:.3g} s",
        )
        ax.legend(fontsize=7)
        paths.append(_save(fig, folder / "compare_current_alpha.png"))
    return paths


# --- everything ------------------------------------------------------------------------------


def write_figures(outcome: IMOutcome, folder: Path) -> list[Path]:
    """Draw the figures of every run (one sub-folder per run when there are several) and the
    comparison figures into ``folder``; returns their paths."""
    folder = Path(folder)
    paths = []
    for label, result in outcome.results.items():
        sub = folder if len(outcome.results) == 1 else folder / label
        sub.mkdir(parents=True, exist_ok=True)
        paths += write_run_figures(result, sub)
    if len(outcome.results) > 1 or step_comparison(outcome.main) is not None:
        paths += write_comparison_figures(outcome, folder)
    return paths


def write_im_outcome(
    outcome: IMOutcome, folder: Path, figures: bool = True, fmt: str = "parquet"
) -> dict:
    """Write the data (as ``fmt``, ``acdrive.columns.FORMATS``, with columns.md) of every run,
    the figures (``write_figures``) and summary.json (the outcome's summary: with the
    step-response comparison where the runs are current steps, and the unit of every data
    column) into ``folder``; returns the summary written."""
    folder = Path(folder)
    for label, result in outcome.results.items():
        sub = folder if len(outcome.results) == 1 else folder / label
        sub.mkdir(parents=True, exist_ok=True)
        result.save(sub, fmt)
    if figures:
        write_figures(outcome, folder)
    summary = dict(outcome.summary)
    # strict JSON: a non-finite figure is written as null
    (folder / "summary.json").write_text(strict_json(summary, indent=2) + "\n")
    return summary
