"""A PM machine identified on acdrive's own bench (SVPWM inverter, PM machine part, noisy quantised
current): at standstill (rotor locked with its d, then its q axis on phase a) the estimates of
R_s, L_d, L_q cover the machines' own values within their 95 % intervals over a few seeded
repetitions, the d test makes no torque while the q test's lock holds n_p psi_pm i_q, and an
excitation that cannot separate R_s from L is refused naming the parameter (identify._pm); a
short-circuit spin test then gives the magnet flux within its intervals (identify._spin)."""

import dataclasses
import math

import numpy as np
import pytest

from acdrive.drives.pm import BLY171D, IPMSM_2KW2
from acdrive.errors import InputError
from acdrive.identify import (
    SpinPlan,
    StandstillPlan,
    axis_test,
    dc_test,
    fit_spin,
    identify_pm_standstill,
    pm_identifiability,
    read_spin_log,
    rl_admittance,
    short_circuit_gain,
    spin_test,
    write_spin_log,
)

pytestmark = pytest.mark.slow

#: a 24 V servo motor: tones up to 320 Hz around its 119 Hz corner R_s / (2 pi L), about its
#: rated 1.8 A peak at the lowest tones
BLY_PLAN = StandstillPlan(dc_levels=(0.3, 0.6, 0.9), dc_step=0.5, base_frequency=2.0,
                          tone_amplitude=0.15, settle=0.5, v_dc=24.0)  # fmt: skip
#: the 2.2 kW interior PMSM from 540 V: corners 16 Hz (d) and 11 Hz (q)
IPM_PLAN = StandstillPlan(dc_levels=(6.0, 12.0, 18.0), dc_step=0.5, base_frequency=1.0,
                          tone_amplitude=2.0, settle=0.5, v_dc=540.0)  # fmt: skip
CASES = [(BLY171D, BLY_PLAN), (IPMSM_2KW2, IPM_PLAN)]


def test_the_sampled_rl_admittance_is_the_exact_discrete_winding():
    """Y_d against the RL branch stepped exactly period by period in a periodic steady state."""
    R, L, T, f = 0.75, 1e-3, 2e-4, 50.0
    n = round(1.0 / (f * T)) * 4
    k = np.arange(n)
    v = np.cos(2 * math.pi * f * k * T)
    a = math.exp(-R * T / L)
    i = np.zeros(n + 1)
    for j in range(n):
        i[j + 1] = a * i[j] + (1 - a) / R * v[j]
    last, tone = n // 4, round(n // 4 * f * T)  # the last period; the tone's bin
    V = np.fft.rfft(v[-last:])[tone]
    I_ = np.fft.rfft(i[-last - 1 : -1])[tone]  # i_k of the same instants k as v_k
    assert I_ / V == pytest.approx(rl_admittance((R, L), 2 * math.pi * f, T), rel=1e-9)


@pytest.mark.parametrize(("machine", "plan"), CASES, ids=["bly171d", "ipmsm-2kw2"])
def test_the_axis_tests_recover_r_s_l_d_l_q_within_their_intervals(machine, plan):
    truth = {"R_s": machine.R_s, "L_d": machine.L_d, "L_q": machine.L_q}
    misses = 0
    for seed in range(3):
        d = axis_test(machine, plan, "d", seed=3 * seed + 1)
        q = axis_test(machine, plan, "q", seed=3 * seed + 2)
        dc = dc_test(machine, plan, seed=3 * seed)
        result = identify_pm_standstill(d.log, q.log, plan.base_frequency, plan.settle, dc=dc,
                                        seed=seed, bootstrap=100)  # fmt: skip
        for e in result.estimates:
            misses += not e.covers(truth[e.name])
            assert abs(e.value - truth[e.name]) < 0.01 * truth[e.name], e
            assert all(np.isfinite(e.bootstrap)), e
        assert result.dc.R_s.covers(machine.R_s)
    # nine 95 % intervals: three misses or more have probability 0.8 % if they are right
    assert misses <= 2


def test_the_d_test_makes_no_torque_and_the_q_tests_lock_holds_n_p_psi_pm_i_q():
    machine, plan = IPMSM_2KW2, IPM_PLAN
    d = axis_test(machine, plan, "d")
    q = axis_test(machine, plan, "q")
    assert d.holding_torque < 1e-9
    # tau = n_p psi_pm i_q with |i_q| = sqrt(3/2) |i_a| (power-invariant): bound by the log's peak
    # current (the sensor's noise and step aside)
    psi_pm = math.sqrt(1.5) * machine.psi_m
    peak = machine.n_p * psi_pm * math.sqrt(1.5) * np.max(np.abs(q.log.i_a))
    assert q.holding_torque == pytest.approx(peak, rel=0.02)
    lines = pm_identifiability(identify_pm_standstill(d.log, q.log, plan.base_frequency,
                                                      plan.settle, bootstrap=20))  # fmt: skip
    assert any("psi_m" in line and "not identifiable" in line for line in lines)


