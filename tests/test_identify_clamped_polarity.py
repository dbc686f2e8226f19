"""The inverter's polarity where it clamps the current at zero (identify._impedance,
identify._polarity).

A real inverter takes each leg's current direction at each of its switching edges, so a current
driven towards zero by less voltage than the inverter's error stays at zero: within a carrier
period the error takes whatever fraction of U holds it there (zero-current clamping). The
log here is the exact sampled inverse-Gamma circuit (``identify._winding``) under that rule, so
its parameters are known exactly: per period, s_k = +1 (or -1) while the current stays positive
(negative) with the full error, else the fraction in [-1, 1] that brings the next sample to
zero. The sensor adds 10 mA of seeded noise, so the clamped samples read noise around zero and
their sign flickers. With tones of 10 V against U = 8.53 V, an estimator whose polarity starts
from the reading's sign lands on a degenerate circuit (L_M of 1e10 H); started from the
uncompensated fit, its simulated sign recovers the parameters to the model error of a
per-sample sign against the clamping (L_sigma 1.3 %, L_M 1.4 % high). That model error is above
the noise floor, and the fit's intervals add the difference to a fit whose polarity clamps
(``_polarity.simulated_polarity(..., clamping=True)``), so they hold the truth; so do the
bootstrap's, and the interval of a sensor offset taken from the injection's mean.
"""

import math

import numpy as np
import pytest

from acdrive.identify import InverseGamma, StandstillLog, fit_impedance
from acdrive.identify._dc import Z_95
from acdrive.identify._offset import OFFSET_ROUNDS, joint_offset
from acdrive.identify._circuit import standstill_state_space
from acdrive.identify._polarity import simulated_polarity
from acdrive.identify._winding import discrete_winding

#: motulator's 2.2 kW IM (inverse Gamma) and its inverter's error at 540 V, 5 kHz, 2 us, 1 V
TRUE = InverseGamma(3.7, 0.021, 2.1, 0.224)
U_ERR = 4.0 / 3.0 * (2e-6 * 5000.0 * 540.0 + 1.0)
HOLD = 1.0 / 5000.0
TONES = (1, 2, 3, 5, 8, 13, 20, 40, 80, 160)


def clamped_log(amplitude: float, seconds: float = 4.0, noise: float = 1e-2) -> StandstillLog:
    """The injection log of the module docstring: Schroeder multisine of ``amplitude`` [V] per
    tone at f_0 = 1 Hz, the exact sampled circuit, the clamping inverter, seeded noise."""
    A, B = standstill_state_space(TRUE.as_array())
    Phi, Gamma, C = discrete_winding(A, B, HOLD, 0.0)
    n = round(seconds / HOLD)
    t = np.arange(n) * HOLD
    phases = [-math.pi * k * (k - 1) / len(TONES) for k in range(1, len(TONES) + 1)]
    v = sum(amplitude * np.cos(2.0 * math.pi * m * t + p)
            for m, p in zip(TONES, phases, strict=True))  # fmt: skip
    reach = float(C @ Gamma)  # the next sample's current per volt held over the period
    x = np.zeros(A.shape[0])
    current = np.empty(n)
    for k in range(n):
        current[k] = C @ x
        free = float(C @ (Phi @ x)) + reach * v[k]
        if current[k] > 0.0 and free > reach * U_ERR:
            s = 1.0
        elif current[k] < 0.0 and free < -reach * U_ERR:
            s = -1.0
        else:  # the error holds the current at zero, or drives it through zero to the end
            s = min(1.0, max(-1.0, free / (reach * U_ERR)))
        x = Phi @ x + Gamma * (v[k] - U_ERR * s)
    reading = current + noise * np.random.default_rng(3).standard_normal(n)
    return StandstillLog(t, v, reading, "clamped log")


