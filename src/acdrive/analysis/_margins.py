"""SISO Nyquist tools: winding numbers on indented contours, margins, crossings, bandwidth.

Definitions (see docs/icad.md for the reasons):

- gain crossover: a frequency where |L(jw)| = 1; ``crossover`` is the highest one;
- phase margin: at each gain crossover, the angle between L(jw) and -1 on the unit circle,
  in [0, 180] degrees (180 + phase for a phase in (-360, 0]); the reported margin is the
  smallest over all crossovers. It measures distance only: stability itself is decided by the
  exact encirclement counts, not by the sign of a margin;
- gain margins: at each phase crossover (Im L = 0, Re L < 0) the factor 1/|L| that would put
  L on -1. Crossings inside the unit circle give upward margins (> 0 dB, ``gm_db`` is the
  smallest); crossings outside it give gain-reduction margins (< 0 dB) of a conditionally
  stable loop (``gm_reduction_db`` is the one closest to 0 dB);
- structural gain margin (critical point +1): over crossings of the positive real axis at
  x > 0, the factor 1/x_max that would put the plot on +1, in dB (> 0 dB when the plot stays
  left of +1);
- bandwidth: the first frequency where |T(jw)| falls below |T(0)|/sqrt(2) (-3 dB).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from acdrive.errors import InputError

Response = Callable[[np.ndarray], np.ndarray]  # frequencies [rad/s] -> complex values


def _refine(f: Callable[[float], float], a: float, b: float) -> float:
    """Root of a scalar function between a and b (bracketing sign change), in log frequency."""
    try:
        return math.exp(brentq(lambda u: f(math.exp(u)), math.log(a), math.log(b), xtol=1e-12))
    except (ValueError, RuntimeError):  # pragma: no cover - bracket lost to rounding
        return math.sqrt(a * b)


def _sign_changes(values: np.ndarray) -> np.ndarray:
    v = np.sign(values)
    return np.flatnonzero((v[:-1] * v[1:] < 0) & np.isfinite(values[:-1]) & np.isfinite(values[1:]))


@dataclass(frozen=True)
class LoopMargins:
    """Classical margins of an open loop L(s) with critical point -1 (see module docstring)."""

    crossovers_rad_s: tuple[float, ...]
    crossover_rad_s: float  # highest gain crossover, nan if none on the grid
    pm_deg: float  # smallest phase margin over the crossovers, inf if none
    phase_crossovers_rad_s: tuple[float, ...]
    gm_db: float  # smallest upward gain margin, inf if none
    gm_reduction_db: float  # gain-reduction margin closest to 0 dB (negative), -inf if none
    gm_rad_s: float  # frequency of gm_db (nan if none)


def loop_margins(L: Response, w: np.ndarray) -> LoopMargins:
    """Margins of the loop L (a function of frequency) on grid w, refined by root finding."""
    vals = L(w)
    logmag = np.log(np.abs(vals))
    crossings = []
    for k in _sign_changes(logmag):
        crossings.append(
            _refine(lambda x: float(np.log(np.abs(L(np.array([x]))[0]))), w[k], w[k + 1])
        )
    pms = [180.0 - abs(math.degrees(np.angle(L(np.array([wc]))[0]))) for wc in crossings]
    up, down, up_w = [], [], []
    phase_crossings = []
    for k in _sign_changes(vals.imag):
        wp = _refine(lambda x: float(L(np.array([x]))[0].imag), w[k], w[k + 1])
        re = L(np.array([wp]))[0].real
        if re >= 0.0:
            continue
        phase_crossings.append(wp)
        margin = -20.0 * math.log10(abs(re))
        if margin > 0:
            up.append(margin)
            up_w.append(wp)
        else:
            down.append(margin)
    gm = min(up) if up else math.inf
    return LoopMargins(
        crossovers_rad_s=tuple(crossings),
        crossover_rad_s=max(crossings) if crossings else math.nan,
        pm_deg=min(pms) if pms else math.inf,
        phase_crossovers_rad_s=tuple(phase_crossings),
        gm_db=gm,
        gm_reduction_db=max(down) if down else -math.inf,
        gm_rad_s=up_w[up.index(gm)] if up else math.nan,
    )


@dataclass(frozen=True)
class StructuralMargin:
    """Distance of a Nyquist plot (gamma or gamma h_j) to the critical point +1."""

    gm_db: float  # -20 log10(x_max) over positive-real-axis crossings x; inf if none
    crossing: float  # x_max (nan if no crossing)
    crossing_rad_s: float  # frequency of x_max (0 for the DC point; nan if none)
    min_distance: float  # min |1 - F(jw)| over the grid


def structural_margin(
    F: Response, w: np.ndarray, dc_value: complex | None = None
) -> StructuralMargin:
    """Structural gain margin of F w.r.t. +1: crossings of the positive real axis (w > 0 and DC)."""
    vals = F(w)
    xs, ws = [], []
    for k in _sign_changes(vals.imag):
        wp = _refine(lambda x: float(F(np.array([x]))[0].imag), w[k], w[k + 1])
        re = F(np.array([wp]))[0].real
        if re > 0.0:
            xs.append(re)
            ws.append(wp)
    if dc_value is not None and np.isfinite(dc_value) and dc_value.real > 0:
        xs.append(float(dc_value.real))
        ws.append(0.0)
    dist = float(np.nanmin(np.abs(1.0 - vals)))
    if not xs:
        return StructuralMargin(math.inf, math.nan, math.nan, dist)
    k = int(np.argmax(xs))
    return StructuralMargin(-20.0 * math.log10(xs[k]), xs[k], ws[k], dist)


def bandwidth(T: Response, w: np.ndarray, dc_gain: float | None = None) -> float:
    """First frequency where |T(jw)| drops below |T(0)|/sqrt(2); nan if not on the grid."""
    mag = np.abs(T(w))
    ref = abs(dc_gain) if dc_gain is not None and np.isfinite(dc_gain) else mag[0]
    level = ref / math.sqrt(2.0)
    below = np.flatnonzero(mag < level)
    if below.size == 0:
        return math.nan
    k = below[0]
    if k == 0:
        return float(w[0])
    return _refine(lambda x: float(np.abs(T(np.array([x]))[0]) - level), w[k - 1], w[k])


# ---------------------------------------------------------------------------------------------
# Winding numbers on an indented Nyquist contour

_MAX_ROUNDS = 40
_MAX_STEP = 0.4  # rad of phase change allowed between consecutive contour points


def winding_number(
    F: Callable[[np.ndarray], np.ndarray],
    radius: float,
    indent_at: np.ndarray,
    indent_radius: np.ndarray,
    scale: float,
) -> int:
    """Clockwise encirclements of 0 by F(s) along the Nyquist D-contour (Z - P inside it).

    The contour runs up the imaginary axis from -j radius to +j radius, passing to the right of
    the points j*indent_at on small half circles of radius indent_radius, and returns along the
    half circle of ``radius`` in the right half-plane. F is a function of complex s. The phase is
    accumulated on an adaptively refined contour (steps < 0.4 rad); an accumulated angle that is
    not close to a multiple of 2 pi raises InputError (F vanishes on or very near the contour).
    """
    order = np.argsort(indent_at)
    indent_at = np.asarray(indent_at, dtype=float)[order]
    indent_radius = np.asarray(indent_radius, dtype=float)[order]
    pieces: list[Callable[[np.ndarray], np.ndarray]] = []
    lo = -radius

    def axis_piece(a: float, b: float):
        ua, ub = np.arcsinh(a / scale), np.arcsinh(b / scale)
        return lambda u: 1j * scale * np.sinh(ua + u * (ub - ua))

    for w0, eps in zip(indent_at, indent_radius):
        pieces.append(axis_piece(lo, w0 - eps))
        pieces.append(lambda u, w0=w0, eps=eps: 1j * w0 + eps * np.exp(1j * np.pi * (u - 0.5)))
        lo = w0 + eps
    pieces.append(axis_piece(lo, radius))
    pieces.append(lambda u: radius * np.exp(1j * np.pi * (0.5 - u)))  # +jR -> -jR through +R

    total = 0.0
    first_value = last_value = None
    for piece in pieces:
        u = np.linspace(0.0, 1.0, 129)
        vals = F(piece(u))
        for _ in range(_MAX_ROUNDS):
            if not np.all(np.isfinite(vals)) or np.any(vals == 0):
                raise InputError("plant", "Nyquist function is singular on the contour")
            step = np.angle(vals[1:] / vals[:-1])
            jump = np.abs(np.log(np.abs(vals[1:] / vals[:-1])))
            bad = np.flatnonzero((np.abs(step) > _MAX_STEP) | (jump > 1.0))
            if bad.size == 0:
                break
            new_u = 0.5 * (u[bad] + u[bad + 1])
            u = np.insert(u, bad + 1, new_u)
            vals = np.insert(vals, bad + 1, F(piece(new_u)))
        else:
            raise InputError("plant", "winding number did not converge (F near 0 on the contour)")
        total += float(np.sum(np.angle(vals[1:] / vals[:-1])))
        if last_value is not None:
            total += float(np.angle(vals[0] / last_value))
        if first_value is None:
            first_value = vals[0]
        last_value = vals[-1]
    total += float(np.angle(first_value / last_value))
    turns = total / (2.0 * np.pi)
    if abs(turns - round(turns)) > 0.05:
        raise InputError("plant", f"winding number {turns:.3f} is not an integer")
    return -round(turns)
