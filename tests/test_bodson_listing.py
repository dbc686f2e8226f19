"""Bodson's listed core control code (end of section IV) against (39), the torque its R_S = 0
law produces on the 0.66 ohm motor, and the speed-step overshoot with K_F = 2/3 (after (27))."""

import math

import numpy as np
import pytest

from acdrive._frames import K_PEAK
from acdrive._report.bodson_listing import (
    LISTING_REL_TOL,
    corrected_listing_verdict,
    delivered_torque_verdict,
    law_39_rotor_voltage,
    listing_differences,
    listing_rotor_voltage,
    lossless_law_torque,
    lossless_law_torque_simulated,
    printed_listing_verdict,
)
from acdrive._report.speed_overshoot import (
    NO_OVERSHOOT_TOL,
    STEP_RAD_S,
    measured_overshoot,
    no_overshoot_verdict,
    step_setup,
)
from acdrive.control import SpeedPIGains
from acdrive.machines import BODSON_DFIM, machine_vector, torque_limits_case1

W_E = 2 * math.pi * 60
V_S = K_PEAK * 11.1
I_MAX = K_PEAK * 6.0


def tau_lim():
    return torque_limits_case1(machine_vector(BODSON_DFIM), W_E, V_S, I_MAX, I_MAX)[2]


@pytest.mark.parametrize("rpm", [0.0, 450.0, 1799.0, 1800.0, 2650.0])
@pytest.mark.parametrize("tau", [-0.3, -0.01, 0.0, 0.12, 0.274])
def test_corrected_listing_is_law_39(rpm, tau):
    w_m = rpm * math.pi / 30
    ref = law_39_rotor_voltage(BODSON_DFIM, W_E, w_m, V_S, tau)
    got = listing_rotor_voltage(BODSON_DFIM, W_E, w_m, V_S, tau)
    assert abs(got - ref) <= 1e-12 * abs(ref)


def test_printed_listing_differs_only_in_the_rotor_frequency():
    # the printed w_e n_P w equals the slip w_e - n_P w at w = w_e / (n_P (w_e + 1)): there the
    # printed and the corrected listing must coincide; elsewhere they must not
    n_p = BODSON_DFIM.n_p
    w_same = W_E / (n_p * (W_E + 1.0))
    a = listing_rotor_voltage(BODSON_DFIM, W_E, w_same, V_S, 0.2, as_printed=True)
    b = listing_rotor_voltage(BODSON_DFIM, W_E, w_same, V_S, 0.2)
    assert abs(a - b) <= 1e-12 * abs(b)
    w_sync = W_E / n_p
    printed = listing_rotor_voltage(BODSON_DFIM, W_E, w_sync, V_S, 0.0, as_printed=True)
    # at synchronous speed and zero torque (39) is R_R v_S / (j w_e M); the printed slip
    # w_e n_P w_sync = w_e^2 adds j w_e^2 L_R v_S / (j w_e M)
    expected = (BODSON_DFIM.R_r + 1j * W_E**2 * BODSON_DFIM.L_r) * V_S / (1j * W_E * BODSON_DFIM.M)
    assert abs(printed - expected) <= 1e-12 * abs(expected)
    worst, low, high = listing_differences(BODSON_DFIM, W_E, V_S, tau_lim())
    assert worst <= LISTING_REL_TOL
    assert high > 1000.0  # the misprint is not a rounding matter
    assert corrected_listing_verdict(worst).holds
    assert not printed_listing_verdict(low, high).holds


def test_listing_verdicts_flip_with_the_numbers():
    assert corrected_listing_verdict(1e-16).holds
    assert not corrected_listing_verdict(1e-9).holds
    assert printed_listing_verdict(1.0, 1.0).holds
    assert not printed_listing_verdict(0.9, 1.0).holds
    assert delivered_torque_verdict(0.274, 0.274).holds
    assert not delivered_torque_verdict(0.2235, 0.274).holds


def test_lossless_law_torque_on_the_066_ohm_motor():
    t3 = tau_lim()
    closed = lossless_law_torque(BODSON_DFIM, W_E, V_S, t3)
    for rpm in (0.0, 1800.0, 2700.0):  # the steady-state torque does not depend on the speed
        solved = lossless_law_torque_simulated(BODSON_DFIM, W_E, rpm * math.pi / 30, V_S, t3)
        assert solved == pytest.approx(closed, rel=1e-12)
    assert closed < t3
    # the produced torque peaks over all commands at tau_MAX,1 (30) = n_P v_S^2 / (4 w_e R_S)
    commands = np.linspace(0.0, 2.0, 200_001)
    produced = [lossless_law_torque(BODSON_DFIM, W_E, V_S, c) for c in commands]
    tau_max_1 = BODSON_DFIM.n_p * V_S**2 / (4 * W_E * BODSON_DFIM.R_s)
    assert max(produced) == pytest.approx(tau_max_1, rel=1e-9)


@pytest.mark.parametrize("k_f", [0.4, 0.5, 2 / 3, 0.67, 1.0])
def test_measured_overshoot_of_the_analytic_response(k_f):
    # continuous loop with the gains of (27): w/w_ref = 1 - e^-x (1 - c x), x = a t, c = 2 K_F - 1
    a, J = 314.0, 3.5e-4
    gains = SpeedPIGains.design(J, a, K_F=k_f)
    t = np.linspace(0.0, 0.2, 400_001)
    x = a * t
    w = 10.0 + 2.0 * (1.0 - np.exp(-x) * (1.0 - (2 * k_f - 1) * x))
    got = measured_overshoot(t, w, 0.0, 10.0, 12.0)
    assert got == pytest.approx(gains.step_overshoot(J), abs=1e-9)
    assert no_overshoot_verdict(got).holds == (gains.step_overshoot(J) <= NO_OVERSHOOT_TOL)


def test_overshoot_verdict_flips():
    assert no_overshoot_verdict(0.0).holds
    assert not no_overshoot_verdict(math.exp(-4) / 3).holds


def test_simulated_step_stays_inside_the_torque_limit():
    # the integrator is never clamped: the feedforward jump K_F K_P step is inside tau_LIM
    gains = step_setup().motors[0].controller.gains
    assert gains.K_F * gains.K_P * STEP_RAD_S < tau_lim()
