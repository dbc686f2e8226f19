"""How a standstill fit judges itself: the noise floor of its log, the timing between its voltage
and current channels, and a model-error term when the residual exceeds the floor.

**The noise floor.** The injection is periodic in the base frequency f_0 and the window holds P
whole periods (``identify._impedance``), so in periodic steady state the log's DFT has content
only at the bins that are multiples of P. The bins between them (the tones' off-frequency
neighbours, k P + 1 ... k P + P - 1 around each excited tone k) hold the sensor noise alone
(and whatever is not periodic in f_0: a drift, an unsettled transient). Their mean squared
magnitude, halved, is the noise variance sigma^2 of each real and imaginary part of a tone's
current coefficient (white noise of deviation s over n samples gives 2 s^2 / n for both,
scaled as the estimator scales them). With one period (P = 1) there are no such bins and the
residual is not judged.

**The residual against the floor.** A model that explains the log leaves at each tone only that
noise: the residual variance s^2 = |r|^2 / (2K - n) is sigma^2 within the spread of two
variance estimates. ``RESIDUAL_FACTOR`` on the rms (a variance ratio of 4, beyond the 0.999
quantile of F(16, 40), the default test's degrees of freedom: noise alone exceeds it in 2 fits
of 10,000) marks a model error: something in
the log the winding's model does not have (an inverter voltage error not compensated or not
compensated well, a current-sensor offset or gain, a timing error, saturation). The residual's
scaling of the Jacobian covariance treats that error as white noise, which it is not: it is
smooth in frequency and moves the parameters together. The fit then adds a model-error term to
its covariance, the delete-one-tone jackknife (K refits each leaving out one tone,
var = (K - 1) / K sum (p_(k) - mean)^2; Efron and Stein, Ann. Stat. 9 (1981) 586, the jackknife
estimate of variance), which sees how much each tone's misfit pulls the parameters.

**Timing.** A current read late by tau against its voltage has the coefficients
I_k e^{-j w_k tau}: a phase growing with frequency that no passive winding's parameters produce
(an RL branch's phase tends to a constant, -pi / 2). The fit is repeated with tau free
(``fit_delay``: the winding's parameters and tau jointly, started from a few multiples of half
the sample period so that a whole row's shift is found), and its tau with its standard error
is the timing the log shows. A delay of ``REFUSED_DELAY`` sample periods or more is a row
shift (a logging error) and is refused naming the current column; a smaller one above
``TIMING_FRACTION`` of the period and significant (``TIMING_SIGMAS`` standard errors) is
compensated (the current coefficients advanced by tau) with a warning naming the channel and
the delay, and its uncertainty carried into the intervals.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acdrive.identify._fit import covariance

#: the residual's rms above this many times the noise floor is a model error (module docstring)
RESIDUAL_FACTOR = 2.0
#: delays from this many sample periods up are refused (a row shift)
REFUSED_DELAY = 0.75
#: delays above this fraction of the sample period (and significant) are compensated and named
TIMING_FRACTION = 0.05
#: a delay is significant beyond this many standard errors
TIMING_SIGMAS = 3.0
#: the level of the F test by which a delay explains the misfit
DELAY_LEVEL = 0.999
#: the delays ``fit_delay`` starts from [sample periods]
DELAY_STARTS = (-1.0, -0.5, 0.0, 0.5, 1.0, 1.5, 2.0)


def off_tone_noise(coefficients: np.ndarray, periods: int,
                   excited: np.ndarray) -> tuple[float, int]:  # fmt: skip
    """(sigma^2, count): the noise variance of a real or imaginary part of a tone coefficient
    from the off-frequency bins around the ``excited`` bins of ``coefficients`` (the window's
    DFT scaled by 2 / n), and how many bins gave it; (NaN, 0) with one period (module
    docstring)."""
    if periods < 2:
        return float("nan"), 0
    offsets = np.concatenate((np.arange(1, periods), -np.arange(1, periods)))
    bins = np.unique((excited[:, None] + offsets[None, :]).ravel())
    bins = bins[(bins > 0) & (bins < coefficients.size) & (bins % periods != 0)]
    if bins.size == 0:
        return float("nan"), 0
    return float(np.mean(np.abs(coefficients[bins]) ** 2) / 2.0), int(bins.size)


@dataclass(frozen=True)
class DelayFit:
    """The current's delay against the voltage found by the joint fit: ``delay`` [s] (positive:
    the current is read late), its standard error ``std`` [s], the winding's log-parameters
    ``theta`` of that fit and its residual cost."""

    delay: float
    std: float
    theta: np.ndarray
    cost: float
    explains: bool = False

    def significant(self, hold: float) -> bool:
        """A delay that ``explains`` the misfit, above ``TIMING_FRACTION`` of the sample period
        and ``TIMING_SIGMAS`` standard errors."""
        return self.explains and abs(self.delay) > max(TIMING_FRACTION * hold,
                                                       TIMING_SIGMAS * self.std)  # fmt: skip

    def refused(self, hold: float) -> bool:
        return self.significant(hold) and abs(self.delay) >= REFUSED_DELAY * hold


def fit_delay(spec, theta: np.ndarray, cost: float, model, residual) -> DelayFit:
    """The winding's log-parameters and the current's delay fitted jointly (module docstring):
    ``residual(theta, spec, model)`` is the fit's own residual, applied to the spectrum whose
    current is advanced by the trial delay. Started at the fit's ``theta`` and at the model's
    starting point of each advanced spectrum, for each of ``DELAY_STARTS``; the lowest cost
    wins. The delay ``explains`` the misfit when it lowers the fit's ``cost`` beyond chance:
    the F statistic of the one added parameter, (cost - cost_d) / (cost_d / (m - n - 1)),
    above its ``DELAY_LEVEL`` quantile, and it lies within the delays searched (a delay found
    far outside them is the joint fit wandering where the data do not determine it)."""
    from scipy.optimize import least_squares
    from scipy.stats import f as f_distribution

    hold = spec.hold

    def joint(x):
        return residual(x[:-1], spec.advanced(x[-1] * hold), model)

    best = None
    for start in DELAY_STARTS:
        shifted = spec.advanced(start * hold)
        with np.errstate(all="ignore"):
            starts = [theta, np.log(model.start(shifted))]
        for first in starts:
            if not np.all(np.isfinite(first)):
                continue
            fit = least_squares(joint, np.append(first, start), method="lm", xtol=1e-12,
                                ftol=1e-12, gtol=1e-12, max_nfev=2000)  # fmt: skip
            better = best is None or fit.cost < best.cost
            if fit.success and np.all(np.isfinite(fit.x)) and better:
                best = fit
    if best is None:
        return DelayFit(0.0, float("inf"), theta, float("inf"))
    dof = max(best.fun.size - best.x.size, 1)
    cov = covariance(best.jac, 2.0 * best.cost / dof)
    std = float(np.sqrt(cov[-1, -1])) * hold if np.isfinite(cov[-1, -1]) else float("inf")
    searched = min(DELAY_STARTS) - 0.5 <= best.x[-1] <= max(DELAY_STARTS) + 0.5
    with np.errstate(divide="ignore", invalid="ignore"):
        statistic = (cost - best.cost) / (best.cost / dof)
    explains = bool(searched and statistic > f_distribution.ppf(DELAY_LEVEL, 1, dof))
    return DelayFit(float(best.x[-1] * hold), std, best.x[:-1].copy(), float(best.cost),
                    explains)  # fmt: skip


def jackknife_covariance(spec, theta: np.ndarray, model, solve) -> np.ndarray:
    """The delete-one-tone jackknife covariance of the log-parameters (module docstring):
    ``solve(spectrum, start)`` refits a spectrum; a refit that fails makes it infinite."""
    count = spec.frequency.size
    refits = []
    for k in range(count):
        keep = np.arange(count) != k
        fit = solve(spec.subset(keep), theta)
        if not (fit.success and np.all(np.isfinite(fit.x))):
            return np.diag(np.full(theta.size, np.inf))
        refits.append(fit.x)
    refits = np.array(refits)
    deviation = refits - refits.mean(axis=0)
    return (count - 1) / count * deviation.T @ deviation
