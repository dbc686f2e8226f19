"""Bodson's DFIM speed controller as sampled parts (Bodson section III and IV-A).

The controller sees samples only and is built from four parts, wired in this order:

* :class:`SpeedEstimator`: shaft speed from the encoder angle, backward difference through a
  first-order low-pass filter;
* :class:`SupplyFrequencyEstimator`: supply frequency from the phase advance of the grid voltage
  over one sample, filtered, starting from the nominal frequency;
* :class:`Synchroniser` (28): with the stator open, the rotor voltage m_adj e^{j theta_adj}
  (Z_R / Z_MS) v_G builds a stator voltage equal to the grid's; m_adj and theta_adj are adjusted
  from the measured stator / grid voltage ratio (this also aligns an encoder of unknown offset);
  it closes the relay once magnitude and phase agree within tolerances for a hold time. Its
  adjustments stay in force afterwards;
* :class:`SpeedController`: once the relay is closed, speed PI (25) within the on-line torque
  window (30), (32), (37) (or, with the R_s = 0 law, (40)-(42)); stator current command (22) (or
  (38)) for the torque and reactive-power commands, then either the rotor voltage (20) (voltage
  command) or the rotor current command (43) through the rotor current loop (45)-(47) with the
  gains (49) (current command); an optional reactive-power PI around the open-loop law (III-B);
  when the current measurement fails it falls back to voltage command.

All four output and hold the rotor voltage in rotor coordinates; the converter applies the
speed controller's. Events use the names of ``acdrive.control._dfim.EVENT_NAMES``.
"""

from __future__ import annotations

from dataclasses import replace
from typing import ClassVar

import numpy as np

from acdrive._frames import clip_magnitude
from acdrive._jit import jit
from acdrive.control._dfim import MIN_SUPPLY_FREQUENCY
from acdrive.control._speed import speed_pi
from acdrive.core._parts import SampledPart
from acdrive.core._signals import Layout, cplx, real
from acdrive.machines import _dfim as dfim
from acdrive.machines._dfim import (
    impedances,
    rotor_current_for,
    rotor_voltage_for,
    stator_current_command,
    stator_current_lossless,
    torque_limit_case2,
    torque_window,
)
from acdrive.machines._dfim_part import WINDINGS

MODE_VOLTAGE, MODE_CURRENT = 0.0, 1.0

#: the controller's estimates of the machine: the DFIM part's winding parameters as declared
#: there, first in the controller's layouts, so they take the slots (declaration order) at which
#: machines._dfim's compiled functions read them
ESTIMATES = tuple(replace(v, doc=f"{v.doc} (controller's estimate)") for v in WINDINGS)


@jit
def _wrap(angle):
    return (angle + np.pi) % (2.0 * np.pi) - np.pi


# --- speed from the encoder ------------------------------------------------------------------

SPEED_PARAMS = Layout(real("tau", "s", "low-pass filter time constant (0: none)", "nonnegative"))
SPEED_STATES = Layout(
    real("started", "", "1 once the first sample has run"),
    real("theta_prev", "rad", "encoder angle at the previous sample"),
    real("w", "rad/s", "filtered speed estimate"),
)
SPEED_INPUTS = Layout(real("theta", "rad", "measured shaft angle"))
SPEED_OUTPUTS = Layout(real("w", "rad/s", "estimated shaft speed"))
_SP_TAU = SPEED_PARAMS.slot("tau")
_SP_STARTED, _SP_PREV, _SP_W = (SPEED_STATES.slot(n) for n in ("started", "theta_prev", "w"))


@jit
def speed_estimator_step(t, T_s, u, p, s, y):
    theta = u[0]
    if s[_SP_STARTED] == 0.0:
        s[_SP_STARTED], s[_SP_PREV], s[_SP_W] = 1.0, theta, 0.0
    else:
        w_raw = (theta - s[_SP_PREV]) / T_s
        s[_SP_PREV] = theta
        s[_SP_W] += T_s / (p[_SP_TAU] + T_s) * (w_raw - s[_SP_W])
    y[0] = s[_SP_W]
    return 0


class SpeedEstimator(SampledPart):
    """Shaft speed from the encoder: backward difference, first-order low-pass of time constant
    ``tau``; zero on the first sample."""

    SOURCE = "Bodson IV-A: speed from the encoder, backward difference, first-order filter"

    PARAMS, STATES, INPUTS, OUTPUTS = SPEED_PARAMS, SPEED_STATES, SPEED_INPUTS, SPEED_OUTPUTS
    DEFAULTS: ClassVar[dict] = {"tau": 0.0}
    step = speed_estimator_step


