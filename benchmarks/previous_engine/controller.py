"""Sampled-data DFIM controller (Bodson section III): synchronisation to the grid, then speed
control in voltage-command or current-command mode.

* Synchronisation (28): with the stator open, the rotor voltage m_adj e^{j theta_adj} (Z_R/Z_MS) v_G
  builds a stator voltage equal to the grid's; m_adj and theta_adj are adjusted from the measured
  stator / grid voltage ratio (this also aligns an encoder with unknown offset), and the relay is
  closed once magnitude and phase agree within tolerances for a hold time.
* Voltage command: speed PI (25) -> torque window (30), (32), (37) -> stator current (22) -> rotor
  voltage (20) with the adjustments of (28); or, for large machines, the R_s = 0 law (38)-(39) with
  the case-2 window (40)-(42) for any reactive-power command.
* Current command: rotor current command (43), limited to the rotor current limit, and the rotor
  current loop (45)-(47) with gains (49); conditional-integration anti-windup when the converter
  saturates. A failed current measurement makes the controller fall back to voltage command.
* Optional reactive-power PI around the open-loop law (Bodson III-B, last paragraph).

The controller sees only samples: stator and grid voltages (stationary frame), stator currents
(stationary frame), rotor currents (rotor coordinates), the encoder angle and the speed reference.
It outputs the rotor voltage in rotor coordinates, held by the converter until the next sample, and
a relay-closing request. Parameters and state are float arrays with the named indices below, so the
compiled loop can run many controllers side by side.
"""

from __future__ import annotations

import numpy as np

from acdrive._jit import jit
from acdrive.control._speed import speed_pi
from acdrive.machines._dfim import (
    L_S,
    M_SR,
    N_P,
    impedances,
    rotor_current_for,
    rotor_voltage_for,
    stator_current_command,
    stator_current_lossless,
    torque_limit_case2,
    torque_window,
)

# fmt: off
# --- controller parameters (per motor) -------------------------------------------------------
(CP_KP, CP_KI, CP_KF, CP_Q_REF, CP_I_S_MAX, CP_I_R_MAX, CP_THETA_ADJ, CP_M_ADJ, CP_W_E_NOM,
 CP_SPEED_TAU, CP_FREQ_TAU, CP_V_MIN, CP_T_S, CP_MODE, CP_KPC, CP_KIC, CP_R_T, CP_V_R_MAX,
 CP_Q_KP, CP_Q_KI, CP_SYNC, CP_SYNC_GAIN, CP_SYNC_TOL_MAG, CP_SYNC_TOL_PHASE, CP_SYNC_HOLD,
 CP_LOSSLESS,
 ) = range(26)
N_CTRL_PARAMS = 26

# --- controller state (per motor) ------------------------------------------------------------
(CS_E_INT, CS_THETA_PREV, CS_W_EST, CS_W_E_EST, CS_V_G_PREV_RE, CS_VR_RE, CS_VR_IM, CS_TAU_COM,
 CS_STARTED, CS_PHASE, CS_THETA_ADJ, CS_M_ADJ, CS_SYNC_OK_TIME, CS_IR_INT_RE, CS_IR_INT_IM,
 CS_Q_INT, CS_MODE, CS_I_R_COM, CS_Q_MEAS, CS_I_R_COM_RE, CS_I_R_COM_IM, CS_I_R_F_RE, CS_I_R_F_IM,
 CS_V_G_PREV_IM, CS_ADJ_RE, CS_ADJ_IM,
 ) = range(26)
N_CTRL_STATES = 26
# fmt: on

MODE_VOLTAGE, MODE_CURRENT = 0.0, 1.0
PHASE_SYNC, PHASE_RUN = 0.0, 1.0

# --- event flags, one bit each, recorded per sample ------------------------------------------
FLAG_TORQUE_LIMIT = 1  # speed PI output clipped to the on-line torque limits
FLAG_SQRT_LIMIT = 2  # radicand of (22)/(24) negative: command limited
FLAG_SUPPLY_LOST = 4  # measured voltage below V_min: last safe output held
FLAG_NO_ROTOR_MARGIN = 8  # rotor current limit below magnetising need: torque window empty
FLAG_CONVERTER_SAT = 16  # converter could not apply the commanded rotor voltage
FLAG_CURRENT_LIMIT = 32  # rotor current command (43) limited to the rotor current limit
FLAG_SENSOR_FALLBACK = 64  # current measurement failed: running in voltage command
FLAG_RELAY_CLOSED = 128  # the synchroniser closed the relay on this sample
EVENT_NAMES = (
    "torque_limit",
    "sqrt_limit",
    "supply_lost",
    "no_rotor_margin",
    "converter_saturation",
    "rotor_current_limit",
    "sensor_fallback",
    "relay_closed",
)
#: below this estimated supply frequency [rad/s] the law (20) is not evaluated (Z_MS -> 0)
MIN_SUPPLY_FREQUENCY = 1.0


