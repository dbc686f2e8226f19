"""The compiled fixed-step engine: plant, sensors, converters and controllers in one loop.

Sampled-data structure (GUIDE: a hard boundary between plant and controller):
at each sample t_k = k T_s the sensors read the plant, each controller computes its rotor voltage
(and may ask its relay to close), the converter holds the voltage (zero-order hold) and the plant
is integrated over [t_k, t_k + T_s] with ``n_sub`` classical Runge-Kutta (RK4) steps. Nothing calls
back into Python inside the loop. ``run_batch`` runs independent variants in parallel over a
leading batch axis.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from acdrive._frames import complex_to_abc_nb
from acdrive._jit import jit, jit_fast

# fmt: off
from acdrive.drives.dfim._result import N_LOG
from acdrive.machines._dfim import electromagnetic_torque
from acdrive.plant._converter import converter_output
from acdrive.plant._sensors import encoder_angle

from .controller import (
    CS_I_R_COM,
    CS_I_R_COM_IM,
    CS_I_R_COM_RE,
    CS_I_R_F_IM,
    CS_I_R_F_RE,
    CS_M_ADJ,
    CS_MODE,
    CS_PHASE,
    CS_TAU_COM,
    CS_THETA_ADJ,
    CS_VR_IM,
    CS_VR_RE,
    FLAG_CONVERTER_SAT,
    controller_step,
)
from .dfim_bus import (
    OMEGA,
    ROT_IM,
    ROT_RE,
    STATES_PER_MOTOR,
    THETA,
    motor_currents,
    plant_derivatives,
    project_phasors,
)
from .profiles import profile_at

(LOG_W, LOG_W_REF, LOG_TAU_COM, LOG_TAU_E, LOG_V_S, LOG_V_R, LOG_I_S, LOG_I_R, LOG_I_RX,
 LOG_I_RY, LOG_FLAGS, LOG_I_R_COM, LOG_Q_S, LOG_V_MISMATCH, LOG_THETA_ADJ, LOG_M_ADJ, LOG_PHASE,
 LOG_MODE, LOG_RELAY, LOG_I_R_COM_D, LOG_I_R_COM_Q, LOG_I_R_D, LOG_I_R_Q) = range(N_LOG)

# --- per-motor sensor and converter data -----------------------------------------------------
SN_ENC_OFFSET, SN_ENC_CPR, SN_V_R_MAX, SN_CURRENT_FAULT_T = range(4)
N_SENSOR = 4
# fmt: on

STATUS_OK, STATUS_NONFINITE = 0, 1


@jit_fast
def rk4_step(t, x, h, machines, bus, supply, load_t, load_tau, v_r, closed, work, v_term):
    """Advance ``x`` in place by one RK4 step of length h with held inputs."""
    k1, k2, k3, k4, xt = work[0], work[1], work[2], work[3], work[4]
    plant_derivatives(t, x, k1, machines, bus, supply, load_t, load_tau, v_r, closed, v_term)
    for i in range(x.shape[0]):
        xt[i] = x[i] + 0.5 * h * k1[i]
    plant_derivatives(
        t + 0.5 * h, xt, k2, machines, bus, supply, load_t, load_tau, v_r, closed, v_term
    )
    for i in range(x.shape[0]):
        xt[i] = x[i] + 0.5 * h * k2[i]
    plant_derivatives(
        t + 0.5 * h, xt, k3, machines, bus, supply, load_t, load_tau, v_r, closed, v_term
    )
    for i in range(x.shape[0]):
        xt[i] = x[i] + h * k3[i]
    plant_derivatives(t + h, xt, k4, machines, bus, supply, load_t, load_tau, v_r, closed, v_term)
    for i in range(x.shape[0]):
        x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])


@jit_fast
def advance_plant(
    t, x, T_s, n_sub, machines, bus, supply, load_t, load_tau, v_r, closed, work, v_term
):
    """Integrate the plant over one sample period with ``n_sub`` RK4 steps (inputs held)."""
    h = T_s / n_sub
    for j in range(n_sub):
        rk4_step(
            t + j * h, x, h, machines, bus, supply, load_t, load_tau, v_r, closed, work, v_term
        )


@jit
def measured_currents(p, x, o, closed):
    """(i_s in the stationary frame, i_r in rotor coordinates) from the plant state."""
    i_s, i_r = motor_currents(p, complex(x[o], x[o + 1]), complex(x[o + 2], x[o + 3]), closed)
    return i_s, i_r * complex(x[o + ROT_RE], -x[o + ROT_IM])  # e^{-j n_p theta}


@jit
def log_sample(row, p, x, o, closed, v_s, v_g, v_r_rotor, w_ref, cs, flags):
    """Fill one row of logged signals for one motor from the true plant state."""
    i_s, i_r_rotor = measured_currents(p, x, o, closed)
    row[LOG_W] = x[o + OMEGA]
    row[LOG_W_REF] = w_ref
    row[LOG_TAU_COM] = cs[CS_TAU_COM]
    row[LOG_TAU_E] = electromagnetic_torque(
        p, i_s, i_r_rotor * complex(x[o + ROT_RE], x[o + ROT_IM])
    )
    row[LOG_V_S] = np.abs(v_s)
    row[LOG_V_R] = np.abs(v_r_rotor)
    row[LOG_I_S] = np.abs(i_s)
    row[LOG_I_R] = np.abs(i_r_rotor)
    # rotor phase currents X and Y from the inverse transform (4) in rotor coordinates
    row[LOG_I_RX], row[LOG_I_RY], _ = complex_to_abc_nb(i_r_rotor, 0.0)
    row[LOG_FLAGS] = flags
    row[LOG_I_R_COM] = cs[CS_I_R_COM]
    row[LOG_Q_S] = (v_s * np.conj(i_s)).imag  # (5)
    row[LOG_V_MISMATCH] = np.abs(v_s - v_g) / max(np.abs(v_g), 1e-12)
    row[LOG_THETA_ADJ] = cs[CS_THETA_ADJ]
    row[LOG_M_ADJ] = cs[CS_M_ADJ]
    row[LOG_PHASE] = cs[CS_PHASE]
    row[LOG_MODE] = cs[CS_MODE]
    row[LOG_RELAY] = 1.0 if closed else 0.0
    # rotor current command (43) and measured rotor current in the controller's stator-voltage frame
    row[LOG_I_R_COM_D], row[LOG_I_R_COM_Q] = cs[CS_I_R_COM_RE], cs[CS_I_R_COM_IM]
    row[LOG_I_R_D], row[LOG_I_R_Q] = cs[CS_I_R_F_RE], cs[CS_I_R_F_IM]


@jit
def run_drive(x, machines, bus, supply, load_t, load_tau, sensors, p_est, cp, cs, ref_t, ref_w,
              closed, T_s, n_sub, n_steps, log_every, log):  # fmt: skip
    """Run ``n_steps`` control samples from state ``x`` (``x``, ``cs``, ``closed`` modified in place).

    Returns (steps done, status). ``log`` has shape (ceil(n_steps / log_every), n_motors, N_LOG).
    Stops early with STATUS_NONFINITE if the state stops being finite (never returns NaN silently).
    """
    n = machines.shape[0]
    work = np.empty((5, x.shape[0]))
    v_term = np.zeros(n, dtype=np.complex128)
    v_r = np.zeros(n, dtype=np.complex128)
    for k in range(n):
        v_r[k] = complex(cs[k, CS_VR_RE], cs[k, CS_VR_IM])  # output held from a previous run
    for step in range(n_steps):
        t = step * T_s
        project_phasors(x, machines)
        # sample: sensors read the plant with the inputs held from the previous period
        v_g = plant_derivatives(
            t, x, work[0], machines, bus, supply, load_t, load_tau, v_r, closed, v_term
        )
        for k in range(n):
            o = STATES_PER_MOTOR * k
            theta_meas = encoder_angle(
                x[o + THETA], sensors[k, SN_ENC_OFFSET], sensors[k, SN_ENC_CPR]
            )
            i_s, i_r_rotor = measured_currents(machines[k], x, o, closed[k])
            if t >= sensors[k, SN_CURRENT_FAULT_T]:
                i_s, i_r_rotor = complex(np.nan, np.nan), complex(np.nan, np.nan)
            w_ref = profile_at(ref_t[k], ref_w[k], t)
            command, flags, close = controller_step(
                p_est[k], cp[k], cs[k], v_term[k], v_g, i_s, i_r_rotor, theta_meas, w_ref
            )
            v_r[k], saturated = converter_output(command, sensors[k, SN_V_R_MAX])
            if saturated:
                flags |= FLAG_CONVERTER_SAT
            if step % log_every == 0:
                log_sample(log[step // log_every, k], machines[k], x, o, closed[k], v_term[k], v_g,
                           v_r[k], w_ref, cs[k], flags)  # fmt: skip
            if close:
                closed[k] = True
        advance_plant(
            t, x, T_s, n_sub, machines, bus, supply, load_t, load_tau, v_r, closed, work, v_term
        )
        for i in range(x.shape[0]):
            if not np.isfinite(x[i]):
                return step + 1, STATUS_NONFINITE
    return n_steps, STATUS_OK


@njit(cache=True, parallel=True, error_model="numpy")
def run_batch(xs, machines, bus, supply, load_t, load_tau, sensors, p_est, cp, cs, ref_t, ref_w,
              closed, T_s, n_sub, n_steps, log_every, logs, steps_done, status):  # fmt: skip
    """``run_drive`` over a leading batch axis of every per-variant array, in parallel."""
    for b in prange(xs.shape[0]):
        steps_done[b], status[b] = run_drive(
            xs[b], machines[b], bus[b], supply, load_t[b], load_tau[b], sensors[b], p_est[b], cp[b],
            cs[b], ref_t[b], ref_w[b], closed[b], T_s, n_sub, n_steps, log_every, logs[b],
        )  # fmt: skip
