"""The synchronous machine with flux linkages as states and a magnetic model as a parameter choice.

One part for the surface and interior PM machine, the synchronous reluctance machine (SyRM) and
the PM-assisted SyRM: what tells them apart is the magnetic model i_dq = i(psi_dq), chosen by the
``saturation`` flag, and its parameters.

States: the stator flux linkage in rotor (dq) coordinates psi_dq = psi_d + j psi_q, the
mechanical rotor angle theta and the rotor phasor e_r = e^{j n_p theta} (d axis, seen from the
stator). Inputs: the stator voltage v_s in the STATIONARY frame and the mechanical speed w;
w_r = n_p w. Space vectors in acdrive's power-invariant scaling (``acdrive._frames``, Bodson (1)),
motor (consumer) reference arrows as in ``machines._pmsm_part``:

    v_dq = v_s conj(e_r)                                   (stationary -> rotor coordinates)
    dpsi_dq/dt = v_dq - R_s i_dq - j w_r psi_dq            (voltage equation, rotor coordinates)
    i_dq = i(psi_dq)                                       (the magnetic model, below)
    tau_e = n_p Im(conj(psi_dq) i_dq) = n_p (psi_d i_q - psi_q i_d)
    dtheta/dt = w,   de_r/dt = j w_r e_r,   i_s = i_dq e_r,   psi_s = psi_dq e_r

With linear magnetics and the same parameters this is Ugalde-Loo et al. (7)-(8) (the PM part)
with psi_dq instead of i_dq as the state. Power balance, for any magnetic model whose currents
are the gradient of a magnetic energy W(psi_d, psi_q) (i_d = dW/dpsi_d, i_q = dW/dpsi_q):

    Re(v_s conj(i_s)) = R_s |i_s|^2 + dW/dt + tau_e w

(Re(dpsi_dq/dt conj(i_dq)) = dW/dt and Re(j w_r psi_dq conj(i_dq)) = w_r Im(conj(psi_dq) i_dq)).
Both models below are such gradients (``magnetic_energy`` gives W), so their incremental
inductance matrices are symmetric (reciprocity) by construction.

**Magnetic models** (``saturation``):

* 0, linear: i_d = (psi_d - psi_pm) / L_d, i_q = psi_q / L_q, with psi_pm = sqrt(3/2) psi_m and
  L_d, L_q, psi_m the PM part's parameters (psi_m peak per phase). W = (psi_d - psi_pm)^2 / (2 L_d)
  + psi_q^2 / (2 L_q).
* 1, algebraic saturation with cross-saturation, the power-function model of Hinkkanen,
  Pescetto, Molsa, Saarakkala, Pellegrino, Bojoi, "Sensorless self-commissioning of synchronous
  reluctance motors at standstill without rotor locking", IEEE Trans. Ind. Appl., 2017
  (doi 10.1109/TIA.2016.2644624)
  (the model motulator calls ``SaturationModelSyRM``), in the published peak-valued variables
  (d measured from the magnet's flux, below):

      i_d = (a_d0 + a_dd |psi_d|^S + a_dq / (V + 2) |psi_d|^U |psi_q|^(V + 2)) psi_d
      i_q = (a_q0 + a_qq |psi_q|^T + a_dq / (U + 2) |psi_d|^(U + 2) |psi_q|^V) psi_q

  the gradient of W = a_d0 psi_d^2 / 2 + a_dd |psi_d|^(S+2) / (S+2) + a_q0 psi_q^2 / 2
  + a_qq |psi_q|^(T+2) / (T+2) + a_dq |psi_d|^(U+2) |psi_q|^(V+2) / ((U+2) (V+2)).
  The exponents are whole numbers up to ``MAX_EXPONENT`` (the published SyRM and PM-SyRM fits
  use 0 to 6; the kernel language has no general power, ``whole_power`` multiplies).

**Scaling of the algebraic model.** Its coefficients are the published ones, for peak-valued
(amplitude-invariant) space vectors, as motulator uses them. acdrive's vectors are power-invariant,
i_pi = K i_pk and psi_pi = K psi_pk with K = sqrt(3/2) (``frames.K_PEAK``). The part evaluates the
published function at psi_pk = psi_pi / K and returns i_pi = K i_pk = G(psi_pk) psi_pi, where
G_d = i_d / psi_d and G_q = i_q / psi_q are the published bracketed factors; in power-invariant
coefficients that is a_d0, a_q0 unchanged (inverse inductances keep their values, as L_d, L_q do),
a_dd K^-S, a_qq K^-T and a_dq K^-(U+V+2). The magnetic energy in power-invariant variables is
K^2 = 3/2 times the published one (``magnetic_energy``).

**Magnet** (PM-SyRM): psi_m > 0 shifts the d axis of the model: psi_d in the formulas above is
the d flux measured from the magnet's, psi_d - psi_pm, so psi_m is the flux linkage at zero
current in both models and the linear model is its own special case. (The PM-SyRM model of
Lelli et al. (2024), with a magnet current and bridge saturation, is not this one.)

No trigonometry in the right-hand side: e_r is a state reset from theta at every sample by
``project`` (as in ``machines._pmsm_part``).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from acdrive._frames import K_PEAK
from acdrive._jit import jit_fast, jit_inline
from acdrive.core._signals import Layout, Relation, cplx, real
from acdrive.machines._record import MachinePart

#: the largest exponent S, T, U, V of the algebraic model (four binary digits, ``whole_power``)
MAX_EXPONENT = 15
#: 1 / sqrt(3/2): power-invariant -> peak-valued space vector
OVER_K_PEAK = 1.0 / K_PEAK
#: the values of ``saturation``
LINEAR, ALGEBRAIC = 0, 1

#: the synchronous machine's parameters, declared once (``machines.SynchronousMachineParams``
#: is generated from them): the linear model's and the algebraic model's, the unused one's
#: left at their defaults
PARAMS = Layout(
    real("R_s", "ohm", "stator resistance", "positive"),
    real("n_p", "", "pole pairs", "count"),
    real("saturation", "", "magnetic model: 0 linear (L_d, L_q), 1 algebraic (a_*)", "flag"),
    real("psi_m", "Wb", "magnet flux linkage at zero current, peak per phase", "nonnegative"),
    real("L_d", "H", "direct-axis inductance of the linear model", "nonnegative"),
    real("L_q", "H", "quadrature-axis inductance of the linear model", "nonnegative"),
    real("a_d0", "A/Wb", "d-axis inverse inductance at zero flux (peak-valued)", "nonnegative"),
    real("a_dd", "A/Wb^(S+1)", "d-axis self-saturation coefficient (peak-valued)", "nonnegative"),
    real("S", "", "d-axis self-saturation exponent", "whole"),
    real("a_q0", "A/Wb", "q-axis inverse inductance at zero flux (peak-valued)", "nonnegative"),
    real("a_qq", "A/Wb^(T+1)", "q-axis self-saturation coefficient (peak-valued)", "nonnegative"),
    real("T", "", "q-axis self-saturation exponent", "whole"),
    real("a_dq", "A/Wb^(U+V+3)", "cross-saturation coefficient (peak-valued)", "nonnegative"),
    real("U", "", "cross-saturation exponent of |psi_d|", "whole"),
    real("V", "", "cross-saturation exponent of |psi_q|", "whole"),
    relations=(
        Relation(
            ("saturation", "L_d"),
            "the linear model (saturation = 0) needs L_d > 0",
            lambda saturation, L_d: saturation != LINEAR or L_d > 0.0,
            c="{saturation} != 0.0 || {L_d} > 0.0",
        ),
        Relation(
            ("saturation", "L_q"),
            "the linear model (saturation = 0) needs L_q > 0",
            lambda saturation, L_q: saturation != LINEAR or L_q > 0.0,
            c="{saturation} != 0.0 || {L_q} > 0.0",
        ),
        Relation(
            ("saturation", "a_d0"),
            "the algebraic model (saturation = 1) needs a_d0 > 0 (a finite unsaturated L_d)",
            lambda saturation, a_d0: saturation != ALGEBRAIC or a_d0 > 0.0,
            c="{saturation} != 1.0 || {a_d0} > 0.0",
        ),
        Relation(
            ("saturation", "a_q0"),
            "the algebraic model (saturation = 1) needs a_q0 > 0 (a finite unsaturated L_q)",
            lambda saturation, a_q0: saturation != ALGEBRAIC or a_q0 > 0.0,
            c="{saturation} != 1.0 || {a_q0} > 0.0",
        ),
        Relation(
            ("S", "T", "U", "V"),
            f"the exponents S, T, U, V of the algebraic model must be at most {MAX_EXPONENT}",
            lambda S, T, U, V: max(S, T, U, V) <= MAX_EXPONENT,
            blame=lambda S, T, U, V: "STUV"[[S, T, U, V].index(max(S, T, U, V))],
            c=" && ".join(f"{{{e}}} <= {MAX_EXPONENT}.0" for e in "STUV"),
        ),
        Relation(
            ("saturation", "L_d", "L_q", "psi_m"),
            "torque needs a magnet or saliency: psi_m > 0 or, in the linear model, L_d != L_q",
            lambda saturation, L_d, L_q, psi_m: (
                psi_m > 0.0 or (saturation == LINEAR and L_d != L_q) or saturation == ALGEBRAIC
            ),
            c="{psi_m} > 0.0 || ({saturation} == 0.0 && {L_d} != {L_q}) || {saturation} == 1.0",
        ),
    ),
)
STATES = Layout(
    cplx("psi_dq", "Wb", "stator flux linkage in rotor coordinates, psi_d + j psi_q"),
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
    cplx("psi_s", "Wb", "stator flux linkage, stationary frame"),
    cplx("psi_dq", "Wb", "stator flux linkage in rotor coordinates, psi_d + j psi_q"),
    real("tau_e", "N m", "electromagnetic torque on the rotor, positive motoring"),
    real("theta", "rad", "mechanical rotor angle"),
)
_R_S, _N_P, _SATURATION, _PSI_M, _L_D, _L_Q = (
    PARAMS.slot(n) for n in ("R_s", "n_p", "saturation", "psi_m", "L_d", "L_q")
)
_A_D0, _A_DD, _S, _A_Q0, _A_QQ, _T, _A_DQ, _U, _V = (
    PARAMS.slot(n) for n in ("a_d0", "a_dd", "S", "a_q0", "a_qq", "T", "a_dq", "U", "V")
)
_PSI_DQ, _THETA, _E_R = (STATES.slot(n) for n in ("psi_dq", "theta", "e_r"))
_V_S, _W = INPUTS.slot("v_s"), INPUTS.slot("w")
_Y_I_S, _Y_I_DQ, _Y_PSI_S, _Y_PSI_DQ, _Y_TAU, _Y_THETA = (
    OUTPUTS.slot(n) for n in ("i_s", "i_dq", "psi_s", "psi_dq", "tau_e", "theta")
)


@jit_inline
def whole_power(x, n):
    """x^n for a whole n from 0 to ``MAX_EXPONENT`` = 15 (x^0 = 1): the product of the powers
    x^8, x^4, x^2, x^1 that the binary digits of n select, digit by digit from the highest."""
    x_2 = x * x
    x_4 = x_2 * x_2
    power = 1.0
    rest = n
    if rest >= 8.0:
        power = x_4 * x_4
        rest = rest - 8.0
    if rest >= 4.0:
        power = power * x_4
        rest = rest - 4.0
    if rest >= 2.0:
        power = power * x_2
        rest = rest - 2.0
    if rest >= 1.0:
        power = power * x
    return power


@jit_inline
def magnetic_currents(p, psi_d, psi_q):
    """i_d, i_q (power-invariant) from psi_d, psi_q (power-invariant) by the model ``saturation``
    chooses: linear, or Hinkkanen et al. (2017)'s power functions evaluated in the published
    peak-valued variables (module docstring)."""
    psi_d_magnet = psi_d - K_PEAK * p[_PSI_M]  # d flux measured from the magnet's
    if p[_SATURATION] == 0.0:
        i_d = psi_d_magnet / p[_L_D]
        i_q = psi_q / p[_L_Q]
    else:
        abs_d = abs(psi_d_magnet * OVER_K_PEAK)  # |psi_d|, |psi_q| peak-valued
        abs_q = abs(psi_q * OVER_K_PEAK)
        cross = p[_A_DQ] * whole_power(abs_d, p[_U]) * whole_power(abs_q, p[_V])
        g_d = (
            p[_A_D0]
            + p[_A_DD] * whole_power(abs_d, p[_S])
            + cross * (abs_q * abs_q) / (p[_V] + 2.0)
        )
        g_q = (
            p[_A_Q0]
            + p[_A_QQ] * whole_power(abs_q, p[_T])
            + cross * (abs_d * abs_d) / (p[_U] + 2.0)
        )
        i_d = g_d * psi_d_magnet  # K g(psi_pk) psi_pk = g(psi_pk) psi_pi
        i_q = g_q * psi_q
    return i_d, i_q


@jit_fast
def synchronous_state_outputs(t, x, p, y):
    i_d, i_q = magnetic_currents(p, x[_PSI_DQ], x[_PSI_DQ + 1])
    write_outputs(x, p, y, i_d, i_q)


@jit_inline
def write_outputs(x, p, y, i_d, i_q):
    """The outputs of the flux states ``x`` with the currents i_d, i_q a magnetic model gives for
    them (this part's or the flux map's, ``machines._flux_map_part``): the currents and fluxes in
    both frames and tau_e = n_p Im(conj(psi_dq) i_dq)."""
    psi_d, psi_q = x[_PSI_DQ], x[_PSI_DQ + 1]
    e_r = complex(x[_E_R], x[_E_R + 1])
    i_s = complex(i_d, i_q) * e_r
    psi_s = complex(psi_d, psi_q) * e_r
    y[_Y_I_S], y[_Y_I_S + 1] = i_s.real, i_s.imag
    y[_Y_I_DQ], y[_Y_I_DQ + 1] = i_d, i_q
    y[_Y_PSI_S], y[_Y_PSI_S + 1] = psi_s.real, psi_s.imag
    y[_Y_PSI_DQ], y[_Y_PSI_DQ + 1] = psi_d, psi_q
    y[_Y_TAU] = p[_N_P] * (psi_d * i_q - psi_q * i_d)  # n_p Im(conj(psi_dq) i_dq)
    y[_Y_THETA] = x[_THETA]


@jit_fast
def synchronous_rhs(t, x, u, p, y, dx):
    """dpsi_dq/dt = v_dq - R_s i_dq - j w_r psi_dq, the currents from this evaluation's outputs
    (module docstring)."""
    e_r = complex(x[_E_R], x[_E_R + 1])
    v_dq = complex(u[_V_S], u[_V_S + 1]) * complex(e_r.real, -e_r.imag)
    psi_d, psi_q = x[_PSI_DQ], x[_PSI_DQ + 1]
    w_r = p[_N_P] * u[_W]
    dx[_PSI_DQ] = v_dq.real - p[_R_S] * y[_Y_I_DQ] + w_r * psi_q
    dx[_PSI_DQ + 1] = v_dq.imag - p[_R_S] * y[_Y_I_DQ + 1] - w_r * psi_d
    dx[_THETA] = u[_W]
    dx[_E_R], dx[_E_R + 1] = -w_r * e_r.imag, w_r * e_r.real  # j w_r e_r


@jit_fast
def synchronous_project(x, p):
    angle = p[_N_P] * x[_THETA]
    x[_E_R], x[_E_R + 1] = np.cos(angle), np.sin(angle)


def magnetic_energy(values: dict, psi_d, psi_q):
    """The magnetic energy W(psi_d, psi_q) [J] of the model in ``values`` (a part's ``values``),
    power-invariant fluxes in (scalars or arrays): the function whose gradient the part's
    currents are (module docstring). For the algebraic model it is K^2 = 3/2 times the published
    (peak-valued) energy at psi / K."""
    psi_d_magnet = np.asarray(psi_d, dtype=float) - K_PEAK * values["psi_m"]
    psi_q = np.asarray(psi_q, dtype=float)
    if values["saturation"] == LINEAR:
        return psi_d_magnet**2 / (2.0 * values["L_d"]) + psi_q**2 / (2.0 * values["L_q"])
    d, q = np.abs(psi_d_magnet / K_PEAK), np.abs(psi_q / K_PEAK)
    S, T, U, V = (values[n] for n in ("S", "T", "U", "V"))
    published = (
        values["a_d0"] * d**2 / 2.0
        + values["a_dd"] * d ** (S + 2) / (S + 2)
        + values["a_q0"] * q**2 / 2.0
        + values["a_qq"] * q ** (T + 2) / (T + 2)
        + values["a_dq"] * d ** (U + 2) * q ** (V + 2) / ((U + 2) * (V + 2))
    )
    return K_PEAK**2 * published


#: the parameters of the model the part does not use, by model: left at these values
_UNUSED = {
    LINEAR: dict.fromkeys(("a_d0", "a_dd", "S", "a_q0", "a_qq", "T", "a_dq", "U", "V"), 0.0),
    ALGEBRAIC: dict.fromkeys(("L_d", "L_q"), 0.0),
}


class SynchronousMachine(MachinePart):
    """Synchronous machine (surface or interior PM, SyRM, PM-SyRM) with flux linkages as states
    and the magnetic model ``saturation`` (0 linear, 1 the algebraic saturation model of
    Hinkkanen et al. (2017)); motor reference arrows (module docstring); parameters as
    ``machines.SynchronousMachineParams`` (its J goes to a ``Shaft``). The parameters of the
    model not chosen default to zero."""

    SOURCE = (
        "voltage equation in rotor coordinates with flux states; currents from a linear or "
        "Hinkkanen et al. (2017) algebraic saturation model (machines._synchronous_part)"
    )

    PARAMS, STATES, INPUTS, OUTPUTS = PARAMS, STATES, INPUTS, OUTPUTS
    DEFAULTS: ClassVar[dict] = {
        "psi_m": 0.0,
        "saturation": LINEAR,
        **_UNUSED[LINEAR],
        **_UNUSED[ALGEBRAIC],
    }
    INITIAL: ClassVar[dict] = {"e_r": 1.0}
    state_outputs = synchronous_state_outputs
    rhs = synchronous_rhs
    project = synchronous_project

    def initial_state(self, **values) -> np.ndarray:
        """As ``Part.initial_state``; psi_dq starts at the magnet's flux (zero current) and e_r
        follows an initial ``theta`` unless given."""
        values.setdefault("psi_dq", K_PEAK * self.values["psi_m"])
        if "theta" in values and "e_r" not in values:
            values["e_r"] = complex(np.exp(1j * self.values["n_p"] * float(values["theta"])))
        return super().initial_state(**values)
