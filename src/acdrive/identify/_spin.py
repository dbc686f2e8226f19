"""A PM machine's magnet flux (back-EMF constant) from a short-circuit spin test.

**The test.** A dynamometer drives the rotor at a few constant speeds (``SpinPlan.speeds``
[rad/s], each held ``hold`` seconds) while the inverter holds the three terminals at the same
potential (a zero voltage command: every leg at the same duty, no line voltage). The magnet's
back-EMF then drives the short-circuit current, limited by the winding: at constant electrical
speed w_r = n_p w, Ugalde-Loo et al. (7) in steady state with v_d = v_q = 0 give

    R_s i_d - w_r L_q i_q = 0,   R_s i_q + w_r L_d i_d = -w_r psi_pm,

so the phase current is a sinusoid at w_r whose phase-peak amplitude is

    I(w_r) = psi_m g(w_r),   g = w_r sqrt(R_s^2 + w_r^2 L_q^2) / (R_s^2 + w_r^2 L_d L_q)

(psi_pm = sqrt(3/2) psi_m and |i_s| = sqrt(3/2) I: the scaling cancels). A short circuit instead
of an open-circuit voltage measurement keeps the test on the drive's own current sensor and
the log of every other test (``time [s]``, ``v_a [V]``, ``i_a [A]``, ``w [rad/s]``); it needs
R_s, L_d, L_q, from the standstill tests (``identify._pm``). At low speed (w_r L << R_s) the
current is about w_r psi_m / R_s, at high speed it tends to psi_m / L_d: the speeds chosen keep
it within the machine's rating, and the estimate leans on R_s or L_d accordingly. The braking
torque the dynamometer supplies is reported (``SpinTest.braking_torque``).

**The estimator.** Plateaus are the runs of constant logged speed (within ``SPEED_RTOL``), each
used after ``settle`` seconds; on each the current's amplitude at w_r is the least-squares fit of
a cosine, a sine and an offset, with its standard error from that fit's residual. psi_m is the
weighted least-squares line through the origin of the amplitudes against g (closed form). 95 %
intervals: the weighted fit's variance plus what the standstill covariance of (R_s, L_d, L_q)
carries into it (central differences; z quantile, the amplitudes averaging thousands of
samples); and a bootstrap redrawing each amplitude with its standard error and R_s, L_d, L_q from
the standstill bootstrap draws. Rules (``InputError`` naming the column or parameter): a plateau
must hold ``MIN_PERIODS`` electrical periods after ``settle`` with ``SAMPLES_PER_PERIOD`` samples
each; the command must be zero (a short circuit); psi_m's interval within +-50 %.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from acdrive._arguments import (
    COUNT,
    COUNT0,
    NONNEGATIVE,
    PATH,
    POSITIVE,
    RESULT,
    SEED,
    TEXT,
    Array,
    Instance,
    Items,
    checked,
)
from acdrive.errors import InputError, require_positive
from acdrive.identify._dc import Z_95
from acdrive.identify._experiment import CurrentSensor, StandstillPlan, run_test
from acdrive.identify._fit import BOOTSTRAP_COUNT, Estimate, percentile_interval
from acdrive.identify._no_load import NO_LOAD_COLUMNS

#: the spin log's columns: those of the no-load run (``identify._no_load``)
SPIN_COLUMNS = NO_LOAD_COLUMNS
SPEED_RTOL = 1e-3
MIN_PERIODS = 5
SAMPLES_PER_PERIOD = 10
MAX_HALF_WIDTH = 0.5


@checked(
    speeds=Items(POSITIVE), hold=POSITIVE, settle=NONNEGATIVE, f_pwm=POSITIVE, v_dc=POSITIVE,
    t_d=NONNEGATIVE, v_drop=NONNEGATIVE, sensor=Instance(CurrentSensor),
)
@dataclass(frozen=True)
class SpinPlan:
    """The spin test (module docstring): ``speeds`` [rad/s, mechanical], each held ``hold``
    [s] of which the first ``settle`` [s] are not used, on the bench of ``f_pwm``, ``v_dc``,
    ``t_d``, ``v_drop`` and ``sensor`` (as ``StandstillPlan``)."""

    speeds: tuple[float, ...] = (20.0, 40.0, 60.0)
    hold: float = 1.0
    settle: float = 0.2
    f_pwm: float = 5000.0
    v_dc: float = 24.0
    t_d: float = 0.0
    v_drop: float = 0.0
    sensor: CurrentSensor = field(default_factory=CurrentSensor)

    def __post_init__(self):
        require_positive("hold", self.hold)
        if not self.speeds or any(not s > 0.0 for s in self.speeds):
            raise InputError("speeds", "needs one speed or more, each > 0")
        if not 0.0 <= self.settle < self.hold:
            raise InputError("settle", "must be >= 0 and shorter than hold")


@checked(time=Array(1), v_a=Array(1), i_a=Array(1), w=Array(1), source=TEXT)
@dataclass(frozen=True)
class SpinLog:
    """A spin test: equal-length ``time`` [s], ``v_a`` [V], ``i_a`` [A], ``w`` [rad/s]."""

    time: np.ndarray
    v_a: np.ndarray
    i_a: np.ndarray
    w: np.ndarray
    source: str = "log"


@checked(log=Instance(SpinLog), braking_torque=RESULT)
@dataclass(frozen=True)
class SpinTest:
    """A simulated spin test: its ``log`` and the peak braking torque the dynamometer held."""

    log: SpinLog
    braking_torque: float


@checked(machine=Instance("acdrive.machines._pmsm:PMSGParams"), plan=Instance(SpinPlan), seed=SEED)
def spin_test(machine, plan: SpinPlan, seed: int = 5) -> SpinTest:
    """The short-circuit spin test of ``plan`` on the PM machine ``machine`` (module
    docstring): one run per speed, the logs joined end to end."""
    bench = StandstillPlan(f_pwm=plan.f_pwm, v_dc=plan.v_dc, t_d=plan.t_d, v_drop=plan.v_drop,
                           sensor=plan.sensor)  # fmt: skip
    parts, torque = [], []
    for k, speed in enumerate(plan.speeds):
        log = run_test(machine, bench, np.zeros_like, plan.hold, seed + k, "simulated spin test",
                       torque=torque, speed=speed)  # fmt: skip
        # each run continues one sample after the previous one's last (a uniform log)
        offset = parts[-1][0][-1] + 1.0 / plan.f_pwm - log.time[0] if parts else 0.0
        parts.append((log.time + offset, log.v_a, log.i_a, np.full(log.time.size, speed)))
    time, v_a, i_a, w = (np.concatenate(c) for c in zip(*parts, strict=True))
    return SpinTest(SpinLog(time, v_a, i_a, w, "simulated spin test"),
                    float(max(np.max(np.abs(t)) for t in torque)))  # fmt: skip


@checked(values=Array(1), w_r=Array())
def short_circuit_gain(values, w_r) -> np.ndarray:
    """g(w_r) [A/Wb] = I / psi_m of the module docstring; ``values`` = (R_s, L_d, L_q)."""
    R, L_d, L_q = (float(v) for v in values)
    w_r = np.asarray(w_r, dtype=float)
    return w_r * np.sqrt(R * R + (w_r * L_q) ** 2) / (R * R + w_r * w_r * L_d * L_q)


@dataclass(frozen=True)
class Plateau:
    """One speed plateau: ``speed`` [rad/s], current ``amplitude`` [A] and its ``stderr``."""

    speed: float
    amplitude: float
    stderr: float


def plateaus(log: SpinLog, n_p: int, settle: float) -> list[Plateau]:
    """The speed plateaus of ``log`` and their current amplitudes (module docstring)."""
    where = f"{log.source}: column 'w'"
    if np.any(log.v_a != 0.0):
        raise InputError(f"{log.source}: column 'v_a'", "a short-circuit spin test commands zero "
                         "voltage throughout")  # fmt: skip
    hold = float(np.median(np.diff(log.time)))
    change = np.abs(np.diff(log.w)) > SPEED_RTOL * np.maximum(np.abs(log.w[:-1]), 1e-9)
    edges = np.concatenate(([0], np.flatnonzero(change) + 1, [log.w.size]))
    found = []
    for start, stop in itertools.pairwise(edges):
        speed = float(np.mean(log.w[start:stop]))
        if speed == 0.0:
            continue
        w_r = n_p * abs(speed)
        if 2.0 * math.pi / (w_r * hold) < SAMPLES_PER_PERIOD:
            raise InputError(f"{log.source}: column 'time'", f"sampling at {1 / hold:g} Hz is too "
                             f"coarse for the plateau at {speed:g} rad/s: at least "
                             f"{SAMPLES_PER_PERIOD} samples per electrical period")  # fmt: skip
        first = start + int(np.searchsorted(log.time[start:stop], log.time[start] + settle))
        t, i = log.time[first:stop], log.i_a[first:stop]
        if t.size == 0 or (t[-1] - t[0]) * w_r < 2.0 * math.pi * MIN_PERIODS:
            raise InputError(where, f"the plateau at {speed:g} rad/s must hold {MIN_PERIODS} "
                             f"electrical periods after {settle:g} s of settling")  # fmt: skip
        basis = np.column_stack((np.cos(w_r * t), np.sin(w_r * t), np.ones(t.size)))
        coef, *_ = np.linalg.lstsq(basis, i, rcond=None)
        residual = i - basis @ coef
        s2 = float(residual @ residual) / (t.size - 3)
        cov = s2 * np.linalg.inv(basis.T @ basis)[:2, :2]
        amplitude = float(math.hypot(coef[0], coef[1]))
        direction = coef[:2] / amplitude
        found.append(Plateau(speed, amplitude, float(math.sqrt(direction @ cov @ direction))))
    if not found:
        raise InputError(where, "no plateau of constant nonzero speed")
    return found


@checked(psi_m=Instance(Estimate), plateaus=Items(Instance(Plateau)), residual=RESULT)
@dataclass(frozen=True)
class SpinFit:
    """psi_m with its intervals, the plateaus and the residual (rms of the amplitudes' errors
    over their standard errors)."""

    psi_m: Estimate
    plateaus: tuple[Plateau, ...]
    residual: float


def _psi(amplitude, stderr, gain) -> float:
    weight = 1.0 / stderr**2
    return float(np.sum(weight * gain * amplitude) / np.sum(weight * gain * gain))


@checked(
    log=Instance(SpinLog), n_p=COUNT, settle=NONNEGATIVE,
    standstill=Instance("acdrive.identify._pm:PMStandstillIdentification"), seed=SEED,
    bootstrap=COUNT0,
)
def fit_spin(log: SpinLog, n_p: int, settle: float, standstill, seed: int = 0,
             bootstrap: int = BOOTSTRAP_COUNT) -> SpinFit:  # fmt: skip
    """psi_m of a spin log (module docstring), with R_s, L_d, L_q from ``standstill`` (a
    ``PMStandstillIdentification``)."""
    found = plateaus(log, n_p, settle)
    speed = np.array([n_p * abs(p.speed) for p in found])
    amplitude = np.array([p.amplitude for p in found])
    stderr = np.array([p.stderr for p in found])
    values = np.array([standstill.value(n) for n in ("R_s", "L_d", "L_q")])
    gain = short_circuit_gain(values, speed)
    psi = _psi(amplitude, stderr, gain)
    var = 1.0 / float(np.sum(gain * gain / stderr**2))
    # the standstill covariance: R_s (combined) with each axis's inductance as its own fit gave
    cov = _standstill_cov(standstill)
    grad = np.empty(3)
    for j in range(3):
        step = 1e-6 * values[j]
        up, down = values.copy(), values.copy()
        up[j] += step
        down[j] -= step
        grad[j] = (_psi(amplitude, stderr, short_circuit_gain(up, speed))
                   - _psi(amplitude, stderr, short_circuit_gain(down, speed))) / (2 * step)  # fmt: skip
    var += float(grad @ cov @ grad)
    half = Z_95 * math.sqrt(var)
    rng = np.random.default_rng(seed)
    d, q = standstill.d.draws, standstill.q.draws
    w_d = standstill.q.cov[0, 0] / (standstill.d.cov[0, 0] + standstill.q.cov[0, 0])
    draws = np.empty(bootstrap)
    for b in range(bootstrap):
        k = rng.integers(min(d.shape[0], q.shape[0]))
        drawn = np.array([w_d * d[k, 0] + (1.0 - w_d) * q[k, 0], d[k, 1], q[k, 1]])
        if not np.all(np.isfinite(drawn)):
            drawn = values
        redrawn = psi * gain + stderr * rng.standard_normal(stderr.size)
        draws[b] = _psi(redrawn, stderr, short_circuit_gain(drawn, speed))
    estimate = Estimate("psi_m", "Wb", "magnet flux linkage, peak per phase (short-circuit "
                        "spin test)", psi, (psi - half, psi + half),
                        percentile_interval(draws))  # fmt: skip
    if not half / psi <= MAX_HALF_WIDTH:
        raise InputError("psi_m", f"not identified by this test: its 95 % interval is "
                         f"+-{half / psi:.0%} of the value, at most +-{MAX_HALF_WIDTH:.0%}")  # fmt: skip
    chi = (amplitude - psi * gain) / stderr
    return SpinFit(estimate, tuple(found), float(np.sqrt(np.mean(chi**2))))


def _standstill_cov(standstill) -> np.ndarray:
    """Covariance of (R_s, L_d, L_q) from a ``PMStandstillIdentification``: R_s's combined
    variance, each inductance's own, and R_s with L_x through the axis fit's covariance (times
    that axis's weight in the combination)."""
    var_r = 1.0 / (1.0 / standstill.d.cov[0, 0] + 1.0 / standstill.q.cov[0, 0])
    cov = np.zeros((3, 3))
    cov[0, 0] = var_r
    weights = [var_r / fit.cov[0, 0] for fit in (standstill.d, standstill.q)]
    for j, (fit, weight) in enumerate(zip((standstill.d, standstill.q), weights, strict=True)):
        cov[j + 1, j + 1] = fit.cov[1, 1]
        cov[0, j + 1] = cov[j + 1, 0] = weight * fit.cov[0, 1]
    return cov


@checked(path=PATH, field=TEXT)
def read_spin_log(path, field: str = "path") -> SpinLog:
    """The spin log in ``path`` (CSV, Parquet or .mat), every rule of ``identify._log``."""
    from acdrive.identify._log import read_columns

    values = read_columns(path, SPIN_COLUMNS, "spin-test", field)
    return SpinLog(values["time"], values["v_a"], values["i_a"], values["w"], field)


@checked(log=Instance(SpinLog), path=PATH)
def write_spin_log(log: SpinLog, path):
    """Write a spin log as CSV, Parquet or .mat (by the suffix of ``path``)."""
    from acdrive.identify._log import write_columns

    columns = {"time": log.time, "v_a": log.v_a, "i_a": log.i_a, "w": log.w}
    return write_columns(columns, SPIN_COLUMNS, path)
