"""A winding at standstill as the sampled drive sees it: the one place for its discrete model.

Every standstill test (the cage IM's stator, a PM machine's d or q axis, a DFIM's rotor with its
stator open or shorted) drives a passive linear winding x' = A x + B v whose first state is the
phase current, i = x[0]: one state for an RL branch (``identify._pm``), two for the inverse-Gamma
circuit (``identify._circuit``). The PWM unit latches one command per carrier period T and the
current is sampled at the period start, so the exact model is the zero-order-hold one,

    x_{k+1} = Phi x_k + Gamma v_k,   Phi = e^{AT},   Gamma = A^{-1} (Phi - I) B,   i_k = C x_k,

with the admittance Y_d(e^{jwT}) = C (zI - Phi)^{-1} Gamma at z = e^{jwT} (a periodic steady
state sampled this way has exactly these Fourier coefficients).

**The sample row C and the dead time.** Without dead time the period start is the middle of
centred PWM's zero vector, where the switched current equals the held-voltage model's: C = e_0.
A dead time t_d delays the rising edge of a leg carrying positive current and the falling edge of
one carrying negative current (``plant._inverter``): either way every switching pulse's centre
moves t_d / 2 later, so the sample is taken t_d / 2 before the middle of the (shifted) zero
vector, on the ripple's slope. In the zero vector the winding is shorted and follows its free
response x' = A x, so the sample reads C = e_0^T e^{-A t_d / 2} instead of e_0. At DC this reads
the current high by R t_d / (2 L) relative, R and L the winding's resistance and series
(transient) inductance. The device drops during the zero vector (a voltage of at most the
inverter's error over t_d / 2) are left out: a current error of the order U_err t_d / (2 L).
"""

from __future__ import annotations

import numpy as np


def expm_small(A: np.ndarray, T: float) -> np.ndarray:
    """e^{AT} of a 1x1 or 2x2 standstill matrix (a passive winding: real, negative, distinct
    eigenvalues in the 2x2 case, ``_expm_2x2``)."""
    if A.shape == (1, 1):
        return np.array([[np.exp(A[0, 0] * T)]])  # inf, not an exception, off range
    return _expm_2x2(A, T)


def _expm_2x2(A: np.ndarray, T: float) -> np.ndarray:
    """e^{AT} of a 2x2 matrix with real distinct eigenvalues by Sylvester's formula (the
    inverse-Gamma circuit's discriminant ((a11 - a22)^2 + 4 a12 a21) is positive since
    a12 a21 = R_R^2 / (L_M L_sigma) > 0)."""
    trace = A[0, 0] + A[1, 1]
    root = np.sqrt((A[0, 0] - A[1, 1]) ** 2 + 4.0 * A[0, 1] * A[1, 0])
    l1, l2 = 0.5 * (trace + root), 0.5 * (trace - root)
    # e^{l2 T} I + (e^{l1 T} - e^{l2 T}) / (l1 - l2) (A - l2 I), with l1 > l2 and the difference
    # written as -e^{l1 T} expm1(-(l1 - l2) T): accurate for close eigenvalues, never overflowing
    slope = -np.exp(l1 * T) * np.expm1(-(l1 - l2) * T) / (l1 - l2)
    return np.exp(l2 * T) * np.eye(2) + slope * (A - l2 * np.eye(2))


def discrete_winding(A: np.ndarray, B: np.ndarray, hold: float,
                     dead_time: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """(Phi, Gamma, C) of the winding (A, B) held over periods ``hold`` = T and sampled t_d / 2
    early by the inverter's dead time ``dead_time`` = t_d [s] (module docstring)."""
    Phi = expm_small(A, hold)
    Gamma = np.linalg.solve(A, (Phi - np.eye(A.shape[0])) @ B)
    if dead_time > 0.0:
        C = expm_small(A, -0.5 * dead_time)[0]
    else:
        C = np.zeros(A.shape[0])
        C[0] = 1.0
    return Phi, Gamma, C


def sampled_response(A: np.ndarray, B: np.ndarray, w, hold: float,
                     dead_time: float = 0.0) -> np.ndarray:  # fmt: skip
    """Y_d(e^{jwT}) = C (zI - Phi)^{-1} Gamma [S] at the angular frequencies ``w`` [rad/s]
    (module docstring)."""
    Phi, Gamma, C = discrete_winding(A, B, hold, dead_time)
    z = np.exp(1j * np.asarray(w, dtype=float) * hold)
    if A.shape == (1, 1):
        return C[0] * Gamma[0] / (z - Phi[0, 0])
    # (zI - Phi)^-1 Gamma for the 2x2 case, by the adjugate
    det = (z - Phi[0, 0]) * (z - Phi[1, 1]) - Phi[0, 1] * Phi[1, 0]
    first = (z - Phi[1, 1]) * Gamma[0] + Phi[0, 1] * Gamma[1]
    second = Phi[1, 0] * Gamma[0] + (z - Phi[0, 0]) * Gamma[1]
    return (C[0] * first + C[1] * second) / det