def current_loop_gains(
    sigma: float, L_r: float, R_T: float, bandwidth: float
) -> tuple[float, float]:
    """K_P,C = sigma L_r a_D,CUR and K_I,C = R_T a_D,CUR (Bodson (49)), which make the rotor
    current loop a_D,CUR / (s + a_D,CUR) (50)."""
    return sigma * L_r * bandwidth, R_T * bandwidth


@jit
def _wrap(angle):
    return (angle + np.pi) % (2.0 * np.pi) - np.pi


@jit
def _unit(angle):
    return complex(np.cos(angle), np.sin(angle))


@jit
def _set_theta_adj(cs, theta_adj):
    """Store theta_adj and its phasor e^{j theta_adj} (computed once per change, not per use)."""
    cs[CS_THETA_ADJ] = theta_adj
    cs[CS_ADJ_RE], cs[CS_ADJ_IM] = np.cos(theta_adj), np.sin(theta_adj)


@jit
def _adjustment(cs):
    return complex(cs[CS_ADJ_RE], cs[CS_ADJ_IM])


@jit
def _clip_magnitude(x, limit):
    magnitude = np.abs(x)
    if magnitude <= limit:
        return x, False
    return x * (limit / magnitude), True


@jit
def estimate_speeds(cp, cs, theta_meas, v_g):
    """Update shaft speed and supply frequency estimates; False on the very first sample.

    Shaft speed: backward difference of the encoder angle through a first-order low-pass filter of
    time constant CP_SPEED_TAU (0: none). Supply frequency: difference of the grid-voltage angle,
    filtered with CP_FREQ_TAU, starting from the nominal value.
    """
    T_s = cp[CP_T_S]
    if cs[CS_STARTED] == 0.0:
        cs[CS_THETA_PREV] = theta_meas
        cs[CS_W_EST] = 0.0
        cs[CS_W_E_EST] = cp[CP_W_E_NOM]
        cs[CS_V_G_PREV_RE], cs[CS_V_G_PREV_IM] = v_g.real, v_g.imag
        cs[CS_STARTED] = 1.0
        cs[CS_PHASE] = PHASE_SYNC if cp[CP_SYNC] != 0.0 else PHASE_RUN
        _set_theta_adj(cs, cp[CP_THETA_ADJ])
        cs[CS_M_ADJ] = cp[CP_M_ADJ]
        cs[CS_MODE] = cp[CP_MODE]
        return False
    w_raw = (theta_meas - cs[CS_THETA_PREV]) / T_s
    cs[CS_THETA_PREV] = theta_meas
    cs[CS_W_EST] += T_s / (cp[CP_SPEED_TAU] + T_s) * (w_raw - cs[CS_W_EST])
    if np.abs(v_g) > cp[CP_V_MIN]:
        # phase advance of the grid voltage over one sample: angle of v_g(k) v_g(k-1)*
        w_e_raw = np.angle(v_g * complex(cs[CS_V_G_PREV_RE], -cs[CS_V_G_PREV_IM])) / T_s
        cs[CS_W_E_EST] += T_s / (cp[CP_FREQ_TAU] + T_s) * (w_e_raw - cs[CS_W_E_EST])
    cs[CS_V_G_PREV_RE], cs[CS_V_G_PREV_IM] = v_g.real, v_g.imag
    return True


