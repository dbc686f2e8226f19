"""Figures of a DFIM drive run, matching Bodson Figs. 4-7 (and 12-13 for several motors)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from acdrive.sim.result import DriveResult  # noqa: E402


def _save(fig, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def first_crossing(result: DriveResult, speed_rpm: float, motor: int = 0) -> float | None:
    """Time at which the shaft speed first reaches ``speed_rpm`` (None if it never does)."""
    hits = np.flatnonzero(result.speed_rpm(motor) >= speed_rpm)
    return float(result.t[hits[0]]) if hits.size else None


def write_drive_figures(result: DriveResult, folder: Path, synchronous_rpm: float) -> list[Path]:
    """Speed (Fig. 4), peak voltages (Fig. 5), peak currents (Fig. 6), rotor phase currents X and Y
    around synchronous speed (Fig. 7); for several motors, speeds and torque commands (Figs. 12-13)."""
    folder = Path(folder)
    t = result.t
    paths = []
    fig, ax = plt.subplots(figsize=(7, 3.5))
    for k in range(result.n_motors):
        ax.plot(
            t,
            result.reference_rpm(k),
            "--",
            lw=1,
            label=f"reference {k + 1}" if result.n_motors > 1 else "reference",
        )
        ax.plot(
            t, result.speed_rpm(k), lw=1, label=f"speed {k + 1}" if result.n_motors > 1 else "speed"
        )
    ax.set(
        xlabel="time (s)", ylabel="speed (rpm)", title=f"{result.name}: speed (cf. Bodson Fig. 4)"
    )
    ax.legend()
    paths.append(_save(fig, folder / "fig4_speed.png"))

    fig, ax = plt.subplots(figsize=(7, 3.5))
    ax.plot(t, result.peak("v_s_mag"), lw=1, label="stator")
    ax.plot(t, result.peak("v_r_mag"), lw=1, label="rotor")
    ax.set(
        xlabel="time (s)",
        ylabel="peak phase voltage (V)",
        title="peak stator and rotor voltages (cf. Fig. 5)",
    )
    ax.legend()
    paths.append(_save(fig, folder / "fig5_voltages.png"))

    fig, ax = plt.subplots(figsize=(7, 3.5))
    ax.plot(t, result.peak("i_s_mag"), lw=1, label="stator")
    ax.plot(t, result.peak("i_r_mag"), lw=1, label="rotor")
    ax.axhline(6.0, color="k", ls=":", lw=1, label="6 A limit")
    ax.set(
        xlabel="time (s)",
        ylabel="peak phase current (A)",
        title="peak stator and rotor currents (cf. Fig. 6)",
    )
    ax.legend()
    paths.append(_save(fig, folder / "fig6_currents.png"))

    t_sync = first_crossing(result, synchronous_rpm)
    if t_sync is not None:
        window = (t > t_sync - 0.6) & (t < t_sync + 0.6)
        fig, ax = plt.subplots(figsize=(7, 3.5))
        ax.plot(t[window], result.signal("i_rx")[window], lw=1, label="phase X")
        ax.plot(t[window], result.signal("i_ry")[window], lw=1, label="phase Y")
        ax.axvline(t_sync, color="k", ls=":", lw=1, label="synchronous speed")
        ax.set(
            xlabel="time (s)",
            ylabel="rotor current (A)",
            title="rotor currents X, Y around synchronous speed (cf. Fig. 7)",
        )
        ax.legend()
        paths.append(_save(fig, folder / "fig7_rotor_currents.png"))

    fig, ax = plt.subplots(figsize=(7, 3.5))
    for k in range(result.n_motors):
        ax.plot(t, result.signal("tau_com", k), lw=1, label=f"motor {k + 1}")
    ax.set(xlabel="time (s)", ylabel="torque command (N m)", title="torque commands (cf. Fig. 13)")
    ax.legend()
    paths.append(_save(fig, folder / "torque_commands.png"))
    return paths


def write_comparison_figures(results: dict, folder: Path) -> list[Path]:
    """Voltage vs current command on one figure: speed with reference (Bodson Figs. 8 and 10) and
    peak rotor current against the 6 A limit (Figs. 9 and 11)."""
    folder = Path(folder)
    labels = {"voltage": "VC", "current": "CC"}
    first = next(iter(results.values()))
    fig, ax = plt.subplots(figsize=(7, 3.5))
    ax.plot(first.t, first.reference_rpm(), "k--", lw=1, label="reference")
    for mode, result in results.items():
        ax.plot(result.t, result.speed_rpm(), lw=1, label=labels.get(mode, mode))
    ax.set(xlabel="time (s)", ylabel="speed (rpm)", title="speed, voltage vs current command (cf. Figs. 8, 10)")
    ax.legend()
    paths = [_save(fig, folder / "fig8_speed_vc_cc.png")]
    fig, ax = plt.subplots(figsize=(7, 3.5))
    for mode, result in results.items():
        ax.plot(result.t, result.peak("i_r_mag"), lw=1, label=labels.get(mode, mode))
    ax.axhline(6.0, color="k", ls=":", lw=1, label="6 A limit")
    ax.set(xlabel="time (s)", ylabel="peak rotor current (A)", title="peak rotor current (cf. Figs. 9, 11)")
    ax.legend()
    paths.append(_save(fig, folder / "fig9_rotor_current_vc_cc.png"))
    return paths


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
