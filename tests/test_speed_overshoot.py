"""The speed-step overshoot of Bodson's speed PI (25)-(27): the closed form of
``SpeedPIGains.step_overshoot`` against a sampled simulation of the controller's own function
(``speed_pi``) on an ideal-torque shaft, and its known values."""

import math

import numpy as np
import pytest

from acdrive.control import SpeedPIGains
from acdrive.control._speed import speed_pi

J = 0.0122  # Bodson's motor inertia [kg m^2]
A = 50.0  # a_D,VEL [rad/s]


def _simulated_overshoot(gains, J, step=1.0, T_s=2e-6, periods=12.0):
    """Step the reference from 0 to ``step`` and integrate J dw/dt = tau exactly over each sample
    (zero-order hold of the controller's torque); limits far away, so it never clamps."""
    w, e_int, peak = 0.0, 0.0, 0.0
    for _ in range(int(periods / A / T_s)):
        tau, e_int, limited = speed_pi(gains.K_P, gains.K_I, gains.K_F, e_int, step, w,
                                       -1e9, 1e9, T_s)  # fmt: skip
        assert not limited
        w += T_s * tau / J
        peak = max(peak, w)
    return peak / step - 1.0


@pytest.mark.parametrize("K_F", [1.0, 2.0 / 3.0, 0.67, 0.6, 0.5, 0.3])
def test_closed_form_matches_the_sampled_controller(K_F):
    gains = SpeedPIGains.design(J, A, K_F)
    expected = gains.step_overshoot(J)
    assert _simulated_overshoot(gains, J) == pytest.approx(expected, abs=2e-4)


def test_known_values():
    assert SpeedPIGains.design(J, A, 1.0).step_overshoot(J) == pytest.approx(math.exp(-2.0))
    assert SpeedPIGains.design(J, A).step_overshoot(J) == pytest.approx(math.exp(-4.0) / 3.0)
    assert SpeedPIGains.design(J, A).step_overshoot(J) == pytest.approx(0.0061, abs=5e-5)
    assert SpeedPIGains.design(J, A, 0.5).step_overshoot(J) == 0.0


def test_other_gains_use_the_same_transfer_function():
    gains = SpeedPIGains(K_P=2 * A * J, K_I=0.5 * A * A * J, K_F=1.0)  # not a double root
    numeric = gains.step_overshoot(J)
    assert numeric == pytest.approx(_simulated_overshoot(gains, J, periods=30.0), abs=2e-4)
    # the closed form, nudged off its double root, agrees with the numeric branch nearby
    near = SpeedPIGains(K_P=2 * A * J, K_I=A * A * J * (1 + 1e-9), K_F=2.0 / 3.0)
    assert near.step_overshoot(J) == pytest.approx(np.exp(-4.0) / 3.0, abs=1e-5)
