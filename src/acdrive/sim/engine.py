"""The compiled fixed-step engine: plant, sensors, converters and controllers in one loop.

Sampled-data structure (GUIDE: a hard boundary between plant and controller):
at each sample t_k = k T_s the sensors read the plant, each controller computes its rotor voltage,
the converter holds it (zero-order hold) and the plant is integrated over [t_k, t_k + T_s] with
``n_sub`` classical Runge-Kutta (RK4) steps. Nothing calls back into Python inside the loop.
``run_batch`` runs many independent variants in parallel over a leading batch axis.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from acdrive.control.dfim import (
    CS_TAU_COM,
    CS_VR_IM,
    CS_VR_RE,
    FLAG_CONVERTER_SAT,
    voltage_command_step,
)
from acdrive.jit import jit
from acdrive.machines.dfim import N_P, electromagnetic_torque
from acdrive.plant.converter import converter_output
from acdrive.plant.dfim_bus import OMEGA, STATES_PER_MOTOR, THETA, motor_currents, plant_derivatives
from acdrive.plant.profiles import profile_at
from acdrive.plant.sensors import encoder_angle

# --- logged signals, per motor and per logged sample -----------------------------------------
(
    LOG_W,
    LOG_W_REF,
    LOG_TAU_COM,
    LOG_TAU_E,
    LOG_V_S,
    LOG_V_R,
    LOG_I_S,
    LOG_I_R,
    LOG_I_RX,
    LOG_I_RY,
    LOG_FLAGS,
) = range(11)
N_LOG = 11
LOG_NAMES = (
    "w",
    "w_ref",
    "tau_com",
    "tau_e",
    "v_s_mag",
    "v_r_mag",
    "i_s_mag",
    "i_r_mag",
    "i_rx",
    "i_ry",
    "flags",
)

# --- per-motor sensor and converter data -----------------------------------------------------
SN_ENC_OFFSET, SN_ENC_CPR, SN_V_R_MAX = range(3)
N_SENSOR = 3

STATUS_OK, STATUS_NONFINITE = 0, 1
SQRT_2_3 = np.sqrt(2.0 / 3.0)


@jit
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


@jit
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
def log_sample(log_row, p, x, o, closed, v_s, v_r_rotor, w_ref, tau_com, flags):
    """Fill one row of logged signals for one motor from the true plant state."""
    i_s, i_r = motor_currents(p, complex(x[o], x[o + 1]), complex(x[o + 2], x[o + 3]), closed)
    i_r_rotor = i_r * np.exp(-1j * p[N_P] * x[o + THETA])
    log_row[LOG_W] = x[o + OMEGA]
    log_row[LOG_W_REF] = w_ref
    log_row[LOG_TAU_COM] = tau_com
    log_row[LOG_TAU_E] = electromagnetic_torque(p, i_s, i_r)
    log_row[LOG_V_S] = np.abs(v_s)
    log_row[LOG_V_R] = np.abs(v_r_rotor)
    log_row[LOG_I_S] = np.abs(i_s)
    log_row[LOG_I_R] = np.abs(i_r)
    # rotor phase currents X and Y from the inverse transform (4) in rotor coordinates
    log_row[LOG_I_RX] = SQRT_2_3 * i_r_rotor.real
    log_row[LOG_I_RY] = SQRT_2_3 * (-0.5 * i_r_rotor.real + 0.5 * np.sqrt(3.0) * i_r_rotor.imag)
    log_row[LOG_FLAGS] = flags


@jit
def run_drive(
    x,
    machines,
    bus,
    supply,
    load_t,
    load_tau,
    sensors,
    p_est,
    cp,
    cs,
    ref_t,
    ref_w,
    closed,
    T_s,
    n_sub,
    n_steps,
    log_every,
    log,
):
    """Run ``n_steps`` control samples from state ``x`` (modified in place).

    Returns (steps done, status). ``log`` has shape (n_steps // log_every, n_motors, N_LOG).
    Stops early with STATUS_NONFINITE if the state stops being finite (never returns NaN silently).
    """
    n = machines.shape[0]
    work = np.empty((5, x.shape[0]))
    v_term = np.zeros(n, dtype=np.complex128)
    v_r = np.zeros(n, dtype=np.complex128)
    flags = np.zeros(n, dtype=np.int64)
    for k in range(n):
        v_r[k] = complex(cs[k, CS_VR_RE], cs[k, CS_VR_IM])  # output held from a previous run
    for step in range(n_steps):
        t = step * T_s
        # sample: sensors read the plant with the inputs held from the previous period
        v_g = plant_derivatives(
            t, x, work[0], machines, bus, supply, load_t, load_tau, v_r, closed, v_term
        )
        for k in range(n):
            o = STATES_PER_MOTOR * k
            theta_meas = encoder_angle(
                x[o + THETA], sensors[k, SN_ENC_OFFSET], sensors[k, SN_ENC_CPR]
            )
            w_ref = profile_at(ref_t[k], ref_w[k], t)
            command, flags[k] = voltage_command_step(
                p_est[k], cp[k], cs[k], v_term[k], v_g, theta_meas, w_ref
            )
            v_r[k], saturated = converter_output(command, sensors[k, SN_V_R_MAX])
            if saturated:
                flags[k] |= FLAG_CONVERTER_SAT
            if step % log_every == 0 and step // log_every < log.shape[0]:
                log_sample(
                    log[step // log_every, k],
                    machines[k],
                    x,
                    o,
                    closed[k],
                    v_term[k],
                    v_r[k],
                    w_ref,
                    cs[k, CS_TAU_COM],
                    flags[k],
                )
        advance_plant(
            t, x, T_s, n_sub, machines, bus, supply, load_t, load_tau, v_r, closed, work, v_term
        )
        for i in range(x.shape[0]):
            if not np.isfinite(x[i]):
                return step + 1, STATUS_NONFINITE
    return n_steps, STATUS_OK


@njit(cache=True, parallel=True, error_model="numpy")
def run_batch(
    xs,
    machines,
    bus,
    supply,
    load_t,
    load_tau,
    sensors,
    p_est,
    cp,
    cs,
    ref_t,
    ref_w,
    closed,
    T_s,
    n_sub,
    n_steps,
    log_every,
    logs,
    steps_done,
    status,
):
    """``run_drive`` over a leading batch axis of every per-variant array, in parallel."""
    for b in prange(xs.shape[0]):
        steps_done[b], status[b] = run_drive(
            xs[b],
            machines[b],
            bus[b],
            supply,
            load_t[b],
            load_tau[b],
            sensors[b],
            p_est[b],
            cp[b],
            cs[b],
            ref_t[b],
            ref_w[b],
            closed[b],
            T_s,
            n_sub,
            n_steps,
            log_every,
            logs[b],
        )
