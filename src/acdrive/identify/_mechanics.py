"""Inertia, viscous and Coulomb friction from speed steps of a running drive.

**The test.** A speed-controlled drive follows a staircase of speed references of one sign
(``MechanicsPlan.levels``, each held ``hold`` seconds): every step accelerates or decelerates
the shaft with the drive's torque, every plateau holds a speed against the friction alone. The
log has one row per logging instant:

- ``time`` [s];
- ``tau_e`` [N m], the machine's torque (a torque transducer's reading; a drive without one logs
  n_p psi_pm i_q from its measured currents, whose flux error then scales J, B and tau_c alike);
- ``w`` [rad/s], the shaft's mechanical speed averaged over the logging period that ends at the
  row: what a drive's encoder gives, its count difference over the period times the angle per
  count over the period (``SpeedSensor``).

On acdrive's own parts the test is a run of a PM speed-drive scenario (found through the drive
registry, like every other run: the PM machine on its converter, the field-oriented current and
speed loops, the encoder) whose speed reference is the staircase and whose shaft
(``plant.Shaft``) carries the inertia, viscous friction and the Coulomb friction under test.
The speed reading is computed after the run from the shaft's angle as a quadrature encoder of
``counts_per_rev`` counts sees it (the angle rounded down to whole counts, plus a seeded random
mounting offset so repeated tests differ), differenced over each logging period: its error is
the encoder's quantisation, about one count per period.

**The model** is the shaft's own equation (``plant._mechanics``, Bodson (26)) while the speed
keeps one sign:

    J dw/dt = tau_e - B w - tau_c sign(w),

linear in w for a given torque record. With the torque linear between logging instants (a
first-order hold of the log), its exact discretisation over a step h, tau_m = J / B and
a = exp(-h / tau_m), is

    w_{k+1} = a w_k + (1 - a) u_k / B + (u_{k+1} - u_k) (1 - tau_m (1 - a) / h) / B,
    u_k = tau_e,k - tau_c sign(w),

so the speed a parameter set predicts from the logged torque is one recursive filter
(``scipy.signal.lfilter``), and its mean over the period ending at row k is
(w_{k-1} + w_k) / 2 to second order in h. **The fit** is the output error: ``least_squares`` of
the logged minus predicted period-mean speed over J, B, tau_c and the first speed w_0 (a
nuisance), unconstrained (a friction estimated below zero is reported as such: its interval
says whether that is noise). Intervals as every estimator of ``identify``: the Jacobian
covariance scaled by the residual variance with Student's t, and a seeded bootstrap of refits on
the predicted speed plus redrawn residuals (``identify._fit``). The encoder's error is the
difference of two quantisation errors, so neighbouring rows are correlated (correlation -1/2):
low frequencies carry less of it than white noise of the same variance, and intervals computed
as for white noise are wider than the error they describe (conservative). Each bootstrap refit is one Gauss-Newton step from
the estimate with the estimate's Jacobian: the predicted speed is linear in the torque terms
and nearly so in J over an interval a fraction of a percent wide, and a full refit of tens of
thousands of rows two hundred times would take seconds.

**What the data identify.** The accelerations give J (the torque that is not friction over the
speed's slope); plateaus at two speeds or more separate the viscous (proportional to the speed)
from the Coulomb (constant) part of the torque that holds a plateau. Rules, each an
``InputError`` naming the column or parameter: the window starts after the last sample below
``MIN_SPEED`` (below it a real shaft's friction is stiction, not a constant) and must hold at
least ``MIN_FRACTION`` of the log; the logging step must resolve the drive's fastest change (at
most ``MAX_STEP`` s); J's 95 % interval within +-50 % of its value; and B, tau_c each
within +-50 % of its value or, for a friction that is small, its torque's interval (B w_max,
tau_c) within +-``FRICTION_FLOOR`` of the largest logged torque: a friction too small to matter
at that level is identified as small, not refused.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from acdrive._arguments import (
    COUNT,
    COUNT0,
    FLAG,
    NONNEGATIVE,
    PATH,
    POSITIVE,
    REAL,
    RESULT,
    SEED,
    TEXT,
    Array,
    Instance,
    Items,
    Number,
    Table,
    checked,
)
from acdrive.errors import InputError, require_positive
from acdrive.identify._fit import (
    BOOTSTRAP_COUNT,
    Estimate,
    FitNotConverged,
    covariance,
    jacobian_interval,
    percentile_interval,
    t_quantile,
)

#: the mechanics log's columns: name -> (unit, meaning)
MECHANICS_COLUMNS = {
    "time": ("s", "logging instant"),
    "tau_e": ("N m", "machine torque on the shaft, positive motoring"),
    "w": ("rad/s", "mechanical speed averaged over the logging period ending at the row"),
}
#: the estimated quantities, in fit order: name, unit, meaning
MECHANICS = (
    ("J", "kg m^2", "inertia of rotor and load"),
    ("B", "N m s/rad", "viscous friction coefficient"),
    ("tau_c", "N m", "Coulomb friction torque"),
)
#: the slowest speed [rad/s] the fit uses (module docstring)
MIN_SPEED = 5.0
#: the part of the log that must lie after the last speed below MIN_SPEED
MIN_FRACTION = 0.8
#: the coarsest logging step [s] (the drive's torque changes within milliseconds)
MAX_STEP = 1e-3
#: a friction identified as small: its torque's interval within +- this of the largest torque
FRICTION_FLOOR = 0.02
MAX_HALF_WIDTH = 0.5


@checked(time=Array(1), tau_e=Array(1), w=Array(1), source=TEXT)
@dataclass(frozen=True)
class MechanicsLog:
    """A speed-step log: equal-length ``time`` [s], ``tau_e`` [N m], ``w`` [rad/s]."""

    time: np.ndarray
    tau_e: np.ndarray
    w: np.ndarray
    source: str = "log"


@checked(counts_per_rev=COUNT)
@dataclass(frozen=True)
class SpeedSensor:
    """The encoder whose counts give the logged speed (module docstring)."""

    counts_per_rev: int = 4096


def encoder_speed(theta: np.ndarray, h: float, sensor: SpeedSensor, rng) -> np.ndarray:
    """Speed over each period h ending at the sample (the first row: NaN, no period before it)
    from the angle ``theta`` [rad] counted by ``sensor`` with a random mounting offset."""
    step = 2.0 * math.pi / sensor.counts_per_rev
    counts = np.floor(theta / step + rng.uniform())
    return np.concatenate(([math.nan], np.diff(counts) * step / h))


@checked(
    levels=Items(REAL), hold=POSITIVE, start=NONNEGATIVE, log_every=COUNT, tau_c=NONNEGATIVE,
    sensor=Instance(SpeedSensor),
)
@dataclass(frozen=True)
class MechanicsPlan:
    """The speed staircase: ``levels`` [rad/s] of one sign, each held ``hold`` [s], the first
    after ``start`` [s] at standstill; the log every ``log_every`` drive samples; the Coulomb
    friction ``tau_c`` [N m] of the simulated shaft (the drive's scenario has no such field)."""

    levels: tuple[float, ...] = (100.0, 250.0, 400.0, 150.0, 300.0)
    hold: float = 0.4
    start: float = 1e-3
    log_every: int = 2
    tau_c: float = 0.0
    sensor: SpeedSensor = field(default_factory=SpeedSensor)

    def __post_init__(self):
        require_positive("hold", self.hold)
        if len(self.levels) < 2 or len({np.sign(v) for v in self.levels}) != 1:
            raise InputError("levels", "needs two speeds or more, all of one sign")

    def duration(self) -> float:
        return self.start + self.hold * len(self.levels)

    def profile(self) -> list[list[float]]:
        """The speed reference as a scenario's ``speed_rad_s_profile`` (steps)."""
        points = [[0.0, 0.0], [self.start, 0.0]]
        for j, level in enumerate(self.levels):
            t = self.start + j * self.hold
            points += [[t, float(level)], [t + self.hold, float(level)]]
        return points


@checked(scenario=Table(), plan=Instance(MechanicsPlan), seed=SEED)
def speed_step_test(scenario: dict, plan: MechanicsPlan, seed: int = 0) -> MechanicsLog:
    """Run the PM speed-drive ``scenario`` (a parsed scenario table: machine, converter, control,
    J and viscous friction) with the staircase of ``plan`` as its speed reference and the
    Coulomb friction ``plan.tau_c`` on its shaft; the log of the module docstring (seeded)."""
    import copy

    from acdrive.drives._registry import for_data

    data = copy.deepcopy(scenario)
    data.setdefault("reference", {})
    data["reference"] = {"speed_rad_s_profile": plan.profile()}
    simulation = data.setdefault("simulation", {})
    simulation["duration"] = plan.duration()
    drive = for_data(data)
    setup = drive.load(data)
    built = drive.build(setup)
    initial, held = built.initial()
    parts = {p.name: p for p in built.system.parts}
    shaft, machine = parts["shaft"], parts["machine"]
    compiled = built.system.compile()
    T = float(simulation["sample_time"])
    result = compiled.run(plan.duration(), T, substeps=int(simulation.get("substeps", 4)),
                          initial=initial, held=held, log=[machine.out.tau_e, shaft.out.theta],
                          log_every=plan.log_every,
                          parts=[shaft.with_params(tau_c=plan.tau_c)])  # fmt: skip
    theta = result.signal(shaft.out.theta)
    h = T * plan.log_every
    reading = encoder_speed(theta, h, plan.sensor, np.random.default_rng(seed))
    return MechanicsLog(result.t[1:].copy(), result.signal(machine.out.tau_e)[1:].copy(),
                        reading[1:], "simulated speed-step test")  # fmt: skip


@checked(values=Array(1), tau_e=Array(1), sign=Number(-1.0, 1.0), h=POSITIVE)
def predicted_speed(values, tau_e: np.ndarray, sign: float, h: float) -> np.ndarray:
    """The speed the shaft model predicts from the torque record (module docstring);
    ``values`` = (J, B, tau_c, w_0)."""
    from scipy.signal import lfilter

    J, B, tau_c, w0 = (float(v) for v in values)
    u = tau_e - tau_c * sign
    x = h / J  # the limit B -> 0 of the coefficients below, for a frictionless shaft
    if abs(B * x) > 1e-12:
        tau_m = J / B
        one_minus_a = -math.expm1(-h / tau_m)
        a = 1.0 - one_minus_a
        c0 = one_minus_a / B
        c1 = (1.0 - tau_m * one_minus_a / h) / B
    else:
        a, c0, c1 = 1.0, x, 0.5 * x
    drive = c0 * u[:-1] + c1 * np.diff(u)
    rest, _ = lfilter([1.0], [1.0, -a], drive, zi=[a * w0])
    return np.concatenate(([w0], rest))


def _window(log: MechanicsLog) -> tuple[np.ndarray, np.ndarray, float, float]:
    """(torque, speed, sign, step) of the samples the fit uses (module docstring)."""
    where = f"{log.source}: column 'w'"
    h = float(np.median(np.diff(log.time)))
    if h > MAX_STEP:
        raise InputError(f"{log.source}: column 'time'", f"sampling every {h:.3g} s is too "
                         f"coarse for a drive's torque steps: at most {MAX_STEP:g} s")  # fmt: skip
    slow = np.flatnonzero(~(np.abs(log.w) >= MIN_SPEED))  # NaN counts as slow
    first = int(slow[-1]) + 1 if slow.size else 0
    if log.w.size - first < MIN_FRACTION * log.w.size:
        raise InputError(where, f"the speed must stay above {MIN_SPEED:g} rad/s in one "
                         f"direction from early in the log on (it is below at row {first}, "
                         f"leaving less than {MIN_FRACTION:.0%} of the log): the Coulomb "
                         "friction is a constant only then")  # fmt: skip
    w, tau = log.w[first:], log.tau_e[first:]
    sign = float(np.sign(w[0]))
    if np.any(np.sign(w) != sign):  # pragma: no cover - |w| >= MIN_SPEED cannot change sign
        raise InputError(where, "the speed must keep one sign")
    if w.size < 4 * len(MECHANICS):
        raise InputError(where, f"too short: {w.size} samples above {MIN_SPEED:g} rad/s")
    if np.ptp(w) == 0.0:
        raise InputError(where, f"the speed never changes ({w[0]:g} rad/s throughout): J needs "
                         "accelerations and B, tau_c plateaus at two speeds or more; step the "
                         "speed between two levels or more")  # fmt: skip
    if not np.any(tau):
        raise InputError(f"{log.source}: column 'tau_e'", "is zero throughout: the fit divides "
                         "the torque among inertia and friction")  # fmt: skip
    return tau, w, sign, h


@checked(estimates=Items(Instance(Estimate)), residual_rms=RESULT, dof=COUNT0)
@dataclass(frozen=True)
class MechanicsFit:
    """J, B, tau_c with their intervals, the residual (rms speed error [rad/s]) and the degrees
    of freedom."""

    estimates: tuple[Estimate, ...]
    residual_rms: float
    dof: int

    def value(self, name: str) -> float:
        return next(e.value for e in self.estimates if e.name == name)


def period_mean(speed: np.ndarray) -> np.ndarray:
    """The mean over each period ending at rows 1, 2, ... of a point speed (trapezoid)."""
    return 0.5 * (speed[:-1] + speed[1:])


def _solve(tau, w, sign, h, scale, start, tolerance=1e-10):
    """The output-error fit over the parameters divided by ``scale`` (all of order one: the
    covariance of numbers as unlike as an inertia and a speed would be ill-conditioned); ``w``
    the logged period means of rows 1, 2, ... of the window, w_0 the point speed at row 0."""
    from scipy.optimize import least_squares

    def residual(theta):
        return w - period_mean(predicted_speed(theta * scale, tau, sign, h))

    return least_squares(residual, start / scale, method="lm", xtol=tolerance, ftol=tolerance,
                         gtol=tolerance, max_nfev=500)  # fmt: skip


def _start(tau, w, sign, h) -> np.ndarray:
    """A straight-line start: plateau torque ~ B w + tau_c by least squares over the samples,
    J from the torque against the speed's slope."""
    slope = np.gradient(w, h)
    A = np.column_stack((slope, w, np.full(w.size, sign)))
    J, B, tau_c = np.linalg.lstsq(A, tau, rcond=None)[0]
    return np.array([max(J, 1e-9), max(B, 0.0), max(tau_c, 0.0), w[0]])


@checked(log=Instance(MechanicsLog), seed=SEED, bootstrap=COUNT0, check=FLAG)
def fit_mechanics(log: MechanicsLog, seed: int = 0, bootstrap: int = BOOTSTRAP_COUNT,
                  check: bool = True) -> MechanicsFit:  # fmt: skip
    """J, B and tau_c of a speed-step log with their intervals (module docstring)."""
    tau, w, sign, h = _window(log)
    start = _start(tau, w, sign, h)
    w = w[1:]  # period means, the first row's period lies before the window
    # B and tau_c scaled by the torque they make at the top speed, J by its start
    top = float(np.max(np.abs(w)))
    torque = float(np.max(np.abs(tau)))
    scale = np.array([start[0], 0.1 * torque / top, 0.1 * torque, max(abs(start[3]), 1.0)])
    try:
        fit = _solve(tau, w, sign, h, scale, start)
    except OverflowError:  # a shaft time constant J / B beyond float range: no speed change
        raise InputError(f"{log.source}: column 'w'", "the speed changes too little to tell the "
                         "inertia from the friction (the fit's time constant J / B overflows); "
                         "step the speed between two levels or more") from None  # fmt: skip
    m, n = w.size, 4
    dof = m - n
    rms = float(np.sqrt(2.0 * fit.cost / m))
    if not fit.success or not np.all(np.isfinite(fit.x)):
        raise FitNotConverged("mechanics", fit.message, rms, "rad/s (rms speed error)")
    cov = np.diag(scale) @ covariance(fit.jac, 2.0 * fit.cost / dof) @ np.diag(scale)
    values = fit.x * scale
    q = t_quantile(dof)
    rng = np.random.default_rng(seed)
    residual = fit.fun * math.sqrt(m / dof)
    # each draw's refit is one Gauss-Newton step from the estimate (module docstring)
    step = np.linalg.pinv(fit.jac)
    draws = np.empty((bootstrap, 3))
    for b in range(bootstrap):
        redrawn = rng.choice(residual, residual.size)
        draws[b] = (fit.x - step @ redrawn)[:3] * scale[:3]
    estimates = tuple(
        Estimate(name, unit, meaning, float(values[j]),
                 jacobian_interval(float(values[j]), cov[j, j], q),
                 percentile_interval(draws[:, j]))
        for j, (name, unit, meaning) in enumerate(MECHANICS)
    )  # fmt: skip
    result = MechanicsFit(estimates, rms, dof)
    if check:
        check_mechanics(result, torque, top)
    return result


def check_mechanics(fit: MechanicsFit, torque_max: float, speed_max: float) -> None:
    """The interval rules of the module docstring, each an InputError naming the parameter."""
    for estimate in fit.estimates:
        low, high = estimate.jacobian
        half = 0.5 * (high - low)
        relative = half / abs(estimate.value) if estimate.value != 0.0 else math.inf
        if relative <= MAX_HALF_WIDTH:
            continue
        scale = {"J": None, "B": speed_max, "tau_c": 1.0}[estimate.name]
        if scale is not None and half * scale <= FRICTION_FLOOR * torque_max:
            continue  # a small friction, identified as small
        told = f"+-{relative:.0%} of the value" if math.isfinite(relative) else "unbounded"
        raise InputError(estimate.name, f"not identified by this test: its 95 % interval is "
                         f"{told} (at most +-{MAX_HALF_WIDTH:.0%}"
                         + ("" if scale is None else f", or a friction torque within "
                            f"+-{FRICTION_FLOOR:.0%} of the largest torque")
                         + "); hold speeds at two levels or more and step between them")  # fmt: skip


@checked(fit=Instance(MechanicsFit))
def mechanics_identifiability(fit: MechanicsFit) -> list[str]:
    """What the speed steps determine, as sentences."""
    return [
        (
            "identified: J from the accelerations, B and tau_c from the torque that holds the "
            "plateaus at different speeds (viscous: proportional to the speed; Coulomb: constant)"
        ),
        (
            f"used: speeds above {MIN_SPEED:g} rad/s only (stiction below is not modelled); the "
            "torque is the log's, its error scales J, B and tau_c alike"
        ),
    ]


@checked(path=PATH, field=TEXT)
def read_mechanics_log(path, field: str = "path") -> MechanicsLog:
    """The speed-step log in ``path`` (CSV, Parquet or .mat with the columns of
    ``MECHANICS_COLUMNS``), every rule of ``identify._log`` checked."""
    from acdrive.identify._log import read_columns

    values = read_columns(path, MECHANICS_COLUMNS, "speed-step", field)
    return MechanicsLog(values["time"], values["tau_e"], values["w"], field)


@checked(log=Instance(MechanicsLog), path=PATH)
def write_mechanics_log(log: MechanicsLog, path):
    """Write a speed-step log as CSV, Parquet or .mat (by the suffix of ``path``)."""
    from acdrive.identify._log import write_columns

    return write_columns({"time": log.time, "tau_e": log.tau_e, "w": log.w}, MECHANICS_COLUMNS,
                         path)  # fmt: skip
