"""The standstill estimators on logs made without the simulator: the exact sampled response of the
standstill circuit (its own ZOH discretisation by scipy, written here) plus seeded white noise.
The fits must recover the circuit within their 95 % intervals, the intervals must cover it over
repetitions, and an excitation or a log that cannot identify a parameter must be refused naming it."""

import math

import numpy as np
import pytest
from scipy.linalg import expm

from acdrive.errors import InputError
from acdrive.identify import (
    StandstillLog,
    fit_dc_steps,
    fit_impedance,
    inverse_gamma,
    standstill_impedance,
)
from acdrive.machines import DELORENZO_IM, UGALDE_IM_300W

HOLD = 2e-4  # a 5 kHz carrier, one sample per period
NOISE = 5e-3  # A


def sampled_response(machine, v):
    """i_k of the locked-rotor a-axis circuit for the held voltages v_k (ZOH, exact), written from
    the T-circuit: states (i_s, psi_r), sigma L_s di/dt = v - (R_s + L_m^2 R_r/L_r^2) i +
    (L_m R_r / L_r^2) psi_r, dpsi_r/dt = (L_m R_r / L_r) i - (R_r / L_r) psi_r."""
    m = machine
    sLs = m.L_s - m.L_m**2 / m.L_r
    A = np.array([[-(m.R_s + m.L_m**2 * m.R_r / m.L_r**2) / sLs, m.L_m * m.R_r / (m.L_r**2 * sLs)],
                  [m.L_m * m.R_r / m.L_r, -m.R_r / m.L_r]])  # fmt: skip
    M = np.zeros((3, 3))
    M[:2, :2], M[0, 2] = A * HOLD, HOLD / sLs
    E = expm(M)
    Phi, Gamma = E[:2, :2], E[:2, 2]
    x = np.zeros(2)
    i = np.empty(v.size)
    for k, vk in enumerate(v):
        i[k] = x[0]
        x = Phi @ x + Gamma * vk
    return i


def multisine(t, tones, f0=1.0, amplitude=15.0):
    K = len(tones)
    return sum(amplitude * np.cos(2 * math.pi * k * f0 * t - math.pi * j * (j - 1) / K)
               for j, k in enumerate(tones, start=1))  # fmt: skip


def injection_log(machine, seed, tones=(1, 2, 3, 5, 8, 13, 20, 40, 80, 160), f0=1.0,
                  duration=4.0, noise=NOISE):  # fmt: skip
    t = np.arange(round(duration / HOLD)) * HOLD
    v = multisine(t, tones, f0)
    i = sampled_response(machine, v)
    rng = np.random.default_rng(seed)
    return StandstillLog(t, v, i + noise * rng.standard_normal(t.size), "synthetic")


@pytest.mark.parametrize("machine", [DELORENZO_IM, UGALDE_IM_300W])
def test_the_impedance_fit_recovers_the_circuit_within_its_intervals(machine):
    truth = inverse_gamma(machine)
    fit = fit_impedance(injection_log(machine, seed=11), 1.0, 2.0)
    for estimate, true in zip(fit.estimates, truth.as_array(), strict=True):
        assert estimate.covers(true), (estimate, true)
        assert estimate.covers(true, "bootstrap"), (estimate, true)
        assert estimate.half_width() < 0.01  # a well-designed test: intervals within 1 %
    # the fitted model at the tones against the analytic Z(jw) of the true parameters
    w = 2 * math.pi * fit.spectrum.frequency
    np.testing.assert_allclose(fit.fitted_impedance(), standstill_impedance(truth, w), rtol=2e-3)
    # the residual is the noise: white noise of std s over n samples gives Fourier coefficients
    # (2/n) sum whose real and imaginary parts have std s sqrt(2/n); the fit takes 4 of the 2K
    n = fit.spectrum.periods / (1.0 * HOLD)
    m = 2 * fit.spectrum.frequency.size
    expected = NOISE * math.sqrt(2.0 / n) * math.sqrt((m - 4) / m)
    assert 0.6 < fit.residual_rms / expected < 1.5


def test_the_95_percent_intervals_cover_the_truth_over_repetitions():
    truth = inverse_gamma(DELORENZO_IM).as_array()
    covered = [fit_impedance(injection_log(DELORENZO_IM, seed=s), 1.0, 2.0, bootstrap=50)
               .estimates for s in range(5)]  # fmt: skip
    hits = sum(e.covers(t) for row in covered for e, t in zip(row, truth, strict=True))
    # 20 intervals of level 0.95: fewer than 17 hits has probability 1.6 % if they are right
    assert hits >= 17, hits


