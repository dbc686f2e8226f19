"""The Gaussian draws that carry the Jacobian covariance's terms beyond the noise into the
bootstrap (identify._impedance.gaussian_draws): their sample covariance is the covariance asked
for, a rank-one term d d^T draws multiples of d only, an unbounded term draws NaN (an unknown
interval) and leaves the bounded parameters' draws as they are, and no term draws zeros."""

import numpy as np

from acdrive.identify._impedance import gaussian_draws


def test_the_draws_have_the_covariance_asked_for():
    cov = np.array([[4.0, 1.2, 0.0], [1.2, 1.0, -0.3], [0.0, -0.3, 0.25]])
    draws = gaussian_draws(cov, 200_000, seed=5)
    sample = np.cov(draws, rowvar=False)
    # the standard error of a sample covariance entry is sqrt((s_ii s_jj + s_ij^2) / N)
    se = np.sqrt((np.outer(np.diag(cov), np.diag(cov)) + cov**2) / draws.shape[0])
    assert np.all(np.abs(sample - cov) < 5.0 * se), sample - cov
    assert np.all(np.abs(draws.mean(axis=0)) < 5.0 * np.sqrt(np.diag(cov) / draws.shape[0]))


def test_a_rank_one_term_draws_along_its_vector():
    d = np.array([0.3, -0.1, 2.0])
    draws = gaussian_draws(np.outer(d, d), 1000, seed=1)
    scale = draws @ d / (d @ d)
    assert np.allclose(draws, np.outer(scale, d), rtol=0.0, atol=1e-12)
    assert 0.9 < np.std(scale) < 1.1


def test_an_unbounded_term_draws_nan_for_its_parameter_only():
    cov = np.diag([1.0, np.inf, 0.04])
    draws = gaussian_draws(cov, 5000, seed=2)
    assert np.all(np.isnan(draws[:, 1]))
    assert np.all(np.isfinite(draws[:, [0, 2]]))
    assert np.std(draws[:, 2]) == np.std(draws[:, 2]) and 0.18 < np.std(draws[:, 2]) < 0.22


def test_no_term_moves_no_draw():
    assert np.array_equal(gaussian_draws(np.zeros((4, 4)), 7, seed=0), np.zeros((7, 4)))
