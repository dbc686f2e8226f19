"""The linearised closed DFIM drive as a python-control StateSpace (``StabilityResult.to_control``):
inputs speed reference and load torque, outputs speed and currents. With the speed PI's integral
action the speed follows a constant reference exactly (DC gain 1) and rejects a constant load
(DC gain 0); the poles are the linearisation's eigenvalues."""

from __future__ import annotations

import math

import numpy as np
import pytest

from acdrive.analysis import DriveModel, OperatingPoint, linearize
from acdrive.drives import get

POINT = OperatingPoint(900 * math.pi / 30, 0.05)


def _same_poles(a, b, rel=1e-6):
    a, b = np.sort_complex(np.asarray(a)), np.sort_complex(np.asarray(b))
    assert a.shape == b.shape
    assert np.max(np.abs(a - b)) <= rel * max(1.0, np.max(np.abs(b)))


@pytest.mark.parametrize("mode", ["voltage", "current"])
def test_continuous_closed_drive_has_unit_reference_gain_and_rejects_load(mode):
    r = linearize(DriveModel(mode=mode, speed_bandwidth=100.0), POINT)
    assert r.stable
    sys = r.to_control()
    assert sys.input_labels == ["w_ref", "tau_L"]
    assert sys.output_labels == ["w", "i_s_re", "i_s_im", "i_r_re", "i_r_im"]
    assert sys.isctime()
    gain = np.asarray(sys.dcgain())
    assert gain[0, 0] == pytest.approx(1.0, abs=1e-6)  # w_ref -> w: integral action
    assert gain[0, 1] == pytest.approx(0.0, abs=1e-6)  # tau_L -> w: rejected
    _same_poles(sys.poles(), r.eigenvalues)
    np.testing.assert_allclose(sys.A, r.jacobian, rtol=1e-9, atol=1e-9 * np.abs(r.jacobian).max())


def test_sampled_closed_drive_of_a_scenario_setup():
    """A scenario's own setup (Bodson's bench held at 900 rpm, a_D,VEL = 100 rad/s): a discrete system with dt = T_s whose
    poles are the one-sample map's eigenvalues; DC gains 1 and 0 as in continuous time."""
    setup = get("dfim").load({"motor": [{"speed_reference_rpm": [[0.0, 900.0]],
                                         "initial_speed_rpm": 900.0,
                                         "controller": {"speed_bandwidth": 100.0}}]})  # fmt: skip
    r = linearize(setup, kind="sampled")  # the setup's final reference and load
    assert r.point.speed == pytest.approx(900 * math.pi / 30)
    assert r.stable
    sys = r.to_control()
    assert sys.dt == setup.sample_time
    gain = np.asarray(sys.dcgain())
    assert gain[0, 0] == pytest.approx(1.0, abs=1e-5)
    assert gain[0, 1] == pytest.approx(0.0, abs=1e-5)
    _same_poles(sys.poles(), r.z_eigenvalues, rel=1e-6)


def test_the_load_slows_the_shaft_at_first_by_one_over_J():
    """Initial response of w to a load step: dw/dt = -tau_L / J (the shaft (26)), i.e. the
    first Markov parameter C B of the continuous model (the speed row) is -1 / J."""
    model = DriveModel(speed_bandwidth=100.0)
    sys = linearize(model, POINT).to_control()
    CB = (sys.C @ sys.B)[0, 1]
    assert CB == pytest.approx(-1.0 / model.machine.J, rel=1e-6)


def test_cli_linearises_a_scenario_as_it_is_set_up(capsys):
    """``acdrive stability --scenario``: the scenario's own drive at its final reference and load,
    the same numbers as ``linearize(setup)``; a cage-IM scenario is refused in one line."""
    from acdrive.cli import main
    from acdrive.scenarios import load_scenario

    assert main(["stability", "--scenario", "bodson-ramp", "--model", "sampled", "--json"]) == 0
    import json

    out = json.loads(capsys.readouterr().out)
    r = linearize(load_scenario("bodson-ramp"), kind="sampled")
    assert out["max_real_part"] == r.max_real_part and out["stable"] == r.stable
    assert out["speed_rpm"] == pytest.approx(r.point.speed_rpm)
    assert main(["stability", "--scenario", "im-locked-rotor"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--scenario" in err
