"""Rotor-side voltage-source converter, averaged model.

The converter applies the commanded rotor voltage, held over the sample period (zero-order
hold), within the linear range of space-vector modulation: a phase-voltage peak of V_dc / sqrt(3),
i.e. a space-vector magnitude of sqrt(3/2) V_dc / sqrt(3) = V_dc / sqrt(2) (Bodson (8)). A command
beyond it is scaled back along its own direction.

Two parts, one formula: ``AveragedConverter`` has a fixed DC-link voltage (parameter ``V_dc``);
``DCFedConverter`` reads it as an input ``v_dc`` from a continuous part (``plant.DCSource``,
a DC link whose voltage may drop), taken at the sample instant like its command. Both report a
command beyond the limit with the event ``saturated`` (beyond it by more than a few ulps,
``_frames.beyond_limit``: a command already limited to it is not counted again).
"""

from __future__ import annotations

import numpy as np

from acdrive._frames import clip_magnitude
from acdrive._jit import jit, python_from_python
from acdrive.core._parts import Modulator
from acdrive.core._signals import Layout, cplx, real


@python_from_python
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

    SOURCE = (
        "averaged converter: the command held over the sample, |v| <= V_dc / sqrt(2) "
        "(plant._converter)"
    )

    PARAMS, INPUTS, OUTPUTS = AVERAGED_PARAMS, AVERAGED_INPUTS, AVERAGED_OUTPUTS
    EVENTS = ("saturated",)
    MAX_SEGMENTS = 1
    segments = averaged_segments


# --- the same converter fed from a DC-link input ----------------------------------------------

FED_INPUTS = Layout(
    cplx("v_ref", "V", "commanded voltage space vector"),
    real("v_dc", "V", "DC-link voltage"),
)
_FED_V_REF, _FED_V_DC = FED_INPUTS.slot("v_ref"), FED_INPUTS.slot("v_dc")


@jit
def fed_segments(T_s, u, p, s, dt, v):
    """As ``averaged_segments`` with the limit v_dc / sqrt(2) from the input v_dc, read at the
    sample instant (a non-positive v_dc applies nothing)."""
    applied, saturated = converter_output(
        complex(u[_FED_V_REF], u[_FED_V_REF + 1]), max_voltage_magnitude(max(u[_FED_V_DC], 0.0))
    )
    dt[0] = T_s
    v[0, _V_OUT], v[0, _V_OUT + 1] = applied.real, applied.imag
    return 1, EVENT_SATURATED if saturated else 0


class DCFedConverter(Modulator):
    """``AveragedConverter`` whose DC-link voltage is the input ``v_dc`` (from a
    ``plant.DCSource``) read at each sample instant: |v| <= v_dc / sqrt(2), a command
    beyond it scaled back along its direction and reported as ``saturated``."""

    SOURCE = (
        "averaged converter fed from a DC link: |v| <= max(v_dc, 0) / sqrt(2) (plant._converter)"
    )

    INPUTS, OUTPUTS = FED_INPUTS, AVERAGED_OUTPUTS
    EVENTS = ("saturated",)
    MAX_SEGMENTS = 1
    segments = fed_segments
