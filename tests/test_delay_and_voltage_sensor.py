"""A one-sample computation delay and a voltage sensor with gain error and failure, as parts in a
compiled system: the delay's output is exactly the previous sample's input; the converter driven
through it applies each command one period later."""

import numpy as np
import pytest

from acdrive.control import ComplexProgram, ComputationDelay
from acdrive.core import Profile
from acdrive.errors import InputError
from acdrive.plant import AveragedConverter, VoltageSensor
from acdrive.sim import System

T_S = 1e-3


def ramp_program():
    times = np.array([0.0, 0.02])
    return ComplexProgram("command", re=Profile(times, [0.0, 20.0]), im=Profile(times, [5.0, -5.0]))


def test_the_delay_outputs_the_previous_samples_input_and_the_converter_applies_it_a_period_late():
    command, delay = ramp_program(), ComputationDelay("delay", initial=1.0 + 2.0j)
    converter = AveragedConverter("converter", V_dc=100.0)
    system = System(
        [command, delay, converter],
        [(command.out.v_ref, delay.inp.x), (delay.out.x, converter.inp.v_ref)],
    )
    r = system.compile().run(0.02, T_S, log=[command.out.v_ref, delay.out.x, converter.out.v])
    given, delayed = r.signal(command.out.v_ref), r.signal(delay.out.x)
    assert delayed[0] == 1.0 + 2.0j  # the initial value, before any input was stored
    np.testing.assert_array_equal(delayed[1:], given[:-1])
    np.testing.assert_array_equal(r.signal(converter.out.v), delayed)


def test_a_real_delay_and_a_wrong_kind():
    delay = ComputationDelay("d", unit="N m", kind="real")
    assert delay.inp.x.var.kind == "real" and delay.inp.x.var.unit == "N m"
    with pytest.raises(InputError, match=r"d\.kind"):
        ComputationDelay("d", kind="vector")


def test_voltage_sensor_gain_and_failure():
    command = ramp_program()
    sensor = VoltageSensor("vs", gain=0.98, fails=1.0, fault_time=0.01)
    system = System([command, sensor], [(command.out.v_ref, sensor.inp.v)])
    r = system.compile().run(0.02, T_S, log=[command.out.v_ref, sensor.out.v, sensor.out.valid])
    true, measured = r.signal(command.out.v_ref), r.signal(sensor.out.v)
    valid = r.signal(sensor.out.valid)
    before = r.t < 0.01 - 1e-12
    np.testing.assert_allclose(measured[before], 0.98 * true[before], rtol=1e-15)
    assert np.all(valid[before] == 1.0) and np.all(valid[~before] == 0.0)
    # after the failure the last valid value is held
    assert np.all(measured[~before] == measured[before][-1])
    assert r.events["vs"]["lost"] == int(np.count_nonzero(~before))
