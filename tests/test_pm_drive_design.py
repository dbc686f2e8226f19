"""Design formulas of the PM drive (``drives/pm/_design.py``) against their definitions.

* MTPA: the closed form equals the textbook root (psi_f - sqrt(psi_f^2 + 8 dL^2 i^2)) / (4 dL)
  and the current angle that maximises the torque of the formula at fixed |i| (found by a
  bounded scalar optimiser, independent of the closed form);
* the torque inverse gives back the torque; the power-invariant torque is the amplitude-invariant
  (3/2) n_p (...) of peak-scaled quantities;
* field weakening: the point lies on the voltage ellipse and inside the current circle, gives
  the torque asked, and no point of the ellipse gives that torque with less current (dense scan);
  the available torque is the largest torque of the feasible region (dense grid);
* current PI: the internal-model gains make the open loop alpha / s (frequency response).
"""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.optimize import minimize_scalar

from acdrive.drives.pm import _design as d
from acdrive.errors import InputError

#: random but physically valid salient machines: L_d, saliency L_q / L_d in [1, 4], psi_f, n_p
machines = st.tuples(
    st.floats(1e-4, 1e-2),  # L_d [H]
    st.floats(1.0, 4.0),  # L_q / L_d
    st.floats(0.01, 1.0),  # psi_f [Wb]
    st.integers(1, 8),  # n_p
)


def _torque_at_angle(n_p, psi_f, L_d, L_q, i_s, beta):
    return d.torque(n_p, psi_f, L_d, L_q, -i_s * np.sin(beta), i_s * np.cos(beta))


@given(machines, st.floats(0.05, 20.0))
def test_mtpa_angle_maximises_torque_per_ampere(machine, i_over_characteristic):
    L_d, ratio, psi_f, n_p = machine
    L_q = ratio * L_d
    i_s = i_over_characteristic * psi_f / L_q  # from far below to far above psi_f / L_q
    best = minimize_scalar(lambda b: -_torque_at_angle(n_p, psi_f, L_d, L_q, i_s, b),
                           bounds=(0.0, math.pi / 2), method="bounded",
                           options={"xatol": 1e-12})  # fmt: skip
    beta = d.mtpa_angle(psi_f, L_d, L_q, i_s)
    assert beta == pytest.approx(best.x, abs=1e-6)
    # the optimum's torque is not beaten by any angle of a fine grid
    grid = np.linspace(0.0, math.pi / 2, 20001)
    t_grid = _torque_at_angle(n_p, psi_f, L_d, L_q, i_s, grid)
    assert _torque_at_angle(n_p, psi_f, L_d, L_q, i_s, beta) >= np.max(t_grid) * (1 - 1e-12)


@given(machines, st.floats(0.05, 20.0))
def test_mtpa_closed_form_is_the_textbook_root(machine, scale):
    L_d, ratio, psi_f, _ = machine
    L_q = ratio * L_d
    if L_q - L_d < 1e-6 * L_d:
        return  # the textbook form is 0/0 for a round rotor
    i_s = scale * psi_f / L_q
    dL = L_q - L_d
    textbook = (psi_f - math.sqrt(psi_f**2 + 8 * dL**2 * i_s**2)) / (4 * dL)
    assert d.mtpa_d_current(psi_f, L_d, L_q, i_s) == pytest.approx(textbook, rel=1e-9)


def test_surface_machine_has_zero_d_current():
    assert d.mtpa_point(0.1, 2e-3, 2e-3, 7.0) == (0.0, 7.0)


@given(machines, st.floats(0.0, 1.0))
def test_torque_inverse_gives_the_torque_back(machine, fraction):
    L_d, ratio, psi_f, n_p = machine
    L_q, i_max = ratio * L_d, 3.0 * psi_f / L_d
    tau_max = d.mtpa_torque(n_p, psi_f, L_d, L_q, i_max)
    tau = fraction * tau_max
    i_s = d.mtpa_current(n_p, psi_f, L_d, L_q, tau, i_max)
    # the bisection resolves the current to 2^-60 i_max: the torque to ~1e-15 of tau_max
    assert d.mtpa_torque(n_p, psi_f, L_d, L_q, i_s) == pytest.approx(tau, abs=1e-12 * tau_max)


