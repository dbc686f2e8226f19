"""Permanent-magnet synchronous generator (PMSG): parameters and the dq current subsystem.

Model of Ugalde-Loo et al. (7)-(11): stator currents (i_d, i_q) driven by stator voltages
(v_d, v_q) in the rotor (dq) frame, with the speed treated as a constant parameter. The
magnet back-EMF term psi_m n_P w_gen of (7) is an input disturbance and does not enter (11).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acdrive.errors import require_finite, require_positive
from acdrive.machines._induction import _pole_pairs


@dataclass(frozen=True)
class PMSGParams:
    """PMSG parameters (Ugalde-Loo et al. (7)-(8)).

    R_s: stator resistance [ohm]; L_d, L_q: dq self inductances [H]; psi_m: magnet flux
    linkage [V s]; n_p: pole pairs; J: combined rotor and generator inertia [kg m^2] (optional).
    """

    R_s: float
    L_d: float
    L_q: float
    psi_m: float
    n_p: int
    J: float | None = None

    def __post_init__(self):
        for name in ("R_s", "L_d", "L_q", "psi_m"):
            object.__setattr__(self, name, require_positive(name, getattr(self, name)))
        object.__setattr__(self, "n_p", _pole_pairs(self.n_p))
        if self.J is not None:
            object.__setattr__(self, "J", require_positive("J", self.J))


def dq_current_ss(p: PMSGParams, w_r: float):
    """Real state-space (A, B, C, D) of the PMSG dq current subsystem, Ugalde-Loo et al. (9)-(11).

    w_r [rad/s] is the electrical rotor speed n_P * w_gen (the papers write n_P w_gen).
    x = y = (i_d, i_q), u = (v_d, v_q).
    """
    w_r = require_finite("w_r", w_r)
    A = np.array(
        [
            [-p.R_s / p.L_d, p.L_q / p.L_d * w_r],
            [-p.L_d / p.L_q * w_r, -p.R_s / p.L_q],
        ]
    )
    B = np.diag([1.0 / p.L_d, 1.0 / p.L_q])
    return A, B, np.eye(2), np.zeros((2, 2))


#: The 2 MW PMSG of Ugalde-Loo et al. section 3.5 (f = 50 Hz). The printed inertia
#: "416, 633 kg m^2" is read as 416 633 kg m^2 (it does not enter the current subsystem).
PMSG_2MW = PMSGParams(R_s=4.523e-3, L_d=322e-6, L_q=322e-6, psi_m=1.79, n_p=2, J=416633.0)
