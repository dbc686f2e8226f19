"""The cage IM at standstill as the inverse-Gamma equivalent circuit: what a standstill test sees.

The T-circuit of ``machines.IMParams`` (R_s, R_r, L_s, L_r, L_m; Amezquita-Brooks et al. (1),
Ugalde-Loo et al. (37)-(39)) has one parameter more than its stator terminals can reveal: scaling
the rotor winding by any turns ratio a changes L_r, L_m and R_r but not a single stator voltage,
current or the torque. Choosing a = L_m / L_r (rotor flux psi_R = a psi_r) gives the
inverse-Gamma circuit, four parameters, all of which a standstill test determines:

    R_s                        stator resistance
    L_sigma = L_s - L_m^2/L_r  transient (total leakage) inductance, = sigma L_s
    L_M     = L_m^2 / L_r      magnetising inductance of the inverse-Gamma circuit
    R_R     = R_r (L_m/L_r)^2  rotor resistance referred through a = L_m / L_r

At standstill (w = 0) the a-axis of the stationary frame carries (the part's equations,
``machines._cage_part``, with psi_R = (L_m / L_r) psi_r):

    L_sigma di/dt = v - (R_s + R_R) i + (R_R / L_M) psi_R
    dpsi_R/dt     = R_R i - (R_R / L_M) psi_R

so the standstill impedance is

    Z(s) = R_s + s L_sigma + s L_M R_R / (R_R + s L_M),

the series stator branch and the rotor branch (L_M parallel to R_R). Its rotor corner is
w_c = R_R / L_M = R_r / L_r = 1 / tau_r. Going back to a T-circuit needs the leakage split,
which the data cannot give: :func:`t_circuit` takes it as an assumption (L_ls = L_lr by default).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acdrive._arguments import (
    COUNT,
    NONNEGATIVE,
    POSITIVE,
    Array,
    Either,
    Instance,
    Text,
    checked,
    optional,
)
from acdrive.errors import InputError, require_positive
from acdrive.identify._winding import sampled_response

#: the inverse-Gamma parameters in the order every fit and table uses, with unit and meaning
INVERSE_GAMMA = (
    ("R_s", "ohm", "stator resistance"),
    ("L_sigma", "H", "transient (total leakage) inductance sigma L_s"),
    ("R_R", "ohm", "rotor resistance of the inverse-Gamma circuit, R_r (L_m/L_r)^2"),
    ("L_M", "H", "magnetising inductance of the inverse-Gamma circuit, L_m^2/L_r"),
)
NAMES = tuple(name for name, _, _ in INVERSE_GAMMA)
UNITS = {name: unit for name, unit, _ in INVERSE_GAMMA}

#: the leakage splits :func:`t_circuit` knows -> what each assumes
LEAKAGE_SPLITS = {
    "equal": "stator and rotor leakage equal, L_ls = L_lr",
    "rotor-only": "all leakage on the rotor side, L_ls = 0 (L_m = L_s)",
}


@checked(R_s=POSITIVE, L_sigma=POSITIVE, R_R=POSITIVE, L_M=POSITIVE)
@dataclass(frozen=True)
class InverseGamma:
    """The four standstill-identifiable parameters of a cage IM (module docstring)."""

    R_s: float
    L_sigma: float
    R_R: float
    L_M: float

    def __post_init__(self):
        for name in NAMES:
            require_positive(name, getattr(self, name))

    def as_array(self) -> np.ndarray:
        return np.array([getattr(self, n) for n in NAMES])

    @classmethod
    def from_array(cls, values) -> InverseGamma:
        return cls(*(float(v) for v in values))

    @property
    def rotor_corner(self) -> float:
        """w_c = R_R / L_M = R_r / L_r = 1 / tau_r [rad/s]."""
        return self.R_R / self.L_M


@checked(machine=Instance("acdrive.machines._induction:IMParams"))
def inverse_gamma(machine) -> InverseGamma:
    """The inverse-Gamma parameters of a T-circuit machine (``IMParams``; module docstring)."""
    a = machine.L_m / machine.L_r
    return InverseGamma(
        R_s=machine.R_s,
        L_sigma=machine.L_s - a * machine.L_m,
        R_R=machine.R_r * a * a,
        L_M=a * machine.L_m,
    )


@checked(params=Instance(InverseGamma), n_p=COUNT, split=Text(LEAKAGE_SPLITS), J=optional(POSITIVE))
def t_circuit(params: InverseGamma, n_p: int, split: str = "equal", J=None):
    """An ``IMParams`` with the terminal behaviour of ``params``, under an assumed leakage split.

    L_s = L_sigma + L_M is fixed by the data; how the leakage divides between the stator
    (L_ls = L_s - L_m) and the rotor (L_lr = L_r - L_m) is not, so ``split`` names an
    assumption (``LEAKAGE_SPLITS``):

    - ``equal`` (L_ls = L_lr, the usual choice): L_r = L_s, L_m = sqrt(L_M L_s);
    - ``rotor-only`` (L_ls = 0, the inverse-Gamma circuit itself): L_m = L_s, L_r = L_m^2 / L_M.

    R_r = R_R (L_r / L_m)^2 in both. Every stator quantity and the torque are the same for any
    split; only the rotor flux's scale (psi_r = psi_R L_r / L_m) differs.
    """
    from acdrive.machines._induction import IMParams

    if split not in LEAKAGE_SPLITS:
        raise InputError("split", f"must be one of {', '.join(LEAKAGE_SPLITS)}")
    L_s = params.L_sigma + params.L_M
    if split == "equal":
        L_r = L_s
        L_m = float(np.sqrt(params.L_M * L_s))
    else:
        L_m = L_s
        L_r = L_m * L_m / params.L_M
    R_r = params.R_R * (L_r / L_m) ** 2
    return IMParams(R_s=params.R_s, R_r=R_r, L_s=L_s, L_r=L_r, L_m=L_m, n_p=n_p, J=J)


@checked(params=Either(Instance(InverseGamma), Array(1)), w=Array())
def standstill_impedance(params, w) -> np.ndarray:
    """Z(jw) = R_s + jw L_sigma + jw L_M R_R / (R_R + jw L_M) [ohm] (module docstring); ``params``
    an ``InverseGamma`` or an array (R_s, L_sigma, R_R, L_M)."""
    R_s, L_sigma, R_R, L_M = np.asarray(
        params.as_array() if isinstance(params, InverseGamma) else params, dtype=float
    )
    s = 1j * np.asarray(w, dtype=float)
    return R_s + s * L_sigma + s * L_M * R_R / (R_R + s * L_M)


def standstill_state_space(params) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of x = (i, psi_R), input v, output i = x[0] (module docstring)."""
    R_s, L_sigma, R_R, L_M = np.asarray(
        params.as_array() if isinstance(params, InverseGamma) else params, dtype=float
    )
    A = np.array([[-(R_s + R_R) / L_sigma, R_R / (L_M * L_sigma)], [R_R, -R_R / L_M]])
    B = np.array([1.0 / L_sigma, 0.0])
    return A, B


@checked(
    params=Either(Instance(InverseGamma), Array(1)), w=Array(), hold=POSITIVE,
    dead_time=NONNEGATIVE,
)
def sampled_admittance(params, w, hold: float, dead_time: float = 0.0) -> np.ndarray:
    """Y_d(e^{jwT}) = i_k / v_k [S] of the standstill circuit driven by a voltage held over each
    period ``hold`` = T (zero-order hold, the inverter's latched command) and its current sampled
    at the period starts, t_d / 2 early by the inverter's dead time ``dead_time`` = t_d: the
    exact discrete model of ``identify._winding`` for the state space of
    :func:`standstill_state_space`. At DC the dead time's shift reads the current high by
    R_s t_d / (2 L_sigma) relative (1.6e-4 on the built-in IMs at t_d = 2 us), which biases
    R_s, R_R, L_sigma and L_M by a few 1e-4 when left out."""
    A, B = standstill_state_space(params)
    return sampled_response(A, B, w, hold, dead_time)