# --- supply frequency from the grid voltage --------------------------------------------------

FREQ_PARAMS = Layout(
    real("w_nominal", "rad/s", "nominal supply frequency (the estimate's start)", "positive"),
    real("tau", "s", "low-pass filter time constant (0: none)", "nonnegative"),
    real("v_min", "V", "grid voltage magnitude below which the estimate is held", "nonnegative"),
)
FREQ_STATES = Layout(
    real("started", "", "1 once the first sample has run"),
    cplx("v_prev", "V", "grid voltage at the previous sample"),
    real("w_e", "rad/s", "filtered supply frequency estimate"),
)
FREQ_INPUTS = Layout(cplx("v_g", "V", "grid voltage, stationary frame"))
FREQ_OUTPUTS = Layout(real("w_e", "rad/s", "estimated supply frequency"))
_FR_W_NOM, _FR_TAU, _FR_V_MIN = (FREQ_PARAMS.slot(n) for n in ("w_nominal", "tau", "v_min"))
_FR_STARTED, _FR_PREV, _FR_W = (FREQ_STATES.slot(n) for n in ("started", "v_prev", "w_e"))


@jit
def frequency_estimator_step(t, T_s, u, p, s, y):
    v_g = complex(u[0], u[1])
    if s[_FR_STARTED] == 0.0:
        s[_FR_STARTED], s[_FR_W] = 1.0, p[_FR_W_NOM]
    elif np.abs(v_g) > p[_FR_V_MIN]:
        # phase advance of the grid voltage over one sample: angle of v_g(k) v_g(k-1)*
        w_raw = np.angle(v_g * complex(s[_FR_PREV], -s[_FR_PREV + 1])) / T_s
        s[_FR_W] += T_s / (p[_FR_TAU] + T_s) * (w_raw - s[_FR_W])
    s[_FR_PREV], s[_FR_PREV + 1] = v_g.real, v_g.imag
    y[0] = s[_FR_W]
    return 0


class SupplyFrequencyEstimator(SampledPart):
    """Supply frequency from the grid voltage's phase advance per sample, low-pass filtered,
    starting from ``w_nominal``; held while the grid voltage is below ``v_min``."""

    SOURCE = "supply frequency from the grid voltage's phase advance per sample, filtered"

    PARAMS, STATES, INPUTS, OUTPUTS = FREQ_PARAMS, FREQ_STATES, FREQ_INPUTS, FREQ_OUTPUTS
    DEFAULTS: ClassVar[dict] = {"tau": 0.01, "v_min": 0.0}
    step = frequency_estimator_step


# --- synchroniser (28) -----------------------------------------------------------------------

SYNC_PARAMS = Layout(
    *ESTIMATES,
    real("enabled", "", "1: start with the stator open and synchronise; 0: start closed", "flag"),
    real("gain", "1/s", "rate of the theta_adj and ln m_adj adjustments", "nonnegative"),
    real("tol_magnitude", "", "|rho - 1| below which the magnitudes agree", "nonnegative"),
    real("tol_phase", "rad", "|phi| below which the phases agree", "nonnegative"),
    real("hold", "s", "both tolerances met this long before closing", "nonnegative"),
    real("v_min", "V", "voltage magnitude below which the supply counts as lost", "nonnegative"),
    real("theta_adj", "rad", "initial phase adjustment theta_adj"),
    real("m_adj", "", "initial magnitude adjustment m_adj", "positive"),
)
SYNC_STATES = Layout(
    real("started", "", "1 once the first sample has run"),
    real("closed", "", "1 once the relay has been closed"),
    real("theta_adj", "rad", "phase adjustment"),
    cplx("adj", "", "e^{j theta_adj}, computed once per change"),
    real("m_adj", "", "magnitude adjustment"),
    real("ok_time", "s", "time both tolerances have been met"),
    cplx("v_r", "V", "rotor voltage held, rotor coordinates"),
)
SYNC_INPUTS = Layout(
    cplx("v_s", "V", "stator terminal voltage, stationary frame"),
    cplx("v_g", "V", "grid voltage, stationary frame"),
    real("w", "rad/s", "estimated shaft speed"),
    real("w_e", "rad/s", "estimated supply frequency"),
    real("theta", "rad", "measured shaft angle"),
)
SYNC_OUTPUTS = Layout(
    cplx("v_r", "V", "rotor voltage command while synchronising, rotor coordinates"),
    real("closed", "", "relay command: 1 closed, 0 open"),
    real("theta_adj", "rad", "phase adjustment (also corrects the encoder offset)"),
    cplx("adj", "", "e^{j theta_adj}"),
    real("m_adj", "", "magnitude adjustment"),
)
_SY = {n: SYNC_PARAMS.slot(n) for n in ("enabled", "gain", "tol_magnitude", "tol_phase", "hold",
                                        "v_min", "theta_adj", "m_adj")}  # fmt: skip
