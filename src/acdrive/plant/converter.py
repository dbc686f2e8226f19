"""Rotor-side voltage-source converter, averaged model.

The converter applies the commanded rotor voltage, held over the sample period (zero-order
hold), within the linear range of space-vector modulation: a phase-voltage peak of V_dc / sqrt(3),
i.e. a space-vector magnitude of sqrt(3/2) V_dc / sqrt(3) = V_dc / sqrt(2) (Bodson (8)). A command
beyond it is scaled back along its own direction.
"""

from __future__ import annotations

import numpy as np

from acdrive.core.parts import Modulator
from acdrive.core.signals import Layout, cplx, real
from acdrive.frames import clip_magnitude
from acdrive.jit import jit


@jit
def max_voltage_magnitude(v_dc):
    """Largest space-vector magnitude the converter applies from DC-link voltage ``v_dc``."""
    return v_dc / np.sqrt(2.0)


@jit
def converter_output(v_command, v_max):
    """(applied voltage, saturated) for a complex command and magnitude limit ``v_max``."""
    return clip_magnitude(v_command, v_max)


# --- the averaged converter as a modulator part -----------------------------------------------

AVERAGED_PARAMS = Layout(real("V_dc", "V", "DC-link voltage", "positive"))
AVERAGED_INPUTS = Layout(cplx("v_ref", "V", "commanded voltage space vector"))
AVERAGED_OUTPUTS = Layout(cplx("v", "V", "applied voltage space vector, held over the sample"))
_V_DC = AVERAGED_PARAMS.slot("V_dc")
_V_REF = AVERAGED_INPUTS.slot("v_ref")
_V_OUT = AVERAGED_OUTPUTS.slot("v")
EVENT_SATURATED = 1


@jit
def averaged_segments(T_s, u, p, s, dt, v):
    """One segment over the whole sample: the command, limited to V_dc / sqrt(2) (ZOH)."""
    applied, saturated = converter_output(
        complex(u[_V_REF], u[_V_REF + 1]), max_voltage_magnitude(p[_V_DC])
    )
    dt[0] = T_s
    v[0, _V_OUT], v[0, _V_OUT + 1] = applied.real, applied.imag
    return 1, EVENT_SATURATED if saturated else 0


class AveragedConverter(Modulator):
    """Averaged voltage-source converter: the sampled command held over the sample (ZOH) within
    the linear range of space-vector modulation, |v| <= V_dc / sqrt(2) (module docstring)."""

    PARAMS, INPUTS, OUTPUTS = AVERAGED_PARAMS, AVERAGED_INPUTS, AVERAGED_OUTPUTS
    EVENTS = ("saturated",)
    MAX_SEGMENTS = 1
    segments = averaged_segments
