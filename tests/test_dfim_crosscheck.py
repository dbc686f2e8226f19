"""The DFIM drive's answer to a sweep's ``[crosscheck]`` (``drives.dfim._crosscheck``): the
largest speed-loop bandwidth a_D,VEL at which the linearised sampled drive is stable at the
setup's final operating point is that linearisation's stability boundary (stable just below,
unstable just above), found to its 1 rad/s tolerance."""

from __future__ import annotations

import math

from acdrive.drives import for_setup
from acdrive.drives.dfim._linearisation._stability import OperatingPoint, linearize
from acdrive.drives.dfim._linearisation._studies import with_speed_bandwidth
from acdrive.scenarios import load_scenario


def test_the_crosscheck_bandwidth_is_the_linearised_stability_boundary():
    setup = load_scenario("bodson-ramp")
    lower, upper = 50.0, 3000.0
    found = for_setup(setup).crosscheck(setup, lower, upper)
    motor = setup.motors[0]
    speed = float(motor.speed_reference[1][-1])
    assert found["speed_rpm"] == speed * 30.0 / math.pi
    assert found["load_nm"] == float(motor.load_torque[1][-1])
    a = found["linearised_tolerated"]
    assert lower < a < upper  # a boundary inside the range, not an end of it
    point = OperatingPoint(speed, found["load_nm"])

    def stable(bandwidth):
        return linearize(with_speed_bandwidth(setup, bandwidth), point, "sampled").stable

    assert stable(a - 1.0) and not stable(a + 2.0)
