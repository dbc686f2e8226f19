"""Permanent-magnet synchronous generator (PMSG): parameters and the dq current subsystem.

Model of Ugalde-Loo et al. (7)-(11): stator currents (i_d, i_q) driven by stator voltages
(v_d, v_q) in the rotor (dq) frame, with the speed treated as a constant parameter. The
magnet back-EMF term psi_m n_P w_gen of (7) is an input disturbance and does not enter (11).
"""

from __future__ import annotations

import numpy as np

from acdrive.errors import require_finite
from acdrive.machines._pmsm_part import PermanentMagnetMachine
from acdrive.machines._record import machine_record


@machine_record(PermanentMagnetMachine, inertia_required=False)
class PMSGParams:
    """PMSG/PMSM parameters (Ugalde-Loo et al. (7)-(8)), those of ``PermanentMagnetMachine``,
    and the mechanics of its ``plant.Shaft``; J (combined rotor and generator inertia) may be
    None (unknown) because the current subsystem does not use it."""


#: The same record under a motor's name: a PM synchronous motor from its datasheet (R_s, L_d,
#: L_q, psi_m as the peak flux per phase, n_p, J) is a ``PMSMParams``.
PMSMParams = PMSGParams


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
