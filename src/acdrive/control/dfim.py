"""Sampled-data DFIM controller: open-loop torque / reactive-power law with voltage command,
speed PI and on-line torque limits (Bodson sections III-A, III-B, III-D).

The controller sees only samples: measured stator and grid voltages (stationary frame), the
encoder angle, the speed reference. It outputs the rotor voltage in rotor coordinates, which the
converter holds until the next sample. Parameters and state are float arrays with named indices
(below) so that the compiled loop can hold many controllers side by side.
"""

from __future__ import annotations

import numpy as np

from acdrive.control.speed import speed_pi
from acdrive.jit import jit
from acdrive.machines.dfim import N_P, rotor_voltage_for, stator_current_command, torque_window

# --- controller parameters (per motor) -------------------------------------------------------
(
    CP_KP,
    CP_KI,
    CP_KF,
    CP_Q_REF,
    CP_I_S_MAX,
    CP_I_R_MAX,
    CP_THETA_ADJ,
    CP_M_ADJ,
    CP_W_E_NOM,
    CP_SPEED_TAU,
    CP_FREQ_TAU,
    CP_V_MIN,
    CP_T_S,
) = range(13)
N_CTRL_PARAMS = 13

# --- controller state (per motor) ------------------------------------------------------------
(
    CS_E_INT,
    CS_THETA_PREV,
    CS_W_EST,
    CS_W_E_EST,
    CS_ANGLE_G_PREV,
    CS_VR_RE,
    CS_VR_IM,
    CS_TAU_COM,
    CS_STARTED,
) = range(9)
N_CTRL_STATES = 9

# --- event flags, one bit each, recorded per sample ------------------------------------------
FLAG_TORQUE_LIMIT = 1  # speed PI output clipped to the on-line torque limits
FLAG_SQRT_LIMIT = 2  # radicand of (22)/(24) negative: command limited
FLAG_SUPPLY_LOST = 4  # measured stator voltage below V_min: last safe output held
FLAG_NO_ROTOR_MARGIN = 8  # rotor current limit below magnetising need: torque window empty
FLAG_CONVERTER_SAT = 16  # converter could not apply the commanded rotor voltage
#: below this estimated supply frequency [rad/s] the law (20) is not evaluated (Z_MS -> 0)
MIN_SUPPLY_FREQUENCY = 1.0

EVENT_NAMES = (
    "torque_limit",
    "sqrt_limit",
    "supply_lost",
    "no_rotor_margin",
    "converter_saturation",
)


@jit
def _wrap(angle):
    return (angle + np.pi) % (2.0 * np.pi) - np.pi


@jit
def estimate_speeds(cp, cs, theta_meas, v_g):
    """Update shaft speed and supply frequency estimates from encoder and grid-voltage samples.

    Shaft speed: backward difference of the encoder angle through a first-order low-pass filter of
    time constant CP_SPEED_TAU (0: none). Supply frequency: difference of the grid-voltage angle,
    filtered with CP_FREQ_TAU, starting from the nominal value.
    """
    T_s = cp[CP_T_S]
    if cs[CS_STARTED] == 0.0:
        cs[CS_THETA_PREV] = theta_meas
        cs[CS_W_EST] = 0.0
        cs[CS_W_E_EST] = cp[CP_W_E_NOM]
        cs[CS_ANGLE_G_PREV] = np.angle(v_g)
        cs[CS_STARTED] = 1.0
        return
    w_raw = (theta_meas - cs[CS_THETA_PREV]) / T_s
    cs[CS_THETA_PREV] = theta_meas
    cs[CS_W_EST] += T_s / (cp[CP_SPEED_TAU] + T_s) * (w_raw - cs[CS_W_EST])
    if np.abs(v_g) > cp[CP_V_MIN]:
        angle_g = np.angle(v_g)
        w_e_raw = _wrap(angle_g - cs[CS_ANGLE_G_PREV]) / T_s
        cs[CS_ANGLE_G_PREV] = angle_g
        cs[CS_W_E_EST] += T_s / (cp[CP_FREQ_TAU] + T_s) * (w_e_raw - cs[CS_W_E_EST])


@jit
def voltage_command_step(p_est, cp, cs, v_s, v_g, theta_meas, w_ref):
    """One controller sample in voltage-command mode; returns (v_r in rotor coordinates, flags).

    Speed PI (25) inside the torque window of case 1 (30), (32), (37) computed from the measured
    stator voltage and frequency; stator current command (22); rotor voltage (20) with the
    adjustment m_adj e^{j theta_adj} of (28); rotation by the stator-voltage angle theta_e and the
    encoder angle n_p theta (Bodson (3)-(4)). ``p_est`` are the controller's machine parameters.
    """
    estimate_speeds(cp, cs, theta_meas, v_g)
    held = complex(cs[CS_VR_RE], cs[CS_VR_IM])
    v_s_mag = np.abs(v_s)
    w_e = cs[CS_W_E_EST]
    if v_s_mag < cp[CP_V_MIN] or w_e < MIN_SUPPLY_FREQUENCY:
        return held, FLAG_SUPPLY_LOST
    flags = 0
    w = cs[CS_W_EST]
    tau_lo, tau_hi, feasible = torque_window(p_est, w_e, v_s_mag, cp[CP_I_S_MAX], cp[CP_I_R_MAX])
    if not feasible:
        flags |= FLAG_NO_ROTOR_MARGIN
    tau_com, cs[CS_E_INT], clipped = speed_pi(
        cp[CP_KP], cp[CP_KI], cp[CP_KF], cs[CS_E_INT], w_ref, w, tau_lo, tau_hi, cp[CP_T_S]
    )
    if clipped:
        flags |= FLAG_TORQUE_LIMIT
    cs[CS_TAU_COM] = tau_com
    i_s_com, sqrt_limited = stator_current_command(p_est, w_e, v_s_mag, tau_com, cp[CP_Q_REF])
    if sqrt_limited:
        flags |= FLAG_SQRT_LIMIT
    adjust = np.exp(1j * cp[CP_THETA_ADJ])
    # (20) is linear in (v_s, i_s): the magnitude adjustment of (28) scales the v_s term only
    v_r = adjust * (
        rotor_voltage_for(p_est, w_e, w, cp[CP_M_ADJ] * v_s_mag, 0.0)
        + rotor_voltage_for(p_est, w_e, w, 0.0, i_s_com)
    )
    # stator-voltage frame -> stationary (e^{j theta_e}) -> rotor coordinates (e^{-j n_p theta})
    v_r_rotor = v_r * (v_s / v_s_mag) * np.exp(-1j * p_est[N_P] * theta_meas)
    cs[CS_VR_RE], cs[CS_VR_IM] = v_r_rotor.real, v_r_rotor.imag
    return v_r_rotor, flags
