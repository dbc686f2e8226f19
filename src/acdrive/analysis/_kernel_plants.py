"""The machines' current subsystems from their compiled kernels, in the coordinates of the models
of ``analysis._plants``, to check those models against the simulated machines.

Each machine part (the ``PART`` of its parameter record) is linearised at an operating point by
``analysis._kernel_jacobian.kernel_jacobian``, and the block of its Jacobian that the model keeps
is carried into the model's coordinates:

- cage IM (``stator_current_ss``, Amezquita-Brooks et al. (1)): the part's states i_s, psi_r and
  input v_s are the model's (stationary frame); the speed input is the mechanical w = w_r / n_p;
  y = i_s;
- PM machine (``dq_current_ss``, Ugalde-Loo et al. (9)-(11)): the state i_dq is the model's; the
  part's input is the stationary v_s = v_dq e_r, e_r = e^{j n_p theta}, so B = (d f / d v_s) e_r;
  y = i_dq; the magnet's back EMF is the affine ``rest`` (not in A, B);
- DFIM (``dfim_rotor_current_ss``, Bodson (9)-(11)): the part's states are the flux linkages
  psi = L i, L = [[L_s, M], [M, L_r]], stationary frame; the model's are the currents in the frame
  turning at w_e, which coincides with the stationary one at the instant t = 0 taken here, so
  A = L^-1 J L - j w_e (the frame's rotation), B = L^-1 (d f / d v_r) conj(e_r) (the part's v_r is
  in rotor coordinates, v_R conj(e_r)), C = (d i_r / d psi) L; the stator connected, its voltage
  v_S (the model's disturbance) in ``rest``.

Complex quantities are real pairs (real part first); a complex gain c is the real matrix
[[Re c, -Im c], [Im c, Re c]]. Every matrix comes with an entrywise bound on its rounding error
(``_kernel_jacobian``, carried through the change of coordinates), with kappa the condition of the
leakage inductance for the induction machines.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acdrive.analysis._kernel_jacobian import OPERATIONS, gamma, kernel_jacobian
from acdrive.machines._dfim import DFIMParams
from acdrive.machines._induction import IMParams
from acdrive.machines._pmsm import PMSGParams


@dataclass(frozen=True)
class KernelSubsystem:
    """A current subsystem x' = A x + B u + rest, y = C x + D u of a machine's kernels at an
    operating point, in a model's coordinates, with entrywise rounding ``bounds`` of A, B, C, D
    (keys "A", "B", "C", "D"). ``rest`` is f(x0, u0) - A x0 - B u0: what the model leaves to a
    disturbance (the PM's back EMF of its magnet)."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    rest: np.ndarray
    bounds: dict


def complex_gain(c: complex) -> np.ndarray:
    """The real 2x2 matrix of multiplication by the complex number ``c`` on (Re, Im)."""
    return np.array([[c.real, -c.imag], [c.imag, c.real]])


def leakage_condition(L_s: float, L_r: float, M: float) -> float:
    """kappa = (L_s L_r + M^2) / (L_s L_r - M^2): the relative condition number of the difference
    L_s L_r - M^2 = sigma L_s L_r that every induction machine kernel computes."""
    return (L_s * L_r + M * M) / (L_s * L_r - M * M)


def _pair(*values: complex) -> np.ndarray:
    return np.array([c for v in values for c in (v.real, v.imag)])


def _carried(M: np.ndarray, bound: np.ndarray, left: np.ndarray, right: np.ndarray, kappa: float):
    """(left M right, its bound): the bound carried through, plus the product's own rounding with
    ``left`` known to the relative precision kappa u (an inverted leakage matrix)."""
    product = left @ M @ right
    carried = np.abs(left) @ bound @ np.abs(right)
    own = gamma(OPERATIONS) * (kappa + 1.0) * (np.abs(left) @ np.abs(M) @ np.abs(right))
    return product, carried + own


def cage_current_subsystem(params: IMParams, w_r: float, i_s: complex, psi_r: complex,
                           v_s: complex) -> KernelSubsystem:  # fmt: skip
    """The cage IM's stator-current subsystem in ``stator_current_ss``'s coordinates (module
    docstring) at electrical speed ``w_r`` [rad/s] and the point (i_s, psi_r, v_s)."""
    part = type(params).PART.from_params("machine", params)
    jac = kernel_jacobian(part, {"i_s": i_s, "psi_r": psi_r},
                          {"v_s": v_s, "w": w_r / params.n_p})  # fmt: skip
    kappa = leakage_condition(params.L_s, params.L_r, params.L_m)
    m, bounds, rest = jac.subsystem(("i_s", "psi_r"), ("v_s",), ("i_s",), kappa)
    return KernelSubsystem(m["A"], m["B"], m["C"], m["D"], rest, bounds)


def pm_current_subsystem(params: PMSGParams, w_r: float, i_dq: complex, v_dq: complex,
                         theta: float) -> KernelSubsystem:  # fmt: skip
    """The PM machine's dq current subsystem in ``dq_current_ss``'s coordinates (module
    docstring) at electrical speed ``w_r`` [rad/s], rotor angle ``theta`` [rad, mechanical] and the
    point (i_dq, v_dq)."""
    part = type(params).PART.from_params("machine", params)
    e_r = complex(np.exp(1j * params.n_p * theta))
    jac = kernel_jacobian(part, {"i_dq": i_dq, "theta": theta, "e_r": e_r},
                          {"v_s": v_dq * e_r, "w": w_r / params.n_p})  # fmt: skip
    m, bounds, _ = jac.subsystem(("i_dq",), ("v_s",), ("i_dq",))
    turn, eye = complex_gain(e_r), np.eye(2)
    B, bound_B = _carried(m["B"], bounds["B"], eye, turn, 1.0)
    D, bound_D = _carried(m["D"], bounds["D"], eye, turn, 1.0)
    f0 = jac.dx[jac.slots(part.STATES, ("i_dq",))]
    rest = f0 - m["A"] @ _pair(i_dq) - B @ _pair(v_dq)
    bounds = {"A": bounds["A"], "B": bound_B, "C": bounds["C"], "D": bound_D}
    return KernelSubsystem(m["A"], B, m["C"], D, rest, bounds)


def dfim_rotor_current_subsystem(params: DFIMParams, w_r: float, w_e: float, i_S: complex,
                                 i_R: complex, v_R: complex, theta: float,
                                 v_S: complex = 0.0) -> KernelSubsystem:  # fmt: skip
    """The DFIM's rotor-current subsystem in ``dfim_rotor_current_ss``'s coordinates (module
    docstring): electrical speed ``w_r`` [rad/s], frame speed ``w_e`` [rad/s], rotor angle
    ``theta`` [rad, mechanical], the point (i_S, i_R, v_R) in the frame turning at w_e; the stator
    voltage ``v_S`` (the model's disturbance) goes to ``rest``."""
    part = type(params).PART.from_params("machine", params)
    L = np.array([[params.L_s, params.M], [params.M, params.L_r]])
    psi_s, psi_r = L @ np.array([i_S, i_R])
    e_r = complex(np.exp(1j * params.n_p * theta))
    jac = kernel_jacobian(
        part,
        {"psi_s": complex(psi_s), "psi_r": complex(psi_r), "theta": theta, "e_r": e_r},
        {"v_s": v_S, "v_r": v_R * e_r.conjugate(), "w": w_r / params.n_p, "connected": 1.0},
    )
    kappa = leakage_condition(params.L_s, params.L_r, params.M)
    m, bounds, _ = jac.subsystem(("psi_s", "psi_r"), ("v_r",), ("i_r",), kappa)
    to_flux = np.kron(L, np.eye(2))
    to_current = np.kron(np.linalg.inv(L), np.eye(2))
    frame = np.kron(np.eye(2), complex_gain(1j * w_e))  # j w_e on each current
    turn = complex_gain(e_r.conjugate())
    A, bound_A = _carried(m["A"], bounds["A"], to_current, to_flux, kappa)
    A = A - frame
    B, bound_B = _carried(m["B"], bounds["B"], to_current, turn, kappa)
    C, bound_C = _carried(m["C"], bounds["C"], np.eye(2), to_flux, 1.0)
    D, bound_D = _carried(m["D"], bounds["D"], np.eye(2), turn, 1.0)
    currents = _pair(i_S, i_R)
    f0 = to_current @ jac.dx[jac.slots(part.STATES, ("psi_s", "psi_r"))] - frame @ currents
    rest = f0 - A @ currents - B @ _pair(v_R)
    bounds = {"A": bound_A, "B": bound_B, "C": bound_C, "D": bound_D}
    return KernelSubsystem(A, B, C, D, rest, bounds)
