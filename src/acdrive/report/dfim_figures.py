"""Figures of a DFIM drive run, matching Bodson Figs. 4-7 (and 12-13 for several motors)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from acdrive.report.markdown import save_figure
from acdrive.sim.result import DriveResult


def _save(fig, path: Path) -> Path:
    save_figure(path, fig)
    return path


def first_crossing(result: DriveResult, speed_rpm: float, motor: int = 0) -> float | None:
    """Time at which the shaft speed first reaches ``speed_rpm`` (None if it never does)."""
    hits = np.flatnonzero(result.speed_rpm(motor) >= speed_rpm)
    return float(result.t[hits[0]]) if hits.size else None


def _line_figure(path: Path, curves, ylabel: str, title: str, limit: float | None = None,
                 marker: float | None = None) -> Path:  # fmt: skip
    """One time plot: ``curves`` is a list of (t, y, label[, style]); optional horizontal limit
    line and vertical marker."""
    fig, ax = plt.subplots(figsize=(7, 3.5))
    for t, y, label, *style in curves:
        ax.plot(t, y, *style, lw=1, label=label)
    if limit is not None:
        ax.axhline(limit, color="k", ls=":", lw=1, label=f"{limit:g} A limit")
    if marker is not None:
        ax.axvline(marker, color="k", ls=":", lw=1, label="synchronous speed")
    ax.set(xlabel="time (s)", ylabel=ylabel, title=title)
    ax.legend()
    return _save(fig, path)


def write_drive_figures(result: DriveResult, folder: Path, synchronous_rpm: float) -> list[Path]:
    """Speed (Fig. 4), peak voltages (Fig. 5), peak currents (Fig. 6), rotor phase currents X and Y
    around synchronous speed (Fig. 7); for several motors, speeds and torque commands (Figs. 12-13)."""
    folder, t, n = Path(folder), result.t, result.n_motors

    def named(label, k):
        return f"{label} {k + 1}" if n > 1 else label

    speeds = []
    for k in range(n):
        speeds += [(t, result.reference_rpm(k), named("reference", k), "--"),
                   (t, result.speed_rpm(k), named("speed", k))]  # fmt: skip
    paths = [
        _line_figure(folder / "fig4_speed.png", speeds, "speed (rpm)",
                     f"{result.name}: speed (cf. Bodson Figs. 4, 12)"),
        _line_figure(folder / "fig5_voltages.png",
                     [(t, result.peak("v_s_mag"), "stator"), (t, result.peak("v_r_mag"), "rotor")],
                     "peak phase voltage (V)", "peak stator and rotor voltages (cf. Fig. 5)"),
        _line_figure(folder / "fig6_currents.png",
                     [(t, result.peak("i_s_mag"), "stator"), (t, result.peak("i_r_mag"), "rotor")],
                     "peak phase current (A)", "peak stator and rotor currents (cf. Fig. 6)", limit=6.0),
        _line_figure(folder / "torque_commands.png",
                     [(t, result.signal("tau_com", k), f"motor {k + 1}") for k in range(n)],
                     "torque command (N m)", "torque commands (cf. Fig. 13)"),
    ]  # fmt: skip
    t_sync = first_crossing(result, synchronous_rpm)
    if t_sync is not None:
        w = (t > t_sync - 0.6) & (t < t_sync + 0.6)
        curves = [
            (t[w], result.signal("i_rx")[w], "phase X"),
            (t[w], result.signal("i_ry")[w], "phase Y"),
        ]
        paths.append(_line_figure(folder / "fig7_rotor_currents.png", curves, "rotor current (A)",
                                  "rotor currents X, Y around synchronous speed (cf. Fig. 7)",
                                  marker=t_sync))  # fmt: skip
    return paths


def write_comparison_figures(results: dict, folder: Path, rotor_limit_pk: float) -> list[Path]:
    """Voltage vs current command on one figure: speed with reference (Bodson Figs. 8 and 10) and
    peak rotor current against the scenario's rotor current limit (Figs. 9 and 11)."""
    folder = Path(folder)
    labels = {"voltage": "VC", "current": "CC"}
    first = next(iter(results.values()))
    speeds = [(first.t, first.reference_rpm(), "reference", "k--")]
    speeds += [(r.t, r.speed_rpm(), labels.get(m, m)) for m, r in results.items()]
    currents = [(r.t, r.peak("i_r_mag"), labels.get(m, m)) for m, r in results.items()]
    return [
        _line_figure(folder / "fig8_speed_vc_cc.png", speeds, "speed (rpm)",
                     "speed, voltage vs current command (cf. Figs. 8, 10)"),
        _line_figure(folder / "fig9_rotor_current_vc_cc.png", currents, "peak rotor current (A)",
                     "peak rotor current (cf. Figs. 9, 11)", limit=rotor_limit_pk),
    ]  # fmt: skip


def write_sync_figure(result: DriveResult, folder: Path) -> Path:
    """Synchronisation (Bodson (28)): voltage mismatch, theta_adj, m_adj, relay and stator current."""
    t = result.t
    fig, axes = plt.subplots(4, 1, figsize=(7, 7), sharex=True)
    axes[0].plot(t, result.signal("v_mismatch"), lw=1)
    axes[0].set(ylabel="|v_S - v_G| / |v_G|", yscale="log")
    axes[1].plot(t, result.signal("theta_adj"), lw=1, label="theta_adj (rad)")
    axes[1].plot(t, result.signal("m_adj"), lw=1, label="m_adj")
    axes[1].legend()
    axes[2].plot(t, result.signal("relay_closed"), lw=1)
    axes[2].set(ylabel="relay closed")
    axes[3].plot(t, result.peak("i_s_mag"), lw=1)
    axes[3].set(ylabel="peak stator current (A)", xlabel="time (s)")
    axes[0].set_title("grid synchronisation with an unaligned encoder")
    return _save(fig, Path(folder) / "sync.png")
