"""What every estimator of ``acdrive.identify`` shares: an estimate with its two 95 % intervals,
the interval from the Jacobian covariance, the bootstrap's percentile interval, and the error of
a fit that did not converge.

**Jacobian interval.** For weighted residuals r(p) whose weights make them unit-variance noise, the
covariance of the least-squares estimate is (J^T J)^-1 (J the Jacobian at the optimum); with
unknown noise it is scaled by the residual variance s^2 = |r|^2 / (m - n) (m residuals, n
parameters) and the interval is p +- t_{0.975, m-n} sqrt(cov_ii) (Student's t for the estimated
variance). **Bootstrap interval.** The 2.5 % and 97.5 % percentiles of the estimates refitted on
``BOOTSTRAP_COUNT`` data sets made of the fitted response plus residuals drawn with replacement
(seeded: the same data give the same interval).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acdrive._arguments import RESULT, Items, Text, checked

#: the confidence level of every interval
LEVEL = 0.95
#: bootstrap resamples per fit (a modest count: intervals to about 2 digits)
BOOTSTRAP_COUNT = 200


@checked(what=Text(), reason=Text(), residual=RESULT, unit=Text(empty=True))
class FitNotConverged(RuntimeError):
    """A least-squares fit that stopped without converging: ``what`` was being fitted, the
    solver's ``reason`` and the residual it reached (``residual`` with its ``unit``)."""

    def __init__(self, what: str, reason: str, residual: float, unit: str):
        self.what, self.reason, self.residual = what, reason, float(residual)
        super().__init__(
            f"{what}: the fit did not converge ({reason}); residual {residual:.4g} {unit}; "
            "no parameters are returned"
        )


@checked(
    name=Text(), unit=Text(empty=True), meaning=Text(empty=True), value=RESULT,
    jacobian=Items(RESULT), bootstrap=Items(RESULT),
)
@dataclass(frozen=True)
class Estimate:
    """One identified quantity: ``value`` [``unit``] with its 95 % interval from the Jacobian
    covariance (``jacobian``) and from the bootstrap (``bootstrap``), each (low, high)."""

    name: str
    unit: str
    meaning: str
    value: float
    jacobian: tuple[float, float]
    bootstrap: tuple[float, float]

    def covers(self, truth: float, which: str = "jacobian") -> bool:
        low, high = getattr(self, which)
        return low <= truth <= high

    def half_width(self) -> float:
        """Half the Jacobian interval's width, relative to the value."""
        low, high = self.jacobian
        return 0.5 * (high - low) / abs(self.value)


def t_quantile(dof: int) -> float:
    """Student's t quantile of the two-sided ``LEVEL`` interval with ``dof`` degrees of freedom."""
    from scipy.stats import t

    return float(t.ppf(0.5 + LEVEL / 2.0, dof))


def covariance(jacobian: np.ndarray, scale: float) -> np.ndarray:
    """``scale`` (J^T J)^-1, by the pseudo-inverse (a singular J gives infinite variances where
    the data say nothing, never an exception)."""
    JTJ = jacobian.T @ jacobian
    cov = np.linalg.pinv(JTJ) * scale
    rank = np.linalg.matrix_rank(JTJ)
    if rank < JTJ.shape[0]:
        cov = cov + np.diag(np.full(JTJ.shape[0], np.inf))
    return cov


def jacobian_interval(value: float, variance: float, quantile: float) -> tuple[float, float]:
    half = quantile * float(np.sqrt(variance))
    return value - half, value + half


def percentile_interval(samples: np.ndarray) -> tuple[float, float]:
    """The central ``LEVEL`` percentile interval of the bootstrap draws (a refit that failed is
    NaN and not counted; with none left the interval is (NaN, NaN), i.e. unknown)."""
    samples = np.asarray(samples, dtype=float)
    samples = samples[np.isfinite(samples)]
    if samples.size == 0:
        return float("nan"), float("nan")
    low, high = np.percentile(samples, [50.0 * (1.0 - LEVEL), 50.0 * (1.0 + LEVEL)])
    return float(low), float(high)


def propagate(function, values: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """Covariance of ``function(values)`` (a vector) to first order: G cov G^T, G by central
    differences with relative steps 1e-6."""
    values = np.asarray(values, dtype=float)
    base = np.asarray(function(values), dtype=float)
    G = np.empty((base.size, values.size))
    for j in range(values.size):
        h = 1e-6 * abs(values[j])
        up, down = values.copy(), values.copy()
        up[j] += h
        down[j] -= h
        G[:, j] = (np.asarray(function(up)) - np.asarray(function(down))) / (2.0 * h)
    return G @ cov @ G.T