_SS = {n: SYNC_STATES.slot(n) for n in ("started", "closed", "theta_adj", "adj", "m_adj",
                                        "ok_time", "v_r")}  # fmt: skip
_SI = {n: SYNC_INPUTS.slot(n) for n in ("v_s", "v_g", "w", "w_e", "theta")}
_SO_VR, _SO_CLOSED, _SO_THETA, _SO_ADJ, _SO_M = (
    SYNC_OUTPUTS.slot(n) for n in ("v_r", "closed", "theta_adj", "adj", "m_adj"))  # fmt: skip
_SP_ENABLED, _SP_GAIN, _SP_TOL_MAG, _SP_TOL_PH, _SP_HOLD = (
    _SY["enabled"], _SY["gain"], _SY["tol_magnitude"], _SY["tol_phase"], _SY["hold"])  # fmt: skip
_SP_VMIN, _SP_THETA0, _SP_M0 = _SY["v_min"], _SY["theta_adj"], _SY["m_adj"]
_SS_STARTED, _SS_CLOSED, _SS_THETA, _SS_ADJ = (
    _SS["started"], _SS["closed"], _SS["theta_adj"], _SS["adj"])  # fmt: skip
_SS_M, _SS_OK, _SS_VR = _SS["m_adj"], _SS["ok_time"], _SS["v_r"]
_SI_VS, _SI_VG, _SI_W, _SI_WE, _SI_THETA = (
    _SI["v_s"], _SI["v_g"], _SI["w"], _SI["w_e"], _SI["theta"])  # fmt: skip
SYNC_EVENTS = ("supply_lost", "relay_closed")
_SYNC_SUPPLY_LOST, _SYNC_CLOSED = 1, 2


@jit
def _set_theta_adj(s, theta_adj):
    """Store theta_adj and its phasor e^{j theta_adj} (computed once per change, not per use)."""
    s[_SS_THETA] = theta_adj
    s[_SS_ADJ], s[_SS_ADJ + 1] = np.cos(theta_adj), np.sin(theta_adj)


@jit
def _sync_outputs(s, y):
    y[_SO_VR], y[_SO_VR + 1] = s[_SS_VR], s[_SS_VR + 1]
    y[_SO_CLOSED] = s[_SS_CLOSED]
    y[_SO_THETA] = s[_SS_THETA]
    y[_SO_ADJ], y[_SO_ADJ + 1] = s[_SS_ADJ], s[_SS_ADJ + 1]
    y[_SO_M] = s[_SS_M]