def test_tones_far_above_the_corner_cannot_separate_the_resistance():
    """Tones of 200 to 500 Hz, 12 to 30 times the interior PMSM's 16 Hz d-axis corner
    R_s / (2 pi L_d): the winding looks like an inductance, R_s is lost and refused by name."""
    plan = dataclasses.replace(IPM_PLAN, base_frequency=100.0, tones=(2, 3, 4, 5), settle=0.1,
                               tone_amplitude=20.0)  # fmt: skip
    d = axis_test(IPMSM_2KW2, plan, "d")
    q = axis_test(IPMSM_2KW2, plan, "q")
    with pytest.raises(InputError, match=r"^R_s: not identified by this excitation: its 95 % "):
        identify_pm_standstill(d.log, q.log, plan.base_frequency, plan.settle, bootstrap=10)


#: the spin tests: speeds whose short-circuit current stays near each machine's rating
BLY_SPIN = SpinPlan(speeds=(20.0, 40.0, 60.0), v_dc=24.0)
IPM_SPIN = SpinPlan(speeds=(5.0, 10.0, 15.0), hold=3.0, v_dc=540.0)


def test_the_short_circuit_gain_is_the_steady_state_of_the_dq_equations():
    """g against (7) solved as a linear system at v_d = v_q = 0 (power-invariant, then phase
    peak: the sqrt(3/2) of psi_pm and of |i_s| cancel)."""
    m = IPMSM_2KW2
    for w_r in (10.0, 100.0, 1000.0):
        A = np.array([[m.R_s, -w_r * m.L_q], [w_r * m.L_d, m.R_s]])
        i_dq = np.linalg.solve(A, [0.0, -w_r * math.sqrt(1.5) * m.psi_m])
        peak = math.hypot(*i_dq) / math.sqrt(1.5)
        assert m.psi_m * short_circuit_gain((m.R_s, m.L_d, m.L_q), w_r) == pytest.approx(peak)


@pytest.mark.parametrize(("machine", "plan", "spin"), [(BLY171D, BLY_PLAN, BLY_SPIN),
                                                       (IPMSM_2KW2, IPM_PLAN, IPM_SPIN)],
                         ids=["bly171d", "ipmsm-2kw2"])  # fmt: skip
def test_the_spin_test_recovers_the_magnet_flux_within_its_intervals(machine, plan, spin):
    standstill = identify_pm_standstill(axis_test(machine, plan, "d").log,
                                        axis_test(machine, plan, "q", seed=2).log,
                                        plan.base_frequency, plan.settle,
                                        dc=dc_test(machine, plan), bootstrap=100)  # fmt: skip
    misses = 0
    for seed in range(2):
        test = spin_test(machine, spin, seed=5 + seed)
        fit = fit_spin(test.log, machine.n_p, spin.settle, standstill, seed=seed)
        misses += not fit.psi_m.covers(machine.psi_m)
        assert abs(fit.psi_m.value - machine.psi_m) < 0.005 * machine.psi_m, fit.psi_m
        # the dynamometer brakes against n_p psi_pm i_q + ...: within the machine's torque range
        assert 0.0 < test.braking_torque < 1.2 * (0.0566 if machine is BLY171D else 14.0)
    assert misses <= 1


def test_a_spin_log_that_is_not_a_short_circuit_or_too_short_is_refused(tmp_path):
    test = spin_test(BLY171D, dataclasses.replace(BLY_SPIN, speeds=(20.0,)))
    from acdrive.identify._pm import PMStandstillIdentification

    # refused before the standstill values are needed: a record without them
    standstill = PMStandstillIdentification.__new__(PMStandstillIdentification)
    log = dataclasses.replace(test.log, v_a=test.log.v_a + 0.1, source="x")
    with pytest.raises(InputError, match=r"^x: column 'v_a': a short-circuit spin test commands"):
        fit_spin(log, BLY171D.n_p, BLY_SPIN.settle, standstill)
    with pytest.raises(InputError, match=r"^x: column 'w': the plateau at 20 rad/s must hold 5 "):
        fit_spin(dataclasses.replace(test.log, source="x"), BLY171D.n_p, 0.9, standstill)
    back = read_spin_log(write_spin_log(test.log, tmp_path / "spin.mat"))
    np.testing.assert_array_equal(back.i_a, test.log.i_a)
