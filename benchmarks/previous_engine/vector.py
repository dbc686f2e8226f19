"""The previous engine's DFIM parameter vector, frozen with it.

The package's compiled DFIM functions read ``DoublyFedMachine.PARAMS``'s slots (R_s, R_r, L_s,
L_r, M, n_p first, in that order); the previous engine appended the shaft's J, B, tau_c after
them (and the converter loss after those), read by its own loop. That layout lives here, with
the only code that reads it.
"""

from __future__ import annotations

import numpy as np

from acdrive.machines._dfim import L_R, L_S, M_SR, N_P, R_R, R_S
from acdrive.machines._dfim_part import WINDINGS

#: the shaft's slots, after the machine's winding parameters
J_INERTIA, B_VISCOUS, TAU_COULOMB = range(WINDINGS.fixed_size, WINDINGS.fixed_size + 3)
N_MACHINE_PARAMS = WINDINGS.fixed_size + 3


def machine_vector(params) -> np.ndarray:
    """``params`` (a ``DFIMParams``) in the previous engine's 9-float layout."""
    p = np.empty(N_MACHINE_PARAMS)
    p[R_S], p[R_R], p[L_S], p[L_R], p[M_SR] = (
        params.R_s,
        params.R_r,
        params.L_s,
        params.L_r,
        params.M,
    )
    p[N_P], p[J_INERTIA], p[B_VISCOUS], p[TAU_COULOMB] = (
        params.n_p,
        params.J,
        params.B,
        params.tau_c,
    )
    return p
