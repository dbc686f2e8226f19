"""The permanent-magnet synchronous machine as a continuous plant part (Ugalde-Loo et al. (7)-(8)).

States: the stator current in rotor (dq) coordinates i_dq = i_d + j i_q (the paper's states (10)),
the mechanical rotor angle theta and the rotor phasor e_r = e^{j n_p theta} (d axis, seen from the
stator). Inputs: the stator voltage v_s in the STATIONARY frame (so any converter or source part
can feed it) and the mechanical speed w; w_r = n_p w is the electrical speed (the paper's
n_P w_gen). Space vectors in acdrive's power-invariant scaling (``acdrive._frames``, Bodson (1)):

    v_dq = v_s conj(e_r)                                      (stationary -> rotor coordinates)
    L_d di_d/dt = v_d - R_s i_d + w_r L_q i_q                                  (7), first line
    L_q di_q/dt = v_q - R_s i_q - w_r (L_d i_d + psi_pm)                       (7), second line
    dtheta/dt = w,   de_r/dt = j w_r e_r
    i_s = i_dq e_r,   psi_s = (L_d i_d + psi_pm + j L_q i_q) e_r
    tau_e = n_p Im(conj(psi_dq) i_dq) = n_p (psi_pm i_q + (L_d - L_q) i_d i_q)  (8), torque

**Sign convention: motor (consumer) reference arrows**, i.e. (7) exactly as printed: rearranged,
(7) reads v_d = R_s i_d + L_d di_d/dt - w_r L_q i_q and v_q = R_s i_q + L_q di_q/dt + w_r psi_d,
the voltage equation v = R_s i + dpsi/dt + j w_r psi with the current flowing INTO the terminals.
Its linear part is (9)-(11), ``machines._pmsm.dq_current_ss``. With these currents the torque
formula of (8) is the torque the machine exerts on its rotor in the direction of rotation
(positive: motoring), which is what ``plant.Shaft`` takes (J dw/dt = tau_e - load).
Power balance (power-invariant, no 3/2):

    Re(v_s conj(i_s)) = R_s |i_s|^2 + dW/dt + tau_e w,   W = (L_d i_d^2 + L_q i_q^2) / 2

(multiply the two lines of (7) by i_d and i_q and add; W is the energy of the field of the stator
currents, the magnet's flux being constant in rotor coordinates). A generator has tau_e < 0 and
Re(v_s conj(i_s)) < 0 (power delivered to the converter). The paper's drive train (8),
J dw_gen/dt = tau_T - tau_em, counts tau_em as the generator's braking torque, i.e. tau_em =
-tau_e here: with a ``Shaft``, the turbine torque tau_T is a negative load (load = -tau_T).

**Scaling.** The paper's dq quantities are amplitude-invariant (peak phase values; hence the 3/2
of (8)); acdrive's are power-invariant, x = sqrt(3/2) x_paper (``frames.K_PEAK``). (7) is linear
in voltages and currents, so R_s, L_d, L_q keep their values; the magnet term scales like a
flux: psi_pm = sqrt(3/2) psi_m, with psi_m the paper's magnet flux linkage (peak per phase, the
``psi_m`` parameter here and in ``PMSGParams``). The torque (3/2) n_P psi_m i_q,paper becomes
n_p psi_pm i_q without the 3/2. Currents and voltages of a balanced set have |x| = sqrt(3/2) X_pk
(Bodson (8)).

No trigonometry in the right-hand side: e_r is a state (de_r/dt = j w_r e_r), reset from theta
onto the unit circle at every sample by ``project`` (as in ``machines._dfim_part``).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from acdrive._frames import K_PEAK
from acdrive._jit import jit_fast, jit_inline, python_from_python
from acdrive.core._signals import Layout, Relation, cplx, real
from acdrive.machines._record import MachinePart

#: the PM machine's parameters, declared once: ``machines.PMSGParams`` is generated from them.
#: psi_m = 0 is allowed: a synchronous reluctance machine (torque from L_d != L_q alone, (8));
#: without magnet and without saliency the machine makes no torque, which the relation refuses.
PARAMS = Layout(
    real("R_s", "ohm", "stator resistance", "positive"),
    real("L_d", "H", "direct-axis stator self inductance", "positive"),
    real("L_q", "H", "quadrature-axis stator self inductance", "positive"),
    real("psi_m", "Wb", "magnet flux linkage, peak per phase (the paper's psi_m)", "nonnegative"),
    real("n_p", "", "pole pairs", "count"),
    relations=(
        Relation(
            ("L_d", "L_q", "psi_m"),
            "torque needs a magnet or saliency: psi_m > 0 or L_d != L_q",
            lambda L_d, L_q, psi_m: psi_m > 0.0 or L_d != L_q,
            c="{psi_m} > 0.0 || {L_d} != {L_q}",
        ),
    ),
)
STATES = Layout(
    cplx("i_dq", "A", "stator current in rotor coordinates, i_d + j i_q"),
    real("theta", "rad", "mechanical rotor angle; the d axis is at n_p theta from phase a"),
    cplx("e_r", "", "rotor phasor e^{j n_p theta}"),
)
INPUTS = Layout(
    cplx("v_s", "V", "stator voltage, stationary frame"),
    real("w", "rad/s", "mechanical rotor speed"),
)
OUTPUTS = Layout(
    cplx("i_s", "A", "stator current (into the machine), stationary frame"),
    cplx("i_dq", "A", "stator current in rotor coordinates, i_d + j i_q"),
    cplx("psi_s", "Wb", "stator flux linkage (currents and magnet), stationary frame"),
    real("tau_e", "N m", "electromagnetic torque on the rotor, positive motoring"),
    real("theta", "rad", "mechanical rotor angle"),
)
_R_S, _L_D, _L_Q, _PSI_M, _N_P = (PARAMS.slot(n) for n in ("R_s", "L_d", "L_q", "psi_m", "n_p"))
_I_DQ, _THETA, _E_R = (STATES.slot(n) for n in ("i_dq", "theta", "e_r"))
_V_S, _W = INPUTS.slot("v_s"), INPUTS.slot("w")
_Y_I_S, _Y_I_DQ, _Y_PSI_S, _Y_TAU, _Y_THETA = (
    OUTPUTS.slot(n) for n in ("i_s", "i_dq", "psi_s", "tau_e", "theta")
)


@python_from_python
@jit_inline
def magnet_flux(p):
    """psi_pm = sqrt(3/2) psi_m: the magnet's flux linkage as a power-invariant space vector."""
    return K_PEAK * p[_PSI_M]