def test_a_flickering_sign_at_the_clamp_does_not_derail_the_compensated_fit():
    log = clamped_log(10.0)
    clamped = clamped_log(10.0, noise=0.0).i_a[-10000:] == 0.0
    assert 0.02 < np.mean(clamped) < 0.5  # the window's samples held at zero by the inverter
    fit = fit_impedance(log, 1.0, 2.0, voltage_error=U_ERR, bootstrap=0, check=False)
    errors = fit.params.as_array() / TRUE.as_array() - 1.0
    assert np.all(np.abs(errors) < 0.02), errors


def test_a_command_below_the_voltage_error_never_moves_a_clamped_current():
    """From rest, a constant command v below U is met by an equal and opposite inverter error:
    s = v / U at every sample and the current stays zero; above U the current flows and s = 1."""
    values = TRUE.as_array()
    below = simulated_polarity(values, np.full(500, 0.4 * U_ERR), HOLD, U_ERR, clamping=True)
    assert np.allclose(below, 0.4)
    above = simulated_polarity(values, np.full(500, 2.0 * U_ERR), HOLD, U_ERR, clamping=True)
    assert np.all(above == 1.0)  # the current leaves zero positive in the first period


def test_the_intervals_hold_the_truth_of_a_clamping_inverters_log():
    """Tones of 15 V against U = 8.53 V: the held-sign fit is biased by the clamping (above its
    noise floor); the intervals carry the clamping fit's difference and hold all four."""
    fit = fit_impedance(clamped_log(15.0), 1.0, 2.0, voltage_error=U_ERR, bootstrap=0)
    assert fit.model_error
    misses = [e.name for e, true in zip(fit.estimates, TRUE.as_array(), strict=True)
              if not e.covers(true)]  # fmt: skip
    assert misses == [], fit.estimates
    assert any("clamps the current" in w for w in fit.warnings), fit.warnings


def test_the_bootstrap_interval_carries_the_model_error_too():
    """The resampled noise alone cannot move a refit by the clamping's bias: each refit is also
    moved by a draw of the model-error terms, so the bootstrap's percentile interval holds the
    truth wherever the Jacobian interval does, and is about as wide."""
    fit = fit_impedance(clamped_log(15.0), 1.0, 2.0, voltage_error=U_ERR, bootstrap=100)
    assert fit.model_error
    for estimate, true in zip(fit.estimates, TRUE.as_array(), strict=True):
        assert estimate.covers(true, "bootstrap"), estimate
        low, high = estimate.bootstrap
        width = 0.5 * (high - low) / estimate.value
        assert 0.5 < width / estimate.half_width() < 2.0, estimate


@pytest.mark.parametrize("amplitude", [12.0, 20.0])
def test_the_offset_from_the_injections_mean_holds_the_truth_under_clamping(amplitude):
    """A sensor offset of 0.05 A, the DC steps' exact intercept U - R_s c and slope R_s: the
    offset comes from the injection's mean through the mean inverter sign P_0, which a held sign
    misplaces where the inverter clamps (by 0.8 mA at 12 V, 5 mA at 20 V: 8 and 56 of the noise's
    standard errors). Above the noise floor the interval adds the clamping sign's difference and
    holds it (identify._offset)."""
    offset, R_s = 0.05, TRUE.R_s
    clean = clamped_log(amplitude)
    log = StandstillLog(clean.time, clean.v_a, clean.i_a + offset, "offset log")
    intercept, value = U_ERR - R_s * offset, 0.0
    for _ in range(OFFSET_ROUNDS):  # identify_standstill's rounds, with the exact DC line
        less = StandstillLog(log.time, log.v_a, log.i_a - value, "offset log")
        trial = fit_impedance(less, 1.0, 2.0, voltage_error=intercept + R_s * value,
                              bootstrap=0, check=False)  # fmt: skip
        joint = joint_offset(log, trial, 1.0, intercept, 0.0, R_s)
        value = joint.value
    assert trial.model_error
    assert abs(joint.value - offset) <= Z_95 * joint.std, (joint.value - offset, joint.std)
