"""Incremental (quadrature) encoder read through its hardware counter: the edges the disc passes
between samples counted into a register that wraps once per revolution, an optional index pulse
that resets the register, a deterministic model of lost edges, and the angle and speed a drive
reads from the register.

The disc angle is ``phi = theta + offset`` (``theta`` the shaft angle, ``offset`` the mounting
offset). A disc of ``lines`` lines gives two square waves in quadrature, hence ``N = 4 lines``
edges per revolution (the "x4" decoding of a quadrature counter); the edge of count ``m`` is at
``phi = m 2 pi / N`` and the index pulse at ``phi = 0`` (the edge of count 0, every N counts).
Between two samples the disc passes ``m_now - m_before`` edges, ``m = floor(phi N / (2 pi))``;
the counter adds them, signed by the direction, minus the lost ones, modulo ``N``. The count
truncates: without lost edges the angle ``count 2 pi / N`` lies in ``(phi - 2 pi / N, phi]``
(mod 2 pi), an error in [0, one count); with ``centred`` the angle is read at the count's
centre, ``(count + 1/2) 2 pi / N``, an error within half a count either way.

Lost edges: with ``lose_every = k`` (0: none) every k-th edge the disc passes is not counted,
whatever its direction (the edges are numbered in the order they are passed, from the first
sample on). Without the index the register then drifts by one count every k edges; with the
index it is set to the disc's count at each sample in which the index edge was passed, so the
error never exceeds the edges lost in one revolution, ``ceil(N / k)``.

The speed is the register's difference over one sample taken modulo N into ``[-N/2, N/2)``: the
wrap of the register at the end of a revolution gives no step (a difference of the wrapped angle
without it would show -2 pi / T_s once per revolution). It is valid while the shaft turns less
than half a revolution per sample."""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from acdrive._jit import jit
from acdrive.core._parts import SampledPart
from acdrive.core._signals import Layout, real
from acdrive.plant._sensors import MAX_COUNTS_PER_REV

PARAMS = Layout(
    real("lines", "", "lines on the disc per revolution (4 lines counts per revolution)", "count"),
    real("pole_pairs", "", "pole pairs of the machine, for the electrical angle", "count"),
    real("offset", "rad", "mounting offset: disc angle minus shaft angle", ""),
    real("index", "", "1: the index pulse resets the register once per revolution", "flag"),
    real("lose_every", "", "every k-th edge passed is not counted (0: none lost)", "whole"),
    real("centred", "", "1: the angle read at the count's centre, (count + 1/2) 2 pi / N", "flag"),
)
STATES = Layout(
    real("started", "", "1 once the first sample has run"),
    real("edge", "", "disc edge count floor(phi N / 2 pi) at the last sample (unwrapped)"),
    real("passed", "", "edges passed since the start, for the lost-edge model"),
    real("counter", "", "counter register, in [0, N)"),
)
INPUTS = Layout(real("theta", "rad", "shaft angle (unwrapped)"))
OUTPUTS = Layout(
    real("count", "", "counter register, in [0, 4 lines)"),
    real("theta", "rad", "mechanical angle read from the register, in [0, 2 pi)"),
    real("theta_e", "rad", "electrical angle pole_pairs theta, in [0, 2 pi)"),
    real("w", "rad/s", "speed from the register's wrapped difference over one sample"),
)
_LINES, _POLE_PAIRS, _OFFSET, _INDEX, _LOSE_EVERY, _CENTRED = (
    PARAMS.slot(n) for n in ("lines", "pole_pairs", "offset", "index", "lose_every", "centred")
)
_STARTED, _EDGE, _PASSED, _REGISTER = (
    STATES.slot(n) for n in ("started", "edge", "passed", "counter")
)
_THETA_IN = INPUTS.slot("theta")
_COUNT, _THETA, _THETA_E, _W = (OUTPUTS.slot(n) for n in ("count", "theta", "theta_e", "w"))
_INDEX_SEEN, _EDGE_LOST = 1, 2  # event bits: bit k is EVENTS[k]
TWO_PI = 2.0 * np.pi


@jit
def wrap_count(count, n):
    """``count`` modulo ``n`` in [0, n) (whole numbers held as floats)."""
    return count - n * np.floor(count / n)


@jit
def quadrature_encoder_step(t, T_s, u, p, s, y):
    """Count the edges passed since the last sample into the wrapping register, lose every
    ``lose_every``-th, reset at the index; read angle, electrical angle and speed from it."""
    events = 0
    n = 4.0 * p[_LINES]
    edge = np.floor((u[_THETA_IN] + p[_OFFSET]) * n / TWO_PI)
    if s[_STARTED] == 0.0:  # the register starts at the disc's count (an aligned start)
        s[_STARTED] = 1.0
        s[_EDGE] = edge
        s[_REGISTER] = wrap_count(edge, n)
    before = s[_REGISTER]
    passed = edge - s[_EDGE]
    magnitude = abs(passed)
    counted = passed
    k = p[_LOSE_EVERY]
    if k > 0.0:
        lost = np.floor((s[_PASSED] + magnitude) / k) - np.floor(s[_PASSED] / k)
        if lost > 0.0:
            events |= _EDGE_LOST
            counted = passed - lost if passed > 0.0 else passed + lost
    s[_PASSED] += magnitude
    register = wrap_count(before + counted, n)
    if p[_INDEX] != 0.0 and np.floor(edge / n) != np.floor(s[_EDGE] / n):
        register = wrap_count(edge, n)  # the index edge was passed: the register re-aligned
        events |= _INDEX_SEEN
    s[_EDGE] = edge
    s[_REGISTER] = register
    step = TWO_PI / n
    position = register + 0.5 if p[_CENTRED] != 0.0 else register
    y[_COUNT] = register
    y[_THETA] = position * step
    y[_THETA_E] = wrap_count(position * p[_POLE_PAIRS], n) * step
    difference = wrap_count(register - before + 0.5 * n, n) - 0.5 * n
    y[_W] = difference * step / T_s
    return events


class QuadratureEncoder(SampledPart):
    """Incremental encoder with its x4 quadrature counter: a register wrapping at 4 ``lines``
    counts, an optional index reset, every ``lose_every``-th edge lost; outputs the wrapped
    mechanical and electrical angles (at the count, or at its centre if ``centred``) and the
    speed from the wrapped count difference."""

    SOURCE = "quadrature encoder and counter register (plant._encoder.quadrature_encoder_step)"

    PARAMS, STATES, INPUTS, OUTPUTS = PARAMS, STATES, INPUTS, OUTPUTS
    DEFAULTS: ClassVar[dict] = {"pole_pairs": 1.0, "offset": 0.0, "index": 0.0,
                                "lose_every": 0.0, "centred": 0.0}  # fmt: skip
    EVENTS = ("index", "edge_lost")
    step = quadrature_encoder_step

    def check(self) -> None:
        from acdrive.errors import InputError

        lines = self.values["lines"]
        if 4.0 * lines > MAX_COUNTS_PER_REV:
            raise InputError(f"{self.name}.lines", f"must be at most {MAX_COUNTS_PER_REV // 4} "
                             f"(a 32-bit count per revolution), got {lines:g}")  # fmt: skip
