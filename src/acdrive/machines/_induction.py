"""Cage induction motor (IM): parameters and the stationary-frame stator-current subsystem.

The linear model is the one of Ugalde-Loo et al. (37)-(41) and Amezquita-Brooks et al. (1)-(2):
states (i_alpha_s, i_beta_s, psi_alpha_r, psi_beta_r), inputs (v_alpha_s, v_beta_s), outputs
(i_alpha_s, i_beta_s), with the electrical rotor speed w_r treated as a constant parameter.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acdrive.errors import require_finite, require_positive
from acdrive.machines._cage_part import CageInductionMachine
from acdrive.machines._record import machine_record
from acdrive.machines._windings import leakage_factor


@machine_record(CageInductionMachine, inertia_required=False)
class IMParams:
    """Electrical parameters of a cage induction motor (Ugalde-Loo et al. (37)-(39)), those of
    ``CageInductionMachine``, and the mechanics of its ``plant.Shaft``; J may be None (unknown)
    because the current subsystem does not use it."""

    @property
    def sigma(self) -> float:
        """Dispersion (leakage) coefficient sigma = 1 - L_m^2/(L_s L_r) (Ugalde-Loo et al. (38))."""
        return leakage_factor(self.L_s, self.L_r, self.L_m)


def stator_current_ss(p: IMParams, w_r: float):
    """Real state-space (A, B, C, D) of the IM stator-current subsystem at electrical speed w_r.

    Stationary frame, Ugalde-Loo et al. (40)-(41) = Amezquita-Brooks et al. (1):
    x = (i_alpha_s, i_beta_s, psi_alpha_r, psi_beta_r), u = (v_alpha_s, v_beta_s),
    y = (i_alpha_s, i_beta_s). w_r [rad/s] is the electrical rotor speed n_p * w_m.
    """
    w_r = require_finite("w_r", w_r)
    sLs = p.sigma * p.L_s
    a11 = -(p.L_r**2 * p.R_s + p.L_m**2 * p.R_r) / (sLs * p.L_r**2)
    a_flux = p.L_m * p.R_r / (sLs * p.L_r**2)  # current eq., rotor-flux (resistive) term
    a_emf = p.L_m * w_r / (sLs * p.L_r)  # current eq., rotor-flux (speed) term
    a_mag = p.L_m * p.R_r / p.L_r  # flux eq., magnetising term
    tau_r = p.R_r / p.L_r
    A = np.array(
        [
            [a11, 0.0, a_flux, a_emf],
            [0.0, a11, -a_emf, a_flux],
            [a_mag, 0.0, -tau_r, -w_r],
            [0.0, a_mag, w_r, -tau_r],
        ]
    )
    B = np.zeros((4, 2))
    B[0, 0] = B[1, 1] = 1.0 / sLs
    C = np.eye(2, 4)
    D = np.zeros((2, 2))
    return A, B, C, D


@dataclass(frozen=True)
class StationaryMatrixFit:
    """Parameters recovered from printed entries of the matrix (41), and the redundant check.

    ``a13_implied`` is the entry L_m R_r/(sigma L_s L_r^2) that the recovered parameters give;
    (41) determines it from the other entries, so its difference from the printed value measures
    the internal consistency (rounding) of the printed matrix.
    """

    params: IMParams
    a13_printed: float
    a13_implied: float


def params_from_stationary_matrix(
    a11: float,
    a13: float,
    a14_per_wr: float,
    a31: float,
    a33: float,
    b11: float,
    n_p: int = 1,
    J: float | None = None,
) -> StationaryMatrixFit:
    """Invert Ugalde-Loo et al. (41): IM parameters from the numeric entries of A and B.

    a11 = -(L_r^2 R_s + L_m^2 R_r)/(sigma L_s L_r^2), a13 = L_m R_r/(sigma L_s L_r^2),
    a14 = (L_m/(sigma L_s L_r)) w_r, a31 = L_m R_r/L_r, a33 = -R_r/L_r, b11 = 1/(sigma L_s).
    Five parameters follow from a11, a14/w_r, a31, a33, b11; a13 is redundant and is returned
    for comparison. Used to reconcile Amezquita-Brooks et al. (13) with their Appendix. ``n_p``
    and the inertia ``J`` do not enter (41) and are passed through.
    """
    c = require_positive("a14_per_wr", a14_per_wr)
    b = require_positive("b11", b11)
    e = require_positive("a31", a31)
    d = require_positive("-a33", -require_finite("a33", a33))
    L_m = e / d
    L_r = L_m * b / c
    R_r = d * L_r
    L_s = 1.0 / b + L_m**2 / L_r
    R_s = (-require_finite("a11", a11) - c * e) / b
    params = IMParams(R_s=R_s, R_r=R_r, L_s=L_s, L_r=L_r, L_m=L_m, n_p=n_p, J=J)
    return StationaryMatrixFit(params, require_finite("a13", a13), c * d)


#: The 300 W IM of Ugalde-Loo et al. section 4.5 (n_P = 1, J = 0.000711 kg m^2).
#: Their printed (80) (a11 = -359.2, b11 = 9.7, a13 = 139.4, 9 w_r, 22.3, -15.4) is these
#: parameters rounded; (41) with them gives a11 = -361.1, b11 = 9.78, a13 = 139.8, 9.09 w_r.
UGALDE_IM_300W = IMParams(R_s=16.19, R_r=24.0, L_s=1.45, L_r=1.56, L_m=1.45, n_p=1, J=0.000711)

#: The DeLorenzo DL10115A1 IM of Amezquita-Brooks et al., Appendix (P = 2 poles, so n_p = 1).
#: Their matrix (13) is NOT what (1) gives with these parameters: the Appendix values give
#: a11 = -386.4, a13 = 152.9, 9.89 w_r, a31 = 21.96, a33 = -15.47, b11 = 10.45, against the printed
#: -359.2, 141.8, 9.2 w_r, 21.9, -15.4, 9.7. Inverting (13) (``params_from_stationary_matrix``)
#: gives R_s = 16.3, R_r = 23.1, L_m = 1.42, L_r = 1.50 (all as in the Appendix) but
#: L_s = 1.451 H instead of 1.44 H: sigma L_s = L_s - L_m^2/L_r is a small difference of large
#: numbers, so the 0.8 % change in L_s moves 1/(sigma L_s) by 8 %. The printed G_M,min = 0.75
#: (-2.47 dB) of (19) follows from (13)'s parameters (0.752); the Appendix ones give 0.766.
#: The paper gives no inertia: J is the one every DeLorenzo scenario and the IM drive's defaults
#: assume (``control.foc.J_ESTIMATE``), the 300 W IM's of Ugalde-Loo et al. section 4.5, whose
#: parameters the same group identified with the same method.
DELORENZO_IM = IMParams(R_s=16.2, R_r=23.2, L_s=1.44, L_r=1.5, L_m=1.42, n_p=1, J=UGALDE_IM_300W.J)

#: Parameters recovered from the printed matrix (13) of Amezquita-Brooks et al. (see above), with
#: the same assumed inertia.
DELORENZO_IM_13 = params_from_stationary_matrix(
    a11=-359.2, a13=141.8, a14_per_wr=9.2, a31=21.9, a33=-15.4, b11=9.7, n_p=1, J=DELORENZO_IM.J
).params
