"""Figures of an ICAD sweep: Nyquist families, Bode families, pole maps and coupling.

Every function takes the typed results of the ICAD analysis (``acdrive.analysis``) and draws on
a matplotlib axis (Agg backend); ``write_sweep_figures`` writes the whole set as PNG files.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from acdrive.analysis._icad import ICADAnalysis
from acdrive.analysis._icad_frequency import ICADResponse


def _colors(n: int):
    return plt.cm.viridis(np.linspace(0.0, 0.9, max(n, 1)))


def _speed_label(speed: float) -> str:
    return "generic" if not np.isfinite(speed) else f"w_r = {speed:g} rad/s"


def nyquist_family(resp: ICADResponse, ax, which: str = "gamma", channel: int = 1, zoom=None):
    """Nyquist plots (w > 0) of gamma or gamma h_j (``which='gamma_h'``) for every speed."""
    data = resp.gamma if which == "gamma" else resp.gamma_h[..., channel - 1]
    for row, speed, col in zip(data, resp.speeds, _colors(len(data))):
        ax.plot(row.real, row.imag, color=col, lw=1.0, label=_speed_label(speed))
    ax.plot([1.0], [0.0], "r+", ms=12, mew=2, label="(1, 0)")
    ax.axhline(0, color="0.7", lw=0.5)
    ax.axvline(0, color="0.7", lw=0.5)
    name = "gamma(jw)" if which == "gamma" else f"gamma(jw) h_{3 - channel}(jw)"
    ax.set_title(f"Nyquist: {name}")
    ax.set_xlabel("Re")
    ax.set_ylabel("Im")
    if zoom is not None:
        ax.set_xlim(*zoom[0])
        ax.set_ylim(*zoom[1])
    ax.legend(fontsize=6, loc="best")


def bode_family(resp: ICADResponse, axes, key: str = "c", channel: int = 1):
    """Bode magnitude/phase of c_i (``key='c'``), k_i g_ii (``'kg'``) or T_i for every speed."""
    data = getattr(resp, key)[..., channel - 1]
    mag_ax, ph_ax = axes
    for row, speed, col in zip(data, resp.speeds, _colors(len(data))):
        mag_ax.semilogx(
            resp.w, 20 * np.log10(np.abs(row)), color=col, lw=1.0, label=_speed_label(speed)
        )
        ph_ax.semilogx(resp.w, np.degrees(np.unwrap(np.angle(row))), color=col, lw=1.0)
    label = {"c": f"c_{channel}", "kg": f"k_{channel} g_{channel}{channel}", "T": f"T_{channel}"}[
        key
    ]
    mag_ax.set_title(f"Bode: {label}(jw)")
    mag_ax.axhline(0, color="0.6", lw=0.5)
    mag_ax.set_ylabel("dB")
    ph_ax.set_ylabel("deg")
    ph_ax.axhline(-180, color="0.6", lw=0.5)
    ph_ax.set_xlabel("w [rad/s]")
    mag_ax.legend(fontsize=6, loc="best")


def pole_map(analyses: Sequence[ICADAnalysis], ax):
    """Open-loop poles (x) and MSF poles (o) over speed, coloured by speed."""
    cols = _colors(len(analyses))
    for a, col in zip(analyses, cols):
        p = a.conditions.plant_poles
        g = a.conditions.gamma_poles
        sp = a.plant.speed if a.plant.speed is not None else np.nan
        ax.plot(p.real, p.imag, "x", color=col, label=f"poles of G, {_speed_label(sp)}")
        if g.size:
            ax.plot(g.real, g.imag, "o", mfc="none", color=col)
    ax.axvline(0, color="0.7", lw=0.5)
    ax.set_title("Poles of G (x) and of gamma (o) over speed")
    ax.set_xlabel("Re [1/s]")
    ax.set_ylabel("Im [rad/s]")
    ax.legend(fontsize=5, loc="best")


def coupling_family(resp: ICADResponse, ax, channel: int = 1):
    """|y_i / r_j| of (10) in dB for every speed."""
    data = resp.coupling[..., channel - 1]
    for row, speed, col in zip(data, resp.speeds, _colors(len(data))):
        with np.errstate(divide="ignore"):
            ax.semilogx(
                resp.w, 20 * np.log10(np.abs(row)), color=col, lw=1.0, label=_speed_label(speed)
            )
    ax.set_title(f"Coupling |y_{channel}/r_{3 - channel}| (10)")
    ax.set_xlabel("w [rad/s]")
    ax.set_ylabel("dB")
    ax.legend(fontsize=6, loc="best")


def write_sweep_figures(
    analyses: Sequence[ICADAnalysis], resp: ICADResponse, out_dir, title: str = ""
) -> list[Path]:
    """Write the ICAD sweep figures as PNG files into ``out_dir``; returns their paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []

    def save(fig, name):
        if title:
            fig.suptitle(title, fontsize=9)
        fig.tight_layout()
        path = out / name
        fig.savefig(path, dpi=120)
        plt.close(fig)
        paths.append(path)

    for which, name in (("gamma", "nyquist_gamma.png"), ("gamma_h", "nyquist_gamma_h.png")):
        fig, axes = plt.subplots(1, 2, figsize=(11, 5))
        nyquist_family(resp, axes[0], which)
        nyquist_family(resp, axes[1], which, zoom=((0.0, 1.2), (-0.6, 0.6)))
        axes[1].set_title(axes[1].get_title() + " (zoom near (1, 0))")
        save(fig, name)
    for key, name in (("c", "bode_channels.png"), ("kg", "bode_kg.png")):
        fig, axes = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
        bode_family(resp, axes, key)
        save(fig, name)
    fig, ax = plt.subplots(figsize=(7, 6))
    pole_map(analyses, ax)
    save(fig, "pole_map.png")
    fig, ax = plt.subplots(figsize=(8, 5))
    coupling_family(resp, ax)
    save(fig, "coupling.png")
    return paths
