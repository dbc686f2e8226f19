"""Continuous-time plant: N DFIMs with their shafts, on one three-phase supply behind a shared
series R-L impedance (Bodson's transformer), each stator connected through a relay.

Model: Bodson (9) written in the stationary frame (theta_e = 0, so w_e = 0 in (9)) with the
stator and rotor flux linkages as states,

    d psi_s/dt = v_s - R_s i_s
    d psi_r/dt = v_r - R_r i_r + j n_p w psi_r
    psi_s = L_s i_s + M i_r,   psi_r = M i_s + L_r i_r,
    J dw/dt = tau_e - tau_L - B w - tau_c tanh(w / W_COULOMB),   d theta/dt = w     (26)

Rotor quantities are referred to the stator (rotor frame value times e^{j n_p theta}, Bodson (3)).
The bus voltage follows from the supply and the shared impedance,
    v_bus = v_g - R_g sum(i_s) - L_g sum(d i_s/dt),
which is linear in v_bus because each d i_s/dt is, so it is solved exactly at every evaluation.
An open relay forces i_s = 0: the stator flux is then M i_r and the stator terminal voltage is
d psi_s/dt = (M / L_r) d psi_r/dt (the voltage the synchroniser matches to the grid).

Rotations without trigonometry: the rotor phasor u_r = e^{j n_p theta} and the supply phasor
u_g = e^{j theta_g} are carried as states, du_r/dt = j n_p w u_r and du_g/dt = j w_g u_g, so the
right-hand side needs no sine or cosine; ``project_phasors`` resets them from the angles at every
sample, so they never drift from the unit circle.

State vector layout: for motor k, x[8k : 8k+8] = (Re psi_s, Im psi_s, Re psi_r, Im psi_r, theta, w,
Re u_r, Im u_r); then the supply angle theta_g (d theta_g/dt = 2 pi f(t)) and Re u_g, Im u_g.
The rotor converter may lose a fundamental voltage against the rotor current (dead time and
device drops, first-harmonic model): v_R,applied = v_R - V_loss i_R / |i_R|.
"""

from __future__ import annotations

import numpy as np

from acdrive._jit import jit_fast
from acdrive.machines._dfim import (
    L_R,
    L_S,
    M_SR,
    N_P,
    R_R,
    R_S,
    currents_from_fluxes,
    electromagnetic_torque,
)

from .profiles import profile_at
from .vector import B_VISCOUS, J_INERTIA, N_MACHINE_PARAMS, TAU_COULOMB

STATES_PER_MOTOR = 8
PSI_S_RE, PSI_S_IM, PSI_R_RE, PSI_R_IM, THETA, OMEGA, ROT_RE, ROT_IM = range(STATES_PER_MOTOR)
# supply states after the motors' (offsets from STATES_PER_MOTOR * n_motors)
THETA_G, SUP_RE, SUP_IM = range(3)
#: speed scale of the smooth Coulomb friction tau_c tanh(w / W_COULOMB) [rad/s]
W_COULOMB = 0.5
from acdrive._frames import K_PEAK as SQRT_3_2  # Bodson (8)

# per-motor plant data: the machine vector (acdrive.machines._dfim) followed by the converter's
# fundamental voltage loss against the rotor current [V, space-vector magnitude]
CONVERTER_LOSS = N_MACHINE_PARAMS
N_MOTOR_DATA = N_MACHINE_PARAMS + 1
#: current scale [A] below which the converter loss fades out (keeps the right-hand side smooth)
LOSS_CURRENT_SCALE = 0.05

# supply / bus parameters
BUS_R, BUS_L = 0, 1


def n_states(n_motors: int) -> int:
    return STATES_PER_MOTOR * n_motors + 3


@jit_fast
def project_phasors(x, machines):
    """Set the rotor and supply phasor states to e^{j n_p theta} and e^{j theta_g} exactly."""
    n = machines.shape[0]
    for k in range(n):
        o = STATES_PER_MOTOR * k
        angle = machines[k, N_P] * x[o + THETA]
        x[o + ROT_RE], x[o + ROT_IM] = np.cos(angle), np.sin(angle)
    g = STATES_PER_MOTOR * n
    x[g + SUP_RE], x[g + SUP_IM] = np.cos(x[g + THETA_G]), np.sin(x[g + THETA_G])


@jit_fast
def motor_currents(p, psi_s, psi_r, closed):
    """(i_s, i_r) from the flux linkages; i_s = 0 and psi_s irrelevant when the relay is open."""
    if closed:
        return currents_from_fluxes(p, psi_s, psi_r)
    return 0.0 + 0.0j, psi_r * (1.0 / p[L_R])