@jit
def synchroniser_step(t, T_s, u, p, s, y):
    """One sample of (28) (module docstring); the measured ratio v_S / v_G = rho e^{j phi}
    drives d theta_adj/dt = -g phi and d ln m_adj/dt = -g ln rho, which converge from any phase
    error in (-pi, pi)."""
    events = 0
    if s[_SS_STARTED] == 0.0:  # first sample: estimates not ready, hold
        s[_SS_STARTED] = 1.0
        s[_SS_CLOSED] = 0.0 if p[_SP_ENABLED] != 0.0 else 1.0
        _set_theta_adj(s, p[_SP_THETA0])
        s[_SS_M] = p[_SP_M0]
    elif s[_SS_CLOSED] == 0.0:
        v_g = complex(u[_SI_VG], u[_SI_VG + 1])
        w_e = u[_SI_WE]
        v_g_mag = np.abs(v_g)
        if v_g_mag < p[_SP_VMIN] or w_e < MIN_SUPPLY_FREQUENCY:
            events |= _SYNC_SUPPLY_LOST
        else:
            v_s = complex(u[_SI_VS], u[_SI_VS + 1])
            gain = p[_SP_GAIN]
            close = False
            if np.abs(v_s) > p[_SP_VMIN]:
                ratio = v_s / v_g
                rho, phi = np.abs(ratio), np.angle(ratio)
                _set_theta_adj(s, _wrap(s[_SS_THETA] - gain * T_s * phi))
                s[_SS_M] *= np.exp(-gain * T_s * np.log(rho))
                if np.abs(rho - 1.0) < p[_SP_TOL_MAG] and np.abs(phi) < p[_SP_TOL_PH]:
                    s[_SS_OK] += T_s
                else:
                    s[_SS_OK] = 0.0
                close = s[_SS_OK] >= p[_SP_HOLD]
            adj = complex(s[_SS_ADJ], s[_SS_ADJ + 1])
            v_r = s[_SS_M] * adj * rotor_voltage_for(p, w_e, u[_SI_W], v_g_mag, 0.0)
            # grid-voltage frame -> stationary -> rotor coordinates (e^{-j n_p theta} measured)
            angle = p[dfim.N_P] * u[_SI_THETA]
            frame = v_g * (1.0 / v_g_mag)
            v_rr = v_r * frame * np.conj(complex(np.cos(angle), np.sin(angle)))
            s[_SS_VR], s[_SS_VR + 1] = v_rr.real, v_rr.imag
            if close:
                s[_SS_CLOSED] = 1.0
                events |= _SYNC_CLOSED
    _sync_outputs(s, y)
    return events


class Synchroniser(SampledPart):
    """Grid synchronisation before the stator relay closes, Bodson (28) (module docstring).
    With ``enabled`` 0 the relay is closed from the start and the adjustments stay at their
    initial values."""

    SOURCE = "Bodson (28): grid synchronisation with the stator open"

    PARAMS, STATES, INPUTS, OUTPUTS = SYNC_PARAMS, SYNC_STATES, SYNC_INPUTS, SYNC_OUTPUTS
    DEFAULTS: ClassVar[dict] = {"enabled": 0.0, "gain": 40.0, "tol_magnitude": 0.02,
                                "tol_phase": 0.035, "hold": 0.02, "v_min": 0.0,
                                "theta_adj": 0.0, "m_adj": 1.0}  # fmt: skip
    EVENTS = SYNC_EVENTS
    step = synchroniser_step

    def held_outputs(self) -> dict:
        return {"closed": 0.0 if self.values["enabled"] else 1.0, "m_adj": self.values["m_adj"]}


# --- speed controller ------------------------------------------------------------------------

