"""Bodson (1)-(8): three-phase <-> complex transforms, power identity, phasors."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from acdrive import _frames as frames
from acdrive.errors import InputError

angle = st.floats(-20.0, 20.0, allow_nan=False)
amplitude = st.floats(0.0, 1e3, allow_nan=False)
value = st.floats(-1e3, 1e3, allow_nan=False)
TWO_PI_3 = 2.0 * math.pi / 3.0


def close(x, y, scale=1.0):
    return np.allclose(x, y, rtol=1e-12, atol=1e-12 * (1.0 + scale))


def reactive_power_abc(v, i):
    """Instantaneous reactive power from phase quantities, the definition that (5) implies.

    Im{(2/3) sum_k sum_l alpha^(k-l) v_k i_l} = (2/3)(sqrt3/2) sum_k v_k (i_(k-1) - i_(k+1))
    which regrouped by current is (1/sqrt3)[(v_b - v_c) i_a + (v_c - v_a) i_b + (v_a - v_b) i_c].
    """
    (va, vb, vc), (ia, ib, ic) = v, i
    return ((vb - vc) * ia + (vc - va) * ib + (va - vb) * ic) / math.sqrt(3.0)


@settings(max_examples=200, deadline=None)
@given(value, value, angle)
def test_abc_complex_abc_round_trip_zero_sum(a, b, theta_e):
    c = -a - b
    x = frames.abc_to_complex(a, b, c, theta_e)
    back = frames.complex_to_abc(x, theta_e)
    assert close(back, (a, b, c), scale=abs(a) + abs(b))


@settings(max_examples=200, deadline=None)
@given(value, value, angle)
def test_complex_abc_complex_round_trip(re, im, theta_e):
    x = complex(re, im)
    a, b, c = frames.complex_to_abc(x, theta_e)
    assert abs(a + b + c) <= 1e-12 * (1.0 + abs(x))
    assert close(frames.abc_to_complex(a, b, c, theta_e), x, scale=abs(x))


def test_zero_sequence_is_dropped():
    x0 = frames.abc_to_complex(1.0, 2.0, -0.5, 0.7)
    assert abs(frames.abc_to_complex(1.0 + 3.0, 2.0 + 3.0, -0.5 + 3.0, 0.7) - x0) < 1e-12


@settings(max_examples=200, deadline=None)
@given(value, value, angle, angle, st.integers(1, 6))
def test_rotor_round_trip_and_angle(x_ph, y_ph, theta_e, theta, n_p):
    z_ph = -x_ph - y_ph
    v_r = frames.rotor_abc_to_complex(x_ph, y_ph, z_ph, theta_e, theta, n_p)
    back = frames.complex_to_rotor_abc(v_r, theta_e, theta, n_p)
    assert close(back, (x_ph, y_ph, z_ph), scale=abs(x_ph) + abs(y_ph))
    # (3) is (1) seen from the rotor: stationary rotor-frame vector turned by n_p theta.
    in_rotor = frames.abc_to_complex(x_ph, y_ph, z_ph, 0.0)
    expected = frames.rotate(in_rotor, n_p * theta - theta_e)
    assert close(v_r, expected, scale=abs(x_ph) + abs(y_ph))


def test_rotor_of_balanced_slip_set_is_constant():
    """Rotor currents at slip frequency w_e - n_p w, rotor at angle w t: constant in the
    synchronous frame (the n_p theta term refers them to the stator)."""
    w_e, w, n_p, peak, phase = 2 * math.pi * 60, 150.0, 2, 4.0, 0.3
    t = np.linspace(0.0, 0.05, 101)
    th_slip = (w_e - n_p * w) * t
    xyz = [peak * np.cos(th_slip + phase - k * TWO_PI_3) for k in range(3)]
    v_r = frames.rotor_abc_to_complex(*xyz, w_e * t, w * t, n_p)
    assert np.allclose(v_r, frames.complex_from_peak(peak, phase), atol=1e-12)


def test_arrays_broadcast_and_numba_versions_agree():
    rng = np.random.default_rng(0)
    a, b, th = rng.normal(size=(3, 50))
    c = -a - b
    x = frames.abc_to_complex(a, b, c, th)
    assert x.shape == (50,)
    for k in range(50):
        assert abs(frames.abc_to_complex_nb(a[k], b[k], c[k], th[k]) - x[k]) < 1e-12
        abc = frames.complex_to_abc_nb(x[k], th[k])
        assert np.allclose(abc, (a[k], b[k], c[k]), atol=1e-12)
        xr = frames.rotor_abc_to_complex_nb(a[k], b[k], c[k], th[k], 0.3, 2)
        assert abs(xr - frames.rotor_abc_to_complex(a[k], b[k], c[k], th[k], 0.3, 2)) < 1e-12
        assert np.allclose(frames.complex_to_rotor_abc_nb(xr, th[k], 0.3, 2), abc, atol=1e-12)
    # broadcasting of one angle over many samples
    assert np.allclose(frames.abc_to_complex(a, b, c, 0.4), frames.rotate(x, th - 0.4))


def test_stationary_frame_alpha_beta():
    # theta_e = 0: phase a alone gives a real vector sqrt(2/3) a; b - c gives the imaginary axis
    assert abs(frames.abc_to_complex(1.0, 0.0, 0.0) - math.sqrt(2 / 3)) < 1e-15
    assert abs(frames.abc_to_complex(0.0, 1.0, -1.0) - 1j * math.sqrt(2)) < 1e-15


three_phase = st.tuples(value, value, value, value, angle)


@settings(max_examples=300, deadline=None)
@given(three_phase, angle)
def test_power_identity_unbalanced(sets, theta_e):
    """(5) for arbitrary zero-sum (unbalanced, non-sinusoidal) voltages and currents."""
    va, vb, ia, ib, _ = sets
    v = (va, vb, -va - vb)
    i = (ia, ib, -ia - ib)
    s = frames.complex_power(frames.abc_to_complex(*v, theta_e), frames.abc_to_complex(*i, theta_e))
    p = sum(vk * ik for vk, ik in zip(v, i))
    q = reactive_power_abc(v, i)
    scale = sum(abs(x) for x in v) * sum(abs(x) for x in i)
    assert abs(s.real - p) <= 1e-11 * (1.0 + scale)
    assert abs(s.imag - q) <= 1e-11 * (1.0 + scale)


@settings(max_examples=200, deadline=None)
@given(amplitude, amplitude, angle, st.floats(-math.pi, math.pi), angle)
def test_power_and_phasor_balanced_steady_state(v_pk, i_pk, theta_e, phi, frame_shift):
    """(6) -> (7) and (8); the power does not depend on the frame angle."""
    th = theta_e
    v = [v_pk * math.cos(th - k * TWO_PI_3) for k in range(3)]
    i = [i_pk * math.cos(th - phi - k * TWO_PI_3) for k in range(3)]
    v_s = frames.abc_to_complex(*v, th)
    i_s = frames.abc_to_complex(*i, th)
    assert close(v_s, frames.complex_from_peak(v_pk), scale=v_pk)  # (8)
    assert close(i_s, math.sqrt(1.5) * i_pk * np.exp(-1j * phi), scale=i_pk)  # (8)
    assert close(frames.complex_from_peak(i_pk, -phi), i_s, scale=i_pk)
    assert close(frames.peak_from_complex(v_s), v_pk, scale=v_pk)
    assert close(frames.peak_from_complex(i_s), i_pk, scale=i_pk)
    s7 = 1.5 * v_pk * i_pk * np.exp(1j * phi)  # (7)
    assert close(frames.complex_power(v_s, i_s), s7, scale=v_pk * i_pk)
    p = sum(vk * ik for vk, ik in zip(v, i))
    assert close(p, s7.real, scale=v_pk * i_pk)
    assert close(reactive_power_abc(v, i), s7.imag, scale=v_pk * i_pk)
    # another frame angle: vectors turn, power does not
    other = th + frame_shift
    s_other = frames.complex_power(
        frames.abc_to_complex(*v, other), frames.abc_to_complex(*i, other)
    )
    assert close(s_other, s7, scale=v_pk * i_pk)


def test_lagging_current_absorbs_positive_reactive_power():
    t = np.linspace(0.0, 1 / 60, 50)
    th = 2 * math.pi * 60 * t
    v = [10 * np.cos(th - k * TWO_PI_3) for k in range(3)]
    i = [2 * np.cos(th - 0.5 - k * TWO_PI_3) for k in range(3)]  # lags by 0.5 rad
    q = reactive_power_abc(v, i)
    assert np.all(q > 0)
    s = frames.complex_power(frames.abc_to_complex(*v), frames.abc_to_complex(*i))
    assert np.allclose(s.imag, q) and np.allclose(s.real, 1.5 * 10 * 2 * math.cos(0.5))


def test_rotate():
    assert abs(frames.rotate(1.0, math.pi / 2) - 1j) < 1e-15
    x = np.array([1 + 2j, -3j])
    assert np.allclose(frames.rotate(frames.rotate(x, 0.7), -0.7), x)


def test_bodson_example_supply_and_current_limit():
    """Bodson III-D: 11.1 V peak gives v_S = 13.6 V; 6 A peak gives 7.35 A, by (8)."""
    assert round(abs(frames.complex_from_peak(11.1)), 1) == 13.6
    assert round(abs(frames.complex_from_peak(6.0)), 2) == 7.35


@pytest.mark.parametrize(
    "call",
    [
        lambda: frames.abc_to_complex(float("nan"), 0.0, 0.0),
        lambda: frames.abc_to_complex(1.0, 0.0, 0.0, float("inf")),
        lambda: frames.abc_to_complex(1j, 0.0, 0.0),
        lambda: frames.complex_to_abc(complex("nan+1j")),
        lambda: frames.rotor_abc_to_complex(1.0, 0.0, -1.0, 0.0, 0.0, 1.5),
        lambda: frames.rotor_abc_to_complex(1.0, 0.0, -1.0, 0.0, 0.0, 0),
        lambda: frames.complex_to_rotor_abc(1.0, 0.0, 0.0, True),
        lambda: frames.peak_from_complex("a"),
    ],
)
def test_bad_input(call):
    with pytest.raises(InputError):
        call()


def test_numba_versions_callable_from_njit_code():
    from numba import njit

    @njit
    def round_trip(a, b, theta_e, theta, n_p):
        x = frames.abc_to_complex_nb(a, b, -a - b, theta_e)
        ra, rb, rc = frames.complex_to_abc_nb(x, theta_e)
        y = frames.rotor_abc_to_complex_nb(a, b, -a - b, theta_e, theta, n_p)
        xa, xb, xc = frames.complex_to_rotor_abc_nb(y, theta_e, theta, n_p)
        c = -a - b
        err = abs(ra - a) + abs(rb - b) + abs(rc - c) + abs(xa - a) + abs(xb - b) + abs(xc - c)
        return err, x, y

    err, x, y = round_trip(1.5, -0.25, 0.8, 0.3, 2)
    assert err < 1e-12
    assert abs(x - frames.abc_to_complex(1.5, -0.25, -1.25, 0.8)) < 1e-12
    assert abs(y - frames.rotor_abc_to_complex(1.5, -0.25, -1.25, 0.8, 0.3, 2)) < 1e-12


# --- the limit's tolerance of a few ulps -------------------------------------------------------
@pytest.mark.parametrize("limit", [1e-3, 1.0, 219.20310216782974, 3.7e5])
def test_beyond_limit_ignores_a_few_ulps_and_counts_1e9_relative(limit):
    assert frames.LIMIT_RTOL == frames.LIMIT_ULPS * np.finfo(float).eps
    one_ulp = math.nextafter(limit, math.inf)
    four_ulps = limit
    for _ in range(frames.LIMIT_ULPS):
        four_ulps = math.nextafter(four_ulps, math.inf)
    for at_limit in (limit, one_ulp, 0.5 * limit):
        assert not frames.beyond_limit(at_limit, limit)
        assert frames.clip_magnitude(complex(0.0, at_limit), limit) == (
            complex(0.0, at_limit),
            False,
        )
    # LIMIT_ULPS ulps above are still at the limit (an ulp of x is at most eps |x|)
    assert not frames.beyond_limit(four_ulps, limit)
    beyond = limit * (1.0 + 1e-9)
    assert frames.beyond_limit(beyond, limit)
    clipped, limited = frames.clip_magnitude(complex(beyond, 0.0), limit)
    assert limited and abs(clipped) == pytest.approx(limit, rel=1e-15)
