"""A current-sensor offset on the simulated standstill bench (identify._offset): the DC steps
alone read it as a voltage error of -R_s c, which the injection's compensation then applies
(0.05 A on the DeLorenzo IM's 16 ohm: 0.8 V); estimated from the injection's mean jointly with
the parameters, it is subtracted, U_err is corrected, and the 95 % intervals hold the machine's
inverse-Gamma parameters and the offset itself."""

import dataclasses

import pytest

from acdrive.identify import (
    CurrentSensor,
    StandstillPlan,
    dc_test,
    identify_standstill,
    injection_test,
    inverse_gamma,
)
from acdrive.identify._coverage import reading
from acdrive.machines import DELORENZO_IM

pytestmark = pytest.mark.slow

#: a bench inverter: 2 us dead time at 5 kHz from 310 V, 1 V per conducting device
DEAD = StandstillPlan(t_d=2e-6, v_drop=1.0)
QUIET = dataclasses.replace(DEAD, sensor=CurrentSensor(noise_std=0.0, offset=0.0, lsb=0.0))


@pytest.fixture(scope="module")
def runs():
    """The noise-free injection and DC-step logs, read by each sensor after the run."""
    return injection_test(DELORENZO_IM, QUIET), dc_test(DELORENZO_IM, QUIET)


@pytest.mark.parametrize("offset", [0.05, 0.2])
def test_a_current_offset_is_estimated_and_the_intervals_hold_the_machine(runs, offset):
    injection, dc = runs
    sensor = dataclasses.replace(DEAD.sensor, offset=offset)
    result = identify_standstill(reading(injection, sensor, 1), DEAD.base_frequency, DEAD.settle,
                                 dc=reading(dc, sensor, 0), n_p=DELORENZO_IM.n_p, bootstrap=50,
                                 dead_time=DEAD.t_d)  # fmt: skip
    truth = inverse_gamma(DELORENZO_IM).as_array()
    misses = [e.name for e, true in zip(result.impedance.estimates, truth, strict=True)
              if not e.covers(true)]  # fmt: skip
    assert misses == [], (misses, result.impedance.estimates)
    # the DC steps' own intercept is the voltage error less R_s c; the one compensated is U_err
    predicted = 4.0 / 3.0 * (DEAD.t_d * DEAD.f_pwm * DEAD.v_dc + DEAD.v_drop)
    assert result.dc.voltage_error.value == pytest.approx(predicted - DELORENZO_IM.R_s * offset,
                                                          abs=0.02)  # fmt: skip
    assert result.voltage_error == pytest.approx(predicted, abs=0.02)
    assert result.current_offset.covers(offset), result.current_offset


def test_tones_within_the_voltage_error_leave_a_residual_that_is_judged_and_named():
    """Tones of 4 V against U_err = 5.47 V (0.73 of it): the compensated fit's residual is
    several times the noise floor; the warning names the tones and U_err, and the intervals
    carry the model-error term."""
    plan = dataclasses.replace(DEAD, tone_amplitude=4.0)
    result = identify_standstill(injection_test(DELORENZO_IM, plan, seed=1), plan.base_frequency,
                                 plan.settle, dc=dc_test(DELORENZO_IM, plan, seed=0),
                                 n_p=DELORENZO_IM.n_p, bootstrap=10, dead_time=plan.t_d)  # fmt: skip
    fit = result.impedance
    assert fit.model_error and fit.residual_ratio > 2.0
    (line,) = [w for w in fit.warnings if "noise floor" in w]
    assert "tones too small for the inverter's voltage error (the smallest 4 V" in line, line
    assert "U_err = 5.4" in line
