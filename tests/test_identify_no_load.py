"""A cage IM's magnetising inductance from a no-load run on acdrive's bench (SVPWM inverter, cage
IM part, rotor driven at or near the synchronous speed, noisy quantised current): the running
machine's sampled admittance is the standstill one at zero speed and the continuous stator
impedance R_s + jw L_s at zero slip; the estimate covers the machine's L_M within its intervals
at zero and at 2 % slip; the parameter file written by ``acdrive identify`` takes it; a run the
estimator cannot use is refused naming the column and the rule (identify._no_load)."""

import dataclasses
import math

import numpy as np
import pytest

from acdrive.cli import main
from acdrive.errors import InputError
from acdrive.identify import (
    NoLoadLog,
    NoLoadPlan,
    StandstillPlan,
    dc_test,
    fit_no_load,
    identify_standstill,
    injection_test,
    inverse_gamma,
    no_load_test,
    read_no_load_log,
    running_admittance,
    sampled_admittance,
    write_log,
    write_no_load_log,
)
from acdrive.machines import DELORENZO_IM, UGALDE_IM_300W

pytestmark = pytest.mark.slow

PLAN = StandstillPlan()


def test_the_running_admittance_is_the_standstill_one_at_rest_and_r_s_plus_jwl_s_in_sync():
    params = inverse_gamma(DELORENZO_IM)
    w = 2 * math.pi * np.array([1.0, 13.0, 160.0])
    np.testing.assert_allclose(running_admittance(params.as_array(), 0.0, w, 2e-4),
                               sampled_admittance(params, w, 2e-4), rtol=1e-10)  # fmt: skip
    # zero slip, a hold so short the sampling is continuous: the rotor branch carries nothing
    w_s = 2 * math.pi * 50.0
    Y = running_admittance(params.as_array(), w_s, w_s, 1e-8)
    Z = params.R_s + 1j * w_s * (params.L_sigma + params.L_M)
    assert Y == pytest.approx(1.0 / Z, rel=1e-5)


def standstill(machine, seed):
    return identify_standstill(injection_test(machine, PLAN, seed=2 * seed + 1),
                               PLAN.base_frequency, PLAN.settle,
                               dc=dc_test(machine, PLAN, seed=2 * seed), n_p=machine.n_p,
                               seed=seed, bootstrap=50)  # fmt: skip


@pytest.mark.parametrize("machine", [DELORENZO_IM, UGALDE_IM_300W], ids=["delorenzo", "ugalde"])
def test_the_no_load_run_recovers_l_m_within_its_intervals(machine):
    truth = inverse_gamma(machine).L_M
    result = standstill(machine, seed=0)
    misses = 0
    for k, slip in enumerate((0.0, 0.02)):
        plan = NoLoadPlan(slip=slip)
        fit = fit_no_load(no_load_test(machine, plan, seed=10 + k), plan.frequency, plan.settle,
                          machine.n_p, result.impedance, seed=k, bootstrap=100)  # fmt: skip
        assert fit.slip == pytest.approx(slip, abs=1e-12)
        assert abs(fit.L_M.value - truth) < 0.005 * truth, fit.L_M
        misses += not fit.L_M.covers(truth)
        assert fit.L_M.bootstrap[0] < fit.L_M.value < fit.L_M.bootstrap[1]
    assert misses <= 1


def test_acdrive_identify_writes_the_no_load_l_m_into_the_parameter_file(tmp_path, capsys):
    import tomllib

    machine = DELORENZO_IM
    injection = write_log(injection_test(machine, PLAN, seed=1), tmp_path / "injection.csv")
    dc = write_log(dc_test(machine, PLAN, seed=0), tmp_path / "dc.mat")
    no_load = write_no_load_log(no_load_test(machine, NoLoadPlan()), tmp_path / "no-load.parquet")
    out = tmp_path / "motor.toml"
    assert main(["identify", str(injection), "--dc-log", str(dc), "--no-load-log", str(no_load),
                 "--pole-pairs", "1", "--out", str(out)]) == 0  # fmt: skip
    data = tomllib.loads(out.read_text())
    L_M = data["identification"]["no_load"]["L_M"]
    assert data["identification"]["magnetising_inductance_from"] == "no-load run at 50 Hz"
    written = data["machine"]["params"]
    # the T-circuit written has the no-load L_M: L_m^2 / L_r of the file is it
    assert written["L_m"] ** 2 / written["L_r"] == pytest.approx(L_M["value"], rel=1e-12)
    low, high = L_M["ci95_jacobian"]
    assert low <= inverse_gamma(machine).L_M <= high
    assert "no_load.L_M" in capsys.readouterr().out


LOG = no_load_test(DELORENZO_IM, dataclasses.replace(NoLoadPlan(), settle=0.1, periods=5))