def test_power_invariant_torque_is_the_amplitude_invariant_textbook_form():
    n_p, psi_m, L_d, L_q = 4, 0.08, 1e-3, 3e-3
    i_d_pk, i_q_pk = -12.0, 30.0  # peak-scaled (amplitude-invariant) dq currents
    textbook = 1.5 * n_p * (psi_m * i_q_pk + (L_d - L_q) * i_d_pk * i_q_pk)
    k = math.sqrt(1.5)
    ours = d.torque(n_p, d.magnet_flux(psi_m), L_d, L_q, k * i_d_pk, k * i_q_pk)
    assert ours == pytest.approx(textbook, rel=1e-14)


@given(machines, st.floats(0.2, 0.95), st.floats(0.05, 0.99))
def test_field_weakening_point_is_the_least_current_on_the_voltage_limit(machine, flux, fraction):
    L_d, ratio, psi_f, n_p = machine
    L_q = ratio * L_d
    i_max = 1.5 * psi_f / L_d  # enough current to weaken the whole magnet flux
    psi_max = flux * psi_f
    tau_avail = d.available_torque(n_p, psi_f, L_d, L_q, i_max, psi_max)
    tau = fraction * tau_avail
    i_d, i_q, flags = d.operating_point(n_p, psi_f, L_d, L_q, tau, i_max, psi_max)
    assert flags & d.VOLTAGE_LIMITED and not flags & d.BEYOND_REACH
    assert d.flux_magnitude(psi_f, L_d, L_q, i_d, i_q) == pytest.approx(psi_max, rel=1e-9)
    assert math.hypot(i_d, i_q) <= i_max * (1 + 1e-12)
    assert i_d < 0.0
    assert d.torque(n_p, psi_f, L_d, L_q, i_d, i_q) == pytest.approx(tau, rel=1e-9)
    # every point of the ellipse with at least this torque takes at least this current
    phi = np.linspace(0.0, math.pi, 200001)
    a = (psi_max * np.cos(phi) - psi_f) / L_d
    b = psi_max * np.sin(phi) / L_q
    enough = d.torque(n_p, psi_f, L_d, L_q, a, b) >= tau
    assert np.min(np.hypot(a, b)[enough]) >= math.hypot(i_d, i_q) * (1 - 1e-6)


@given(machines, st.floats(0.3, 3.0), st.floats(0.2, 2.0))
def test_available_torque_is_the_largest_feasible_torque(machine, current, flux):
    L_d, ratio, psi_f, n_p = machine
    L_q = ratio * L_d
    i_max, psi_max = current * psi_f / L_q, flux * psi_f
    found = d.available_torque(n_p, psi_f, L_d, L_q, i_max, psi_max)
    i_d, i_q = np.meshgrid(np.linspace(-i_max, i_max, 1201), np.linspace(0, i_max, 601))
    ok = (np.hypot(i_d, i_q) <= i_max) & (d.flux_magnitude(psi_f, L_d, L_q, i_d, i_q) <= psi_max)
    if not ok.any():
        assert found == 0.0
        return
    best = np.max(np.where(ok, d.torque(n_p, psi_f, L_d, L_q, i_d, i_q), -np.inf))
    assert found >= best * (1 - 1e-9)  # nothing on the grid beats it
    # and it is feasible: its point lies in both regions (within the bisection's resolution)
    i_d, i_q, _flags = d.operating_point(n_p, psi_f, L_d, L_q, np.inf, i_max, psi_max)
    assert math.hypot(i_d, i_q) <= i_max * (1 + 1e-9)
    assert d.flux_magnitude(psi_f, L_d, L_q, i_d, i_q) <= psi_max * (1 + 1e-9)


