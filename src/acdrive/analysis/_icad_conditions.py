"""The structure conditions i-iv of ICAD (Ugalde-Loo et al., (a.1)-(a.3)) for a 2x2 plant: stable
plant poles, no RHP poles of the multivariable structure function gamma, gamma -> 0 at high
frequency, and no encirclement of 1 by gamma (an exact count from state-space data,
``_icad_roots``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from acdrive._arguments import FLAG, checked
from acdrive.analysis._freqresp import evaluate_ss
from acdrive.analysis._icad_frequency import PointEvaluator
from acdrive.analysis._icad_roots import (
    NyquistCount,
    invariant_zeros,
    nyquist_count,
    on_axis,
    relative_degree,
    scalar_d,
)
from acdrive.analysis._plants import PLANT, Plant2x2, as_plant
from acdrive.errors import InputError

# ---------------------------------------------------------------------------------------------
# structure conditions i-iv / (a.1)-(a.3)


@dataclass(frozen=True)
class StructureConditions:
    """ICAD conditions of Ugalde-Loo et al. sec. 2 (i-iv) = Amezquita-Brooks et al. (a.1)-(a.3).

    i: open-loop poles in the open LHP; ii (a.1): gamma has no poles in the closed RHP;
    iii (a.3): gamma(s) -> 0 as s -> infinity; iv (a.2): the Nyquist plot of gamma neither
    encircles nor passes through (1, 0). ``gamma_count`` gives Z and P of 1 - gamma: Z counts the
    RHP transmission zeros of G plus the RHP poles of G, P the RHP poles of gamma.
    """

    i: bool
    ii: bool
    iii: bool
    iv: bool
    plant_poles: np.ndarray
    gamma_poles: np.ndarray  # zeros of g11 g22 (before any cancellation with g12 g21)
    gamma_identically_zero: bool
    gamma_limit: float  # |gamma(s)| as s -> infinity
    transmission_zeros: np.ndarray
    gamma_count: NyquistCount


def _gamma_limit(plant: Plant2x2) -> tuple[float, bool]:
    """(|gamma(inf)|, gamma identically zero) from relative degrees (Markov parameters)."""
    rd = {}
    for i in range(2):
        for j in range(2):
            rd[i, j] = relative_degree(*scalar_d(plant.siso(i, j)))
    if rd[0, 1] is None or rd[1, 0] is None:
        return 0.0, True
    if rd[0, 0] is None or rd[1, 1] is None:
        raise InputError("plant", "a diagonal element g_ii is identically zero (gamma undefined)")
    excess = rd[0, 1] + rd[1, 0] - rd[0, 0] - rd[1, 1]
    if excess > 0:
        return 0.0, False
    if excess < 0:
        return math.inf, False

    def lead(i, j):
        A, b, c, d = plant.siso(i, j)
        r = rd[i, j]
        if r == 0:
            return float(d[0, 0])
        return float(c.ravel() @ np.linalg.matrix_power(A, r - 1) @ b.ravel())

    return abs(lead(0, 1) * lead(1, 0) / (lead(0, 0) * lead(1, 1))), False


def siso_zeros(plant: Plant2x2, i: int, j: int) -> np.ndarray:
    A, b, c, d = plant.siso(i, j)
    return invariant_zeros(A, b, c, d)


@checked(plant=PLANT, verify=FLAG)
def structure_conditions(plant, *, verify: bool = True) -> StructureConditions:
    """Check conditions i-iv for a 2x2 plant (exact counts; ``verify`` adds the contour check)."""
    plant = as_plant(plant)
    poles = plant.poles()
    cond_i = bool(np.all(poles.real < 0) and not np.any(on_axis(poles)))
    limit, gamma_zero = _gamma_limit(plant)
    if gamma_zero:
        empty = np.zeros(0, dtype=complex)
        count = NyquistCount(1.0, 0, 0, (), (), 0, 0 if verify else None)
        return StructureConditions(
            cond_i,
            True,
            True,
            True,
            poles,
            empty,
            True,
            0.0,
            invariant_zeros(plant.A, plant.B, plant.C, plant.D),
            count,
        )
    z11, z22 = siso_zeros(plant, 0, 0), siso_zeros(plant, 1, 1)
    z12, z21 = siso_zeros(plant, 0, 1), siso_zeros(plant, 1, 0)
    tz = invariant_zeros(plant.A, plant.B, plant.C, plant.D)
    if _det_identically_zero(plant):
        raise InputError("plant", "det G(s) is identically zero (gamma = 1, no 2x2 structure)")
    # poles of gamma: zeros of g11 g22 not cancelled by zeros of g12 g21
    gp = list(np.concatenate([z11, z22]))
    for z in np.concatenate([z12, z21]):
        for idx, p in enumerate(gp):
            if abs(z - p) <= 1e-6 * max(1.0, abs(p)):
                gp.pop(idx)
                break
    gamma_poles = np.array(gp, dtype=complex)
    cond_ii = not np.any((gamma_poles.real > 0) | on_axis(gamma_poles))
    ev = PointEvaluator(plant, None, None)
    F = (lambda s: 1.0 - ev.gamma(s)) if verify else None
    count = nyquist_count([poles, tz], [z11, z22], 1.0, F)
    return StructureConditions(
        i=cond_i,
        ii=bool(cond_ii),
        iii=limit == 0.0,
        iv=count.encirclements == 0,
        plant_poles=poles,
        gamma_poles=gamma_poles,
        gamma_identically_zero=False,
        gamma_limit=limit,
        transmission_zeros=tz,
        gamma_count=count,
    )


def _det_identically_zero(plant: Plant2x2) -> bool:
    rng = np.random.default_rng(12345)
    scale = max(1.0, float(np.max(np.abs(plant.poles()))) if plant.n_states else 1.0)
    s = scale * (rng.uniform(0.5, 2.0, 3) + 1j * rng.uniform(-2.0, 2.0, 3))
    G = evaluate_ss(plant.A, plant.B, plant.C, plant.D, s)
    det = G[:, 0, 0] * G[:, 1, 1] - G[:, 0, 1] * G[:, 1, 0]
    ref = np.abs(G[:, 0, 0] * G[:, 1, 1]) + np.abs(G[:, 0, 1] * G[:, 1, 0])
    return bool(np.all(np.abs(det) <= 1e-10 * ref))
