"""The inverse-Gamma parameters from a single-axis multisine injection at standstill.

**Why the frequency domain.** The injection is periodic, so after the transient the log's
Fourier coefficients at the injected frequencies hold all it says about the machine: a handful
of complex numbers instead of tens of thousands of samples, each with (for white sensor noise)
the same noise variance, and a model that is exact without simulating anything: the sampled,
zero-order-hold admittance Y_d(e^{jwT}) of the standstill circuit (``identify._circuit``). The
time-domain alternative (simulate the circuit over the log and fit the samples) would need the
initial transient modelled or discarded anyway, and costs a simulation per iteration.

**The window.** The first ``settle`` seconds are dropped; of the rest, the largest whole number of
periods of the base frequency f_0 (the step between tones: every tone is a multiple of it) is
analysed, the last ones of the log. A period must be a whole number of samples. The excited
tones are the bins at multiples of f_0 whose commanded voltage exceeds ``EXCITED_FRACTION`` of
the largest (DC excluded): what the experimenter injected, before any compensation.

**Voltage error.** The log's voltage is the command; the inverter applied v_a - U sign(i_a)
(``identify._dc``). Given the voltage error U of a DC-step fit, the estimator compensates the
logged voltage by it at the tones (command - U times the coefficients of sign(i_a)); without it,
the dead time acts on the tones as a resistance-like describing function and biases R_s and R_R.
U is itself an estimate: its standard error s_U, given, adds g g^T s_U^2 to the covariance
(g = dp/dU from two refits at U +- s_U), and each bootstrap refit draws its own U from
N(U, s_U^2).

**Which sign.** The inverter's error follows the sign of the true current at each sample; the
sign of the noisy reading is wrong wherever the current is within a few noise deviations of
zero, and its mean there is a smoothed step (E sign(i + n) = erf(i / (sqrt 2 s))), not the
inverter's. Measured on the Ugalde-Loo IM (40 noise draws on one noise-free run, the true U
compensated): with the reading's sign R_s came out 1.2e-3 high and R_R, L_M 1.1e-3 low, with
five times the spread of the estimates from the true current's sign, which were unbiased
within 1e-4. Worse, where the current
approaches zero the dead time clamps it there: the inverter's polarity flips from one sample to
the next, and no smoothing of the reading recovers that pattern. The estimator therefore takes
the sign the inverter itself saw: that of the current the fitted circuit draws from the logged
command with the voltage error fed back sample by sample (``identify._polarity``). It fits
first with the reading's sign, then ``POLARITY_ROUNDS`` times with the sign of the current
simulated from the previous fit. Where the inverter clamps the current at zero, the reading
there is noise around zero and its sign flickers; on motulator's 2.2 kW IM behind its
carrier-comparison inverter (2 us, 1 V, 540 V, tones of 15 V against an 8.5 V error; 7 % of the
window's samples within 0.05 A of zero) that first fit went to L_M = 4.5e11 H, from where no
simulated sign recovers. A compensated fit that ends with a larger residual than the
uncompensated one has started from a wrong sign: the rounds are then run from the
uncompensated fit (a passive circuit whose resistances carry the error) until the simulated
sign repeats (at most ``FAR_ROUNDS``); on that noise-free log they end within 9e-3 of
R_s, L_sigma, R_R, L_M (``benchmarks/coverage_motulator.py``).

**Held or clamped at a zero crossing.** The simulated sign is held over each period (acdrive's
inverter part does the same); a real inverter takes each leg's direction at each switching edge
and holds a current that its error drives towards zero at zero (``identify._polarity``). The two
bracket a bench: on the noise-free motulator log above, the held sign leaves R_s, L_sigma, R_R,
L_M off by -6.8e-4, +8.8e-3, +1.5e-3, +6.7e-4 and the clamping one by +9.7e-4, -4.2e-3,
-1.6e-3, -2.5e-3, with a residual of 1.0e-3 A against the held sign's 2.4e-3 A. When the
residual is above the noise floor (below), the fit is repeated with the clamping polarity, and
if that explains the log at least as well (a residual no larger), the difference d of the two
estimates adds d d^T to the covariance. On acdrive's own bench, whose inverter holds the sign,
the held fit explains the log better and the intervals stay as they were.
The estimate's own noise then moves the sign it is compensated
with; its intervals include that feedback (``_polarity.feedback_gain``). This applies to every
model that declares its winding's state space (``AdmittanceModel.state_space``: the cage IM's
circuit, a PM axis, the DFIM's rotor open or shorted). A failure mode, measured on the BLY171D
with tones of about half the voltage error (docs/guide/identification.md): where the current is
clamped near zero much of the time, the iteration can settle on a self-consistent sign away from
the truth (L_d 2 % low), with intervals wide enough to hold the truth.

**Dead time also moves the sample instant.** The voltage error is what dead time does to a
period's mean voltage; it also shifts every switching pulse t_d / 2 later, so the current is
sampled on the ripple's slope instead of at its symmetric point. Measured on the noise-free
bench (t_d = 2 us, no device drop, the true U compensated), that alone leaves R_s, L_sigma, R_R,
L_M low by 1.4e-4, 3.1e-4, 4.3e-4, 2.6e-4, while a device drop of the same U leaves the ideal
inverter's few 1e-5. Given the programmed dead time, the model reads its current t_d / 2 early
(``identify._winding``, for any model with a state space).

**The fit.** ``least_squares`` of the current residuals I_k - Y_d(w_k; p) V_k (real and
imaginary parts) over log-parameters (positive by construction); their maximum-likelihood
weight is one for white current noise. 95 % intervals: Jacobian covariance scaled by the residual
variance with Student's t over 2K - 4 degrees of freedom, and a bootstrap redrawing the K complex
residuals (inflated by sqrt(2K / (2K - 4)) for the fitted degrees of freedom) (``identify._fit``).
The terms the resampled noise cannot carry (the compensated delay's uncertainty, the model-error
terms below) are added to the Jacobian covariance and, as a Gaussian draw of the same covariance,
to each bootstrap refit, so both intervals carry them.

**Judged by its own data** (``identify._judge``): the residual against the noise floor of the
off-tone bins (a model-error term and a warning above it), and the current's timing against the
voltage by a joint delay fit (a row's shift refused naming ``i_a``, a smaller delay compensated
and named).

**Plausibility**, checked before the fit: every tone carries current, and the winding absorbs
power at every tone (Re(V conj(I)) > 0: a reversed current sign or another phase's current is
refused, naming ``i_a``).

**Identifiability**, checked on the fit, each an ``InputError`` naming the parameter and the rule:
at least ``MIN_TONES`` tones; at least ``SAMPLES_PER_TONE`` samples per period of the highest
tone; the tones must bracket the fitted rotor corner R_R / (2 pi L_M) (all tones far below it
cannot separate L_sigma from R_R, all far above it cannot see L_M); and every parameter's 95 %
interval within +-``MAX_HALF_WIDTH`` of its value.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from acdrive._arguments import (
    COUNT0,
    FLAG,
    NONNEGATIVE,
    POSITIVE,
    REAL,
    SEED,
    TEXT,
    Function,
    Instance,
    Items,
    checked,
    optional,
)
from acdrive.errors import InputError, require_nonnegative, require_positive
from acdrive.identify._circuit import (
    INVERSE_GAMMA,
    InverseGamma,
    standstill_impedance,
    standstill_state_space,
)
from acdrive.identify._experiment import StandstillLog
from acdrive.identify._fit import (
    BOOTSTRAP_COUNT,
    Estimate,
    FitNotConverged,
    covariance,
    jacobian_interval,
    percentile_interval,
    t_quantile,
)
from acdrive.identify._judge import (
    RESIDUAL_FACTOR,
    DelayFit,
    fit_delay,
    jackknife_covariance,
    off_tone_noise,
)
from acdrive.identify._polarity import feedback_gain, simulated_polarity
from acdrive.identify._winding import sampled_response

EXCITED_FRACTION = 1e-2
MIN_TONES = 3
SAMPLES_PER_TONE = 10
MAX_HALF_WIDTH = 0.5
#: tones below this many times the compensated voltage error are named as a model error's cause
TONE_MARGIN = 2.0
#: refits with the sign of the current simulated from the previous fit (module docstring)
POLARITY_ROUNDS = 2
#: at most this many such refits from the uncompensated fit or towards the clamping inverter's
#: fit, fewer when the simulated sign repeats (module docstring)
FAR_ROUNDS = 10
#: the polarity's feedback is measured by secants of this many noise deviations of each parameter
FEEDBACK_STEP_SIGMAS = 2.0
#: a period is a whole number of samples to this relative tolerance
_WHOLE_RTOL = 1e-6


@dataclass(frozen=True)
class Spectrum:
    """The analysed window's Fourier coefficients at the excited tones: ``frequency`` [Hz],
    ``voltage`` [V] (compensated) and ``current`` [A] (complex amplitudes), the sample ``hold``
    [s]; ``command`` [V] is the voltage before compensation and ``polarity`` the coefficients of
    sign(i_a), so the voltage for an error U is command - U polarity."""

    frequency: np.ndarray
    voltage: np.ndarray
    current: np.ndarray
    hold: float
    periods: int
    command: np.ndarray
    polarity: np.ndarray
    noise: float = float("nan")
    noise_bins: int = 0

    def compensated(self, voltage_error: float, current=None) -> Spectrum:
        """This spectrum with the voltage compensated by ``voltage_error`` (and ``current``
        replacing the measured one, for the bootstrap)."""
        return replace(self, voltage=self.command - voltage_error * self.polarity,
                       current=self.current if current is None else current)  # fmt: skip

    def advanced(self, delay: float) -> Spectrum:
        """This spectrum with its current read ``delay`` [s] earlier (a current logged late by
        ``delay``, re-aligned: I_k e^{j w_k delay}; ``identify._judge``)."""
        turn = np.exp(2j * np.pi * self.frequency * delay)
        return replace(self, current=self.current * turn)

    def subset(self, keep: np.ndarray) -> Spectrum:
        """The tones selected by the boolean ``keep`` only (the jackknife's refits)."""
        return replace(self, frequency=self.frequency[keep], voltage=self.voltage[keep],
                       current=self.current[keep], command=self.command[keep],
                       polarity=self.polarity[keep])  # fmt: skip


@dataclass(frozen=True)
class ImpedanceFit:
    """The fitted inverse-Gamma parameters (``estimates`` in ``_circuit.NAMES`` order) with their
    intervals, the spectrum fitted, the residual (rms [A] and relative to the currents), the
    degrees of freedom, the voltage error compensated and the bootstrap draws; how the fit
    judged itself (``identify._judge``): ``residual_ratio`` its residual's rms over the noise
    floor of the off-tone bins (NaN: not judged), ``timing`` the joint delay fit (None: not
    run), ``delay`` the current's delay [s] compensated (0: none), ``model_error`` whether the
    jackknife's model-error term is in ``cov``, and ``warnings`` one line per finding."""

    estimates: tuple[Estimate, ...]
    spectrum: Spectrum
    residual_rms: float
    residual_relative: float
    dof: int
    voltage_error: float | None
    draws: np.ndarray
    cov: np.ndarray
    model: AdmittanceModel | None = None
    residual_ratio: float = float("nan")
    timing: DelayFit | None = None
    delay: float = 0.0
    model_error: bool = False
    warnings: tuple[str, ...] = ()
    source: str = "log"

    @property
    def noise_rms(self) -> float:
        """The noise floor [A]: the deviation of a real or imaginary part of a tone's current
        coefficient, from the off-tone bins (``identify._judge``)."""
        return math.sqrt(self.spectrum.noise)

    @property
    def params(self):
        """The parameter record of the model fitted (``InverseGamma`` for the cage IM)."""
        model = INVERSE_GAMMA_MODEL if self.model is None else self.model
        return model.record([e.value for e in self.estimates])

    def measured_impedance(self) -> np.ndarray:
        """V_k / I_k at the tones [ohm]: the log's own impedance, sampled-data effects included."""
        return self.spectrum.voltage / self.spectrum.current

    def fitted_impedance(self) -> np.ndarray:
        """Z(jw) of the fitted circuit at the tones [ohm] (continuous time)."""
        return standstill_impedance(self.params, 2.0 * math.pi * self.spectrum.frequency)


def spectrum(log: StandstillLog, base_frequency: float, settle: float,
             voltage_error: float | None = None) -> Spectrum:  # fmt: skip
    """The window and tones of ``log`` (module docstring)."""
    require_positive("base_frequency", base_frequency)
    if not (math.isfinite(settle) and settle >= 0.0):
        raise InputError("settle", "must be a finite number >= 0")
    where = f"{log.source}: column 'time'"
    hold = float(np.median(np.diff(log.time)))
    per_period = 1.0 / (base_frequency * hold)
    samples = round(per_period)
    if samples < 1 or abs(per_period - samples) > _WHOLE_RTOL * per_period:
        raise InputError("base_frequency", f"a period 1 / {base_frequency:g} Hz must be a whole "
                         f"number of samples of {hold:.6g} s, got {per_period:.6g}")  # fmt: skip
    first = int(np.searchsorted(log.time, log.time[0] + settle - 0.5 * hold))
    periods = (log.time.size - first) // samples
    if periods < 1:
        raise InputError(where, f"too short: needs {settle:g} s to settle and at least one period "
                         f"1 / {base_frequency:g} Hz after it, the log has "
                         f"{log.time[-1] - log.time[0] + hold:g} s")  # fmt: skip
    n = periods * samples
    v, i = log.v_a[-n:], log.i_a[-n:]
    V = np.fft.rfft(v) * (2.0 / n)
    I = np.fft.rfft(i) * (2.0 / n)
    bins = np.arange(periods, V.size, periods)  # multiples of the base frequency, DC excluded
    strongest = np.max(np.abs(V[bins])) if bins.size else 0.0
    excited = bins[np.abs(V[bins]) > EXCITED_FRACTION * strongest] if strongest > 0.0 else bins[:0]
    polarity = np.fft.rfft(np.sign(i)) * (2.0 / n)
    if excited.size < MIN_TONES:
        raise InputError(f"{log.source}: column 'v_a'", f"the injected voltage must excite at "
                         f"least {MIN_TONES} tones at multiples of {base_frequency:g} Hz, found "
                         f"{excited.size}" + (" (the column is zero)" if strongest == 0.0 else ""))  # fmt: skip
    frequency = (excited // periods) * base_frequency
    if frequency[-1] * hold * SAMPLES_PER_TONE > 1.0 + 1e-12:
        raise InputError(where, f"sampling at {1 / hold:g} Hz is too coarse for the tone at "
                         f"{frequency[-1]:g} Hz: at least {SAMPLES_PER_TONE} samples per period")  # fmt: skip
    current = I[excited]
    if np.any(current == 0.0):
        raise InputError(f"{log.source}: column 'i_a'", "carries no current at the injected "
                         "tones (is the motor connected and the current the phase-a one?)")  # fmt: skip
    # twice the mean power at each tone, the sampled current advanced by the half hold period
    # the zero-order hold delays it (identify._circuit.sampled_admittance, far below 1 / T)
    power = (V[excited] * np.conj(current * np.exp(1j * np.pi * frequency * hold))).real
    if np.any(power <= 0.0):
        bad = frequency[int(np.argmax(power <= 0.0))]
        raise InputError(f"{log.source}: column 'i_a'", f"the winding would deliver power at "
                         f"{bad:g} Hz (Re(V conj(I)) <= 0; a passive winding absorbs it): the "
                         "current's sign is reversed or it is not phase a's")  # fmt: skip
    # the tones are the command's; the voltage is what was applied
    U = 0.0 if voltage_error is None else voltage_error
    applied = V[excited] - U * polarity[excited]
    noise, noise_bins = off_tone_noise(I, periods, excited)
    return Spectrum(frequency, applied, I[excited], hold, periods, V[excited], polarity[excited],
                    noise, noise_bins)  # fmt: skip


def _tone_coefficients(x: np.ndarray, spec: Spectrum, base_frequency: float) -> np.ndarray:
    """The Fourier coefficients of the log-length series ``x`` at the tones of ``spec``, over
    the same window (``spectrum``)."""
    samples = round(1.0 / (base_frequency * spec.hold))
    n = spec.periods * samples
    bins = np.round(spec.frequency / base_frequency).astype(int) * spec.periods
    return (np.fft.rfft(x[-n:]) * (2.0 / n))[bins]


#: the residual of a parameter set that leaves the physical range (a solver's wild trial step)
_FAR = 1e6


def _residual(theta, spec: Spectrum, model: AdmittanceModel):
    with np.errstate(all="ignore"):
        params = np.exp(theta)
        try:
            Y = model.admittance(params, 2.0 * np.pi * spec.frequency, spec.hold)
        except (np.linalg.LinAlgError, ZeroDivisionError):  # a parameter underflowed to zero
            Y = np.full(spec.frequency.size, np.nan)
    error = spec.current - Y * spec.voltage
    if not np.all(np.isfinite(error)):
        error = np.full(error.size, _FAR * (1.0 + 1.0j))
    return np.concatenate((error.real, error.imag))


def _start(spec: Spectrum) -> np.ndarray:
    """A starting point read off the measured impedance: R_s and L_sigma + L_M from the lowest
    tone, L_sigma and R_s + R_R from the highest."""
    Z = spec.voltage / spec.current
    w = 2.0 * np.pi * spec.frequency
    R_s = max(Z[0].real, 1e-6)
    L_sigma = max(Z[-1].imag / w[-1], 1e-9)
    R_R = max(Z[-1].real - R_s, 0.1 * R_s)
    L_M = max(Z[0].imag / w[0] - L_sigma, L_sigma)
    return np.log([R_s, L_sigma, R_R, L_M])


@checked(
    fields=Items(Items(TEXT)), admittance=Function(), start=Function(), record=Function(),
    dead_time=NONNEGATIVE, state_space=Function(optional=True),
)
@dataclass(frozen=True)
class AdmittanceModel:
    """A winding at standstill as the fit sees it: its parameters ``fields`` ((name, unit,
    meaning), in fit order), ``admittance(values, w, hold)`` its zero-order-hold sampled
    admittance Y_d(e^{jwT}) [S], ``start(spectrum)`` a starting point (positive values) and
    ``record(values)`` the parameter record of the values; ``state_space(values)`` its (A, B)
    (``identify._winding``: what the dead-time compensation simulates and shifts; None: a model
    without one is fitted as given); ``dead_time`` [s] the inverter dead time its sample instant
    includes (``with_dead_time``)."""

    fields: tuple[tuple[str, str, str], ...]
    admittance: Callable
    start: Callable
    record: Callable
    dead_time: float = field(default=0.0)
    state_space: Callable | None = field(default=None)


def winding_model(fields, state_space: Callable, start: Callable, record: Callable):
    """The ``AdmittanceModel`` of a winding given by its state space (``identify._winding``):
    its admittance is the exact sampled one of that state space, so the fit and the dead-time
    compensation use one model."""

    def admittance(values, w, hold):
        return sampled_response(*state_space(values), w, hold)

    return AdmittanceModel(fields, admittance, start, record, state_space=state_space)


#: the cage IM at standstill: the inverse-Gamma circuit (``identify._circuit``)
INVERSE_GAMMA_MODEL = winding_model(
    INVERSE_GAMMA, standstill_state_space, lambda spec: np.exp(_start(spec)),
    InverseGamma.from_array,
)  # fmt: skip


def with_dead_time(model: AdmittanceModel, dead_time: float) -> AdmittanceModel:
    """``model`` with its current sampled t_d / 2 off the ripple's symmetric point by the
    inverter's dead time ``dead_time`` [s] (``identify._winding``); 0: as is. The shift is the
    winding's free response, so the model must have a state space."""
    if dead_time == 0.0:
        return model
    state_space = model.state_space
    if state_space is None:
        raise InputError("dead_time", "the sample-offset model needs the winding's state space; "
                         "give 0 for a model without one")  # fmt: skip

    def admittance(values, w, hold):
        return sampled_response(*state_space(values), w, hold, dead_time)

    return replace(model, admittance=admittance, dead_time=dead_time)


def _solve(spec: Spectrum, theta0, tolerance: float = 1e-12, model=INVERSE_GAMMA_MODEL):
    from scipy.optimize import least_squares

    return least_squares(_residual, theta0, args=(spec, model), method="lm", xtol=tolerance,
                         ftol=tolerance, gtol=tolerance, max_nfev=2000)  # fmt: skip


#: tolerance of the bootstrap's refits, which start at the estimate: their percentiles need a
#: few digits, not the estimate's full precision
BOOTSTRAP_TOLERANCE = 1e-8


@checked(
    log=Instance(StandstillLog), base_frequency=POSITIVE, settle=NONNEGATIVE,
    voltage_error=optional(REAL), seed=SEED, bootstrap=COUNT0, check=FLAG,
    voltage_error_std=NONNEGATIVE, model=Instance(AdmittanceModel), dead_time=NONNEGATIVE,
)
def fit_impedance(log: StandstillLog, base_frequency: float, settle: float,
                  voltage_error: float | None = None, seed: int = 0,
                  bootstrap: int = BOOTSTRAP_COUNT, check: bool = True,
                  voltage_error_std: float = 0.0,
                  model: AdmittanceModel = INVERSE_GAMMA_MODEL,
                  dead_time: float = 0.0) -> ImpedanceFit:  # fmt: skip
    """The inverse-Gamma parameters of an injection log with their intervals (module docstring).
    ``voltage_error_std`` [V], the standard error of ``voltage_error``, widens the intervals by
    what it carries into the fit (module docstring). ``check=False`` skips the identifiability
    rules (to show what a bad test gives, e.g. the bias of an uncompensated voltage error); the
    intervals are returned all the same. ``model`` is the winding fitted (default the cage IM's
    inverse-Gamma circuit; ``identify._pm`` fits a PM machine's axis). ``dead_time`` [s], the
    inverter's programmed dead time, moves the model's sample instant by half of it (module
    docstring)."""
    require_nonnegative("dead_time", dead_time)
    model = with_dead_time(model, dead_time)
    spec = spectrum(log, base_frequency, settle, voltage_error)
    theta0 = np.log(model.start(spec))
    fit = _solve(spec, theta0, model=model)
    simulated = voltage_error is not None and model.state_space is not None

    def polarity(theta, clamping=False):
        try:  # a parameter off any physical range (a wild round): no sign to tell
            with np.errstate(all="ignore"):
                signs = simulated_polarity(np.exp(theta), log.v_a, spec.hold, voltage_error,
                                           model.dead_time, model.state_space, clamping)  # fmt: skip
        except (np.linalg.LinAlgError, ZeroDivisionError):
            return np.full(spec.frequency.size, np.nan + 0j)
        if not np.all(np.isfinite(signs)):
            return np.full(spec.frequency.size, np.nan + 0j)
        return _tone_coefficients(signs, spec, base_frequency)

    def polarity_rounds(spec, fit, clamping=False, rounds=POLARITY_ROUNDS):
        previous = None
        for _ in range(rounds if simulated else 0):  # the inverter's own sign
            if not (fit.success and np.all(np.isfinite(fit.x))):
                break
            coefficients = polarity(fit.x, clamping)
            if not np.all(np.isfinite(coefficients)):
                break
            if previous is not None and np.array_equal(coefficients, previous):
                break  # the simulated sign repeats: the fit is its own fixed point
            previous = coefficients
            spec = replace(spec, polarity=coefficients).compensated(voltage_error)
            fit = _solve(spec, fit.x, model=model)
        return spec, fit

    def converged(fit):
        return fit.success and np.all(np.isfinite(fit.x)) and fit.cost < _FAR

    if simulated:  # from the reading's sign; from the uncompensated fit if that ends worse
        plain = spectrum(log, base_frequency, settle)
        uncompensated = _solve(plain, np.log(model.start(plain)), model=model)
        rounds = polarity_rounds(spec, fit)
        if not converged(rounds[1]) or rounds[1].cost > uncompensated.cost:
            rounds = polarity_rounds(spec, uncompensated, rounds=FAR_ROUNDS)
        spec, fit = rounds
    m, n = 2 * spec.frequency.size, len(model.fields)
    if m - n < 1:
        raise InputError("excitation", f"{spec.frequency.size} tones cannot determine "
                         f"{n} parameters with a residual left to judge the fit")  # fmt: skip
    dof = m - n
    warnings = []
    timing, delay = None, 0.0
    if m - n > 1 and fit.success and np.all(np.isfinite(fit.x)):  # the channels' timing
        timing = fit_delay(spec, fit.x, fit.cost, model, _residual)
        if timing.refused(spec.hold):
            told = _delay_text(timing.delay, spec.hold)
            if check:
                raise InputError(f"{log.source}: column 'i_a'", f"is read {told} column 'v_a' "
                                 "(the phase of the current against the voltage grows with "
                                 "frequency as a delay's does): the channels are misaligned by "
                                 "about a row; align them and identify again")  # fmt: skip
            warnings.append(f"column 'i_a' is read {told} column 'v_a': not compensated")
        elif timing.significant(spec.hold):
            delay = timing.delay
            spec = spec.advanced(delay)
            spec, fit = polarity_rounds(spec, _solve(spec, timing.theta, model=model))
            warnings.append(f"column 'i_a' is read {_delay_text(delay, spec.hold)} column "
                            f"'v_a' (+-{1.96 * timing.std * 1e6:.2g} us, from a joint fit of "
                            "the delay): compensated, its uncertainty is in the intervals; "
                            "check the channels' timing")  # fmt: skip
    rms = float(np.sqrt(2.0 * fit.cost / m))
    if not fit.success or not np.all(np.isfinite(fit.x)) or fit.cost >= _FAR:
        reached = (
            rms if fit.cost < _FAR else float(np.sqrt(np.mean(_residual(theta0, spec, model) ** 2)))
        )
        raise FitNotConverged(
            "impedance", fit.message, reached, "A (rms of the tones' current error)"
        )
    values = np.exp(fit.x)
    s2 = 2.0 * fit.cost / dof
    cov_theta = covariance(fit.jac, s2)
    gain = np.eye(n)
    if simulated and np.all(np.isfinite(cov_theta)):  # the polarity's feedback (_polarity)
        sensitivity = voltage_error * model.admittance(values, 2.0 * np.pi * spec.frequency,
                                                       spec.hold)  # fmt: skip
        steps = np.maximum(FEEDBACK_STEP_SIGMAS * np.sqrt(np.diag(cov_theta)), 1e-6)
        gain = feedback_gain(fit.jac, fit.x, steps, polarity, sensitivity)
        cov_theta = gain @ cov_theta @ gain.T
    with np.errstate(invalid="ignore"):  # an unbounded direction stays unbounded (inf, NaN)
        cov = np.diag(values) @ cov_theta @ np.diag(values)  # d p = p d theta
    U = 0.0 if voltage_error is None else voltage_error
    spread = voltage_error_std if voltage_error is not None else 0.0
    if spread > 0.0:  # + g g^T var(U), g = dp/dU by central differences of two refits
        up = np.exp(_solve(spec.compensated(U + spread), fit.x, model=model).x)
        down = np.exp(_solve(spec.compensated(U - spread), fit.x, model=model).x)
        g = (up - down) / (2.0 * spread)
        cov = cov + np.outer(g, g) * spread**2
    beyond_noise = np.zeros((n, n))  # the terms the noise resampling cannot draw (below)
    if delay != 0.0 and math.isfinite(timing.std) and timing.std > 0.0:  # + g g^T var(delay)
        up = np.exp(_solve(spec.advanced(timing.std), fit.x, model=model).x)
        down = np.exp(_solve(spec.advanced(-timing.std), fit.x, model=model).x)
        g = (up - down) / (2.0 * timing.std)
        beyond_noise = beyond_noise + np.outer(g, g) * timing.std**2
    ratio = math.sqrt(s2 / spec.noise) if spec.noise > 0.0 else float("nan")
    model_error = ratio > RESIDUAL_FACTOR
    clamping_term = False
    if model_error:  # + the delete-one-tone jackknife (identify._judge)
        jackknife = jackknife_covariance(spec, fit.x, model,
                                         lambda sub, start: _solve(sub, start, model=model))  # fmt: skip
        with np.errstate(invalid="ignore"):
            beyond_noise = beyond_noise + np.diag(values) @ jackknife @ np.diag(values)
        if simulated:  # + d d^T, d the clamping inverter's estimate less this one (_polarity),
            # when the clamping inverter explains the log at least as well as the held sign
            _, clamped = polarity_rounds(spec, fit, clamping=True, rounds=FAR_ROUNDS)
            if converged(clamped) and clamped.cost <= fit.cost:
                d = np.exp(clamped.x) - values
                beyond_noise = beyond_noise + np.outer(d, d)
                clamping_term = True
        smallest = float(np.min(np.abs(spec.command)))
        if voltage_error is None:
            causes = "an inverter voltage error left uncompensated (no DC-step log)"
        elif smallest < TONE_MARGIN * abs(voltage_error):
            causes = (f"tones too small for the inverter's voltage error (the smallest "
                      f"{smallest:.3g} V against U_err = {voltage_error:.3g} V, less than "
                      f"{TONE_MARGIN:g} times it: the compensation's polarity model is least "
                      "accurate there; raise the tones)")  # fmt: skip
        else:
            causes = "an inverter voltage error compensated imperfectly (dead time, device drops)"
        warnings.append(f"the residual is {ratio:.3g} times the noise floor of the off-tone "
                        f"bins ({math.sqrt(s2):.3g} A against {math.sqrt(spec.noise):.3g} A, "
                        f"at most {RESIDUAL_FACTOR:g} accepted as noise): the model misses part "
                        f"of the log; likely {causes}, a current-sensor offset or gain, or a "
                        "timing error between the channels; the intervals include a "
                        "model-error term (delete-one-tone jackknife"
                        + (", and the difference to a fit whose inverter clamps the current at "
                           "its zero crossings" if clamping_term else "") + ")")  # fmt: skip
    with np.errstate(invalid="ignore"):
        cov = cov + beyond_noise
    q = t_quantile(dof)
    rng = np.random.default_rng(seed)
    residual = fit.fun[: m // 2] + 1j * fit.fun[m // 2 :]
    residual = residual * math.sqrt(m / dof)
    response = spec.current - (fit.fun[: m // 2] + 1j * fit.fun[m // 2 :])
    draws = np.empty((bootstrap, n))
    for b in range(bootstrap):
        redrawn = response + rng.choice(residual, residual.size)
        resampled = spec.compensated(U + spread * rng.standard_normal(), redrawn)
        refit = _solve(resampled, fit.x, BOOTSTRAP_TOLERANCE, model)
        moved = fit.x + gain @ (refit.x - fit.x)  # the feedback, to first order
        draws[b] = np.exp(moved) if refit.success and refit.cost < _FAR else np.nan
    draws = draws + gaussian_draws(beyond_noise, bootstrap, seed)
    estimates = tuple(
        Estimate(name, unit, meaning, float(values[j]),
                 jacobian_interval(values[j], cov[j, j], q), percentile_interval(draws[:, j]))
        for j, (name, unit, meaning) in enumerate(model.fields)
    )  # fmt: skip
    current_scale = float(np.sqrt(np.mean(np.abs(spec.current) ** 2) / 2.0))
    result = ImpedanceFit(estimates, spec, rms, rms / current_scale, dof, voltage_error, draws,
                          cov, model, ratio, timing, delay, model_error, tuple(warnings),
                          log.source)  # fmt: skip
    if check:
        check_identified(result)
    return result


def gaussian_draws(cov: np.ndarray, count: int, seed: int) -> np.ndarray:
    """``count`` draws of N(0, ``cov``) (rows), for the bootstrap: the delay's and the model
    error's terms of the Jacobian covariance are not in the resampled noise, so each refit is
    moved by a draw of them and the percentile interval carries what the Jacobian interval
    carries. Its own generator (``seed`` and a second word), so a fit without these terms draws
    exactly the bootstrap it drew without them; a parameter whose term is unbounded (inf or NaN)
    draws NaN, i.e. an unknown interval. ``cov`` is symmetric positive semidefinite up to
    rounding: the square root keeps its eigenvalues above the rounding of the largest."""
    n = cov.shape[0]
    if not np.any(cov):
        return np.zeros((count, n))
    bounded = np.all(np.isfinite(cov), axis=0) & np.all(np.isfinite(cov), axis=1)
    draws = np.full((count, n), np.nan)
    inner = cov[np.ix_(bounded, bounded)]
    eigenvalues, vectors = np.linalg.eigh(0.5 * (inner + inner.T))
    rounding = inner.shape[0] * np.finfo(float).eps * max(float(np.max(eigenvalues)), 0.0)
    root = vectors * np.sqrt(np.where(eigenvalues > rounding, eigenvalues, 0.0))
    normal = np.random.default_rng([seed, 1]).standard_normal((count, inner.shape[0]))
    draws[:, bounded] = normal @ root.T
    return draws


def _delay_text(delay: float, hold: float) -> str:
    """'0.5 sample periods (100 us) after' (or 'before'), for messages."""
    side = "after" if delay > 0.0 else "before"
    return f"{abs(delay) / hold:.2g} sample periods ({abs(delay) * 1e6:.3g} us) {side}"


def check_identified(fit: ImpedanceFit) -> None:
    """The identifiability rules of the module docstring, on a fit (the rotor-corner rule for the
    cage IM's circuit, the interval rule for every model)."""
    low, high = fit.spectrum.frequency[0], fit.spectrum.frequency[-1]
    if fit.model is None or fit.model.fields is INVERSE_GAMMA:
        try:
            _check_rotor_corner(fit.params, low, high)
        except InputError:
            if fit.voltage_error is not None or not fit.model_error:
                raise
            # the residual says the model misses the log: the corner it places is no evidence
            # against the tones; the uncompensated inverter is (identify._judge)
            corner = fit.params.rotor_corner / (2.0 * math.pi)
            raise InputError("dc", f"no DC-step log: the injection is fitted without the "
                             "inverter's voltage error U_err (and R_s) the DC steps measure, "
                             f"and its residual is {fit.residual_ratio:.3g} times the noise "
                             f"floor, so the rotor corner {corner:.3g} Hz it places outside "
                             f"the tones ({low:g} to {high:g} Hz) is not to be trusted; give "
                             "the DC-step log") from None  # fmt: skip
    _check_widths(fit.estimates, f"tones {low:g} to {high:g} Hz")


def _check_rotor_corner(params: InverseGamma, low: float, high: float) -> None:
    corner = params.rotor_corner / (2.0 * math.pi)
    if high < corner:
        raise InputError("R_R", f"not separable from L_sigma: every tone ({low:g} to {high:g} Hz) "
                         f"lies below the rotor corner R_R / (2 pi L_M) = {corner:.3g} Hz of the "
                         "fit; the tones must bracket it")  # fmt: skip
    if low > corner:
        raise InputError("L_M", f"not seen: every tone ({low:g} to {high:g} Hz) lies above the "
                         f"rotor corner R_R / (2 pi L_M) = {corner:.3g} Hz of the fit; the tones "
                         "must bracket it")  # fmt: skip


def _check_widths(estimates, excitation: str) -> None:
    """Every estimate's 95 % interval within +-``MAX_HALF_WIDTH`` of its value, else an
    InputError naming the parameter (``excitation`` says what the test was)."""
    for estimate in estimates:
        width = estimate.half_width()
        if not width <= MAX_HALF_WIDTH:
            told = f"+-{width:.0%} of the value" if math.isfinite(width) else "unbounded"
            raise InputError(estimate.name, f"not identified by this excitation: its 95 % "
                             f"interval is {told}, at most +-{MAX_HALF_WIDTH:.0%} of the value "
                             f"accepted ({excitation})")  # fmt: skip