@jit_inline
def pmsm_torque(p, i_d, i_q):
    """tau_e = n_p (psi_pm i_q + (L_d - L_q) i_d i_q), Ugalde-Loo et al. (8) without its 3/2."""
    return p[_N_P] * (magnet_flux(p) * i_q + (p[_L_D] - p[_L_Q]) * i_d * i_q)


@jit_fast
def pmsm_state_outputs(t, x, p, y):
    i_d, i_q = x[_I_DQ], x[_I_DQ + 1]
    e_r = complex(x[_E_R], x[_E_R + 1])
    i_s = complex(i_d, i_q) * e_r
    psi_s = complex(p[_L_D] * i_d + magnet_flux(p), p[_L_Q] * i_q) * e_r
    y[_Y_I_S], y[_Y_I_S + 1] = i_s.real, i_s.imag
    y[_Y_I_DQ], y[_Y_I_DQ + 1] = i_d, i_q
    y[_Y_PSI_S], y[_Y_PSI_S + 1] = psi_s.real, psi_s.imag
    y[_Y_TAU] = pmsm_torque(p, i_d, i_q)
    y[_Y_THETA] = x[_THETA]


@jit_fast
def pmsm_rhs(t, x, u, p, y, dx):
    """Ugalde-Loo et al. (7) in rotor coordinates, fed from the stationary frame (module
    docstring)."""
    e_r = complex(x[_E_R], x[_E_R + 1])
    v_dq = complex(u[_V_S], u[_V_S + 1]) * complex(e_r.real, -e_r.imag)
    i_d, i_q = x[_I_DQ], x[_I_DQ + 1]
    w_r = p[_N_P] * u[_W]
    dx[_I_DQ] = (v_dq.real - p[_R_S] * i_d + w_r * p[_L_Q] * i_q) / p[_L_D]
    dx[_I_DQ + 1] = (v_dq.imag - p[_R_S] * i_q - w_r * (p[_L_D] * i_d + magnet_flux(p))) / p[_L_Q]
    dx[_THETA] = u[_W]
    dx[_E_R], dx[_E_R + 1] = -w_r * e_r.imag, w_r * e_r.real  # j w_r e_r


@jit_fast
def pmsm_project(x, p):
    angle = p[_N_P] * x[_THETA]
    x[_E_R], x[_E_R + 1] = np.cos(angle), np.sin(angle)


class PermanentMagnetMachine(MachinePart):
    """PMSM/PMSG, Ugalde-Loo et al. (7)-(8), motor reference arrows (module docstring);
    parameters as ``machines.PMSGParams`` (its J goes to a ``Shaft``)."""

    SOURCE = (
        "Ugalde-Loo et al. (7)-(8) in rotor coordinates, fed from the stationary frame "
        "(machines._pmsm_part)"
    )

    PARAMS, STATES, INPUTS, OUTPUTS = PARAMS, STATES, INPUTS, OUTPUTS
    INITIAL: ClassVar[dict] = {"e_r": 1.0}
    state_outputs = pmsm_state_outputs
    rhs = pmsm_rhs
    project = pmsm_project

    def initial_state(self, **values) -> np.ndarray:
        """As ``Part.initial_state``; e_r follows an initial ``theta`` unless given."""
        if "theta" in values and "e_r" not in values:
            values["e_r"] = complex(np.exp(1j * self.values["n_p"] * float(values["theta"])))
        return super().initial_state(**values)