@jit_fast
def supply_voltage(u_g, t, supply_V_t, supply_V):
    """Grid space vector sqrt(3/2) V_pk(t) e^{j theta_g}, with u_g = e^{j theta_g} (Bodson (8))."""
    return SQRT_3_2 * profile_at(supply_V_t, supply_V, t) * u_g


@jit_fast
def plant_derivatives(t, x, dx, machines, bus, supply, load_t, load_tau, v_r_rotor, closed, v_term):
    """Write dx/dt into ``dx`` and the stator terminal voltages into ``v_term``; return v_g.

    supply: tuple (V_times, V_pk_values, f_times, f_values); load_t/load_tau: per-motor profiles.
    v_r_rotor[k]: rotor voltage of motor k in rotor coordinates (held by the converter).
    """
    n = machines.shape[0]
    g = STATES_PER_MOTOR * n
    u_g = complex(x[g + SUP_RE], x[g + SUP_IM])
    v_g = supply_voltage(u_g, t, supply[0], supply[1])
    # First pass: currents, rotor-flux derivatives, and the terms of the bus equation.
    sum_i_s = 0.0 + 0.0j
    sum_a = 0.0  # sum of d(di_s/dt)/d v_bus
    sum_b = 0.0 + 0.0j  # sum of the v_bus-independent parts of di_s/dt
    for k in range(n):
        p = machines[k]
        o = STATES_PER_MOTOR * k
        psi_s = complex(x[o + PSI_S_RE], x[o + PSI_S_IM])
        psi_r = complex(x[o + PSI_R_RE], x[o + PSI_R_IM])
        i_s, i_r = motor_currents(p, psi_s, psi_r, closed[k])
        u_r = complex(x[o + ROT_RE], x[o + ROT_IM])
        w_el = p[N_P] * x[o + OMEGA]  # electrical rotor speed
        v_r = v_r_rotor[k] * u_r
        if p[CONVERTER_LOSS] > 0.0:  # dead time and device drops oppose the rotor current
            squared = i_r.real * i_r.real + i_r.imag * i_r.imag + LOSS_CURRENT_SCALE**2
            v_r -= p[CONVERTER_LOSS] / np.sqrt(squared) * i_r
        dpsi_r = v_r - p[R_R] * i_r + 1j * w_el * psi_r
        du_r = 1j * w_el * u_r
        dx[o + ROT_RE], dx[o + ROT_IM] = du_r.real, du_r.imag
        dx[o + PSI_R_RE], dx[o + PSI_R_IM] = dpsi_r.real, dpsi_r.imag
        if closed[k]:
            inv_det = 1.0 / (p[L_S] * p[L_R] - p[M_SR] * p[M_SR])
            sum_i_s += i_s
            sum_a += p[L_R] * inv_det
            sum_b += (-p[L_R] * p[R_S] * i_s - p[M_SR] * dpsi_r) * inv_det
        # mechanics (26) with load and friction
        w = x[o + OMEGA]
        tau_l = profile_at(load_t[k], load_tau[k], t) + p[B_VISCOUS] * w
        if p[TAU_COULOMB] != 0.0:
            tau_l += p[TAU_COULOMB] * np.tanh(w / W_COULOMB)
        dx[o + OMEGA] = (electromagnetic_torque(p, i_s, i_r) - tau_l) / p[J_INERTIA]
        dx[o + THETA] = w
    v_bus = (v_g - bus[BUS_R] * sum_i_s - bus[BUS_L] * sum_b) * (1.0 / (1.0 + bus[BUS_L] * sum_a))
    # Second pass: stator fluxes, which need the bus voltage.
    for k in range(n):
        p = machines[k]
        o = STATES_PER_MOTOR * k
        if closed[k]:
            psi_s = complex(x[o + PSI_S_RE], x[o + PSI_S_IM])
            psi_r = complex(x[o + PSI_R_RE], x[o + PSI_R_IM])
            i_s, _ = motor_currents(p, psi_s, psi_r, True)
            dpsi_s = v_bus - p[R_S] * i_s
            v_term[k] = v_bus
        else:
            dpsi_s = (p[M_SR] / p[L_R]) * complex(dx[o + PSI_R_RE], dx[o + PSI_R_IM])
            v_term[k] = dpsi_s
        dx[o + PSI_S_RE], dx[o + PSI_S_IM] = dpsi_s.real, dpsi_s.imag
    w_g = 2.0 * np.pi * profile_at(supply[2], supply[3], t)
    du_g = 1j * w_g * u_g
    dx[g + THETA_G], dx[g + SUP_RE], dx[g + SUP_IM] = w_g, du_g.real, du_g.imag
    return v_g
