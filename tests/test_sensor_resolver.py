"""The resolver and its RDC tracking loop (acdrive.plant.Resolver): an amplitude imbalance gives
the analytic second-harmonic angle error, a quadrature error its offset and second harmonic,
an eccentricity its first harmonic; the type-II loop follows a constant speed with no error and
answers a speed step as its designed second-order poles do; a loop unstable at the run's
sample time and a bad imbalance are refused naming the field."""

from __future__ import annotations

import numpy as np
import pytest
from test_sensor_encoder import column, step_through, wrapped

from acdrive.errors import InputError
from acdrive.plant import Resolver

TWO_PI = 2.0 * np.pi
T_S = 1e-4
W_N = TWO_PI * 200.0  # the tracking loop's natural frequency


def _static_error(revolutions_per_s: float = 1.0, **errors) -> tuple[np.ndarray, np.ndarray]:
    """The angle error of the loop (read - shaft angle, wrapped) over the second revolution at a
    slow constant speed (the first lets the loop lock), with the shaft angle there."""
    resolver = Resolver("res", bandwidth=W_N, **errors)
    per_rev = round(1.0 / revolutions_per_s / T_S)
    theta = TWO_PI * np.arange(2 * per_rev) / per_rev
    y, _ = step_through(resolver, theta)
    error = wrapped(y[:, column(resolver, "theta")] - theta)
    return error[per_rev:], theta[per_rev:]


def _fourier(signal, angle, k: int) -> tuple[float, float]:
    """(sine, cosine) coefficients of harmonic k over whole, evenly sampled periods."""
    return 2 * np.mean(signal * np.sin(k * angle)), 2 * np.mean(signal * np.cos(k * angle))


def test_an_amplitude_imbalance_gives_the_analytic_second_harmonic():
    """(1 + a) sin against cos: tan(th + e) = (1 + a) tan th gives e = sum_k q^k sin(2 k th) / k,
    q = a / (2 + a); to first order (a/2) sin 2 th, positive. The slow angle's second harmonic is
    q (sine) and 0 (cosine), its fourth q^2 / 2, its mean zero."""
    a = 0.02
    q = a / (2 + a)
    error, theta = _static_error(imbalance=a)
    sine, cosine = _fourier(error, theta, 2)
    assert sine == pytest.approx(q, rel=1e-3) and abs(cosine) < 1e-3 * q
    assert sine == pytest.approx(a / 2, rel=2e-2)  # the first-order value, within a / 2 of it
    assert _fourier(error, theta, 4)[0] == pytest.approx(q**2 / 2, rel=2e-2)
    assert abs(np.mean(error)) < 1e-3 * q


def test_a_quadrature_error_gives_an_offset_and_a_second_harmonic():
    """cos(th + g) against sin: e = (g/2)(1 - cos 2 th) to first order."""
    g = 0.01
    error, theta = _static_error(quadrature=g)
    assert np.mean(error) == pytest.approx(g / 2, rel=1e-2)
    assert _fourier(error, theta, 2)[1] == pytest.approx(-g / 2, rel=1e-2)


def test_an_eccentricity_gives_a_first_harmonic_of_the_mechanical_angle():
    """(R1): e = eps sin(th - psi): first harmonic of amplitude eps at the angle psi."""
    eps, psi = 0.003, 0.8
    error, theta = _static_error(eccentricity=eps, eccentricity_angle=psi)
    sine, cosine = _fourier(error, theta, 1)
    assert sine == pytest.approx(eps * np.cos(psi), rel=1e-3)
    assert cosine == pytest.approx(-eps * np.sin(psi), rel=1e-3)


def test_the_type_two_loop_follows_a_constant_speed_without_error():
    """Two integrators in the loop: after the transient the angle error to a ramp is zero (to
    the rounding of sin and cos) and the speed is the shaft's; the angle and the electrical
    angle are wrapped."""
    w = 250.0
    resolver = Resolver("res", bandwidth=W_N, pole_pairs=3)
    theta = w * np.arange(4000) * T_S
    y, _ = step_through(resolver, theta)
    settled = slice(2000, None)  # 0.2 s: 50 time constants of the poles
    read = y[:, column(resolver, "theta")]
    assert np.max(np.abs(wrapped(read - theta)[settled])) < 1e-9
    assert np.max(np.abs(y[settled, column(resolver, "w")] - w)) < 1e-6 * w
    theta_e = y[:, column(resolver, "theta_e")]
    assert np.all((read >= 0) & (read < TWO_PI) & (theta_e >= 0) & (theta_e < TWO_PI))
    assert np.max(np.abs(wrapped(theta_e - 3 * theta)[settled])) < 1e-8


def _step_deviation(damping: float, T_s: float, w_0: float = 20.0) -> float:
    """Largest |loop speed - w_0 x the step response of the designed poles| / w_0 after the
    shaft starts turning at w_0 from rest at t = 0."""
    resolver = Resolver("res", bandwidth=W_N, damping=damping)
    t = np.arange(round(0.03 / T_s)) * T_s
    y, _ = step_through(resolver, w_0 * t, T_s)
    sigma = damping * W_N
    if damping < 1.0:
        w_d = W_N * np.sqrt(1 - damping**2)
        expected = 1 - np.exp(-sigma * t) * (np.cos(w_d * t) - sigma / w_d * np.sin(w_d * t))
    else:  # a double pole at -w_n
        expected = 1 - np.exp(-W_N * t) * (1 - W_N * t)
    return float(np.max(np.abs(y[:, column(resolver, "w")] / w_0 - expected)))


@pytest.mark.parametrize("damping", [0.5, 1 / np.sqrt(2), 1.0])
def test_a_speed_step_follows_the_designed_second_order_poles(damping):
    """From rest, the shaft turning at w_0 from t = 0 (small enough for sin(e) ~ e): the loop's
    speed is w_0 times the step response of (2 zeta w_n s + w_n^2) / (s^2 + 2 zeta w_n s + w_n^2),
    the design (R4), to first order in w_n T_s (the forward-Euler loop (R3)): within w_n T_s of
    it at T_s = 10 us, and four times closer at a quarter of the sample time."""
    coarse, fine = _step_deviation(damping, 1e-5), _step_deviation(damping, 2.5e-6)
    assert coarse < W_N * 1e-5
    assert 3.0 < coarse / fine < 5.0


def test_an_unstable_sampled_loop_and_a_bad_imbalance_are_refused():
    resolver = Resolver("res", bandwidth=3e4)
    resolver.check_run(1e-5)  # stable at 10 us
    with pytest.raises(InputError, match=r"^res\.bandwidth: .*unstable"):
        resolver.check_run(1e-4)
    with pytest.raises(InputError, match=r"^res\.imbalance: "):
        Resolver("res", bandwidth=1e3, imbalance=-1.0)
    with pytest.raises(InputError, match=r"^res\.bandwidth: "):
        Resolver("res", bandwidth=0.0)
