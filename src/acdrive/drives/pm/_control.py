"""Field-oriented control of the permanent-magnet synchronous motor as sampled parts.

The cascade, sample by sample (wired in this order by ``drives.pm._build``):

* ``plant.Encoder`` -> ``control.SpeedEstimator``: the shaft angle and its backward difference;
* :class:`PMSpeedPI`: speed PI (Bodson (25), ``control._speed.speed_pi``, clamping anti-windup)
  whose torque limit is the smaller of its own ``tau_max`` and the torque the drive can give at
  the measured speed within the current and voltage limits (``_design.available_torque``), so
  the integral freezes as soon as the torque is limited, whichever limit acts;
* :class:`PMTorqueReference`: torque -> rotor-frame current reference, MTPA below base speed and
  field weakening on the voltage limit above it (``_design.operating_point``);
* :class:`RotorFrameCurrentController`: PI per axis in rotor (dq) coordinates with decoupling and
  back-EMF feed-forward and back-calculation anti-windup at the converter's voltage limit.

Every part takes the controller's own machine estimates (``R_s``, ``L_d``, ``L_q``, ``psi_m``,
``n_p``: a detuned controller is built with other values than the plant's) in the machine part's
scaling (``machines._pmsm_part``: power-invariant space vectors, psi_m the peak flux per phase).

**The rotor angle** is the encoder angle times n_p (theta_e = n_p theta, the d axis of the part);
a mounting offset of the encoder is a misalignment of the dq frame that the controller does not
know about. Measured currents turn into rotor coordinates with the angle of the sample instant;
the voltage command turns back with the angle advanced by ``advance`` samples of rotation,
theta_e + advance w_e T_s: the command is held over the sample (zero-order hold) while the rotor
turns by w_e T_s, and advance = 1/2 applies it at the mean angle of the hold interval.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from acdrive._frames import beyond_limit
from acdrive._jit import jit
from acdrive.control._speed import require_feedforward_fraction, speed_pi
from acdrive.core._parts import SampledPart
from acdrive.core._signals import Layout, cplx, real
from acdrive.drives.pm._design import (
    BEYOND_REACH,
    CURRENT_LIMITED,
    VOLTAGE_LIMITED,
    available_torque,
    flux_limit,
    magnet_flux,
    operating_point,
    require_salient_or_round,
    torque,
)
from acdrive.errors import InputError
from acdrive.plant._converter import max_voltage_magnitude


#: the controller's machine estimates, declared once for the three parts
ESTIMATES = (
    real("R_s", "ohm", "stator resistance (controller's estimate)", "positive"),
    real("L_d", "H", "d-axis inductance (controller's estimate)", "positive"),
    real("L_q", "H", "q-axis inductance (controller's estimate)", "positive"),
    real("psi_m", "Wb", "magnet flux linkage, peak per phase (controller's estimate)", "positive"),
    real("n_p", "", "pole pairs", "count"),
)
#: the limits the references respect, declared once
LIMITS = (
    real("i_max", "A", "stator current magnitude limit (space vector)", "positive"),
    real("V_dc", "V", "DC-link voltage: the voltage limit is V_dc / sqrt(2)", "positive"),
    real("margin", "", "fraction of the voltage limit the references may use", "fraction"),
)
_ESTIMATE_NAMES = tuple(v.name for v in ESTIMATES)
_LIMIT_NAMES = tuple(v.name for v in LIMITS)


def _check_machine(part: SampledPart) -> None:
    v = part.values
    require_salient_or_round(f"{part.name}.L_q", v["L_d"], v["L_q"])


def _check_limits(part: SampledPart) -> None:
    """The voltage budget of (V) must be positive: margin V_max > R_s i_max."""
    v = part.values
    budget = v["margin"] * v["V_dc"] / np.sqrt(2.0) - v["R_s"] * v["i_max"]
    if budget <= 0.0:
        raise InputError(
            f"{part.name}.margin",
            "margin V_dc / sqrt(2) must exceed R_s i_max (the resistive "
            f"drop at full current), got {budget + v['R_s'] * v['i_max']:g} V <= "
            f"{v['R_s'] * v['i_max']:g} V",
        )


# --- torque -> current reference (MTPA and field weakening) -----------------------------------

REF_PARAMS = Layout(*ESTIMATES, *LIMITS)
REF_INPUTS = Layout(
    real("tau_ref", "N m", "torque reference"),
    real("w", "rad/s", "measured shaft speed"),
)
REF_OUTPUTS = Layout(
    cplx("i_dq_ref", "A", "stator current reference i_d + j i_q, rotor frame"),
    real("tau_lim", "N m", "torque of the current reference (after the limits)"),
    real("psi_max", "Wb", "flux magnitude allowed by the voltage limit at this speed"),
)
REF_EVENTS = ("current_limit", "voltage_limit", "beyond_reach")
_R_RS, _R_LD, _R_LQ, _R_PSI, _R_NP, _R_IMAX, _R_VDC, _R_M = (
    REF_PARAMS.slot(n) for n in (*_ESTIMATE_NAMES, *_LIMIT_NAMES)
)
_R_TAU, _R_W = REF_INPUTS.slot("tau_ref"), REF_INPUTS.slot("w")
_R_O_I, _R_O_TAU, _R_O_PSI = (REF_OUTPUTS.slot(n) for n in ("i_dq_ref", "tau_lim", "psi_max"))


@jit
def torque_reference_step(t, T_s, u, p, s, y):
    """i_dq_ref = ``_design.operating_point`` of the torque reference at the measured speed;
    events current_limit (bit 1), voltage_limit (bit 2), beyond_reach (bit 4)."""
    n_p, L_d, L_q = p[_R_NP], p[_R_LD], p[_R_LQ]
    psi_f = magnet_flux(p[_R_PSI])
    w_e = n_p * u[_R_W]
    psi_max = flux_limit(p[_R_RS], max_voltage_magnitude(p[_R_VDC]), p[_R_M], p[_R_IMAX], w_e)
    i_d, i_q, flags = operating_point(n_p, psi_f, L_d, L_q, u[_R_TAU], p[_R_IMAX], psi_max)
    y[_R_O_I], y[_R_O_I + 1] = i_d, i_q
    y[_R_O_TAU] = torque(n_p, psi_f, L_d, L_q, i_d, i_q)
    y[_R_O_PSI] = min(1e300, psi_max)
    events = 0
    if flags & CURRENT_LIMITED:
        events |= 1
    if flags & VOLTAGE_LIMITED:
        events |= 2
    if flags & BEYOND_REACH:
        events |= 4
    return events


class PMTorqueReference(SampledPart):
    """Torque reference to rotor-frame current reference: MTPA below base speed, field weakening
    on the voltage limit (V) above it, |i| <= i_max (``drives.pm._design``). ``tau_lim`` is the
    torque the reference gives (smaller than asked when a limit acts)."""

    SOURCE = "torque -> rotor-frame current reference: MTPA, field weakening on (V)"

    PARAMS, INPUTS, OUTPUTS = REF_PARAMS, REF_INPUTS, REF_OUTPUTS
    DEFAULTS: ClassVar[dict] = {"margin": 0.9}
    EVENTS = REF_EVENTS
    step = torque_reference_step

    def check(self) -> None:
        _check_machine(self)
        _check_limits(self)


# --- speed PI with the available torque as its limit ------------------------------------------

SPEED_PARAMS = Layout(
    real("K_P", "N m s/rad", "proportional gain", "nonnegative"),
    real("K_I", "N m/rad", "integral gain", "nonnegative"),
    real("K_F", "", "reference weight of the proportional term (1: PI on the error)", "fraction"),
    real("tau_max", "N m", "torque limit of the speed controller", "positive"),
    *ESTIMATES,
    *LIMITS,
)
SPEED_STATES = Layout(real("e_int", "rad", "integral of the speed error"))
SPEED_INPUTS = Layout(
    real("w_ref", "rad/s", "speed reference"),
    real("w", "rad/s", "measured shaft speed"),
)
SPEED_OUTPUTS = Layout(
    real("tau_ref", "N m", "torque reference"),
    real("tau_avail", "N m", "torque limit at this speed: min(tau_max, available torque)"),
)
_S_KP, _S_KI, _S_KF, _S_TMAX, _S_RS, _S_LD, _S_LQ, _S_PSI, _S_NP, _S_IMAX, _S_VDC, _S_M = (
    SPEED_PARAMS.slot(n) for n in ("K_P", "K_I", "K_F", "tau_max", *_ESTIMATE_NAMES, *_LIMIT_NAMES)
)
_S_EINT = SPEED_STATES.slot("e_int")
_S_WREF, _S_W = SPEED_INPUTS.slot("w_ref"), SPEED_INPUTS.slot("w")
_S_O_TAU, _S_O_AVAIL = SPEED_OUTPUTS.slot("tau_ref"), SPEED_OUTPUTS.slot("tau_avail")


@jit
def pm_speed_pi_step(t, T_s, u, p, s, y):
    """Bodson (25) with the limit +-min(tau_max, available torque at the measured speed);
    clamping: the integral advances only while the output is inside the limit (event bit 1)."""
    n_p = p[_S_NP]
    w = u[_S_W]
    psi_max = flux_limit(p[_S_RS], max_voltage_magnitude(p[_S_VDC]), p[_S_M], p[_S_IMAX], n_p * w)
    limit = min(
        p[_S_TMAX],
        available_torque(n_p, magnet_flux(p[_S_PSI]), p[_S_LD], p[_S_LQ], p[_S_IMAX], psi_max),
    )
    tau, s[_S_EINT], limited = speed_pi(
        p[_S_KP], p[_S_KI], p[_S_KF], s[_S_EINT], u[_S_WREF], w, -limit, limit, T_s
    )
    y[_S_O_TAU] = tau
    y[_S_O_AVAIL] = limit
    return 1 if limited else 0


class PMSpeedPI(SampledPart):
    """Speed PI of Bodson (25) (gains from ``control.SpeedPIGains.design``) whose torque limit at
    each sample is min(tau_max, the torque available at the measured speed within i_max and the
    voltage limit), with clamping anti-windup (event ``torque_limit``)."""

    SOURCE = "Bodson (25) limited to min(tau_max, the torque available at the measured speed)"

    PARAMS, STATES, INPUTS, OUTPUTS = SPEED_PARAMS, SPEED_STATES, SPEED_INPUTS, SPEED_OUTPUTS
    DEFAULTS: ClassVar[dict] = {"K_F": 1.0, "margin": 0.9}
    EVENTS = ("torque_limit",)
    step = pm_speed_pi_step

    def check(self) -> None:
        require_feedforward_fraction(f"{self.name}.K_F", self.values["K_F"])
        _check_machine(self)
        _check_limits(self)


# --- rotor-frame current controller ----------------------------------------------------------

CURRENT_PARAMS = Layout(
    real("K_P_d", "ohm", "d-axis proportional gain", "nonnegative"),
    real("K_P_q", "ohm", "q-axis proportional gain", "nonnegative"),
    real("K_I_d", "ohm/s", "d-axis integral gain", "nonnegative"),
    real("K_I_q", "ohm/s", "q-axis integral gain", "nonnegative"),
    *ESTIMATES,
    real("V_dc", "V", "DC-link voltage: the voltage limit is V_dc / sqrt(2)", "positive"),
    real(
        "advance", "", "angle advance of the voltage command, in samples of rotation", "nonnegative"
    ),
    real("decouple", "", "1: cross-coupling and back-EMF fed forward, 0: plain PI", "fraction"),
)
CURRENT_STATES = Layout(cplx("x", "V", "integral parts x_d + j x_q of the two PIs"))
CURRENT_INPUTS = Layout(
    cplx("i_dq_ref", "A", "stator current reference, rotor frame"),
    cplx("i_s", "A", "measured stator current, stationary frame"),
    real("theta", "rad", "measured shaft angle (encoder)"),
    real("w", "rad/s", "measured shaft speed"),
)
CURRENT_OUTPUTS = Layout(
    cplx("v_ref", "V", "voltage command, stationary frame (within the limit)"),
    cplx("v_dq_ref", "V", "voltage command, rotor frame (within the limit)"),
    cplx("v_dq_wanted", "V", "voltage command before the limit, rotor frame"),
    cplx("i_dq", "A", "measured stator current, rotor frame"),
)
(_C_KPD, _C_KPQ, _C_KID, _C_KIQ, _C_RS, _C_LD, _C_LQ, _C_PSI, _C_NP, _C_VDC, _C_ADV, _C_DEC) = (
    CURRENT_PARAMS.slot(n)
    for n in ("K_P_d", "K_P_q", "K_I_d", "K_I_q", *_ESTIMATE_NAMES, "V_dc", "advance", "decouple")
)
_C_X = CURRENT_STATES.slot("x")
_C_IREF, _C_IS, _C_TH, _C_W = (CURRENT_INPUTS.slot(n) for n in ("i_dq_ref", "i_s", "theta", "w"))
_C_O_V, _C_O_VDQ, _C_O_WANT, _C_O_I = (
    CURRENT_OUTPUTS.slot(n) for n in ("v_ref", "v_dq_ref", "v_dq_wanted", "i_dq")
)


@jit
def rotor_current_step(t, T_s, u, p, s, y):
    """One sample (module docstring):

        i_dq = i_s e^{-j theta_e},  e = i_dq_ref - i_dq,  theta_e = n_p theta, w_e = n_p w
        v_d = K_P_d e_d + x_d - w_e L_q i_q                      (d: PI + cross term)
        v_q = K_P_q e_q + x_q + w_e (L_d i_d + psi_f)            (q: PI + cross term + back-EMF)
        v = v_dq limited to |v| <= V_dc / sqrt(2) along its direction (event ``saturated``)
        x_{k+1} = x_k + T_s K_I (e + (v - v_dq) / K_P)  per axis   (back-calculation)
        v_ref = v e^{j (theta_e + advance w_e T_s)}

    The back-calculation integrates the realisable error, the error that would have given the
    limited command exactly, so nothing winds up while the converter limits (the conditioning
    technique of ``control._current``); an axis with K_P = 0 integrates its plain error."""
    n_p = p[_C_NP]
    theta_e = n_p * u[_C_TH]
    w_e = n_p * u[_C_W]
    rotor = complex(np.cos(theta_e), np.sin(theta_e))
    i_dq = complex(u[_C_IS], u[_C_IS + 1]) * rotor.conjugate()
    e_d = u[_C_IREF] - i_dq.real
    e_q = u[_C_IREF + 1] - i_dq.imag
    k = p[_C_DEC]
    ff_d = -k * w_e * p[_C_LQ] * i_dq.imag
    ff_q = k * w_e * (p[_C_LD] * i_dq.real + magnet_flux(p[_C_PSI]))
    v_d = p[_C_KPD] * e_d + s[_C_X] + ff_d
    v_q = p[_C_KPQ] * e_q + s[_C_X + 1] + ff_q
    v_max = max_voltage_magnitude(p[_C_VDC])
    magnitude = np.sqrt(v_d * v_d + v_q * v_q)
    events = 0
    scale = 1.0
    if beyond_limit(magnitude, v_max):
        scale = v_max / magnitude
        events = 1
    a_d, a_q = scale * v_d, scale * v_q
    r_d = e_d + ((a_d - v_d) / p[_C_KPD] if p[_C_KPD] > 0.0 else 0.0)
    r_q = e_q + ((a_q - v_q) / p[_C_KPQ] if p[_C_KPQ] > 0.0 else 0.0)
    s[_C_X] += T_s * p[_C_KID] * r_d
    s[_C_X + 1] += T_s * p[_C_KIQ] * r_q
    angle = theta_e + p[_C_ADV] * w_e * T_s
    v = complex(a_d, a_q) * complex(np.cos(angle), np.sin(angle))
    y[_C_O_V], y[_C_O_V + 1] = v.real, v.imag
    y[_C_O_VDQ], y[_C_O_VDQ + 1] = a_d, a_q
    y[_C_O_WANT], y[_C_O_WANT + 1] = v_d, v_q
    y[_C_O_I], y[_C_O_I + 1] = i_dq.real, i_dq.imag
    return events


class RotorFrameCurrentController(SampledPart):
    """PI current control in rotor coordinates with decoupling, back-EMF feed-forward and
    back-calculation anti-windup at |v| <= V_dc / sqrt(2) (event ``saturated``); gains from
    ``drives.pm._design.CurrentPIGains.design`` (module docstring of ``_design``)."""

    SOURCE = (
        "rotor-frame PI per axis with decoupling, back-EMF feed-forward and back-calculation anti-"
        "windup at V_dc / sqrt(2)"
    )

    PARAMS, STATES, INPUTS, OUTPUTS = (
        CURRENT_PARAMS,
        CURRENT_STATES,
        CURRENT_INPUTS,
        CURRENT_OUTPUTS,
    )
    DEFAULTS: ClassVar[dict] = {"advance": 0.5, "decouple": 1.0}
    EVENTS = ("saturated",)
    step = rotor_current_step