def test_below_base_speed_the_reference_is_the_mtpa_point():
    n_p, psi_f, L_d, L_q = 4, 0.1, 1e-3, 2.5e-3
    i_d, i_q, flags = d.operating_point(n_p, psi_f, L_d, L_q, -2.0, 50.0, np.inf)
    i_s = d.mtpa_current(n_p, psi_f, L_d, L_q, 2.0, 50.0)
    assert flags == 0
    assert (i_d, -i_q) == pytest.approx(d.mtpa_point(psi_f, L_d, L_q, i_s), rel=1e-15)


def test_current_pi_design_gives_a_first_order_loop():
    R, L, alpha = 0.3, 2e-3, 2000.0
    g = d.CurrentPIGains.design(R, L, 3 * L, alpha)
    for K_P, K_I, L_axis in ((g.K_P_d, g.K_I_d, L), (g.K_P_q, g.K_I_q, 3 * L)):
        s = 1j * np.logspace(0, 6, 50)
        loop = (K_P + K_I / s) / (L_axis * s + R)
        assert np.allclose(loop, alpha / s, rtol=1e-12)
    with pytest.raises(InputError, match="current_bandwidth"):
        d.CurrentPIGains.design(R, L, L, 0.0)


def test_flux_limit_bounds_the_steady_state_voltage():
    """|v| = |R i + j w_e psi| <= R i_max + |w_e| psi_max = margin v_max, checked on points."""
    R, v_max, margin, i_max, w_e = 0.2, 300.0, 0.9, 40.0, 3000.0
    psi_max = d.flux_limit(R, v_max, margin, i_max, w_e)
    rng = np.random.default_rng(1)
    for _ in range(100):
        i = i_max * rng.random() * np.exp(2j * np.pi * rng.random())
        psi = psi_max * rng.random() * np.exp(2j * np.pi * rng.random())
        assert abs(R * i + 1j * w_e * psi) <= margin * v_max * (1 + 1e-12)
    assert d.flux_limit(R, v_max, margin, i_max, 0.0) == np.inf


@given(machines, st.floats(0.3, 3.0), st.floats(0.05, 0.5))
def test_base_speed_solves_the_steady_state_voltage_equation(machine, current, drop):
    """``base_speed``: the steady-state voltage R_s i + j w_e psi_dq of the MTPA point of full
    current has magnitude margin v_max at w_e = n_p base_speed, and less at any lower speed;
    ``voltage_bound_speed`` (the drive's bound R_s |i| + |w_e| |psi| of (V)) lies below it."""
    L_d, ratio, psi_f, n_p = machine
    L_q = ratio * L_d
    i_max = current * psi_f / L_q
    v_max, margin = 400.0, 0.9
    R_s = drop * margin * v_max / i_max  # the resistive drop: 5 ... 50 % of the limit
    w_b = d.base_speed(R_s, L_d, L_q, psi_f, n_p, i_max, v_max, margin)
    i_d, i_q = d.mtpa_point(psi_f, L_d, L_q, i_max)
    psi_dq = complex(L_d * i_d + psi_f, L_q * i_q)

    def voltage(w_mech):
        return abs(R_s * complex(i_d, i_q) + 1j * n_p * w_mech * psi_dq)

    assert voltage(w_b) == pytest.approx(margin * v_max, rel=1e-12)
    speeds = np.linspace(0.0, w_b, 1001)
    assert max(voltage(w) for w in speeds[:-1]) < margin * v_max
    bound = d.voltage_bound_speed(R_s, L_d, L_q, psi_f, n_p, i_max, v_max, margin)
    assert R_s * i_max + n_p * bound * abs(psi_dq) == pytest.approx(margin * v_max, rel=1e-12)
    assert bound <= w_b * (1 + 1e-12)


def test_base_speed_refuses_a_resistive_drop_beyond_the_limit():
    with pytest.raises(InputError, match="i_max"):
        d.base_speed(10.0, 1e-3, 2e-3, 0.1, 4, 40.0, 400.0, 0.9)