@pytest.mark.parametrize(
    ("log", "frequency", "message"),
    [
        (dataclasses.replace(LOG, w=LOG.w * (1 + 0.05 * (LOG.time > 0.15))), 50.0,
         r"^x: column 'w': the speed must be constant within 1%"),
        (dataclasses.replace(LOG, v_a=LOG.v_a + 60 * np.cos(2 * math.pi * 150 * LOG.time)),
         50.0, r"^x: column 'v_a': a no-load run applies one frequency"),
        (LOG, 500.0, r"^x: column 'time': sampling at 5000 Hz is too coarse for 500 Hz"),
        (LOG, 3.0, r"^frequency: a period 1 / 3 Hz must be a whole number of samples"),
    ],
)  # fmt: skip
def test_a_run_the_estimator_cannot_use_is_refused_naming_the_column(log, frequency, message):
    result = standstill(DELORENZO_IM, seed=0)
    log = dataclasses.replace(log, source="x")
    with pytest.raises(InputError, match=message):
        fit_no_load(log, frequency, 0.1, 1, result.impedance, bootstrap=5)


def test_a_no_load_file_needs_the_speed_column(tmp_path):
    path = tmp_path / "run.csv"
    from acdrive.identify._experiment import StandstillLog

    write_log(StandstillLog(LOG.time, LOG.v_a, LOG.i_a), path)  # the standstill columns only
    with pytest.raises(InputError, match=r"^path: column 'w': is missing; a no-load log has"):
        read_no_load_log(path)
    assert isinstance(read_no_load_log(write_no_load_log(LOG, tmp_path / "run.mat")), NoLoadLog)


def test_the_pulses_second_moment_is_the_held_voltage_models_error_and_modelling_it_removes_it():
    """Noise-free 5 kHz run with the true standstill parameters: the current at f differs from
    the held-voltage model by exactly the centred pulses' second-order term (identify._no_load),
    which biases L_M high when left out; with the link voltage given it is modelled."""
    import types

    from acdrive.identify._no_load import _phasors, pulse_moment, ripple_admittance

    machine = DELORENZO_IM
    params = inverse_gamma(machine)
    plan = NoLoadPlan(slip=0.02, sensor=dataclasses.replace(
        PLAN.sensor, noise_std=0.0, offset=0.0, lsb=0.0))  # fmt: skip
    log = no_load_test(machine, plan)
    V, I, _, hold, speed = _phasors(log, plan.frequency, plan.settle)
    w, w_r = 2 * math.pi * plan.frequency, machine.n_p * speed
    left = I - running_admittance(params.as_array(), w_r, w, hold) * V
    moment = pulse_moment(V, plan.frequency, hold, plan.v_dc, round(1 / (plan.frequency * hold)))
    predicted = ripple_admittance(params.as_array(), w_r, w, hold) * moment
    assert abs(predicted / left - 1.0) < 1e-3, (predicted, left)
    known = types.SimpleNamespace(params=params, cov=np.zeros((4, 4)), draws=np.empty((0, 4)))
    errors = {}
    for v_dc in (None, plan.v_dc):
        fit = fit_no_load(log, plan.frequency, plan.settle, machine.n_p, known, bootstrap=10,
                          v_dc=v_dc)  # fmt: skip
        errors[v_dc] = fit.L_M.value / params.L_M - 1.0
    assert errors[None] > 1e-4  # the pattern adds to the sampled current: L_M reads high
    assert abs(errors[plan.v_dc]) < 1e-6, errors


def test_the_no_load_interval_is_the_noise_carried_through_the_models_slope_in_henry():
    """With the standstill parameters known exactly, L_M's Jacobian half-width is
    z_0.975 sqrt(var / |d(Y V)/d L_M|^2), var the noise variance of each part of I at f and the
    slope taken in henry (a log-parameter slope must be divided by L_M, not multiplied)."""
    import types

    from acdrive.identify._dc import Z_95
    from acdrive.identify._no_load import _phasors

    machine = DELORENZO_IM
    params = inverse_gamma(machine)
    plan = NoLoadPlan(slip=0.02)
    log = no_load_test(machine, plan, seed=5)
    V, _, variance, hold, speed = _phasors(log, plan.frequency, plan.settle)
    w, w_r = 2 * math.pi * plan.frequency, machine.n_p * speed
    known = types.SimpleNamespace(params=params, cov=np.zeros((4, 4)), draws=np.empty((0, 4)))
    fit = fit_no_load(log, plan.frequency, plan.settle, machine.n_p, known, bootstrap=10)
    L_M = fit.L_M.value
    step = 1e-6 * L_M
    base = params.as_array()[:3]
    slope = (running_admittance((*base, L_M + step), w_r, w, hold)
             - running_admittance((*base, L_M - step), w_r, w, hold)) * V / (2 * step)  # fmt: skip
    expected = Z_95 * math.sqrt(variance) / abs(slope)
    low, high = fit.L_M.jacobian
    assert 0.5 * (high - low) == pytest.approx(expected, rel=1e-3)