def test_all_tones_far_below_the_rotor_corner_cannot_separate_the_rotor_resistance():
    # the corner R_r / (2 pi L_r) is 2.5 Hz; tones of 0.05 to 0.25 Hz stay a decade below it
    log = injection_log(DELORENZO_IM, seed=3, tones=(1, 2, 3, 5), f0=0.05, duration=40.0)
    with pytest.raises(InputError, match=r"^(R_R|L_sigma|L_M): not (separable|identified)"):
        fit_impedance(log, 0.05, 20.0)


def test_too_few_tones_too_short_and_too_coarse_logs_are_refused():
    log = injection_log(DELORENZO_IM, seed=1, tones=(1, 2))
    with pytest.raises(InputError, match=r"column 'v_a': the injected voltage must excite at "
                       r"least 3 tones"):  # fmt: skip
        fit_impedance(log, 1.0, 2.0)
    short = injection_log(DELORENZO_IM, seed=1, duration=2.5)
    with pytest.raises(InputError, match=r"column 'time': too short"):
        fit_impedance(short, 1.0, 2.0)
    with pytest.raises(InputError, match=r"^base_frequency: a period 1 / 0.3 Hz must be a whole"):
        fit_impedance(injection_log(DELORENZO_IM, seed=1), 0.3, 2.0)
    coarse = injection_log(DELORENZO_IM, seed=1, tones=(1, 2, 3, 600))
    with pytest.raises(InputError, match=r"column 'time': sampling at 5000 Hz is too coarse for "
                       r"the tone at 600 Hz"):  # fmt: skip
        fit_impedance(coarse, 1.0, 2.0)


def test_the_dc_steps_give_the_resistance_and_the_voltage_error():
    """V_k = R_s I_k + U: a log of three settled plateaus with an offset U in the applied voltage."""
    R_s, U = DELORENZO_IM.R_s, 5.0
    levels = (12.0, 24.0, 36.0)
    t = np.arange(3 * 10000) * HOLD
    v = np.repeat(levels, 10000)
    i = sampled_response(DELORENZO_IM, v - U)
    rng = np.random.default_rng(5)
    fit = fit_dc_steps(StandstillLog(t, v, i + NOISE * rng.standard_normal(t.size), "dc"))
    assert fit.R_s.covers(R_s) and fit.R_s.covers(R_s, "bootstrap")
    assert fit.voltage_error.covers(U) and fit.voltage_error.covers(U, "bootstrap")
    # one level alone: V / I = R_s + U / I, biased by U / I = U R_s / (36 V - U)
    single = fit.single_level
    assert single.covers(R_s + U * R_s / (levels[-1] - U))
    assert not single.covers(R_s)


def test_a_dc_level_that_has_not_settled_or_a_single_level_is_refused():
    t = np.arange(3 * 1000) * HOLD  # 0.2 s per level: the slow pole (about 0.15 s) still acts
    v = np.repeat((12.0, 24.0, 36.0), 1000)
    i = sampled_response(DELORENZO_IM, v)
    with pytest.raises(InputError, match=r"column 'i_a': the current of the level 12 V has not "
                       r"settled"):  # fmt: skip
        fit_dc_steps(StandstillLog(t, v, i, "dc"))
    t = np.arange(10000) * HOLD
    v = np.full(t.size, 12.0)
    with pytest.raises(InputError, match=r"needs at least two different nonzero levels"):
        fit_dc_steps(StandstillLog(t, v, sampled_response(DELORENZO_IM, v), "dc"))


def test_a_current_that_is_absent_or_reversed_is_refused_before_the_fit():
    log = injection_log(DELORENZO_IM, seed=2)
    reversed_sign = StandstillLog(log.time, log.v_a, -log.i_a, "log")
    with pytest.raises(InputError, match=r"^log: column 'i_a': the winding would deliver power"):
        fit_impedance(reversed_sign, 1.0, 2.0)
    nothing = StandstillLog(log.time, log.v_a, np.zeros(log.time.size), "log")
    with pytest.raises(InputError, match=r"^log: column 'i_a': carries no current"):
        fit_impedance(nothing, 1.0, 2.0)


def test_a_test_plan_with_a_bad_field_is_refused_naming_it():
    from acdrive.identify import StandstillPlan

    with pytest.raises(InputError, match=r"^tones\[1\]: must be an integer >= 1, got 2.5"):
        StandstillPlan(tones=(1, 2.5))
    with pytest.raises(InputError, match=r"^dc_step: must be > 0"):
        StandstillPlan(dc_step=0.0)
    with pytest.raises(InputError, match=r"^periods: must be an integer >= 1"):
        StandstillPlan(periods=0)
