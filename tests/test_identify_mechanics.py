"""Inertia, viscous and Coulomb friction from speed steps of the PM speed drive (the BLY171D on its
20 kHz SVPWM inverter, the speed read from a 4096-count encoder): the estimates cover the
shaft's own J, B, tau_c within their 95 % intervals, a test that holds one speed cannot separate
the two frictions and is refused by name, and a log that is too coarse, too slow or badly
labelled is refused naming the column and the rule (identify._mechanics)."""

import dataclasses
import math

import numpy as np
import pytest

from acdrive.drives.pm import BLY171D
from acdrive.drives.pm._machines import BLY171D_B
from acdrive.errors import InputError
from acdrive.identify import (
    MECHANICS_COLUMNS,
    MechanicsLog,
    MechanicsPlan,
    fit_mechanics,
    predicted_speed,
    read_mechanics_log,
    speed_step_test,
    write_mechanics_log,
)

pytestmark = pytest.mark.slow

SCENARIO = {
    "drive": "pm",
    "name": "bly171d-speed-steps",
    "machine": {"machine": "bly171d", "viscous_friction": BLY171D_B},
    "converter": {"model": "switching", "pwm_frequency_hz": 20000.0, "dc_link_voltage": 24.0},
    "control": {"current_limit_pk_a": 1.8, "current_bandwidth_rad_s": 2 * math.pi * 400,
                "speed_bandwidth_rad_s": 200.0},
    "simulation": {"sample_time": 5e-5},
}  # fmt: skip
#: the table gives no Coulomb friction: 2 mN m, 3.5 % of the rated torque, is assumed
PLAN = MechanicsPlan(tau_c=2e-3)
TRUTH = {"J": BLY171D.J, "B": BLY171D_B, "tau_c": PLAN.tau_c}


def test_the_discretised_shaft_is_exact_for_a_torque_linear_between_samples():
    """predicted_speed against the closed-form response of J dw/dt = u(t) - B w to a ramp."""
    J, B, h = 2e-6, 1e-5, 1e-4
    t = np.arange(200) * h
    u = 0.05 * t / t[-1]  # a ramp: linear between the samples, as the model assumes
    tau_m, slope = J / B, 0.05 / t[-1]
    exact = (slope / B) * (t - tau_m * (1 - np.exp(-t / tau_m)))  # w(0) = 0
    np.testing.assert_allclose(predicted_speed((J, B, 0.0, 0.0), u, 1.0, h), exact,
                               rtol=1e-9, atol=1e-12)  # fmt: skip


def test_the_speed_steps_recover_j_b_and_tau_c_within_their_intervals():
    misses = 0
    for seed in range(2):
        fit = fit_mechanics(speed_step_test(SCENARIO, PLAN, seed=seed), seed=seed, bootstrap=20)
        for e in fit.estimates:
            misses += not e.covers(TRUTH[e.name])
            assert abs(e.value - TRUTH[e.name]) < 0.01 * TRUTH[e.name], e
    # six 95 % intervals: two misses or more have probability 3 % if they are right
    assert misses <= 1


def test_one_speed_cannot_separate_viscous_from_coulomb_friction(tmp_path):
    """A staircase of one level: the plateau's torque is B w + tau_c at a single w."""
    log = speed_step_test(SCENARIO, dataclasses.replace(PLAN, levels=(300.0, 300.0)))
    with pytest.raises(InputError, match=r"^(B|tau_c): not identified by this test"):
        fit_mechanics(log, bootstrap=5)
    # the same log written and read back as .mat keeps every number
    back = read_mechanics_log(write_mechanics_log(log, tmp_path / "steps.mat"))
    np.testing.assert_array_equal(back.w, log.w)


T = np.arange(400) * 1e-4
GOOD = MechanicsLog(T, np.full(T.size, 0.01), 100.0 + 10.0 * T, "x")


@pytest.mark.parametrize(
    ("log", "message"),
    [
        (dataclasses.replace(GOOD, time=T * 20), r"x: column 'time': sampling every 0.002 s is too coarse"),
        (dataclasses.replace(GOOD, w=np.where(T > 0.01, 1.0, 100.0)),
         r"x: column 'w': the speed must stay above 5 rad/s"),
    ],
)  # fmt: skip
def test_a_log_the_model_cannot_use_is_refused_naming_the_column(log, message):
    with pytest.raises(InputError, match="^" + message):
        fit_mechanics(log, bootstrap=5)


def test_a_mechanics_file_is_checked_like_every_log(tmp_path):
    path = tmp_path / "steps.csv"
    path.write_text("time [s],tau_e [N m],w [rpm]\n" + "\n".join(f"{t},0.01,100" for t in T))
    with pytest.raises(InputError, match=r"^path: column 'w': must be in rad/s, got 'rpm'"):
        read_mechanics_log(path)
    assert set(MECHANICS_COLUMNS) == {"time", "tau_e", "w"}
