"""The current sensor's offset in a standstill identification, and why it matters.

The injection fit uses the tones only, so a constant offset c on the current reading does not
enter it. The DC steps do: every plateau reads I_k + c, and the straight line
I_k + c = (V_k - U) / R_s has the slope of the true one and the intercept of a voltage error
U - R_s c. The injection is then compensated by a wrong U (``identify._impedance``): an offset of
0.05 A on a 16 ohm winding is 0.8 V of voltage error that is not there, which biases R_s, R_R
and L_M far outside their intervals (``tests/test_identify_offset.py`` measures it). With one
sign of current in the DC steps, U and c are not separable there.

Two ways to measure c:

1. **A zero-current stretch** in the DC-step log: a run of zero command whose current has
   settled (to zero, since nothing drives it). Its mean reading is c; the DC fit subtracts it
   (``identify._dc.rests``).
2. **The injection's mean**, jointly with the parameters. Over the analysed window (whole periods
   of a periodic steady state) the mean current is Y_d(1) times the mean applied voltage:
   I_0 = Y_0 (V_0 - U P_0) + c, with V_0 the command's mean (zero for a multisine over whole
   periods), P_0 the mean of the inverter's polarity (the fitted circuit's simulated current
   sign, ``identify._polarity``) and Y_0 the fitted model's DC admittance. With the DC steps'
   intercept U' = U - R_s c:

       c = (I_0 - Y_0 V_0 + Y_0 P_0 U') / (1 - Y_0 R_s P_0),   U = U' + R_s c,

   solved with P_0 from the fit compensated by the previous U, round after round until c moves
   by less than a tenth of its standard error (``OFFSET_ROUNDS``, ``OFFSET_TOLERANCE``). It is
   separable while the injection's current changes sign, |1 - Y_0 R_s P_0| >= ``SEPARABLE``
   (P_0 = +-1: a current of one sign, where the mean carries U P_0 and c alike).

Its standard error: the mean of n white-noise samples of deviation s has s^2 / n, which is half
the off-tone noise variance of a tone coefficient (2 s^2 / n, ``identify._judge``); U's then
adds R_s^2 var(c) to the DC intercept's variance, which the injection's intervals carry. Where
the injection's residual is above its noise floor (``ImpedanceFit.model_error``), P_0 is as
uncertain as the inverter's sign near zero current: the variance adds d^2, d the offset that a
clamping inverter's mean sign gives less this one (the model-error term of
``identify._impedance``, "Held or clamped at a zero crossing").

The voltage column is the latched command, so it has no offset; a log of a measured voltage
whose channel has one moves the DC intercept as U does and is not separable from it with
levels of one sign (docs/guide/identification.md states it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from acdrive.errors import InputError
from acdrive.identify._dc import Z_95
from acdrive.identify._fit import Estimate, FitNotConverged, jacobian_interval
from acdrive.identify._polarity import simulated_polarity

#: at most this many rounds of (offset, U, refit) when the offset comes from the injection's
#: mean, stopping when the offset moves by less than ``OFFSET_TOLERANCE`` of its standard error
OFFSET_ROUNDS = 6
OFFSET_TOLERANCE = 0.1
#: the smallest |1 - Y_0 R_s P_0| at which the offset separates from U (module docstring)
SEPARABLE = 0.5


@dataclass(frozen=True)
class JointOffset:
    """The offset ``value`` [A] and its standard error ``std`` [A] from the injection's mean, and
    the voltage error ``voltage_error`` [V] it implies with its standard error."""

    value: float
    std: float
    voltage_error: float
    voltage_error_std: float


def joint_offset(log, fit, base_frequency: float, intercept: float, intercept_std: float,
                 R_s: float) -> JointOffset:  # fmt: skip
    """The offset of ``log``'s current from the window of the injection ``fit`` (an
    ``ImpedanceFit`` of ``log`` or of ``log`` less a trial offset, compensated by some U) and
    the DC steps' ``intercept`` U' [V] (standard error ``intercept_std``) and slope ``R_s``
    [ohm] (module docstring)."""
    spec, model = fit.spectrum, fit.model
    n = spec.periods * round(1.0 / (base_frequency * spec.hold))
    values = np.array([e.value for e in fit.estimates])
    if model.state_space is not None and fit.voltage_error is not None:
        signs = simulated_polarity(values, log.v_a, spec.hold, fit.voltage_error,
                                   model.dead_time, model.state_space)[-n:]  # fmt: skip
    else:
        signs = np.sign(log.i_a[-n:])
    P_0 = float(np.mean(signs))
    Y_0 = float(model.admittance(values, np.zeros(1), spec.hold)[0].real)
    mean_current, mean_command = float(np.mean(log.i_a[-n:])), float(np.mean(log.v_a[-n:]))

    def offset(P_0):
        return (mean_current - Y_0 * mean_command + Y_0 * P_0 * intercept) / (1.0 - Y_0 * R_s * P_0)

    denominator = 1.0 - Y_0 * R_s * P_0
    if abs(denominator) < SEPARABLE:
        raise InputError(f"{log.source}: column 'i_a'", f"a current-sensor offset cannot be "
                         "separated from the inverter's voltage error: the DC-step log has no "
                         "zero-current stretch and the injection's current keeps one sign "
                         f"({P_0:+.2f} of the samples' mean sign); log a rest at zero command "
                         "in the DC-step test")  # fmt: skip
    value = offset(P_0)
    if not math.isfinite(value):  # a trial fit off any physical range: no DC gain or polarity
        raise FitNotConverged("current-sensor offset from the injection's mean", "the trial "
                              "fit's circuit has no finite DC admittance or polarity",
                              fit.residual_rms, "A (rms of the tones' current error)")  # fmt: skip
    noise = spec.noise if math.isfinite(spec.noise) else (fit.residual_rms**2)
    variance = (0.5 * noise + (Y_0 * P_0 * intercept_std) ** 2) / denominator**2
    if fit.model_error and model.state_space is not None and fit.voltage_error is not None:
        # + d^2, d the offset a clamping inverter's mean sign gives less this one (the model
        # error's term of identify._impedance, on P_0)
        clamped = simulated_polarity(values, log.v_a, spec.hold, fit.voltage_error,
                                     model.dead_time, model.state_space, True)[-n:]  # fmt: skip
        difference = offset(float(np.mean(clamped))) - value
        if math.isfinite(difference):
            variance += difference**2
    std = math.sqrt(variance)
    U = intercept + R_s * value
    U_std = math.sqrt(intercept_std**2 + (R_s * std) ** 2)
    return JointOffset(float(value), std, float(U), U_std)


def offset_estimate(value: float, std: float, meaning: str) -> Estimate:
    """The offset as an ``Estimate`` [A] with its 95 % interval (both kinds: a z interval)."""
    interval = jacobian_interval(value, std**2, Z_95)
    return Estimate("i_a_offset", "A", meaning, float(value), interval, interval)
