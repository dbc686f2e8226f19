"""The summary's speed-oscillation finding against the linearised whole drive, on the built-in
single-motor DFIM scenarios (issue "Reliability": the finding agrees with the linearised
stability verdict).

For each scenario the linearised sampled-data drive (``analysis.drive_stability``, the compiled
loop's own one-sample map) is evaluated at the operating points where the speed reference rests
(its plateaus, with the scenario's load there). The drive model takes the scenario's machine,
mode, speed-PI gains ((27) inverted: a = 2 K_I / K_P, J = K_P^2 / (4 K_I)), K_F, current loop,
supply, speed filter, sample time and converter loss. If any plateau point is unstable within the
controller's limits, the simulation must report the oscillation finding; if every point is
stable, it must not. Both occur: `bodson-ramp-ideal` is unstable at 2,700 rpm (and reports the
limit cycle), the others are stable at every plateau.

Not covered: the multi-motor built-ins (the linearisation models one motor on its supply) and
the scenarios whose plateaus lie outside the model (synchronisation with the stator open, the
sensor fallback, a varying supply).
"""

import numpy as np
import pytest

from acdrive.analysis._drive_stability import DriveModel, OperatingPoint, linearize
from acdrive.drives.dfim._outcome import run_scenario
from acdrive.errors import InputError
from acdrive.scenarios._loader import load_scenario

SCENARIOS = ("bodson-ramp", "bodson-ramp-ideal", "bodson-step", "bodson-mixed-steps")


def model_of(setup, mode: str) -> DriveModel:
    motor = setup.motors[0]
    c, g = motor.controller, motor.controller.gains
    supply = setup.supply
    return DriveModel(
        mode=mode,
        machine=motor.machine,
        controller_params=c.params,
        speed_bandwidth=2.0 * g.K_I / g.K_P,
        design_inertia=g.K_P**2 / (4.0 * g.K_I),
        K_F=g.K_F,
        current_bandwidth=c.current_bandwidth,
        R_T=c.R_T,
        supply_voltage_pk=float(supply.voltage_pk[1][0]),
        supply_frequency_hz=float(supply.frequency_hz[1][0]),
        supply_resistance=supply.resistance,
        supply_inductance=supply.inductance,
        speed_filter_tau=c.speed_filter_tau,
        current_limit_pk=min(c.stator_current_limit_pk, c.rotor_current_limit_pk),
        sample_time=setup.sample_time,
        substeps=setup.substeps,
        converter_loss=float(motor.converter.fundamental_loss(motor.dc_link_voltage)),
    )


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
                r = linearize(model_of(setup, mode), OperatingPoint(w, load), "sampled")
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
