"""The doubly-fed induction machine as a continuous plant part (Bodson (9), stationary frame).

States: stator and rotor flux linkages psi_s, psi_r in the stationary frame (rotor quantities
referred to the stator, Bodson (3)), the rotor angle theta and its phasor e_r = e^{j n_p theta}:

    dpsi_s/dt = v_s - R_s i_s                     (stator connected to the bus)
    dpsi_r/dt = v_r e_r - R_r i_r + j n_p w psi_r
    psi_s = L_s i_s + M i_r,   psi_r = M i_s + L_r i_r,   tau_e = n_p M Im(i_s conj(i_r))
    dtheta/dt = w,   de_r/dt = j n_p w e_r

v_r is the rotor voltage in rotor coordinates (what the rotor converter applies). Carrying e_r as
a state keeps trigonometry out of the right-hand side; ``project`` resets it from theta at every
sample so it never leaves the unit circle. theta is the shaft's angle integrated again from the
same speed input (the same numbers as the shaft's own angle).

The stator relay is the input ``connected`` (0 or 1, held between samples). An open relay forces
i_s = 0: psi_s = M i_r and the open stator's terminal voltage is (M/L_r) dpsi_r/dt (output
``v_open``, what a synchroniser compares with the grid).

A shared supply impedance (``plant.SupplyBus``) is solved exactly: with the stator
connected, di_s/dt = a v_s + b is affine in the stator voltage, a = L_r / (L_s L_r - M^2) and
b = -(L_r R_s i_s + M dpsi_r/dt) / (L_s L_r - M^2) (from the flux equations above); the machine
outputs a and b, the bus sums them over its machines.

The rotor converter's fundamental voltage loss (dead time and device drops, first-harmonic model)
opposes the rotor current, v_r,applied = v_r - V_loss i_r / sqrt(|i_r|^2 + i_0^2), with i_0 =
``LOSS_CURRENT_SCALE`` keeping the right-hand side smooth through zero current. It acts on the
continuous rotor current, so it lives with the rotor circuit here, not in the sampled converter.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from acdrive._jit import jit, jit_fast, jit_inline
from acdrive.core._signals import Layout, cplx, real
from acdrive.machines._record import MachinePart
from acdrive.machines._windings import winding_params

#: current scale [A] below which the converter loss fades out (keeps the right-hand side smooth)
LOSS_CURRENT_SCALE = 0.05

#: the DFIM's parameters, declared once: ``machines.DFIMParams`` is generated from them (less
#: V_loss, the rotor converter's), and every compiled DFIM function (``machines._dfim``, the
#: controller's estimates in ``control._bodson``) reads the slots below
WINDINGS = winding_params("M", "stator-rotor mutual inductance")
PARAMS = WINDINGS.extended(
    real(
        "V_loss",
        "V",
        "rotor converter's fundamental voltage loss against the rotor current",
        "nonnegative",
    ),
)
R_S, R_R, L_S, L_R, M_SR, N_P = (PARAMS.slot(n) for n in ("R_s", "R_r", "L_s", "L_r", "M", "n_p"))
_V_LOSS = PARAMS.slot("V_loss")
STATES = Layout(
    cplx("psi_s", "Wb", "stator flux linkage, stationary frame"),
    cplx("psi_r", "Wb", "rotor flux linkage referred to the stator, stationary frame"),
    real("theta", "rad", "mechanical rotor angle"),
    cplx("e_r", "", "rotor phasor e^{j n_p theta}"),
)
INPUTS = Layout(
    cplx("v_s", "V", "stator bus voltage, stationary frame (used while connected)"),
    cplx("v_r", "V", "rotor voltage in rotor coordinates"),
    real("w", "rad/s", "mechanical speed"),
    real("connected", "", "stator relay: 1 closed, 0 open"),
)
OUTPUTS = Layout(
    cplx("i_s", "A", "stator current, stationary frame"),
    cplx("i_r", "A", "rotor current referred to the stator, stationary frame"),
    cplx("i_r_rotor", "A", "rotor current in rotor coordinates"),
    real("tau_e", "N m", "electromagnetic torque"),
    cplx("v_open", "V", "stator terminal voltage while disconnected, (M/L_r) dpsi_r/dt; else 0"),
    cplx("dpsi_r", "V", "rotor flux linkage derivative dpsi_r/dt, stationary frame"),
    real("bus_gain", "1/H", "a of di_s/dt = a v_s + b (zero while disconnected)"),
    cplx("bus_drive", "A/s", "b of di_s/dt = a v_s + b (zero while disconnected)"),
)
_PSI_S, _PSI_R, _THETA, _E_R = (STATES.slot(n) for n in ("psi_s", "psi_r", "theta", "e_r"))
_V_S, _V_R, _W, _CONNECTED = (INPUTS.slot(n) for n in ("v_s", "v_r", "w", "connected"))
_Y_I_S, _Y_I_R, _Y_I_RR, _Y_TAU, _Y_V_OPEN, _Y_DPSI_R, _Y_A, _Y_B = (
    OUTPUTS.slot(n)
    for n in ("i_s", "i_r", "i_r_rotor", "tau_e", "v_open", "dpsi_r", "bus_gain", "bus_drive")
)


@jit_fast
def currents_from_fluxes(p, psi_s, psi_r):
    """(i_s, i_r) from the flux linkages: the inverse of psi_s = L_s i_s + M i_r,
    psi_r = M i_s + L_r i_r (Bodson (9)), with a real determinant (no complex division)."""
    inv_det = 1.0 / (p[L_S] * p[L_R] - p[M_SR] * p[M_SR])
    i_s = (p[L_R] * psi_s - p[M_SR] * psi_r) * inv_det
    i_r = (p[L_S] * psi_r - p[M_SR] * psi_s) * inv_det
    return i_s, i_r


@jit
def electromagnetic_torque(p, i_s, i_r):
    """tau_e = n_p M Im(i_s i_r*) (Bodson (9), third line)."""
    return p[N_P] * p[M_SR] * (i_s * np.conj(i_r)).imag


@jit_inline
def winding_currents(p, psi_s, psi_r, connected):
    """(i_s, i_r) from the flux linkages; i_s = 0 while the stator is disconnected."""
    if connected:
        return currents_from_fluxes(p, psi_s, psi_r)
    return 0.0 + 0.0j, psi_r * (1.0 / p[L_R])


@jit_inline
def rotor_flux_derivative(x, u, p, i_r, psi_r):
    """dpsi_r/dt = v_r e_r - (converter loss) - R_r i_r + j n_p w psi_r (module docstring)."""
    e_r = complex(x[_E_R], x[_E_R + 1])
    v_r = complex(u[_V_R], u[_V_R + 1]) * e_r
    if p[_V_LOSS] > 0.0:
        squared = i_r.real * i_r.real + i_r.imag * i_r.imag + LOSS_CURRENT_SCALE**2
        v_r -= p[_V_LOSS] / np.sqrt(squared) * i_r
    return v_r - p[R_R] * i_r + 1j * (p[N_P] * u[_W]) * psi_r


@jit_fast
def dfim_direct_outputs(t, x, u, p, y):
    connected = u[_CONNECTED] != 0.0
    psi_r = complex(x[_PSI_R], x[_PSI_R + 1])
    i_s, i_r = winding_currents(p, complex(x[_PSI_S], x[_PSI_S + 1]), psi_r, connected)
    i_rr = i_r * complex(x[_E_R], -x[_E_R + 1])
    dpsi_r = rotor_flux_derivative(x, u, p, i_r, psi_r)
    y[_Y_I_S], y[_Y_I_S + 1] = i_s.real, i_s.imag
    y[_Y_I_R], y[_Y_I_R + 1] = i_r.real, i_r.imag
    y[_Y_I_RR], y[_Y_I_RR + 1] = i_rr.real, i_rr.imag
    y[_Y_TAU] = electromagnetic_torque(p, i_s, i_r)
    y[_Y_DPSI_R], y[_Y_DPSI_R + 1] = dpsi_r.real, dpsi_r.imag
    # both branches give every output a value and the stores come after them: a kernel that
    # writes the same slots on every path vectorises over lanes (sim._lockstep_source)
    if connected:
        inv_det = 1.0 / (p[L_S] * p[L_R] - p[M_SR] * p[M_SR])
        b = (-p[L_R] * p[R_S] * i_s - p[M_SR] * dpsi_r) * inv_det
        a = p[L_R] * inv_det
        v_open = 0.0 + 0.0j
    else:
        v_open = (p[M_SR] / p[L_R]) * dpsi_r
        a, b = 0.0, 0.0 + 0.0j
    y[_Y_A] = a
    y[_Y_B], y[_Y_B + 1] = b.real, b.imag
    y[_Y_V_OPEN], y[_Y_V_OPEN + 1] = v_open.real, v_open.imag


@jit_fast
def dfim_state_outputs(t, x, p, y):
    pass  # every output depends on the relay input: see dfim_direct_outputs


@jit_fast
def dfim_rhs(t, x, u, p, y, dx):
    """Bodson (9) with theta_e = 0 (module docstring); the currents and dpsi_r/dt are this
    evaluation's outputs ``y``."""
    if u[_CONNECTED] != 0.0:
        dx[_PSI_S] = u[_V_S] - p[R_S] * y[_Y_I_S]
        dx[_PSI_S + 1] = u[_V_S + 1] - p[R_S] * y[_Y_I_S + 1]
    else:
        dx[_PSI_S], dx[_PSI_S + 1] = y[_Y_V_OPEN], y[_Y_V_OPEN + 1]
    dx[_PSI_R], dx[_PSI_R + 1] = y[_Y_DPSI_R], y[_Y_DPSI_R + 1]
    w_el = p[N_P] * u[_W]
    de_r = 1j * w_el * complex(x[_E_R], x[_E_R + 1])
    dx[_THETA] = u[_W]
    dx[_E_R], dx[_E_R + 1] = de_r.real, de_r.imag


@jit_fast
def dfim_project(x, p):
    angle = p[N_P] * x[_THETA]
    x[_E_R], x[_E_R + 1] = np.cos(angle), np.sin(angle)


class DoublyFedMachine(MachinePart):
    """DFIM electrical model, Bodson (9); parameters as ``DFIMParams`` (mechanics separate)."""

    SOURCE = (
        "Bodson (9) in the stationary frame, flux linkages as states, the stator relay and the "
        "rotor converter's loss (machines._dfim_part)"
    )

    PARAMS, STATES, INPUTS, OUTPUTS = PARAMS, STATES, INPUTS, OUTPUTS
    DEFAULTS: ClassVar[dict] = {"V_loss": 0.0}
    INITIAL: ClassVar[dict] = {"e_r": 1.0}
    DIRECT_FROM = ("v_r", "w", "connected")
    DIRECT_OUTPUTS = ("i_s", "i_r", "i_r_rotor", "tau_e", "v_open", "bus_gain", "bus_drive")
    state_outputs = dfim_state_outputs
    direct_outputs = dfim_direct_outputs
    rhs = dfim_rhs
    project = dfim_project
