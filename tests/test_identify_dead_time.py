"""What the inverter's dead time does to a standstill identification, and what removes it
(identify._circuit.sampled_admittance, identify._polarity, identify._impedance):

- every switching pulse moves t_d / 2 later, so the sample at the period start reads the current
  high by R_s t_d / (2 L_sigma) at DC (a first-order expansion of the model's e^{-A t_d / 2});
  the simulated DC steps show exactly that on their slope;
- the inverter's polarity is the sign of the true current; the current simulated from the
  fitted circuit has it, the noisy reading does not;
- without compensation the dead time is an extra resistance of the size its voltage's Fourier
  coefficients predict; with it, the estimate of a noise-free log is exact to a fraction of the
  noisy intervals (the bias that decides their coverage).
"""

import dataclasses

import numpy as np
import pytest

from acdrive.identify import (
    CurrentSensor,
    StandstillPlan,
    dc_test,
    fit_dc_steps,
    fit_impedance,
    identify_standstill,
    injection_test,
    inverse_gamma,
    sampled_admittance,
)
from acdrive.identify._coverage import reading
from acdrive.identify._impedance import spectrum
from acdrive.identify._polarity import simulated_polarity
from acdrive.machines import DELORENZO_IM, UGALDE_IM_300W

T_D = 2e-6
DEAD = StandstillPlan(t_d=T_D, v_drop=1.0)
QUIET = CurrentSensor(noise_std=0.0, offset=0.0, lsb=0.0)
MACHINES = pytest.mark.parametrize("machine", [DELORENZO_IM, UGALDE_IM_300W],
                                   ids=["delorenzo", "ugalde"])  # fmt: skip


def voltage_error(plan):
    """plant._inverter: phase a loses 4/3 (t_d f_pwm v_dc + v_drop) with i_b = i_c = -i_a / 2."""
    return 4.0 / 3.0 * (plan.t_d * plan.f_pwm * plan.v_dc + plan.v_drop)


@MACHINES
def test_the_dead_time_moves_the_sample_by_half_of_it_on_the_models_dc_gain(machine):
    p = inverse_gamma(machine)
    hold = DEAD.sample_time
    shifted = sampled_admittance(p, 0.0, hold, dead_time=T_D)
    plain = sampled_admittance(p, 0.0, hold)
    assert plain == pytest.approx(1.0 / p.R_s, rel=1e-12)  # DC: a resistance
    first_order = p.R_s * T_D / (2.0 * p.L_sigma)
    assert (shifted / plain).real - 1.0 == pytest.approx(first_order, rel=1e-3)


@pytest.mark.slow
@MACHINES
def test_the_dc_steps_slope_reads_the_shift_the_dead_time_predicts(machine):
    """Same voltage error U from dead time alone and from device drops alone: only the dead time
    shifts the pulses, and it lowers the DC slope by R_s t_d / (2 L_sigma)."""
    p = inverse_gamma(machine)
    by_dead_time = dataclasses.replace(DEAD, v_drop=0.0, sensor=QUIET)
    by_drop = dataclasses.replace(by_dead_time, t_d=0.0, v_drop=voltage_error(by_dead_time) * 0.75)
    assert voltage_error(by_drop) == pytest.approx(voltage_error(by_dead_time), rel=1e-12)
    slope = {}
    for name, plan in (("dead time", by_dead_time), ("drop", by_drop)):
        fit = fit_dc_steps(dc_test(machine, plan), bootstrap=0)
        assert fit.voltage_error.value == pytest.approx(voltage_error(plan), rel=1e-4)
        slope[name] = fit.R_s.value
    predicted = -p.R_s * T_D / (2.0 * p.L_sigma)  # about -1.6e-4
    assert slope["dead time"] / slope["drop"] - 1.0 == pytest.approx(predicted, rel=0.1)


@pytest.mark.slow
@MACHINES
def test_dead_time_bias_uncompensated_and_removed(machine):
    quiet = dataclasses.replace(DEAD, sensor=QUIET)
    injection, dc = injection_test(machine, quiet), dc_test(machine, quiet)
    truth = inverse_gamma(machine).as_array()
    U = voltage_error(DEAD)

    # the inverter's polarity: the circuit simulated from the logged command has the true
    # current's sign almost everywhere; a 5 mA noisy reading misses it about 30 times as often
    signs = simulated_polarity(truth, injection.v_a, DEAD.sample_time, U, T_D)
    noisy = reading(injection, DEAD.sensor, 1)
    simulated_misses = np.mean(signs != np.sign(injection.i_a))
    reading_misses = np.mean(np.sign(noisy.i_a) != np.sign(injection.i_a))
    assert simulated_misses < reading_misses / 10.0, (simulated_misses, reading_misses)

    # uncompensated: the dead-time voltage -U sign(i) is, tone by tone, an extra resistance
    # Re(U P_k / I_k) (P_k the coefficients of sign(i)); the fitted R_s lies among them
    raw = fit_impedance(injection, DEAD.base_frequency, DEAD.settle, check=False, bootstrap=0)
    spec = spectrum(injection, DEAD.base_frequency, DEAD.settle)
    extra = (U * spec.polarity / spec.current).real
    assert np.all(extra > 0.0)
    assert extra.min() < raw.params.R_s - truth[0] < extra.max()

    # compensated (DC-step U and the programmed dead time): the noise-free estimate's error is
    # below a quarter of the noisy test's half-width for every parameter (a bias that small
    # keeps a 95 % interval's coverage above 93 %)
    exact = identify_standstill(injection, DEAD.base_frequency, DEAD.settle, dc=dc,
                                n_p=machine.n_p, bootstrap=5, dead_time=T_D)  # fmt: skip
    noisy_fit = identify_standstill(noisy, DEAD.base_frequency, DEAD.settle,
                                    dc=reading(dc, DEAD.sensor, 0), n_p=machine.n_p,
                                    bootstrap=5, dead_time=T_D)  # fmt: skip
    for e, n, true in zip(exact.impedance.estimates, noisy_fit.impedance.estimates, truth,
                          strict=True):  # fmt: skip
        error = abs(e.value - true) / true
        assert error < 0.25 * n.half_width(), (e.name, error, n.half_width())
        raw_error = abs(raw.params.as_array()[list(truth).index(true)] - true) / true
        assert error < raw_error


def test_a_dead_time_needs_the_windings_state_space():
    """The sample shift is the winding's free response e^{-A t_d / 2}: every built-in winding
    (the cage IM's, a PM axis, the DFIM's rotor open or shorted) has one, a model without it is
    refused by name."""
    from acdrive.errors import InputError
    from acdrive.identify._dfim import OPEN_MODEL, SHORTED_MODEL
    from acdrive.identify._impedance import INVERSE_GAMMA_MODEL, with_dead_time
    from acdrive.identify._pm import axis_model

    assert with_dead_time(INVERSE_GAMMA_MODEL, 0.0) is INVERSE_GAMMA_MODEL
    for model in (INVERSE_GAMMA_MODEL, axis_model("d"), OPEN_MODEL, SHORTED_MODEL):
        assert with_dead_time(model, T_D).dead_time == T_D
    other = dataclasses.replace(INVERSE_GAMMA_MODEL, state_space=None)
    with pytest.raises(InputError, match="dead_time"):
        with_dead_time(other, T_D)
