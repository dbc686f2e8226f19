"""The cage induction motor as a continuous plant part (Amezquita-Brooks et al. (1)-(2)).

Stationary frame, states the stator current i_s and the rotor flux psi_r (complex space vectors in
acdrive's power-invariant scaling, Bodson (8)); w_r = n_p w is the electrical rotor speed:

    sigma L_s di_s/dt = v_s - (R_s + L_m^2 R_r / L_r^2) i_s + (L_m / L_r) (R_r / L_r - j w_r) psi_r
    dpsi_r/dt        = (L_m R_r / L_r) i_s - (R_r / L_r - j w_r) psi_r
    tau_e            = n_p (L_m / L_r) Im(conj(psi_r) i_s)

The first two lines are the rows of (1) (matrix A, B) written as complex numbers; the torque is
(2) with the paper's amplitude-invariant 3/2 absorbed by the power-invariant scaling. The
right-hand side divides by L_r and by sigma L_s through their reciprocals (and so does the C
generated from it).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from acdrive._jit import jit_fast
from acdrive.core._signals import Layout, cplx, real
from acdrive.machines._record import MachinePart
from acdrive.machines._windings import winding_params

#: the cage IM's parameters, declared once: ``machines.IMParams`` is generated from them
PARAMS = winding_params("L_m", "magnetising (mutual) inductance")
STATES = Layout(
    cplx("i_s", "A", "stator current, stationary frame"),
    cplx("psi_r", "Wb", "rotor flux linkage, stationary frame"),
)
INPUTS = Layout(
    cplx("v_s", "V", "stator voltage, stationary frame"),
    real("w", "rad/s", "mechanical rotor speed"),
)
OUTPUTS = Layout(
    cplx("i_s", "A", "stator current, stationary frame"),
    cplx("psi_r", "Wb", "rotor flux linkage, stationary frame"),
    real("tau_e", "N m", "electromagnetic torque"),
)
_R_S, _R_R, _L_S, _L_R, _L_M, _N_P = (
    PARAMS.slot(n) for n in ("R_s", "R_r", "L_s", "L_r", "L_m", "n_p")
)
_I_S, _PSI_R = STATES.slot("i_s"), STATES.slot("psi_r")
_V_S, _W = INPUTS.slot("v_s"), INPUTS.slot("w")
_Y_I_S, _Y_PSI_R, _Y_TAU = OUTPUTS.slot("i_s"), OUTPUTS.slot("psi_r"), OUTPUTS.slot("tau_e")


@jit_fast
def cage_torque(p, i_s, psi_r):
    """tau_e = n_p (L_m / L_r) Im(conj(psi_r) i_s) (Amezquita-Brooks et al. (2))."""
    return p[_N_P] * p[_L_M] / p[_L_R] * (np.conj(psi_r) * i_s).imag


@jit_fast
def cage_state_outputs(t, x, p, y):
    i_s = complex(x[_I_S], x[_I_S + 1])
    psi_r = complex(x[_PSI_R], x[_PSI_R + 1])
    y[_Y_I_S], y[_Y_I_S + 1] = i_s.real, i_s.imag
    y[_Y_PSI_R], y[_Y_PSI_R + 1] = psi_r.real, psi_r.imag
    y[_Y_TAU] = cage_torque(p, i_s, psi_r)


@jit_fast
def cage_rhs(t, x, u, p, y, dx):
    """Amezquita-Brooks et al. (1) in complex form (module docstring)."""
    i_s = complex(x[_I_S], x[_I_S + 1])
    psi_r = complex(x[_PSI_R], x[_PSI_R + 1])
    v_s = complex(u[_V_S], u[_V_S + 1])
    R_s, R_r, L_s, L_r, L_m = p[_R_S], p[_R_R], p[_L_S], p[_L_R], p[_L_M]
    # each division once, as a reciprocal (a division costs several multiplications, and the
    # compiler may not make this change itself without changing where the results round)
    over_L_r = 1.0 / L_r
    sigma_L_s = L_s - L_m * L_m * over_L_r
    rotor_pole = R_r * over_L_r - 1j * p[_N_P] * u[_W]  # R_r/L_r - j w_r
    di_s = (
        v_s
        - (R_s + L_m * L_m * R_r * (over_L_r * over_L_r)) * i_s
        + L_m * over_L_r * rotor_pole * psi_r
    )
    over_sigma_L_s = 1.0 / sigma_L_s
    di_s = complex(di_s.real * over_sigma_L_s, di_s.imag * over_sigma_L_s)
    dpsi_r = L_m * R_r * over_L_r * i_s - rotor_pole * psi_r
    dx[_I_S], dx[_I_S + 1] = di_s.real, di_s.imag
    dx[_PSI_R], dx[_PSI_R + 1] = dpsi_r.real, dpsi_r.imag


class CageInductionMachine(MachinePart):
    """Cage induction motor, Amezquita-Brooks et al. (1)-(2); parameters as ``IMParams``."""

    SOURCE = "Amezquita-Brooks et al. (1)-(2), complex form (machines._cage_part)"

    PARAMS, STATES, INPUTS, OUTPUTS = PARAMS, STATES, INPUTS, OUTPUTS
    DEFAULTS: ClassVar[dict] = {"n_p": 1}
    state_outputs = cage_state_outputs
    rhs = cage_rhs