@jit
def synchronise(p_est, cp, cs, v_s, v_g, w_e, w):
    """One sample of grid synchronisation (Bodson (28)); returns (v_R in the grid-voltage frame,
    close_relay).

    The open stator carries v_S = (Z_MS / Z_R) v_R in steady state, so v_R = m (Z_R/Z_MS) v_G gives
    v_S = v_G for a perfect model and encoder. The measured ratio v_S / v_G = rho e^{j phi} drives
    integral adjustments d theta_adj/dt = -g phi and d ln m_adj/dt = -g ln rho (g = CP_SYNC_GAIN),
    which converge from any phase error in (-pi, pi), e.g. that of an unaligned encoder.
    """
    T_s, gain = cp[CP_T_S], cp[CP_SYNC_GAIN]
    close = False
    v_g_mag = np.abs(v_g)
    if np.abs(v_s) > cp[CP_V_MIN]:
        ratio = v_s / v_g
        rho, phi = np.abs(ratio), np.angle(ratio)
        _set_theta_adj(cs, _wrap(cs[CS_THETA_ADJ] - gain * T_s * phi))
        cs[CS_M_ADJ] *= np.exp(-gain * T_s * np.log(rho))
        if np.abs(rho - 1.0) < cp[CP_SYNC_TOL_MAG] and np.abs(phi) < cp[CP_SYNC_TOL_PHASE]:
            cs[CS_SYNC_OK_TIME] += T_s
        else:
            cs[CS_SYNC_OK_TIME] = 0.0
        close = cs[CS_SYNC_OK_TIME] >= cp[CP_SYNC_HOLD]
    v_r = cs[CS_M_ADJ] * _adjustment(cs) * rotor_voltage_for(p_est, w_e, w, v_g_mag, 0.0)
    return v_r, close


@jit
def rotor_current_loop(p_est, cp, cs, w_e, w, v_s, i_s, i_r, i_r_com):
    """Rotor current control law (46)-(47) in the stator-voltage frame; returns (v_R, saturated).

    u_R = Z_R i_R + Z_MR i_S + (M/L_S)(v_S - Z_S i_S - Z_MS i_R) cancels the coupling (45); then
    v_R = u_R - R_T i_R + K_P,C e + K_I,C int e with e = i_R,COM - i_R. The integral advances only
    while the converter can apply v_R (conditional-integration anti-windup).
    """
    Z_S, Z_MS, Z_R, Z_MR = impedances(p_est, w_e, w)
    u_r = Z_R * i_r + Z_MR * i_s + p_est[M_SR] / p_est[L_S] * (v_s - Z_S * i_s - Z_MS * i_r)
    error = i_r_com - i_r
    integral = complex(cs[CS_IR_INT_RE], cs[CS_IR_INT_IM])
    v_r = u_r - cp[CP_R_T] * i_r + cp[CP_KPC] * error + cp[CP_KIC] * integral
    v_r, saturated = _clip_magnitude(v_r, cp[CP_V_R_MAX])
    if not saturated:
        integral += cp[CP_T_S] * error
        cs[CS_IR_INT_RE], cs[CS_IR_INT_IM] = integral.real, integral.imag
    return v_r, saturated


@jit
def reactive_power_command(cp, cs, v_s_mag, i_s, currents_valid):
    """Q command: Q_ref, plus a PI on the measured Q = Im(v_S i_S*) (5) when gains are set."""
    q_ref = cp[CP_Q_REF]
    if not currents_valid or (cp[CP_Q_KP] == 0.0 and cp[CP_Q_KI] == 0.0):
        return q_ref
    q_meas = -v_s_mag * i_s.imag  # v_S real in its own frame: Im(v_S i_S*) = -v_S Im(i_S)
    cs[CS_Q_MEAS] = q_meas
    error = q_ref - q_meas
    cs[CS_Q_INT] += cp[CP_T_S] * error
    return q_ref + cp[CP_Q_KP] * error + cp[CP_Q_KI] * cs[CS_Q_INT]


