"""Figures of a DFIM drive run, matching Bodson Figs. 4-7 (and 12-13 for several motors).

Long traces are drawn as their min/max envelope and the figures are made without pyplot
(``_figures``); the current limits drawn are the scenario's (``current_limits``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from acdrive._figures import (
    TIME_PLOT_MARGINS_IN,
    TimePlots,
    new_figure,
    plot_trace,
    save_figure,
)
from acdrive.drives.dfim._result import DriveResult

#: Colours of the stator and rotor curves of the current figures, and of their limit lines.
_COLOURS = {"stator": "C0", "rotor": "C1"}


def _save(fig, path: Path) -> Path:
    save_figure(path, fig)
    return path


def first_crossing(result: DriveResult, speed_rpm: float, motor: int = 0) -> float | None:
    """Time at which the shaft speed first reaches ``speed_rpm`` (None if it never does)."""
    hits = np.flatnonzero(result.speed_rpm(motor) >= speed_rpm)
    return float(result.t[hits[0]]) if hits.size else None


def current_limits(setup, motor: int = 0) -> dict[str, float]:
    """The stator and rotor current limits of ``motor`` in ``setup`` (peak phase amperes, the
    scenario's ``stator_current_limit_pk`` and ``rotor_current_limit_pk``)."""
    c = setup.motors[motor].controller
    return {"stator": float(c.stator_current_limit_pk), "rotor": float(c.rotor_current_limit_pk)}


def limit_lines(limits_pk: dict[str, float]) -> list[tuple[float, str, str]]:
    """(value, label, colour) of the horizontal line of each limit in ``limits_pk`` (name -> peak
    phase amperes, e.g. ``current_limits``): several limits of one value share one black line;
    different values get a line each in the colour of their curve; a single limit is black."""
    values = set(limits_pk.values())
    if len(limits_pk) > 1 and len(values) == 1:
        (value,) = values
        return [(value, f"{value:g} A limit ({' and '.join(limits_pk)})", "k")]
    single = len(limits_pk) == 1
    return [
        (v, f"{v:g} A {name} limit", "k" if single else _COLOURS.get(name, "k"))
        for name, v in limits_pk.items()
    ]


#: size [in] of the single time plots
TIME_PLOT_SIZE = (7, 3.5)


def line_figure(curves, ylabel: str, title: str, limits=(), marker: float | None = None,
                plots: TimePlots | None = None):  # fmt: skip
    """One time plot, not yet saved: ``curves`` is a list of (t, y, label[, style]) drawn as their
    envelopes; ``limits`` (value, label, colour) horizontal lines (``limit_lines``); an optional
    vertical marker at synchronous speed. Drawn on a figure of its own, or on the next plot of
    ``plots`` (a ``TimePlots`` of ``TIME_PLOT_SIZE``: save it before the next)."""
    if plots is None:
        fig, ax = new_figure(TIME_PLOT_SIZE, margins_in=TIME_PLOT_MARGINS_IN)
    else:
        fig, ax = plots.next()
    for t, y, label, *style in curves:
        plot_trace(ax, t, y, *style, lw=1, label=label)
    for value, label, colour in limits:
        ax.axhline(value, color=colour, ls=":", lw=1, label=label)
    if marker is not None:
        ax.axvline(marker, color="k", ls=":", lw=1, label="synchronous speed")
    ax.set(xlabel="time (s)", ylabel=ylabel, title=title)
    ax.legend()
    return fig


def drive_figures(
    result: DriveResult, synchronous_rpm: float, current_limits_pk: dict[str, float]
) -> dict[str, object]:
    """File name -> figure (not saved): speed (Fig. 4), peak voltages (Fig. 5), peak currents
    with ``current_limits_pk`` (Fig. 6; ``current_limits``), rotor phase currents X and Y around
    synchronous speed (Fig. 7); for several motors, speeds and torque commands (Figs. 12-13).
    Voltages and currents are motor 1's."""
    plots = _drive_plots(result, synchronous_rpm, current_limits_pk)
    return {name: line_figure(*args, **kwargs) for name, (args, kwargs) in plots.items()}


def _drive_plots(result, synchronous_rpm, current_limits_pk) -> dict[str, tuple[tuple, dict]]:
    """File name -> the (arguments, keyword arguments) of ``line_figure`` of ``drive_figures``."""
    t, n = result.t, result.n_motors

    def named(label, k):
        return f"{label} {k + 1}" if n > 1 else label

    speeds = []
    for k in range(n):
        speeds += [(t, result.reference_rpm(k), named("reference", k), "--"),
                   (t, result.speed_rpm(k), named("speed", k))]  # fmt: skip
    currents = [(t, result.peak("i_s_mag"), "stator", _COLOURS["stator"]),
                (t, result.peak("i_r_mag"), "rotor", _COLOURS["rotor"])]  # fmt: skip
    plots = {
        "fig4_speed.png": ((speeds, "speed (rpm)",
                            f"{result.name}: speed (cf. Bodson Figs. 4, 12)"), {}),
        "fig5_voltages.png": ((
            [(t, result.peak("v_s_mag"), "stator"), (t, result.peak("v_r_mag"), "rotor")],
            "peak phase voltage (V)", "peak stator and rotor voltages (cf. Fig. 5)"), {}),
        "fig6_currents.png": ((
            currents, "peak phase current (A)", "peak stator and rotor currents (cf. Fig. 6)"),
            {"limits": limit_lines(current_limits_pk)}),
        "torque_commands.png": ((
            [(t, result.signal("tau_com", k), f"motor {k + 1}") for k in range(n)],
            "torque command (N m)", "torque commands (cf. Fig. 13)"), {}),
    }  # fmt: skip
    t_sync = first_crossing(result, synchronous_rpm)
    if t_sync is not None:
        w = (t > t_sync - 0.6) & (t < t_sync + 0.6)
        curves = [
            (t[w], result.signal("i_rx")[w], "phase X"),
            (t[w], result.signal("i_ry")[w], "phase Y"),
        ]
        title = "rotor currents X, Y around synchronous speed (cf. Fig. 7)"
        plots["fig7_rotor_currents.png"] = ((curves, "rotor current (A)", title), {"marker": t_sync})
    return plots


def write_drive_figures(
    result: DriveResult, folder: Path, synchronous_rpm: float, current_limits_pk: dict[str, float]
) -> list[Path]:
    """Save ``drive_figures`` into ``folder``, drawn in turn on one ``TimePlots``; returns their
    paths."""
    folder = Path(folder)
    shared = TimePlots(TIME_PLOT_SIZE)
    return [
        _save(line_figure(*args, **kwargs, plots=shared), folder / name)
        for name, (args, kwargs) in _drive_plots(result, synchronous_rpm, current_limits_pk).items()
    ]


def write_comparison_figures(results: dict, folder: Path, rotor_limit_pk: float) -> list[Path]:
    """Voltage vs current command on one figure: speed with reference (Bodson Figs. 8 and 10) and
    peak rotor current against the scenario's rotor current limit (Figs. 9 and 11)."""
    folder = Path(folder)
    labels = {"voltage": "VC", "current": "CC"}
    first = next(iter(results.values()))
    speeds = [(first.t, first.reference_rpm(), "reference", "k--")]
    speeds += [(r.t, r.speed_rpm(), labels.get(m, m)) for m, r in results.items()]
    currents = [(r.t, r.peak("i_r_mag"), labels.get(m, m)) for m, r in results.items()]
    shared = TimePlots(TIME_PLOT_SIZE)
    return [
        _save(line_figure(speeds, "speed (rpm)", "speed, voltage vs current command (cf. Figs. 8, 10)",
                          plots=shared),
              folder / "fig8_speed_vc_cc.png"),
        _save(line_figure(currents, "peak rotor current (A)", "peak rotor current (cf. Figs. 9, 11)",
                          limits=limit_lines({"rotor": rotor_limit_pk}), plots=shared),
              folder / "fig9_rotor_current_vc_cc.png"),
    ]  # fmt: skip


def write_sync_figure(result: DriveResult, folder: Path) -> Path:
    """Synchronisation (Bodson (28)): voltage mismatch, theta_adj, m_adj, relay and stator current."""
    t = result.t
    fig, axes = new_figure((7, 7), 4, 1, sharex=True)
    plot_trace(axes[0], t, result.signal("v_mismatch"), lw=1)
    axes[0].set(ylabel="|v_S - v_G| / |v_G|", yscale="log")
    plot_trace(axes[1], t, result.signal("theta_adj"), lw=1, label="theta_adj (rad)")
    plot_trace(axes[1], t, result.signal("m_adj"), lw=1, label="m_adj")
    axes[1].legend()
    plot_trace(axes[2], t, result.signal("relay_closed"), lw=1)
    axes[2].set(ylabel="relay closed")
    plot_trace(axes[3], t, result.peak("i_s_mag"), lw=1)
    axes[3].set(ylabel="peak stator current (A)", xlabel="time (s)")
    axes[0].set_title("grid synchronisation with an unaligned encoder")
    return _save(fig, Path(folder) / "sync.png")
