"""Physics of the DFIM model: steady state, torque law, limits, poles (Bodson (9)-(42))."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from acdrive.errors import InputError
from acdrive.machines import (
    BODSON_DFIM,
    DFIMParams,
    delta_z_coefficients,
    electrical_poles,
    electromagnetic_torque,
    machine_vector,
    rotor_current_for,
    rotor_voltage_for,
    shifted_delta_z_coefficients,
    stator_current_command,
    stator_current_per_rotor_voltage,
    steady_state_currents,
    torque_limit_case2,
    torque_limits_case1,
)

P = machine_vector(BODSON_DFIM)
W_E = 2 * math.pi * 60
V_S = math.sqrt(1.5) * 11.1
I_MAX = math.sqrt(1.5) * 6.0


@settings(max_examples=60, deadline=None)
@given(tau=st.floats(-0.3, 0.3), Q=st.floats(-20, 20), w_m=st.floats(-300, 300))
def test_open_loop_law_gives_commanded_torque_and_reactive_power(tau, Q, w_m):
    """(20) + (22): the steady state reached with the computed rotor voltage has tau_e = tau and
    Q_s = Im(v_s i_s*) = Q (power identity (5))."""
    i_s, limited = stator_current_command(P, W_E, V_S, tau, Q)
    assert not limited
    v_r = rotor_voltage_for(P, W_E, w_m, V_S, i_s)
    i_s2, i_r2 = steady_state_currents(P, W_E, w_m, V_S, v_r)
    assert abs(i_s2 - i_s) < 1e-9 * max(1.0, abs(i_s))
    assert electromagnetic_torque(P, i_s2, i_r2) == pytest.approx(tau, abs=1e-9)
    assert (V_S * np.conj(i_s2)).imag == pytest.approx(Q, abs=1e-8)
    assert rotor_current_for(P, W_E, V_S, i_s) == pytest.approx(i_r2, abs=1e-9)


@settings(max_examples=60, deadline=None)
@given(tau=st.floats(-0.3, 0.3), w_m=st.floats(-300, 300))
def test_steady_state_power_balance(tau, w_m):
    """Stator + rotor electrical power = copper losses + mechanical power tau_e * w_m."""
    i_s, _ = stator_current_command(P, W_E, V_S, tau, 0.0)
    v_r = rotor_voltage_for(P, W_E, w_m, V_S, i_s)
    i_s, i_r = steady_state_currents(P, W_E, w_m, V_S, v_r)
    p_in = (V_S * np.conj(i_s)).real + (v_r * np.conj(i_r)).real
    losses = BODSON_DFIM.R_s * abs(i_s) ** 2 + BODSON_DFIM.R_r * abs(i_r) ** 2
    assert p_in == pytest.approx(
        losses + electromagnetic_torque(P, i_s, i_r) * w_m, rel=1e-9, abs=1e-9
    )


def test_torque_limits_match_paper_example():
    """Bodson III-D example: 0.371, 0.341, 0.274 N m (printed to 3 digits)."""
    t1, t2, t3, _, _, feasible = torque_limits_case1(P, W_E, V_S, I_MAX, I_MAX)
    assert feasible
    assert (round(t1, 3), round(t2, 3), round(t3, 3)) == (0.371, 0.341, 0.274)
    assert V_S == pytest.approx(13.6, abs=0.01) and I_MAX == pytest.approx(7.35, abs=0.01)


@pytest.mark.parametrize("v_pk, f", [(11.1, 60.0), (8.0, 45.0), (14.0, 70.0)])
def test_limits_are_where_the_constraints_bind(v_pk, f):
    """At each case-1 limit the corresponding constraint holds with equality."""
    w_e, v_s = 2 * math.pi * f, math.sqrt(1.5) * v_pk
    t1, t2, t3, m2, m3, _ = torque_limits_case1(P, w_e, v_s, I_MAX, I_MAX)
    i_s1, limited = stator_current_command(P, w_e, v_s, t1 * (1 - 1e-12), 0.0)
    assert i_s1.real == pytest.approx(
        v_s / (2 * BODSON_DFIM.R_s), rel=1e-4
    )  # radicand of (24) -> 0
    for tau, bound in ((t2, "s"), (m2, "s"), (t3, "r"), (m3, "r")):
        if bound == "r" and abs(tau) >= t1:
            continue
        i_s, _ = stator_current_command(P, w_e, v_s, tau, 0.0)
        current = abs(i_s) if bound == "s" else abs(rotor_current_for(P, w_e, v_s, i_s))
        assert current == pytest.approx(I_MAX, rel=1e-9)
    _, limited = stator_current_command(P, w_e, v_s, 1.01 * t1, 0.0)
    assert limited


def test_case2_limits_satisfy_constraints_40_42():
    machine = DFIMParams(R_s=1e-9, R_r=0.94, L_s=13.1e-3, L_r=9.8e-3, M=9.7e-3, n_p=2, J=3.5e-4)
    p = machine_vector(machine)
    for Q in (-5.0, 0.0, 5.0, V_S**2 / (W_E * machine.L_s)):
        t2, t3 = torque_limit_case2(p, W_E, V_S, Q, I_MAX, I_MAX)
        for tau, bound in ((t2, "s"), (t3, "r")):
            i_s = W_E * tau / (V_S * 2) - 1j * Q / V_S  # (38)
            current = abs(i_s) if bound == "s" else abs(rotor_current_for(p, W_E, V_S, i_s))
            assert current == pytest.approx(I_MAX, rel=1e-6)
    # the rotor-limited torque is largest at Q = v_s^2 / (w_e L_s)
    best = V_S**2 / (W_E * machine.L_s)
    assert (
        torque_limit_case2(p, W_E, V_S, best, I_MAX, I_MAX)[1]
        >= torque_limit_case2(p, W_E, V_S, 0.0, I_MAX, I_MAX)[1]
    )


@settings(max_examples=50, deadline=None)
@given(w_m=st.floats(-1000, 1000), w_e=st.floats(1.0, 800.0))
def test_electrical_poles_stable_and_shift_identity(w_m, w_e):
    """Bodson's fact: the roots of Delta Z are in the open LHP at every speed, and they are the
    roots of Delta Z(s - j w_e) (15)-(16) shifted by j w_e."""
    poles = electrical_poles(BODSON_DFIM, w_e, w_m)
    assert np.all(poles.real < 0)
    shifted = np.roots(shifted_delta_z_coefficients(BODSON_DFIM, w_m)) - 1j * w_e
    assert np.allclose(np.sort_complex(poles), np.sort_complex(shifted), rtol=1e-7, atol=1e-6)


def test_transfer_function_14_matches_matrix_inverse():
    for s in (0.0, 10j, -3 + 400j, 50.0):
        Z_S, Z_MS = BODSON_DFIM.R_s + 1j * W_E * BODSON_DFIM.L_s, 1j * W_E * BODSON_DFIM.M
        w_slip = W_E - 2 * 100.0
        Z_R, Z_MR = BODSON_DFIM.R_r + 1j * w_slip * BODSON_DFIM.L_r, 1j * w_slip * BODSON_DFIM.M
        m = BODSON_DFIM.M
        A = np.array(
            [[s * BODSON_DFIM.L_s + Z_S, s * m + Z_MS], [s * m + Z_MR, s * BODSON_DFIM.L_r + Z_R]]
        )
        expected = np.linalg.solve(A, np.array([0.0, 1.0]))[0]
        assert stator_current_per_rotor_voltage(BODSON_DFIM, W_E, 100.0, s) == pytest.approx(
            expected
        )
        assert np.polyval(delta_z_coefficients(BODSON_DFIM, W_E, 100.0), s) == pytest.approx(
            np.linalg.det(A)
        )


@pytest.mark.parametrize(
    "field, value", [("R_s", -1.0), ("L_r", 0.0), ("J", float("nan")), ("n_p", 2.5)]
)
def test_invalid_parameters_name_the_field(field, value):
    kwargs = {
        "R_s": 0.66,
        "R_r": 0.94,
        "L_s": 13.1e-3,
        "L_r": 9.8e-3,
        "M": 9.7e-3,
        "n_p": 2,
        "J": 3.5e-4,
    }
    kwargs[field] = value
    with pytest.raises(InputError, match=field):
        DFIMParams(**kwargs)


def test_sigma_must_be_positive():
    with pytest.raises(InputError, match="sigma"):
        DFIMParams(R_s=1, R_r=1, L_s=1e-2, L_r=1e-2, M=1e-2, n_p=1, J=1)


def test_the_divisions_by_j_w_e_m_and_by_v_s_give_the_complex_division_s_numbers():
    """rotor_voltage_for, rotor_current_for and the stator current commands divide by the
    imaginary Z_MS and by the real v_s written out (no branch, no raise path): the numbers of the
    complex division (CPython's algorithm, which numba's and the C mirror's follow), the signs of
    zeros aside. The reference is Python's own division: numba compiles its complex division
    once per process and may reuse a fast-math build of it in a strict caller."""
    from numba import njit

    from acdrive.machines._dfim import _minus_j_over, _over_j

    @njit(error_model="numpy")
    def written_out(z, x, Q, v_s, i_d):
        return _over_j(z, x), _minus_j_over(i_d, Q, v_s)

    rng = np.random.default_rng(4)
    for _ in range(2_000):
        z = complex(*rng.normal(size=2) * 10.0 ** rng.uniform(-3, 3, size=2))
        x, Q, v_s, i_d = (float(v) for v in rng.normal(size=4) * 10.0 ** rng.uniform(-3, 3, size=4))
        by_division = z / complex(0.0, x), i_d - 1j * Q / v_s
        for a, b in zip(by_division, written_out(z, x, Q, v_s, i_d), strict=True):
            assert a == b
