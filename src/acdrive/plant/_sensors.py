"""Sensors seen by the controller (Bodson section IV-A): the encoder, the current sensors and a
voltage sensor, as functions and as sampled parts. A voltage may also be wired straight to a
controller (an ideal measurement)."""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from acdrive._jit import jit, python_from_python
from acdrive.core._parts import SampledPart
from acdrive.core._signals import Layout, cplx, real


@python_from_python
@jit
def encoder_angle(theta, offset, counts_per_rev):
    """Incremental-encoder reading: the shaft angle plus an unknown ``offset``, truncated to whole
    counts of 2 pi / counts_per_rev (counts_per_rev <= 0 means an ideal sensor)."""
    reading = theta + offset
    if counts_per_rev <= 0.0:
        return reading
    step = 2.0 * np.pi / counts_per_rev
    return np.floor(reading / step) * step


#: the finest encoder resolution a scenario accepts [counts per revolution]: a 32-bit count per
#: turn. Finer counts quantise nothing a float64 angle resolves after a few thousand turns (the
#: step 2 pi / N against the angle's spacing of 2^-52 of its value), and at 1e30 the step is far
#: below it from the first turn on.
MAX_COUNTS_PER_REV = 2**32


def check_counts_per_rev(field: str, value) -> float:
    """``value`` (an encoder's counts per revolution; 0: ideal) as float, or an ``InputError``
    on ``field`` unless it is a whole number from 0 to ``MAX_COUNTS_PER_REV``."""
    from acdrive.errors import InputError, require_nonnegative

    value = require_nonnegative(field, value)
    if value > MAX_COUNTS_PER_REV or value != int(value):
        raise InputError(field, f"must be a whole number of counts from 0 (ideal) to "
                         f"{MAX_COUNTS_PER_REV} (2^32) per revolution, got {value:g}")  # fmt: skip
    return value


# --- sensors as sampled parts ----------------------------------------------------------------

ENCODER_PARAMS = Layout(
    real("offset", "rad", "unknown mounting offset added to the shaft angle"),
    real("counts_per_rev", "", "resolution in counts per revolution (0: ideal)", "nonnegative"),
)
ENCODER_INPUTS = Layout(real("theta", "rad", "shaft angle"))
ENCODER_OUTPUTS = Layout(real("theta", "rad", "measured shaft angle"))
_ENC_OFFSET, _ENC_CPR = ENCODER_PARAMS.slot("offset"), ENCODER_PARAMS.slot("counts_per_rev")


@jit
def encoder_step(t, T_s, u, p, s, y):
    y[0] = encoder_angle(u[0], p[_ENC_OFFSET], p[_ENC_CPR])
    return 0


class Encoder(SampledPart):
    """Incremental encoder read at each sample (``encoder_angle``)."""

    SOURCE = "Bodson IV-A: incremental encoder (plant._sensors.encoder_angle)"

    PARAMS, INPUTS, OUTPUTS = ENCODER_PARAMS, ENCODER_INPUTS, ENCODER_OUTPUTS
    DEFAULTS: ClassVar[dict] = {"offset": 0.0, "counts_per_rev": 0.0}
    step = encoder_step


CURRENT_PARAMS = Layout(
    real("fails", "", "1: the measurement fails at fault_time, 0: never", "flag"),
    real("fault_time", "s", "time from which the measurement fails", "nonnegative"),
)
CURRENT_INPUTS = Layout(
    cplx("i_s", "A", "stator current, stationary frame"),
    cplx("i_r", "A", "rotor current in rotor coordinates"),
)
CURRENT_OUTPUTS = Layout(
    cplx("i_s", "A", "measured stator current (last valid value after a failure)"),
    cplx("i_r", "A", "measured rotor current (last valid value after a failure)"),
    real("valid", "", "1 while the measurement works, 0 after it failed"),
)
_CUR_FAILS, _CUR_FAULT_T = CURRENT_PARAMS.slot("fails"), CURRENT_PARAMS.slot("fault_time")
_CUR_VALID = CURRENT_OUTPUTS.slot("valid")
EVENT_CURRENT_LOST = 1


@jit
def current_sensors_step(t, T_s, u, p, s, y):
    if p[_CUR_FAILS] != 0.0 and t >= p[_CUR_FAULT_T]:
        y[_CUR_VALID] = 0.0
        return EVENT_CURRENT_LOST
    for i in range(4):
        y[i] = u[i]
    y[_CUR_VALID] = 1.0
    return 0


class CurrentSensors(SampledPart):
    """Stator and rotor current sensors sampled together; from ``fault_time`` on (if ``fails``)
    the measurement is lost: ``valid`` drops to 0 and the currents keep their last values."""

    SOURCE = "Bodson IV-A: current sensors, lost from fault_time (plant._sensors)"

    PARAMS, INPUTS, OUTPUTS = CURRENT_PARAMS, CURRENT_INPUTS, CURRENT_OUTPUTS
    DEFAULTS: ClassVar[dict] = {"fails": 0.0, "fault_time": 0.0}
    EVENTS = ("lost",)
    step = current_sensors_step

    def held_outputs(self) -> dict:
        return {"valid": 1.0}


VOLTAGE_PARAMS = Layout(
    real("gain", "", "measured / true (1: exact; a calibration error otherwise)", "positive"),
    real("fails", "", "1: the measurement fails at fault_time, 0: never", "flag"),
    real("fault_time", "s", "time from which the measurement fails", "nonnegative"),
)
VOLTAGE_INPUTS = Layout(cplx("v", "V", "voltage space vector"))
VOLTAGE_OUTPUTS = Layout(
    cplx("v", "V", "measured voltage (last valid value after a failure)"),
    real("valid", "", "1 while the measurement works, 0 after it failed"),
)
_V_GAIN, _V_FAILS, _V_FAULT_T = (VOLTAGE_PARAMS.slot(n) for n in ("gain", "fails", "fault_time"))
_V_VALID = VOLTAGE_OUTPUTS.slot("valid")


@jit
def voltage_sensor_step(t, T_s, u, p, s, y):
    if p[_V_FAILS] != 0.0 and t >= p[_V_FAULT_T]:
        y[_V_VALID] = 0.0
        return EVENT_CURRENT_LOST  # bit 0: "lost", as for the current sensors
    y[0], y[1] = p[_V_GAIN] * u[0], p[_V_GAIN] * u[1]
    y[_V_VALID] = 1.0
    return 0


class VoltageSensor(SampledPart):
    """A voltage space-vector measurement with a gain error; from ``fault_time`` on (if
    ``fails``) it is lost: ``valid`` drops to 0 and the voltage keeps its last value."""

    SOURCE = "voltage sensor with a gain error, lost from fault_time (plant._sensors)"

    PARAMS, INPUTS, OUTPUTS = VOLTAGE_PARAMS, VOLTAGE_INPUTS, VOLTAGE_OUTPUTS
    DEFAULTS: ClassVar[dict] = {"gain": 1.0, "fails": 0.0, "fault_time": 0.0}
    EVENTS = ("lost",)
    step = voltage_sensor_step

    def held_outputs(self) -> dict:
        return {"valid": 1.0}
