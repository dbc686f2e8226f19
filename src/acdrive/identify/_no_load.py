"""A cage IM's magnetising inductance from a no-load run.

**The test.** The inverter applies a balanced three-phase voltage of one frequency f (phase peak
``voltage``; the space vector K_PEAK V e^{j 2 pi f t}) while the rotor turns at (or near) the
synchronous speed 2 pi f / n_p: uncoupled and running light, or held there by a dynamometer.
At zero slip the rotor branch carries no current and the stator draws only the magnetising
current, so the stator impedance is R_s + j w (L_sigma + L_M): with R_s, L_sigma and R_R known
from the standstill tests, the one unknown is L_M, at the flux of the run (a test at rated
voltage and frequency gives L_M at rated flux, where a real machine's saturation puts it; the
standstill injection sees it at the injection's small flux). The log is the standstill log plus
the shaft's speed: ``time [s]``, ``v_a [V]`` (the latched command), ``i_a [A]`` (measured),
``w [rad/s]`` (mechanical speed, e.g. the encoder's).

On acdrive's bench (``identify._experiment``): the DC source, the SVPWM inverter with its dead time
and device drops, the cage IM part and ``plant.PrescribedSpeed`` holding the run's speed (a
``slip`` may be given: a motor running light slips a little against its friction).

**The model** is the machine's own at the logged speed: in the stationary frame the
inverse-Gamma circuit (``identify._circuit``) turning at the electrical speed w_r = n_p w,

    L_sigma di/dt = v - (R_s + R_R) i + (R_R / L_M - j w_r) psi_R
    dpsi_R/dt     = R_R i - (R_R / L_M - j w_r) psi_R,

sampled as the drive samples it (voltage held over each carrier period, current read at its
start): the exact discrete model x_{k+1} = Phi x_k + Gamma v_k (Phi = e^{AT}, complex) gives the
admittance Y_d(e^{jwT}) = i / v of a positive-sequence excitation (``running_admittance``;
at w_r = 0 it is ``identify._circuit.sampled_admittance``). Any slip is in the model, through the
logged speed, so the run need not be exactly synchronous.

**The fit.** The window is the whole periods of f after ``settle``; the phase-a Fourier
coefficients V, I at f are the data. The current's noise variance s^2 comes from the window's
residual about the fitted sinusoid (thousands of samples: a z quantile), so each part of I has
variance 2 s^2 / n. L_M minimises |I - Y_d(L_M) V|^2 (``least_squares``, in log L_M). Its 95 %
intervals: the Jacobian variance plus what the standstill parameters' covariance carries into it
(g Sigma g^T, g = dL_M / d(R_s, L_sigma, R_R) by central differences of refits); and a bootstrap
of refits on I redrawn with the noise and, if the standstill fit gave bootstrap draws, the
standstill parameters drawn from them.

**The switching pattern's second-order term.** The model holds the voltage constant over each
period; the inverter's centred pulses have the same mean and the same first moment about the
period's centre, but not the same second moment. Over one period
x(T) = e^{AT/2} int e^{-As} B v(s) ds (s from the centre), so the pattern adds
e^{AT/2} A^2 B W_k / 2 to the state, W_k the space vector of the legs' second moments
int s^2 (e_x - d_x v_dc) ds = v_dc T^3 (d_x^3 - d_x) / 12. Measured on the noise-free 5 kHz
bench (DeLorenzo IM, 150 V, 2 % slip, true standstill parameters): left out, L_M came out
2.5e-4 high (6.2e-5 at 10 kHz, 1.6e-5 at 20 kHz: as T^2; the same with four times the
integrator's substeps); the current's residual at f was this term's prediction to 1e-4 of
itself at 5 and 20 kHz. With the link voltage ``v_dc`` given, the model adds
W ripple_admittance, W the fundamental of W_k for the balanced command of the fitted phasor V
and the min-max zero sequence of the SVPWM (``pulse_moment``).

**The link voltage** comes from the caller (``fit_no_load(..., v_dc=)``, ``--link-voltage-v``)
or from the log's optional column ``v_dc`` [V] (``NO_LOAD_OPTIONAL``: what a drive's DC-link
sensor reads at each sample instant), as ``link_voltage`` decides: the column's mean over the
log is used, so the column must stay within ``LINK_RTOL`` of its mean (the term is a correction
of a few 1e-4 of L_M and varies about as the link voltage does, so a link within +-5 % changes
the estimate by a few 1e-5 of L_M, far inside its interval; a link that varies more is not the
one-voltage pattern the model describes). Given both ways, they must agree within ``LINK_RTOL``
and the column's mean is used (measured during the run). Without either, the model holds the
voltage over each period and the estimate carries the bias above.

**Rules**, each an ``InputError`` naming the column or parameter: at least one whole period
after ``settle``; ``SAMPLES_PER_PERIOD`` samples per period of f; the voltage a single frequency
(the tone at f carries at least ``TONE_SHARE`` of the window's AC voltage power); the speed
constant within ``SPEED_RTOL`` over the window; L_M's interval within +-50 % of its value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from acdrive._arguments import (
    COUNT,
    COUNT0,
    NONNEGATIVE,
    PATH,
    POSITIVE,
    REAL,
    RESULT,
    SEED,
    TEXT,
    Array,
    Attributes,
    Either,
    Instance,
    checked,
    optional,
)
from acdrive.errors import InputError, require_positive
from acdrive.identify._dc import Z_95
from acdrive.identify._experiment import CurrentSensor, StandstillPlan, run_test
from acdrive.identify._fit import BOOTSTRAP_COUNT, Estimate, FitNotConverged, percentile_interval

#: the no-load log's columns: the standstill log's and the shaft's speed
NO_LOAD_COLUMNS = {
    "time": ("s", "start of the carrier period (the sample instant)"),
    "v_a": ("V", "phase-a voltage command latched by the PWM unit for this period"),
    "i_a": ("A", "phase-a current measured at the sample instant"),
    "w": ("rad/s", "mechanical speed of the rotor"),
}
#: columns a no-load log may add (module docstring): name -> (unit, meaning)
NO_LOAD_OPTIONAL = {
    "v_dc": ("V", "DC-link voltage of the inverter at the sample instant"),
}
#: the largest relative deviation of the link voltage from its mean, and the largest relative
#: difference between a link voltage given and the log's (module docstring)
LINK_RTOL = 0.05
SAMPLES_PER_PERIOD = 20
TONE_SHARE = 0.95
SPEED_RTOL = 0.01
MAX_HALF_WIDTH = 0.5


@checked(
    time=Array(1), v_a=Array(1), i_a=Array(1), w=Array(1), source=TEXT,
    v_dc=Array(1, optional=True),
)
@dataclass(frozen=True)
class NoLoadLog:
    """A no-load run: equal-length ``time`` [s], ``v_a`` [V], ``i_a`` [A], ``w`` [rad/s] and, if
    logged, ``v_dc`` [V] (the DC-link voltage; None: not logged)."""

    time: np.ndarray
    v_a: np.ndarray
    i_a: np.ndarray
    w: np.ndarray
    source: str = "log"
    v_dc: np.ndarray | None = None


@checked(
    frequency=POSITIVE, voltage=POSITIVE, settle=NONNEGATIVE, periods=COUNT, slip=REAL,
    f_pwm=POSITIVE, v_dc=POSITIVE, t_d=NONNEGATIVE, v_drop=NONNEGATIVE,
    sensor=Instance(CurrentSensor),
)
@dataclass(frozen=True)
class NoLoadPlan:
    """The no-load run (module docstring): ``frequency`` [Hz], phase-peak ``voltage`` [V],
    ``settle`` [s] then ``periods`` whole periods, the ``slip`` of the rotor, on the bench of
    ``f_pwm``, ``v_dc``, ``t_d``, ``v_drop`` and ``sensor`` (as ``StandstillPlan``)."""

    frequency: float = 50.0
    voltage: float = 150.0
    settle: float = 1.0
    periods: int = 25
    slip: float = 0.0
    f_pwm: float = 5000.0
    v_dc: float = 310.0
    t_d: float = 0.0
    v_drop: float = 0.0
    sensor: CurrentSensor = field(default_factory=CurrentSensor)

    def __post_init__(self):
        for name in ("frequency", "voltage", "f_pwm", "v_dc"):
            require_positive(name, getattr(self, name))

    def bench(self) -> StandstillPlan:
        return StandstillPlan(f_pwm=self.f_pwm, v_dc=self.v_dc, t_d=self.t_d,
                              v_drop=self.v_drop, sensor=self.sensor)  # fmt: skip

    def duration(self) -> float:
        return self.settle + self.periods / self.frequency


@checked(
    machine=Instance("acdrive.machines._induction:IMParams"), plan=Instance(NoLoadPlan), seed=SEED,
)
def no_load_test(machine, plan: NoLoadPlan, seed: int = 3) -> NoLoadLog:
    """The no-load run of ``plan`` on the cage IM ``machine`` (module docstring)."""
    w = 2.0 * math.pi * plan.frequency * (1.0 - plan.slip) / machine.n_p
    omega = 2.0 * math.pi * plan.frequency
    log = run_test(machine, plan.bench(), lambda t: plan.voltage * np.exp(1j * omega * t),
                   plan.duration(), seed, "simulated no-load run", speed=w)  # fmt: skip
    return NoLoadLog(log.time, log.v_a, log.i_a, np.full(log.time.size, w), log.source)


@checked(
    params=Either(Instance("acdrive.identify._circuit:InverseGamma"), Array(1)), w_r=REAL,
    w=Array(), hold=POSITIVE,
)
def running_admittance(params, w_r: float, w, hold: float) -> np.ndarray:
    """Y_d(e^{jwT}) [S] of the inverse-Gamma circuit turning at electrical speed ``w_r``
    [rad/s], voltage held over each period T = ``hold``, current sampled at its start
    (module docstring); ``params`` = (R_s, L_sigma, R_R, L_M)."""
    R_s, L_sigma, R_R, L_M = (float(v) for v in params)
    rotor = R_R / L_M - 1j * w_r
    A = np.array([[-(R_s + R_R) / L_sigma, rotor / L_sigma], [R_R, -rotor]], dtype=complex)
    B = np.array([1.0 / L_sigma, 0.0], dtype=complex)
    Phi = _expm_2x2(A, hold)
    Gamma = np.linalg.solve(A, (Phi - np.eye(2)) @ B)
    z = np.exp(1j * np.asarray(w, dtype=float) * hold)
    det = (z - Phi[0, 0]) * (z - Phi[1, 1]) - Phi[0, 1] * Phi[1, 0]
    return ((z - Phi[1, 1]) * Gamma[0] + Phi[0, 1] * Gamma[1]) / det


def _expm_2x2(A: np.ndarray, T: float) -> np.ndarray:
    """e^{AT} of a 2x2 matrix with distinct eigenvalues l1, l2 (Sylvester's formula):
    e^{l2 T} I + (e^{l1 T} - e^{l2 T}) / (l1 - l2) (A - l2 I). The running machine's two modes
    (stator transient and rotor flux) are distinct for every positive parameter set."""
    half_trace = 0.5 * (A[0, 0] + A[1, 1])
    root = np.sqrt(half_trace**2 - (A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]))
    l1, l2 = half_trace + root, half_trace - root
    slope = (np.exp(l1 * T) - np.exp(l2 * T)) / (l1 - l2)
    return np.exp(l2 * T) * np.eye(2) + slope * (A - l2 * np.eye(2))


@checked(
    L_M=Instance(Estimate), frequency=RESULT, speed=RESULT, slip=RESULT, residual=RESULT,
    link_voltage=optional(RESULT),
)
@dataclass(frozen=True)
class NoLoadFit:
    """L_M of the no-load run with its intervals, the run's frequency [Hz], mean speed [rad/s]
    and slip, the residual (rms of the current's error at f [A]) and the link voltage used."""

    L_M: Estimate
    frequency: float
    speed: float
    slip: float
    residual: float
    #: the link voltage whose pulses' second-order term the model includes [V] (None: held)
    link_voltage: float | None = None


def _phasors(log: NoLoadLog, frequency: float, settle: float):
    """(V, I, noise variance of each part of I, hold, mean speed) of the window."""
    require_positive("frequency", frequency)
    where = f"{log.source}: column 'time'"
    hold = float(np.median(np.diff(log.time)))
    per_period = 1.0 / (frequency * hold)
    samples = round(per_period)
    if abs(per_period - samples) > 1e-6 * per_period:
        raise InputError("frequency", f"a period 1 / {frequency:g} Hz must be a whole number of "
                         f"samples of {hold:.6g} s, got {per_period:.6g}")  # fmt: skip
    if samples < SAMPLES_PER_PERIOD:
        raise InputError(where, f"sampling at {1 / hold:g} Hz is too coarse for {frequency:g} Hz: "
                         f"at least {SAMPLES_PER_PERIOD} samples per period")  # fmt: skip
    first = int(np.searchsorted(log.time, log.time[0] + settle - 0.5 * hold))
    periods = (log.time.size - first) // samples
    if periods < 1:
        raise InputError(where, f"too short: needs {settle:g} s to settle and one period of "
                         f"{frequency:g} Hz after it")  # fmt: skip
    n = periods * samples
    t, v, i, w = log.time[-n:], log.v_a[-n:], log.i_a[-n:], log.w[-n:]
    phase = np.exp(-2j * math.pi * frequency * (t - t[0]))
    V, I = 2.0 / n * np.sum(v * phase), 2.0 / n * np.sum(i * phase)
    ac = v - v.mean()
    if 0.5 * abs(V) ** 2 < TONE_SHARE * np.mean(ac**2):
        raise InputError(f"{log.source}: column 'v_a'", f"a no-load run applies one frequency: "
                         f"the tone at {frequency:g} Hz must carry at least {TONE_SHARE:.0%} of "
                         "the voltage's AC power")  # fmt: skip
    speed = float(np.mean(w))
    if speed == 0.0 or np.max(np.abs(w - speed)) > SPEED_RTOL * abs(speed):
        raise InputError(f"{log.source}: column 'w'", f"the speed must be constant within "
                         f"{SPEED_RTOL:.0%} over the analysed window (and not zero)")  # fmt: skip
    fitted = (I * np.conj(phase)).real + i.mean()
    variance = 2.0 * float(np.sum((i - fitted) ** 2) / (n - 3)) / n
    return V, I, variance, hold, speed


def pulse_moment(V, frequency: float, hold: float, v_dc: float, n: int) -> complex:
    """The fundamental coefficient W of the switching pattern's second moment (module
    docstring): the balanced command of phasor ``V`` [V] at ``frequency`` [Hz], its min-max
    zero sequence and duties d_x over ``n`` periods ``hold`` [s] from a link of ``v_dc`` [V];
    per leg int s^2 (e_x - d_x v_dc) ds = v_dc T^3 (d_x^3 - d_x) / 12 about the period's
    centre, their space vector's coefficient at +frequency."""
    phase = 2.0 * math.pi * frequency * hold * np.arange(n)
    legs = np.array([(V * np.exp(1j * (phase - k * 2.0 * math.pi / 3.0))).real for k in range(3)])
    offset = -0.5 * (legs.max(axis=0) + legs.min(axis=0))
    duty = np.clip(0.5 + (legs + offset) / v_dc, 0.0, 1.0)
    moment = v_dc * hold**3 * (duty**3 - duty) / 12.0
    a = np.exp(2j * math.pi / 3.0)
    vector = (2.0 / 3.0) * (moment[0] + a * moment[1] + a * a * moment[2])
    return complex(np.mean(vector * np.exp(-1j * phase)))


def ripple_admittance(params, w_r: float, w: float, hold: float) -> complex:
    """I / W [S / s^2]: how the second moment W enters the sampled current, C (zI - Phi)^-1 E
    with E = e^{AT/2} A^2 B / 2 (module docstring; A, B those of ``running_admittance``)."""
    R_s, L_sigma, R_R, L_M = (float(v) for v in params)
    rotor = R_R / L_M - 1j * w_r
    A = np.array([[-(R_s + R_R) / L_sigma, rotor / L_sigma], [R_R, -rotor]], dtype=complex)
    B = np.array([1.0 / L_sigma, 0.0], dtype=complex)
    E = _expm_2x2(A, 0.5 * hold) @ (A @ A @ B) / 2.0
    z = np.exp(1j * w * hold)
    return complex(np.linalg.solve(z * np.eye(2) - _expm_2x2(A, hold), E)[0])


def _solve_L_M(V, I, variance, known, w_r, w, hold, start, moment=0.0):
    from scipy.optimize import least_squares

    def residual(theta):
        params = (*known, math.exp(theta[0]))
        Y = running_admittance(params, w_r, w, hold)
        model = Y * V
        if moment != 0.0:
            model = model + ripple_admittance(params, w_r, w, hold) * moment
        error = (I - model) / math.sqrt(variance)
        return np.array([error.real, error.imag])

    return least_squares(residual, [math.log(start)], method="lm", xtol=1e-12, ftol=1e-12)


@checked(log=Instance(NoLoadLog), given=optional(POSITIVE), given_field=TEXT)
def link_voltage(log: NoLoadLog, given: float | None = None,
                 given_field: str = "given") -> float | None:  # fmt: skip
    """The link voltage [V] of the run (module docstring): the mean of the log's ``v_dc``
    column, checked to stay within ``LINK_RTOL`` of it and, if a voltage is ``given`` (named
    ``given_field`` in messages), to agree with it within ``LINK_RTOL``; else ``given``
    (checked > 0); None if neither."""
    if given is not None:
        require_positive(given_field, given)
    if log.v_dc is None:
        return None if given is None else float(given)
    where = f"{log.source}: column 'v_dc'"
    column = np.asarray(log.v_dc, dtype=float)
    mean = float(np.mean(column))
    if not mean > 0.0:
        raise InputError(where, f"the DC-link voltage must be > 0, its mean is {mean:g} V")
    worst = float(np.max(np.abs(column - mean))) / mean
    if worst > LINK_RTOL:
        raise InputError(where, f"must stay within {LINK_RTOL:.0%} of its mean {mean:.6g} V (the "
                         f"model takes one link voltage), it deviates by {worst:.2%}")  # fmt: skip
    if given is not None and abs(given - mean) > LINK_RTOL * mean:
        raise InputError(f"{given_field} and {where}", f"must agree within {LINK_RTOL:.0%}: "
                         f"{given:g} V given, the column's mean is {mean:.6g} V (give one, or "
                         "correct the other)")  # fmt: skip
    return mean


@checked(
    log=Instance(NoLoadLog), frequency=POSITIVE, settle=NONNEGATIVE, n_p=COUNT,
    standstill=Attributes("params", "cov", "draws", what="the standstill test's ImpedanceFit"),
    seed=SEED, bootstrap=COUNT0, v_dc=optional(POSITIVE),
)
def fit_no_load(log: NoLoadLog, frequency: float, settle: float, n_p: int, standstill,
                seed: int = 0, bootstrap: int = BOOTSTRAP_COUNT,
                v_dc: float | None = None) -> NoLoadFit:  # fmt: skip
    """L_M of a no-load run (module docstring), with R_s, L_sigma, R_R and their covariance from
    ``standstill`` (an ``ImpedanceFit`` of the standstill injection). The link voltage of the
    run, ``v_dc`` [V] or the log's ``v_dc`` column (``link_voltage``), adds the switching
    pattern's second-order term to the model (module docstring); neither leaves it out."""
    v_dc = link_voltage(log, v_dc, "v_dc")
    V, I, variance, hold, speed = _phasors(log, frequency, settle)
    moment = 0.0
    if v_dc is not None:
        moment = pulse_moment(V, frequency, hold, float(v_dc), round(1.0 / (frequency * hold)))
    w = 2.0 * math.pi * frequency
    w_r = n_p * speed
    values = standstill.params.as_array()
    known = values[:3]
    fit = _solve_L_M(V, I, variance, known, w_r, w, hold, values[3], moment)
    residual = float(math.sqrt(2.0 * fit.cost * variance))
    if not fit.success or not np.isfinite(fit.x[0]):
        raise FitNotConverged("no-load run", fit.message, residual, "A (current error at f)")
    L_M = math.exp(fit.x[0])
    J = fit.jac[:, 0] / L_M  # d residual / d L_M = (d residual / d log L_M) / L_M
    var = 1.0 / float(J @ J)
    g = np.empty(3)
    for j in range(3):
        step = 1e-4 * known[j]
        up, down = known.copy(), known.copy()
        up[j] += step
        down[j] -= step
        g[j] = (math.exp(_solve_L_M(V, I, variance, up, w_r, w, hold, L_M, moment).x[0])
                - math.exp(_solve_L_M(V, I, variance, down, w_r, w, hold, L_M, moment).x[0])) / (2 * step)  # fmt: skip
    var += float(g @ standstill.cov[:3, :3] @ g)
    rng = np.random.default_rng(seed)
    Y = running_admittance((*known, L_M), w_r, w, hold)
    response = Y * V + ripple_admittance((*known, L_M), w_r, w, hold) * moment
    draws = np.empty(bootstrap)
    sources = standstill.draws[np.all(np.isfinite(standstill.draws), axis=1)]
    for b in range(bootstrap):
        noise = math.sqrt(variance) * (rng.standard_normal() + 1j * rng.standard_normal())
        drawn = sources[rng.integers(sources.shape[0]), :3] if sources.size else known
        refit = _solve_L_M(V, response + noise, variance, drawn, w_r, w, hold, L_M, moment)
        draws[b] = math.exp(refit.x[0]) if refit.success else math.nan
    half = Z_95 * math.sqrt(var)
    estimate = Estimate("L_M", "H", "magnetising inductance of the inverse-Gamma circuit at the "
                        "no-load run's flux", L_M, (L_M - half, L_M + half),
                        percentile_interval(draws))  # fmt: skip
    if not half / L_M <= MAX_HALF_WIDTH:
        raise InputError("L_M", f"not identified by this run: its 95 % interval is "
                         f"+-{half / L_M:.0%} of the value, at most +-{MAX_HALF_WIDTH:.0%}")  # fmt: skip
    slip = 1.0 - w_r / w
    return NoLoadFit(estimate, frequency, speed, slip, residual, v_dc)


@checked(path=PATH, field=TEXT)
def read_no_load_log(path, field: str = "path") -> NoLoadLog:
    """The no-load log in ``path`` (CSV, Parquet or .mat), every rule of ``identify._log``; the
    column ``v_dc`` [V] may be added (``NO_LOAD_OPTIONAL``)."""
    from acdrive.identify._log import read_columns

    values = read_columns(path, NO_LOAD_COLUMNS, "no-load", field, optional=NO_LOAD_OPTIONAL)
    return NoLoadLog(values["time"], values["v_a"], values["i_a"], values["w"], field,
                     values.get("v_dc"))  # fmt: skip


@checked(log=Instance(NoLoadLog), path=PATH)
def write_no_load_log(log: NoLoadLog, path):
    """Write a no-load log as CSV, Parquet or .mat (by the suffix of ``path``), with its
    ``v_dc`` column if it has one."""
    from acdrive.identify._log import write_columns

    columns = {"time": log.time, "v_a": log.v_a, "i_a": log.i_a, "w": log.w}
    spec = dict(NO_LOAD_COLUMNS)
    if log.v_dc is not None:
        columns["v_dc"] = log.v_dc
        spec |= NO_LOAD_OPTIONAL
    return write_columns(columns, spec, path)