@jit
def controller_step(p_est, cp, cs, v_s, v_g, i_s, i_r_rotor, theta_meas, w_ref):
    """One controller sample. Returns (rotor voltage in rotor coordinates, flags, close_relay).

    ``i_s`` (stationary frame) and ``i_r_rotor`` (rotor coordinates) are the current
    measurements; a non-finite value means the measurement failed.
    """
    held = complex(cs[CS_VR_RE], cs[CS_VR_IM])
    if not estimate_speeds(cp, cs, theta_meas, v_g):
        return held, 0, False
    w_e, w = cs[CS_W_E_EST], cs[CS_W_EST]
    rotor_angle = _unit(p_est[N_P] * theta_meas)  # e^{j n_p theta} as measured
    flags = 0
    close = False
    if cs[CS_PHASE] == PHASE_SYNC:
        if np.abs(v_g) < cp[CP_V_MIN] or w_e < MIN_SUPPLY_FREQUENCY:
            return held, FLAG_SUPPLY_LOST, False
        frame = v_g * (1.0 / np.abs(v_g))
        v_r, close = synchronise(p_est, cp, cs, v_s, v_g, w_e, w)
        if close:
            cs[CS_PHASE] = PHASE_RUN
            flags |= FLAG_RELAY_CLOSED
            # bumpless handover: the speed PI starts from zero torque command
            cs[CS_E_INT] = (cp[CP_KP] * w - cp[CP_KF] * cp[CP_KP] * w_ref) / cp[CP_KI]
    else:
        v_s_mag = np.abs(v_s)
        if v_s_mag < cp[CP_V_MIN] or w_e < MIN_SUPPLY_FREQUENCY:
            return held, FLAG_SUPPLY_LOST, False
        frame = v_s * (1.0 / v_s_mag)
        currents_valid = np.isfinite(i_s.real + i_s.imag + i_r_rotor.real + i_r_rotor.imag)
        if cs[CS_MODE] == MODE_CURRENT and not currents_valid:
            cs[CS_MODE] = MODE_VOLTAGE
        if cs[CS_MODE] == MODE_VOLTAGE and cp[CP_MODE] == MODE_CURRENT:
            flags |= FLAG_SENSOR_FALLBACK
        # measured currents in the stator-voltage frame; theta_adj corrects the encoder offset
        rotor_to_stator = rotor_angle * np.conj(_adjustment(cs))
        i_s_f = i_s * np.conj(frame)
        i_r_f = i_r_rotor * rotor_to_stator * np.conj(frame)

        q_com = reactive_power_command(cp, cs, v_s_mag, i_s_f, currents_valid)
        lossless = cp[CP_LOSSLESS] != 0.0  # the R_s = 0 law (39) with the case-2 limits
        if lossless:
            tau_max_2, tau_max_3 = torque_limit_case2(
                p_est, w_e, v_s_mag, q_com, cp[CP_I_S_MAX], cp[CP_I_R_MAX]
            )
            tau_hi = max(min(tau_max_2, tau_max_3), 0.0)
            tau_lo, feasible = -tau_hi, min(tau_max_2, tau_max_3) >= 0.0
        else:
            tau_lo, tau_hi, feasible = torque_window(
                p_est, w_e, v_s_mag, cp[CP_I_S_MAX], cp[CP_I_R_MAX]
            )
        if not feasible:
            flags |= FLAG_NO_ROTOR_MARGIN
        tau_com, cs[CS_E_INT], clipped = speed_pi(
            cp[CP_KP], cp[CP_KI], cp[CP_KF], cs[CS_E_INT], w_ref, w, tau_lo, tau_hi, cp[CP_T_S]
        )
        if clipped:
            flags |= FLAG_TORQUE_LIMIT
        cs[CS_TAU_COM] = tau_com
        if lossless:
            i_s_com, sqrt_limited = (
                stator_current_lossless(p_est, w_e, v_s_mag, tau_com, q_com),
                False,
            )
        else:
            i_s_com, sqrt_limited = stator_current_command(p_est, w_e, v_s_mag, tau_com, q_com)
        if sqrt_limited:
            flags |= FLAG_SQRT_LIMIT
        i_r_com, limited = _clip_magnitude(
            rotor_current_for(p_est, w_e, v_s_mag, i_s_com), cp[CP_I_R_MAX]
        )
        cs[CS_I_R_COM] = np.abs(i_r_com)
        cs[CS_I_R_COM_RE], cs[CS_I_R_COM_IM] = i_r_com.real, i_r_com.imag
        if currents_valid:  # a failed measurement leaves the last valid value
            cs[CS_I_R_F_RE], cs[CS_I_R_F_IM] = i_r_f.real, i_r_f.imag
        if cs[CS_MODE] == MODE_CURRENT:
            if limited:
                flags |= FLAG_CURRENT_LIMIT
            v_r, saturated = rotor_current_loop(
                p_est, cp, cs, w_e, w, v_s_mag, i_s_f, i_r_f, i_r_com
            )
            if saturated:
                flags |= FLAG_CONVERTER_SAT
            v_r = v_r * _adjustment(cs)
        else:
            # (20) with the adjustments of (28): m_adj scales the v_s term, theta_adj rotates both
            v_r = _adjustment(cs) * rotor_voltage_for(
                p_est, w_e, w, cs[CS_M_ADJ] * v_s_mag, i_s_com
            )
    # voltage frame -> stationary (frame) -> rotor coordinates (e^{-j n_p theta})
    v_r_rotor = v_r * frame * np.conj(rotor_angle)
    cs[CS_VR_RE], cs[CS_VR_IM] = v_r_rotor.real, v_r_rotor.imag
    return v_r_rotor, flags, close
