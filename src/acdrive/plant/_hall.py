"""Three Hall sensors 120 electrical degrees apart, read at each sample, with the angle
interpolated between their edges and the speed from the time between edges.

With the electrical angle ``x = pole_pairs theta + offset`` (``offset`` the sensors' mounting
offset, electrical radians) the sensors give ``h_a = 1`` for x mod 2 pi in [0, pi), ``h_b = 1``
in [2 pi/3, 5 pi/3), ``h_c = 1`` in [4 pi/3, 2 pi) and [0, pi/3): six sectors of 60 degrees,
sector k covering [k pi/3, (k + 1) pi/3). The angle is estimated in the sensors' frame (an
offset the drive does not know is an error of the estimate, as a mounting error is).

Edges are seen at the samples (up to one sample period ``T_s`` after they happen). A step of
the sector by +1 (mod 6) is an edge passed forwards at the sector's lower border, by -1 one
passed backwards at the old sector's lower border; a step by 2 or 3 sectors in one sample raises
``skipped`` and is taken as the shorter way round (3: forwards).

The speed is the 60 degrees between the last two edges over the time between their samples,
signed by the direction (``w = (pi/3) / (t_k - t_(k-1)) / pole_pairs``); while no edge follows
for longer than that interval, the speed decays as (pi/3) / (t - t_k), so a stopping shaft reads
a falling speed, and it is zero before the second edge and after a reversal. The angle is the
last edge's angle plus the electrical speed times the time since that edge, held at the far
border of the sector; before the first edge it is the sector's centre.

Interpolation error at a constant electrical speed w_e > 0 with D = (pi/3) / w_e > T_s between
edges (each edge seen a delay d in [0, T_s) late): the interval measured is D + d_k - d_(k-1),
so the speed is off by at most w_e T_s / (D - T_s) relative, and the angle at a sample a time
r <= D + T_s after the seen edge is off by at most w_e T_s + w_e T_s (D + T_s) / (D - T_s)
(the delay of the edge plus the speed error over the interpolation), from the second edge on.
Between the first and the second edge the angle is the edge's, off by less than
pi/3 + w_e T_s."""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from acdrive._jit import jit
from acdrive.core._parts import SampledPart
from acdrive.core._signals import Layout, real

PARAMS = Layout(
    real("pole_pairs", "", "pole pairs of the machine (and of the sensors' magnet ring)", "count"),
    real("offset", "rad", "mounting offset: the sensors' angle minus the electrical angle", ""),
)
STATES = Layout(
    real("started", "", "1 once the first sample has run"),
    real("sector", "", "sector at the last sample, 0 .. 5"),
    real("edges", "", "edges seen in the present direction, up to 2"),
    real("edge_angle", "rad", "electrical angle of the last edge"),
    real("edge_time", "s", "sample time at which the last edge was seen"),
    real("interval", "s", "time between the last two edges"),
    real("direction", "", "+1 forwards, -1 backwards (last edge)"),
)
INPUTS = Layout(real("theta", "rad", "shaft angle"))
OUTPUTS = Layout(
    real("h_a", "", "Hall sensor a (0 or 1)"),
    real("h_b", "", "Hall sensor b (0 or 1)"),
    real("h_c", "", "Hall sensor c (0 or 1)"),
    real("sector", "", "sector 0 .. 5 of 60 electrical degrees"),
    real("theta_e", "rad", "interpolated electrical angle, in [0, 2 pi)"),
    real("w", "rad/s", "mechanical speed from the time between edges"),
)
_POLE_PAIRS, _OFFSET = PARAMS.slot("pole_pairs"), PARAMS.slot("offset")
(_STARTED, _SECTOR, _EDGES, _EDGE_ANGLE, _EDGE_TIME, _INTERVAL,
 _DIRECTION) = (STATES.slot(v.name) for v in STATES)  # fmt: skip
_THETA_IN = INPUTS.slot("theta")
_H_A, _H_B, _H_C, _Y_SECTOR, _THETA_E, _W = (OUTPUTS.slot(v.name) for v in OUTPUTS)
_EDGE_SEEN, _SKIPPED = 1, 2  # event bits: bit k is EVENTS[k]
TWO_PI = 2.0 * np.pi
SECTOR = np.pi / 3.0


@jit
def hall_step(t, T_s, u, p, s, y):
    """Hall signals and sector at this sample; an edge updates the edge angle, time and interval;
    the angle interpolated from the last edge, the speed from the interval (module docstring)."""
    events = 0
    x = p[_POLE_PAIRS] * u[_THETA_IN] + p[_OFFSET]
    x = x - TWO_PI * np.floor(x / TWO_PI)
    sector = np.floor(x / SECTOR)
    if sector > 5.0:  # x rounded up to 2 pi
        sector = 5.0
    y[_H_A] = 1.0 if sector <= 2.0 else 0.0
    y[_H_B] = 1.0 if sector >= 2.0 and sector <= 4.0 else 0.0
    y[_H_C] = 1.0 if sector >= 4.0 or sector == 0.0 else 0.0
    y[_Y_SECTOR] = sector
    if s[_STARTED] == 0.0:
        s[_STARTED] = 1.0
        s[_SECTOR] = sector
        s[_EDGES] = 0.0
        s[_DIRECTION] = 0.0
    step = sector - s[_SECTOR]
    step = step - 6.0 * np.floor(step / 6.0)  # 0 .. 5 sectors forwards
    if step != 0.0:
        events |= _EDGE_SEEN
        if step != 1.0 and step != 5.0:
            events |= _SKIPPED
        direction = 1.0 if step <= 3.0 else -1.0
        edge_angle = sector * SECTOR if direction > 0.0 else s[_SECTOR] * SECTOR
        if direction == s[_DIRECTION] and s[_EDGES] >= 1.0:
            s[_INTERVAL] = t - s[_EDGE_TIME]
            s[_EDGES] = 2.0
        else:
            s[_EDGES] = 1.0
        s[_DIRECTION] = direction
        s[_EDGE_ANGLE] = edge_angle
        s[_EDGE_TIME] = t
        s[_SECTOR] = sector
    w_e = 0.0
    if s[_EDGES] >= 2.0:
        elapsed = t - s[_EDGE_TIME]
        interval = elapsed if elapsed > s[_INTERVAL] else s[_INTERVAL]
        w_e = s[_DIRECTION] * SECTOR / interval
    if s[_EDGES] == 0.0:
        angle = (sector + 0.5) * SECTOR
    else:
        advance = w_e * (t - s[_EDGE_TIME])
        if advance > SECTOR:
            advance = SECTOR
        elif advance < -SECTOR:
            advance = -SECTOR
        angle = s[_EDGE_ANGLE] + advance
    y[_THETA_E] = angle - TWO_PI * np.floor(angle / TWO_PI)
    y[_W] = w_e / p[_POLE_PAIRS]
    return events


class HallSensors(SampledPart):
    """Three Hall sensors (60-degree sectors, a mounting offset); the electrical angle
    interpolated from the last edge with the speed from the time between the last two edges."""

    SOURCE = "three Hall sensors, angle interpolated between edges (plant._hall.hall_step)"

    PARAMS, STATES, INPUTS, OUTPUTS = PARAMS, STATES, INPUTS, OUTPUTS
    DEFAULTS: ClassVar[dict] = {"pole_pairs": 1.0, "offset": 0.0}
    EVENTS = ("edge", "skipped")
    step = hall_step