CTRL_PARAMS = Layout(
    *ESTIMATES,
    real("K_P", "N m s/rad", "speed PI proportional gain (25)", "nonnegative"),
    real("K_I", "N m/rad", "speed PI integral gain (25)", "positive"),
    real("K_F", "", "speed reference feedforward fraction (25)", "nonnegative"),
    real("Q_ref", "var", "reactive power command"),
    real("Q_kp", "1/V", "reactive-power PI proportional gain (0: open loop)", "nonnegative"),
    real("Q_ki", "1/(V s)", "reactive-power PI integral gain (0: open loop)", "nonnegative"),
    real("i_s_max", "A", "stator current limit, space-vector magnitude", "positive"),
    real("i_r_max", "A", "rotor current limit, space-vector magnitude", "positive"),
    real(
        "v_min",
        "V",
        "stator voltage magnitude below which the supply counts as lost",
        "nonnegative",
    ),
    real("mode", "", "0 voltage command, 1 current command", "flag"),
    real("K_PC", "ohm", "rotor current loop proportional gain (49)", "nonnegative"),
    real("K_IC", "ohm/s", "rotor current loop integral gain (49)", "nonnegative"),
    real("R_T", "ohm", "virtual resistance of the rotor current loop (47)", "nonnegative"),
    real("v_r_max", "V", "rotor voltage the converter can apply (anti-windup)", "positive"),
    real("lossless", "", "1: the R_s = 0 law (38)-(39) with the case-2 limits (40)-(42)", "flag"),
)
CTRL_STATES = Layout(
    real("started", "", "1 once the first sample has run"),
    real("was_closed", "", "relay state at the previous sample"),
    real("mode", "", "present mode (falls back to voltage command on sensor loss)"),
    real("e_int", "rad", "speed error integral (25)"),
    real("q_int", "var s", "reactive power error integral"),
    cplx("ir_int", "A s", "rotor current error integral (47)"),
    cplx("v_r", "V", "rotor voltage held, rotor coordinates"),
    real("tau_com", "N m", "torque command"),
    cplx("i_r_com", "A", "rotor current command (43), stator-voltage frame"),
    cplx("i_r_f", "A", "last valid measured rotor current, stator-voltage frame"),
    real("q_meas", "var", "measured reactive power"),
)
CTRL_INPUTS = Layout(
    cplx("v_s", "V", "stator terminal voltage, stationary frame"),
    cplx("i_s", "A", "measured stator current, stationary frame"),
    cplx("i_r", "A", "measured rotor current, rotor coordinates"),
    real("currents_valid", "", "1 while the current measurement works"),
    real("theta", "rad", "measured shaft angle"),
    real("w", "rad/s", "estimated shaft speed"),
    real("w_e", "rad/s", "estimated supply frequency"),
    real("w_ref", "rad/s", "speed reference"),
    real("closed", "", "relay command from the synchroniser"),
    cplx("v_r_sync", "V", "synchroniser's rotor voltage, rotor coordinates"),
    cplx("adj", "", "synchroniser's e^{j theta_adj}"),
    real("m_adj", "", "synchroniser's magnitude adjustment"),
)
CTRL_OUTPUTS = Layout(
    cplx("v_r", "V", "rotor voltage command, rotor coordinates"),
    real("tau_com", "N m", "torque command"),
    cplx("i_r_com", "A", "rotor current command (43), stator-voltage frame"),
    cplx("i_r_f", "A", "measured rotor current, stator-voltage frame"),
    real("mode", "", "0 voltage command, 1 current command"),
)
CTRL_EVENTS = ("torque_limit", "sqrt_limit", "supply_lost", "no_rotor_margin",
               "converter_saturation", "rotor_current_limit", "sensor_fallback")  # fmt: skip
(_EV_TORQUE_LIMIT, _EV_SQRT, _EV_SUPPLY_LOST, _EV_NO_MARGIN, _EV_SAT, _EV_CURRENT_LIMIT,
 _EV_FALLBACK) = (1 << b for b in range(len(CTRL_EVENTS)))  # fmt: skip
_CP = {v.name: CTRL_PARAMS.slot(v.name) for v in CTRL_PARAMS}
_CS = {v.name: CTRL_STATES.slot(v.name) for v in CTRL_STATES}
_CI = {v.name: CTRL_INPUTS.slot(v.name) for v in CTRL_INPUTS}
_O_VR, _O_TAU, _O_IRCOM, _O_IRF, _O_MODE = (
    CTRL_OUTPUTS.slot(n) for n in ("v_r", "tau_com", "i_r_com", "i_r_f", "mode"))  # fmt: skip
(_P_KP, _P_KI, _P_KF, _P_QREF, _P_QKP, _P_QKI, _P_ISMAX, _P_IRMAX, _P_VMIN, _P_MODE, _P_KPC,
 _P_KIC, _P_RT, _P_VRMAX, _P_LOSSLESS) = (
    _CP[n] for n in ("K_P", "K_I", "K_F", "Q_ref", "Q_kp", "Q_ki", "i_s_max", "i_r_max", "v_min",
                     "mode", "K_PC", "K_IC", "R_T", "v_r_max", "lossless"))  # fmt: skip
(_S_STARTED, _S_WAS_CLOSED, _S_MODE, _S_EINT, _S_QINT, _S_IRINT, _S_VR, _S_TAU, _S_IRCOM,
 _S_IRF, _S_QMEAS) = (
    _CS[n] for n in ("started", "was_closed", "mode", "e_int", "q_int", "ir_int", "v_r",
                     "tau_com", "i_r_com", "i_r_f", "q_meas"))  # fmt: skip
(_I_VS, _I_IS, _I_IR, _I_VALID, _I_THETA, _I_W, _I_WE, _I_WREF, _I_CLOSED, _I_VRSYNC, _I_ADJ,
 _I_MADJ) = (
    _CI[n] for n in ("v_s", "i_s", "i_r", "currents_valid", "theta", "w", "w_e", "w_ref",
                     "closed", "v_r_sync", "adj", "m_adj"))  # fmt: skip


@jit
def _cget(a, i):
    return complex(a[i], a[i + 1])


