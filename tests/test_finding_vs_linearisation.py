"""The summary's speed-oscillation finding against the linearised whole drive, on the built-in
single-motor DFIM scenarios (issue "Reliability": the finding agrees with the linearised
stability verdict).

For each scenario the linearised sampled-data drive (``analysis.drive_stability``, the compiled
loop's own one-sample map) is evaluated at the operating points where the speed reference rests
(its plateaus, with the scenario's load there). The linearisation takes the scenario's own setup
(motor 0 on its supply, in each compared mode), so machine, gains, current loop, supply, speed
filter, converter, sample time and substeps are the scenario's. If any plateau point is unstable within the
controller's limits, the simulation must report the oscillation finding; if every point is
stable, it must not. Both occur: `bodson-ramp-ideal` is unstable at 2,700 rpm (and reports the
limit cycle), the others are stable at every plateau.

Not covered: the multi-motor built-ins (the linearisation models one motor on its supply) and
the scenarios whose plateaus lie outside the model (synchronisation with the stator open, the
sensor fallback, a varying supply).
"""

import numpy as np
import pytest

from acdrive.analysis import OperatingPoint, linearize
from acdrive.drives.dfim import run_scenario
from acdrive.errors import InputError
from acdrive.scenarios import load_scenario

SCENARIOS = ("bodson-ramp", "bodson-ramp-ideal", "bodson-step", "bodson-mixed-steps")


def plateaus(setup):
    """(speed [rad/s], load [N m]) at the middle of every interval where the reference rests."""
    motor = setup.motors[0]
    times, speeds = motor.speed_reference
    out = []
    for i in range(len(times) - 1):
        if speeds[i] == speeds[i + 1] and times[i + 1] > times[i]:
            t = 0.5 * (times[i] + times[i + 1])
            out.append((float(speeds[i]), float(np.interp(t, *motor.load_torque))))
    return out


@pytest.mark.parametrize("name", SCENARIOS)
def test_the_oscillation_finding_agrees_with_the_linearised_drive(name):
    setup = load_scenario(name)
    modes = setup.compare_modes or (setup.motors[0].controller.mode,)
    outcome = run_scenario(setup)
    found = outcome.summary.get("finding", "")
    for mode in modes:
        verdicts = []
        for w, load in plateaus(setup):
            try:
                r = linearize(setup.with_mode(mode), OperatingPoint(w, load), "sampled")
            except InputError:
                continue  # no equilibrium inside the limits there
            if r.within_limits:
                verdicts.append(r.stable)
        assert verdicts, f"{name}: no operating point to judge"
        unstable = not all(verdicts)
        assert unstable == (f"{mode} command: the speed oscillates" in found), (
            name,
            mode,
            verdicts,
            found,
        )
