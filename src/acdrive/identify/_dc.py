"""R_s and the inverter's voltage error from DC steps at standstill.

With a constant phase-a command V_k held until the current has settled, the rotor branch carries
no current (L_M is a short at DC) and the stator winding is a resistance. The inverter applies
less than its command: with a positive phase-a current, dead time t_d and device drops v_drop
cost each leg sign(i_x) (t_d f_pwm v_dc + v_drop) of mean pole voltage (``plant._inverter``),
phase a (i_a > 0, i_b = i_c = -i_a / 2 < 0) loses U = 4/3 (t_d f_pwm v_dc + v_drop). Hence

    V_k = R_s I_k + U        (each settled plateau k),

a straight line whose slope is R_s and whose intercept is the voltage error U; two levels or more
separate them. One level alone gives V_k / I_k = R_s + U / I_k: R_s biased by U / I_k
(``single_level``).

**The current sensor's offset.** A reading I_k + c moves the intercept to U - R_s c
(``identify._offset``). Runs of zero command (rests) whose current has settled carry no current:
their mean reading is c (``rests``), subtracted from every plateau before the fit, and its
standard error adds R_s^2 se_c^2 to U's variance (the bootstrap redraws it too). A log without a
rest leaves c in the intercept; ``identify._standstill`` then separates it with the injection.

**Estimator.** Plateaus are the runs of equal command in the log; each must hold at least
``MIN_PLATEAU_ROWS`` rows, and only its last ``SETTLED_FRACTION`` is used, where the two halves
must agree within ``SETTLED_SIGMAS`` standard errors of their difference or ``SETTLED_FLOOR`` of
the current, whichever is larger (else the level was not held long enough).
The mean current of plateau k, I_k, has the standard error s_k / sqrt(n_k) of its n_k samples'
spread s_k (white sensor noise). The fit is ``least_squares`` of (I_k - (V_k - U) / R_s) / se_k,
the error sitting in the measured current; the covariance (J^T J)^-1 is scaled by the residual
variance when that exceeds 1 (never shrunk below what the noise gives: with two or three levels
the residual has at most one degree of freedom). The bootstrap redraws each plateau's samples
around its mean (``identify._fit``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acdrive._arguments import COUNT0, SEED, Instance, checked
from acdrive.errors import InputError
from acdrive.identify._experiment import StandstillLog
from acdrive.identify._fit import (
    BOOTSTRAP_COUNT,
    Estimate,
    FitNotConverged,
    covariance,
    jacobian_interval,
    percentile_interval,
)

MIN_PLATEAU_ROWS = 40
SETTLED_FRACTION = 0.25
SETTLED_SIGMAS = 4.0
SETTLED_FLOOR = 1e-4
#: a z-quantile for the DC intervals: the noise variance is known from thousands of samples
Z_95 = 1.959963984540054


@dataclass(frozen=True)
class Plateau:
    """One settled DC level: command ``voltage`` [V], mean current ``current`` [A], its standard
    error ``stderr`` [A] and the settled window's deviations from that mean ``deviations``."""

    voltage: float
    current: float
    stderr: float
    deviations: np.ndarray


@dataclass(frozen=True)
class DCStepFit:
    """R_s and the voltage error U from the plateaus (module docstring), the single-level
    R_s of the highest level for comparison, the residual and the plateaus."""

    R_s: Estimate
    voltage_error: Estimate
    single_level: Estimate
    plateaus: tuple[Plateau, ...]
    chi2: float
    dof: int
    offset: Estimate | None = None

    @property
    def voltage_error_std(self) -> float:
        """The standard error of U [V] (its Jacobian interval's half-width over z_0.975)."""
        low, high = self.voltage_error.jacobian
        return 0.5 * (high - low) / Z_95


def _settled_window(log: StandstillLog, start: int, stop: int):
    """(window, mean, stderr, drift) of the last ``SETTLED_FRACTION`` of rows start:stop, drift
    being the difference of its halves' means, or None when the current has not settled there
    (module docstring)."""
    rows = stop - start
    window = log.i_a[stop - max(4, int(SETTLED_FRACTION * rows)) : stop]
    mean = float(np.mean(window))
    spread = float(np.std(window, ddof=1))
    stderr = spread / np.sqrt(window.size)
    first, second = np.array_split(window, 2)
    drift = abs(float(np.mean(second) - np.mean(first)))
    # the halves' means differ with standard error 2 se; a drift below SETTLED_FLOOR of the
    # current is no error worth a refusal (a noise-free log has se = 0)
    settled = drift <= max(SETTLED_SIGMAS * 2.0 * stderr, SETTLED_FLOOR * abs(mean))
    return window, mean, stderr, drift, settled


def rests(log: StandstillLog) -> list[Plateau]:
    """The zero-current stretches of ``log``: runs of zero command of at least
    ``MIN_PLATEAU_ROWS`` rows whose current has settled (to zero: what the sensor reads there is
    its offset, module docstring); a rest that has not settled is left out."""
    found = []
    edges = np.flatnonzero(np.diff(log.v_a) != 0.0) + 1
    for start, stop in zip(np.concatenate(([0], edges)), np.concatenate((edges, [log.v_a.size])),
                           strict=True):  # fmt: skip
        if log.v_a[start] != 0.0 or stop - start < MIN_PLATEAU_ROWS:
            continue
        window, mean, stderr, _, settled = _settled_window(log, start, stop)
        if settled:
            found.append(Plateau(0.0, mean, stderr, window - mean))
    return found