@jit
def _cset(a, i, z):
    a[i], a[i + 1] = z.real, z.imag


@jit
def rotor_current_loop(p, s, T_s, w_e, w, v_s, i_s, i_r, i_r_com):
    """Rotor current control law (46)-(47) in the stator-voltage frame; returns (v_R, saturated).

    u_R = Z_R i_R + Z_MR i_S + (M/L_S)(v_S - Z_S i_S - Z_MS i_R) cancels the coupling (45); then
    v_R = u_R - R_T i_R + K_P,C e + K_I,C int e with e = i_R,COM - i_R. The integral advances only
    while the converter can apply v_R (conditional-integration anti-windup).
    """
    Z_S, Z_MS, Z_R, Z_MR = impedances(p, w_e, w)
    u_r = Z_R * i_r + Z_MR * i_s + p[dfim.M_SR] / p[dfim.L_S] * (v_s - Z_S * i_s - Z_MS * i_r)
    error = i_r_com - i_r
    integral = _cget(s, _S_IRINT)
    v_r = u_r - p[_P_RT] * i_r + p[_P_KPC] * error + p[_P_KIC] * integral
    v_r, saturated = clip_magnitude(v_r, p[_P_VRMAX])
    if not saturated:
        _cset(s, _S_IRINT, integral + T_s * error)
    return v_r, saturated


@jit
def reactive_power_command(p, s, T_s, v_s_mag, i_s, currents_valid):
    """Q command: Q_ref, plus a PI on the measured Q = Im(v_S i_S*) (5) when gains are set."""
    q_ref = p[_P_QREF]
    if not currents_valid or (p[_P_QKP] == 0.0 and p[_P_QKI] == 0.0):
        return q_ref
    q_meas = -v_s_mag * i_s.imag  # v_S real in its own frame: Im(v_S i_S*) = -v_S Im(i_S)
    s[_S_QMEAS] = q_meas
    error = q_ref - q_meas
    s[_S_QINT] += T_s * error
    return q_ref + p[_P_QKP] * error + p[_P_QKI] * s[_S_QINT]


@jit
def _controller_outputs(s, y):
    _cset(y, _O_VR, _cget(s, _S_VR))
    y[_O_TAU] = s[_S_TAU]
    _cset(y, _O_IRCOM, _cget(s, _S_IRCOM))
    _cset(y, _O_IRF, _cget(s, _S_IRF))
    y[_O_MODE] = s[_S_MODE]


