"""Doubly-fed induction machine (DFIM): parameters, complex model, steady state.

All relations follow M. Bodson, "Speed Control for Doubly-Fed Induction Motors With and Without
Current Feedback" (called "Bodson" below). Space vectors are complex numbers in the
power-invariant scaling of Bodson (1)-(8); rotor quantities are referred to the stator frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from acdrive.errors import InputError, require_nonnegative, require_positive


@dataclass(frozen=True)
class DFIMParams:
    """Electrical and mechanical parameters of a DFIM (Bodson (9), (26)).

    R_s, R_r: stator and rotor resistances [ohm]; L_s, L_r: stator and rotor self inductances [H];
    M: stator-rotor mutual inductance [H]; n_p: pole pairs; J: inertia of motor and load [kg m^2];
    B: viscous friction [N m s/rad]; tau_c: Coulomb friction [N m].
    """

    R_s: float
    R_r: float
    L_s: float
    L_r: float
    M: float
    n_p: int
    J: float
    B: float = 0.0
    tau_c: float = 0.0

    def __post_init__(self):
        for name in ("R_s", "R_r", "L_s", "L_r", "M", "J"):
            object.__setattr__(self, name, require_positive(name, getattr(self, name)))
        for name in ("B", "tau_c"):
            object.__setattr__(self, name, require_nonnegative(name, getattr(self, name)))
        n_p = self.n_p
        if isinstance(n_p, bool) or not isinstance(n_p, (int, float, np.integer, np.floating)):
            raise InputError("n_p", "must be a positive integer")
        if not math.isfinite(float(n_p)) or float(n_p) != int(n_p) or int(n_p) < 1:
            raise InputError("n_p", f"must be a positive integer, got {n_p}")
        object.__setattr__(self, "n_p", int(n_p))
        if self.sigma <= 0.0:
            raise InputError("M", "leakage factor sigma = 1 - M^2/(L_s L_r) must be > 0")

    @property
    def sigma(self) -> float:
        """Leakage factor sigma = 1 - M^2 / (L_s L_r) (Bodson, after (45))."""
        return 1.0 - self.M**2 / (self.L_s * self.L_r)


#: The laboratory DFIM of Bodson section III-D / IV-A (standstill estimates, J of motor + DC load).
BODSON_DFIM = DFIMParams(R_s=0.66, R_r=0.94, L_s=13.1e-3, L_r=9.8e-3, M=9.7e-3, n_p=2, J=3.5e-4)
