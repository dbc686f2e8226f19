"""The doubly-fed induction machine as a continuous plant part (Bodson (9), stationary frame).

States: stator and rotor flux linkages psi_s, psi_r in the stationary frame, rotor quantities
referred to the stator (Bodson (3)). With e_r = e^{j n_p theta}:

    dpsi_s/dt = v_s - R_s i_s
    dpsi_r/dt = v_r e_r - R_r i_r + j n_p w psi_r
    psi_s = L_s i_s + M i_r,   psi_r = M i_s + L_r i_r,   tau_e = n_p M Im(i_s conj(i_r))

v_r is the rotor voltage in rotor coordinates (what the rotor converter applies); ``i_r_rotor``
= i_r conj(e_r) is the rotor current a rotor-side sensor measures.
"""

from __future__ import annotations

import numpy as np

from acdrive.core.signals import Layout, cplx, real
from acdrive.jit import jit_fast
from acdrive.machines import dfim
from acdrive.machines.dfim import currents_from_fluxes, electromagnetic_torque
from acdrive.machines.windings import InductionWindings, winding_params

PARAMS = winding_params("M", "stator-rotor mutual inductance")
_R_S, _R_R, _L_S, _L_R, _M, _N_P = (
    PARAMS.slot(n) for n in ("R_s", "R_r", "L_s", "L_r", "M", "n_p")
)
# machines.dfim's compiled torque and current functions, reused here, read the same slots
if (_R_S, _R_R, _L_S, _L_R, _M, _N_P) != (
    dfim.R_S,
    dfim.R_R,
    dfim.L_S,
    dfim.L_R,
    dfim.M_SR,
    dfim.N_P,
):
    raise ImportError("DoublyFedMachine.PARAMS no longer matches machines.dfim's parameter slots")
STATES = Layout(
    cplx("psi_s", "Wb", "stator flux linkage, stationary frame"),
    cplx("psi_r", "Wb", "rotor flux linkage referred to the stator, stationary frame"),
)
INPUTS = Layout(
    cplx("v_s", "V", "stator terminal voltage, stationary frame"),
    cplx("v_r", "V", "rotor voltage in rotor coordinates"),
    real("w", "rad/s", "mechanical speed"),
    real("theta", "rad", "mechanical angle"),
)
OUTPUTS = Layout(
    cplx("i_s", "A", "stator current, stationary frame"),
    cplx("i_r", "A", "rotor current referred to the stator, stationary frame"),
    cplx("i_r_rotor", "A", "rotor current in rotor coordinates"),
    real("tau_e", "N m", "electromagnetic torque"),
)
_PSI_S, _PSI_R = STATES.slot("psi_s"), STATES.slot("psi_r")
_V_S, _V_R, _W, _THETA = (INPUTS.slot(n) for n in ("v_s", "v_r", "w", "theta"))
_Y_I_S, _Y_I_R, _Y_I_RR, _Y_TAU = (OUTPUTS.slot(n) for n in ("i_s", "i_r", "i_r_rotor", "tau_e"))


@jit_fast
def dfim_direct_outputs(t, x, u, p, y):
    i_s, i_r = currents_from_fluxes(
        p, complex(x[_PSI_S], x[_PSI_S + 1]), complex(x[_PSI_R], x[_PSI_R + 1])
    )
    angle = p[_N_P] * u[_THETA]
    i_rr = i_r * complex(np.cos(angle), -np.sin(angle))
    y[_Y_I_S], y[_Y_I_S + 1] = i_s.real, i_s.imag
    y[_Y_I_R], y[_Y_I_R + 1] = i_r.real, i_r.imag
    y[_Y_I_RR], y[_Y_I_RR + 1] = i_rr.real, i_rr.imag
    y[_Y_TAU] = electromagnetic_torque(p, i_s, i_r)


@jit_fast
def dfim_state_outputs(t, x, p, y):
    pass  # every output needs the rotor angle: see dfim_direct_outputs


@jit_fast
def dfim_rhs(t, x, u, p, dx):
    """Bodson (9) with theta_e = 0 (module docstring)."""
    psi_s = complex(x[_PSI_S], x[_PSI_S + 1])
    psi_r = complex(x[_PSI_R], x[_PSI_R + 1])
    i_s, i_r = currents_from_fluxes(p, psi_s, psi_r)
    angle = p[_N_P] * u[_THETA]
    v_r = complex(u[_V_R], u[_V_R + 1]) * complex(np.cos(angle), np.sin(angle))
    dpsi_s = complex(u[_V_S], u[_V_S + 1]) - p[_R_S] * i_s
    dpsi_r = v_r - p[_R_R] * i_r + 1j * p[_N_P] * u[_W] * psi_r
    dx[_PSI_S], dx[_PSI_S + 1] = dpsi_s.real, dpsi_s.imag
    dx[_PSI_R], dx[_PSI_R + 1] = dpsi_r.real, dpsi_r.imag


class DoublyFedMachine(InductionWindings):
    """DFIM electrical model, Bodson (9); parameters as ``DFIMParams`` (mechanics separate)."""

    PARAMS, STATES, INPUTS, OUTPUTS = PARAMS, STATES, INPUTS, OUTPUTS
    MUTUAL = "M"
    DIRECT_FROM = ("theta",)
    DIRECT_OUTPUTS = ("i_s", "i_r", "i_r_rotor", "tau_e")
    state_outputs = dfim_state_outputs
    direct_outputs = dfim_direct_outputs
    rhs = dfim_rhs

    @classmethod
    def from_params(cls, name, params) -> DoublyFedMachine:
        """From an ``acdrive.machines.dfim.DFIMParams`` (its J, B, tau_c go to a ``Shaft``)."""
        return cls(name, R_s=params.R_s, R_r=params.R_r, L_s=params.L_s, L_r=params.L_r,
                   M=params.M, n_p=params.n_p)  # fmt: skip