@jit
def _run(t, T_s, u, p, s):
    """One sample with the relay closed; returns (rotor voltage in rotor coordinates, events),
    or (held voltage, supply-lost event) when the supply is lost."""
    w_e, w = u[_I_WE], u[_I_W]
    v_s = _cget(u, _I_VS)
    v_s_mag = np.abs(v_s)
    if v_s_mag < p[_P_VMIN] or w_e < MIN_SUPPLY_FREQUENCY:
        return _cget(s, _S_VR), _EV_SUPPLY_LOST
    events = 0
    angle = p[dfim.N_P] * u[_I_THETA]
    rotor_angle = complex(np.cos(angle), np.sin(angle))  # e^{j n_p theta} as measured
    frame = v_s * (1.0 / v_s_mag)
    currents_valid = u[_I_VALID] != 0.0
    if s[_S_MODE] == MODE_CURRENT and not currents_valid:
        s[_S_MODE] = MODE_VOLTAGE
    if s[_S_MODE] == MODE_VOLTAGE and p[_P_MODE] == MODE_CURRENT:
        events |= _EV_FALLBACK
    # measured currents in the stator-voltage frame; theta_adj corrects the encoder offset
    adj = _cget(u, _I_ADJ)
    rotor_to_stator = rotor_angle * np.conj(adj)
    i_s_f = _cget(u, _I_IS) * np.conj(frame)
    i_r_f = _cget(u, _I_IR) * rotor_to_stator * np.conj(frame)

    q_com = reactive_power_command(p, s, T_s, v_s_mag, i_s_f, currents_valid)
    lossless = p[_P_LOSSLESS] != 0.0
    if lossless:
        tau_max_2, tau_max_3 = torque_limit_case2(p, w_e, v_s_mag, q_com, p[_P_ISMAX], p[_P_IRMAX])
        tau_hi = max(min(tau_max_2, tau_max_3), 0.0)
        tau_lo, feasible = -tau_hi, min(tau_max_2, tau_max_3) >= 0.0
    else:
        tau_lo, tau_hi, feasible = torque_window(p, w_e, v_s_mag, p[_P_ISMAX], p[_P_IRMAX])
    if not feasible:
        events |= _EV_NO_MARGIN
    tau_com, s[_S_EINT], clipped = speed_pi(
        p[_P_KP], p[_P_KI], p[_P_KF], s[_S_EINT], u[_I_WREF], w, tau_lo, tau_hi, T_s
    )
    if clipped:
        events |= _EV_TORQUE_LIMIT
    s[_S_TAU] = tau_com
    if lossless:
        i_s_com, sqrt_limited = stator_current_lossless(p, w_e, v_s_mag, tau_com, q_com), False
    else:
        i_s_com, sqrt_limited = stator_current_command(p, w_e, v_s_mag, tau_com, q_com)
    if sqrt_limited:
        events |= _EV_SQRT
    i_r_com, limited = clip_magnitude(rotor_current_for(p, w_e, v_s_mag, i_s_com), p[_P_IRMAX])
    _cset(s, _S_IRCOM, i_r_com)
    if currents_valid:  # a failed measurement leaves the last valid value
        _cset(s, _S_IRF, i_r_f)
    if s[_S_MODE] == MODE_CURRENT:
        if limited:
            events |= _EV_CURRENT_LIMIT
        v_r, saturated = rotor_current_loop(p, s, T_s, w_e, w, v_s_mag, i_s_f, i_r_f, i_r_com)
        if saturated:
            events |= _EV_SAT
        v_r = v_r * adj
    else:
        # (20) with the adjustments of (28): m_adj scales the v_s term, theta_adj rotates both
        v_r = adj * rotor_voltage_for(p, w_e, w, u[_I_MADJ] * v_s_mag, i_s_com)
    # voltage frame -> stationary (frame) -> rotor coordinates (e^{-j n_p theta})
    return v_r * frame * np.conj(rotor_angle), events


@jit
def speed_controller_step(t, T_s, u, p, s, y):
    events = 0
    closed = u[_I_CLOSED] != 0.0
    if s[_S_STARTED] == 0.0:  # first sample: estimates not ready, hold
        s[_S_STARTED] = 1.0
        s[_S_MODE] = p[_P_MODE]
        s[_S_WAS_CLOSED] = 1.0 if closed else 0.0
    elif not closed:  # synchronising: the synchroniser's voltage
        _cset(s, _S_VR, _cget(u, _I_VRSYNC))
    elif s[_S_WAS_CLOSED] == 0.0:
        # the relay closed on this sample: bumpless handover, the speed PI starts from zero
        # torque command
        s[_S_WAS_CLOSED] = 1.0
        w, w_ref = u[_I_W], u[_I_WREF]
        s[_S_EINT] = (p[_P_KP] * w - p[_P_KF] * p[_P_KP] * w_ref) / p[_P_KI]
        _cset(s, _S_VR, _cget(u, _I_VRSYNC))
    else:
        v_r, events = _run(t, T_s, u, p, s)
        _cset(s, _S_VR, v_r)
    _controller_outputs(s, y)
    return events


class SpeedController(SampledPart):
    """Bodson's speed controller once the relay is closed (module docstring): speed PI within
    the on-line torque limits, torque and reactive-power law, voltage or current command, sensor
    fallback. While the relay is open it passes the synchroniser's voltage on."""

    SOURCE = (
        "Bodson section III: speed PI (25), torque limits (30)-(42), law (20)-(24), rotor current "
        "loop (45)-(49), sensor fallback"
    )

    PARAMS, STATES, INPUTS, OUTPUTS = CTRL_PARAMS, CTRL_STATES, CTRL_INPUTS, CTRL_OUTPUTS
    DEFAULTS: ClassVar[dict] = {"K_F": 2.0 / 3.0, "Q_ref": 0.0, "Q_kp": 0.0, "Q_ki": 0.0,
                                "v_min": 0.0, "mode": MODE_VOLTAGE, "K_PC": 0.0, "K_IC": 0.0,
                                "R_T": 0.0, "lossless": 0.0}  # fmt: skip
    EVENTS = CTRL_EVENTS
    step = speed_controller_step

    def held_outputs(self) -> dict:
        return {"mode": self.values["mode"]}