def plateaus(log: StandstillLog) -> list[Plateau]:
    """The settled plateaus of ``log`` (module docstring); an InputError names the rule broken."""
    where = f"{log.source}: column 'v_a'"
    edges = np.flatnonzero(np.diff(log.v_a) != 0.0) + 1
    starts = np.concatenate(([0], edges))
    stops = np.concatenate((edges, [log.v_a.size]))
    found = []
    for start, stop in zip(starts, stops, strict=True):
        voltage = float(log.v_a[start])
        if voltage == 0.0:
            continue  # a rest between levels (``rests``)
        rows = stop - start
        if rows < MIN_PLATEAU_ROWS:
            raise InputError(where, f"the level {voltage:g} V is held for {rows} rows, a DC step "
                             f"needs at least {MIN_PLATEAU_ROWS}")  # fmt: skip
        window, mean, stderr, drift, settled = _settled_window(log, start, stop)
        if not settled:  # the current drifts: its column is the one named
            raise InputError(
                f"{log.source}: column 'i_a'",
                f"the current of the level {voltage:g} V has not settled in its last "
                f"{SETTLED_FRACTION:.0%} (drift {drift:.3g} A); hold each level longer",
            )
        found.append(Plateau(voltage, mean, stderr, window - mean))
    if len({p.voltage for p in found}) < 2:
        raise InputError(where, "a DC-step test needs at least two different nonzero levels")
    if len({np.sign(p.voltage) for p in found}) > 1 or any(
        np.sign(p.current) != np.sign(p.voltage) for p in found
    ):
        raise InputError(where, "the levels and their currents must all have one sign (the "
                         "inverter's voltage error changes sign with the current)")  # fmt: skip
    return found


def _solve(V, I, se, start):
    from scipy.optimize import least_squares

    def residual(p):
        R_s, U = p
        return (I - (V - U) / R_s) / se

    fit = least_squares(residual, start, method="lm", xtol=1e-12, ftol=1e-12)
    return fit


@checked(log=Instance(StandstillLog), seed=SEED, bootstrap=COUNT0)
def fit_dc_steps(log: StandstillLog, seed: int = 0, bootstrap: int = BOOTSTRAP_COUNT) -> DCStepFit:
    """R_s and the inverter voltage error U from a DC-step log (module docstring)."""
    found = plateaus(log)
    zero = rests(log)
    V = np.array([p.voltage for p in found])
    se = np.array([p.stderr for p in found])
    offset, offset_se, offset_deviations = 0.0, 0.0, np.zeros(1)
    if zero:  # the current sensor's offset, read where the current is zero (module docstring)
        offset_deviations = np.concatenate([p.deviations + p.current for p in zero])
        offset = float(np.mean(offset_deviations))
        offset_deviations = offset_deviations - offset
        offset_se = float(np.std(offset_deviations, ddof=1) / np.sqrt(offset_deviations.size))
    I = np.array([p.current for p in found]) - offset
    slope, intercept = np.polyfit(I, V, 1)  # the straight line as the start
    fit = _solve(V, I, se, np.array([slope, intercept]))
    dof = V.size - 2
    chi2 = float(2.0 * fit.cost)
    if not fit.success or not np.all(np.isfinite(fit.x)) or fit.x[0] <= 0.0:
        raise FitNotConverged("DC steps", fit.message, np.sqrt(chi2 / V.size) * se.mean(), "A")
    scale = max(1.0, chi2 / dof) if dof > 0 else 1.0
    cov = covariance(fit.jac, scale)
    cov[1, 1] += (fit.x[0] * offset_se) ** 2  # U = V - R_s (I - offset): dU / d offset = R_s
    rng = np.random.default_rng(seed)
    model = (V - fit.x[1]) / fit.x[0]
    draws = np.empty((bootstrap, 2))
    for b in range(bootstrap):
        redrawn = model + np.array([rng.choice(p.deviations, p.deviations.size).mean()
                                    for p in found])  # fmt: skip
        if zero:
            redrawn -= rng.choice(offset_deviations, offset_deviations.size).mean()
        draws[b] = _solve(V, redrawn, se, fit.x).x
    top = int(np.argmax(np.abs(V)))
    single = V[top] / I[top]
    single_se = abs(V[top]) * se[top] / I[top] ** 2
    single_draws = V[top] / (I[top] + np.array(
        [rng.choice(found[top].deviations, found[top].deviations.size).mean()
         for _ in range(bootstrap)]))  # fmt: skip
    R_s = Estimate("R_s", "ohm", "resistance of the driven winding (slope of the DC steps: the "
                   "stator's, or the rotor's from a DFIM's rotor converter)", float(fit.x[0]),
                   jacobian_interval(fit.x[0], cov[0, 0], Z_95),
                   percentile_interval(draws[:, 0]))  # fmt: skip
    U = Estimate("U_err", "V", "inverter voltage error on phase a (intercept of the DC steps)",
                 float(fit.x[1]), jacobian_interval(fit.x[1], cov[1, 1], Z_95),
                 percentile_interval(draws[:, 1]))  # fmt: skip
    single_level = Estimate(
        "R_s_single", "ohm", f"V/I at the {V[top]:g} V level alone (biased by U_err / I)",
        float(single), jacobian_interval(single, single_se**2, Z_95),
        percentile_interval(single_draws),
    )  # fmt: skip
    measured = None
    if zero:
        measured = Estimate("i_a_offset", "A", "current-sensor offset, the mean reading of the "
                            "DC log's zero-current stretches (subtracted)", offset,
                            jacobian_interval(offset, offset_se**2, Z_95),
                            jacobian_interval(offset, offset_se**2, Z_95))  # fmt: skip
    return DCStepFit(R_s, U, single_level, tuple(found), chi2, dof, measured)
