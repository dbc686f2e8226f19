"""Roots and exact Nyquist counts of the ICAD functions from state-space data (Ugalde-Loo et al.,
Amezquita-Brooks et al.).

Every Nyquist function of ICAD is a ratio of characteristic polynomials of state-space
realisations, so its right-half-plane (RHP) zeros and poles are eigenvalues or invariant zeros
computed from state-space data:

- 1 - gamma      = det(sI - A) z_G(s) / (n_11(s) n_22(s))
- 1 - gamma h_j  = zeta_i(s) det(sI - A) / (n_ii(s) phi_j(s))
- 1 + k_i g_ii   = phi_i(s) / (det(sI - A) d_ki(s))
- 1 + c_i        = phi_cl(s) / (phi_j(s) d_ki(s))

with z_G the invariant-zero polynomial of G (Rosenbrock pencil), n_ij the numerator of g_ij over
det(sI - A), d_k the controller denominator, phi_j the characteristic polynomial of the plant with
loop j closed, zeta_i the numerator of u_i -> y_i with loop j closed and phi_cl that of the full
loop. Clockwise encirclements of the critical point are N = Z - P (Nyquist). Roots on the
imaginary axis of the denominators (integrators, imaginary zeros of g_ii) are excluded by
indenting the contour to their right; uncancelled roots of the numerators on the axis mean the
plot passes through the critical point and are reported as such (encirclements = None). The
same count is cross-checked by the winding number of F on the indented contour
(``margins.winding_number``); a mismatch raises InputError instead of returning a wrong count.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from acdrive._arguments import Array, checked
from acdrive.analysis._freqresp import LTI
from acdrive.analysis._margins import winding_number
from acdrive.errors import InputError

AXIS_TOL = 1e-9  # |Re s| <= AXIS_TOL * max(1, |s|): root on the imaginary axis
MARKOV_TOL = 1e-10  # relative size below which a Markov parameter counts as zero
INFINITE_EIG = 1e8  # generalised eigenvalues above this times the pencil norm are infinite


# ---------------------------------------------------------------------------------------------
# roots from state-space data


def markov_zero(A, b, c, d) -> bool:
    """True if the SISO transfer c (sI - A)^-1 b + d is identically zero."""
    if abs(d) > 0.0:
        return False
    n = A.shape[0]
    scale = max(np.linalg.norm(A, 2), 1e-300)
    v = b.ravel().astype(float)
    cn = np.linalg.norm(c) * np.linalg.norm(b)
    if cn == 0.0:
        return True
    for k in range(n):
        if abs(float(c.ravel() @ v)) > MARKOV_TOL * cn * scale**k:
            return False
        v = A @ v
    return True


def relative_degree(A, b, c, d) -> int | None:
    """Relative degree of a SISO element from its Markov parameters (None if identically 0)."""
    if abs(d) > 0.0:
        return 0
    n = A.shape[0]
    scale = max(np.linalg.norm(A, 2), 1e-300)
    cn = np.linalg.norm(c) * np.linalg.norm(b)
    v = b.ravel().astype(float)
    for k in range(n):
        if cn > 0 and abs(float(c.ravel() @ v)) > MARKOV_TOL * cn * scale**k:
            return k + 1
        v = A @ v
    return None


@checked(A=Array(2, empty=True), B=Array(2, empty=True), C=Array(2, empty=True), D=Array(2))
def invariant_zeros(A, B, C, D) -> np.ndarray:
    """Finite invariant zeros of a square system: finite eigenvalues of the Rosenbrock pencil.

    For a SISO element these are the roots of its numerator over det(sI - A); for the 2x2 plant
    they are the roots of z_G(s) = det(sI - A) det G(s).
    """
    A = np.atleast_2d(A)
    n = A.shape[0]
    m = B.shape[1]
    M = np.block([[A, B], [C, D]])
    N = np.zeros_like(M)
    N[:n, :n] = np.eye(n)
    if M.size == 0:
        return np.zeros(0, dtype=complex)
    alpha, beta = scipy.linalg.eig(M, N, right=False, homogeneous_eigvals=True)
    limit = INFINITE_EIG * max(1.0, np.linalg.norm(M, 2))
    finite = np.abs(alpha) < limit * np.abs(beta)
    zeros = alpha[finite] / beta[finite]
    if zeros.size > n + m:  # pragma: no cover - singular pencil
        raise InputError("plant", "Rosenbrock pencil is singular (zeros undefined)")
    return zeros


def close_loop(A, B, C, D, j_in: int, j_out: int, k: LTI):
    """Close u_{j_in} = k (r - y_{j_out}) (r = 0) around a state-space plant.

    Returns (A', B', C', D') with states (x, x_k), the input j_in removed and all outputs kept.
    Raises InputError if the loop is ill-posed (1 + k(inf) D[j_out, j_in] = 0).
    """
    n, m = B.shape
    rest = [i for i in range(m) if i != j_in]
    Ak, Bk, Ck, Dk = k.A, k.B, k.C, float(k.D[0, 0])
    nk = Ak.shape[0]
    djj = D[j_out, j_in]
    if abs(1.0 + Dk * djj) < 1e-12:
        raise InputError("controller", "feedback loop is ill-posed (1 + k(inf) d_jj = 0)")
    mfac = 1.0 / (1.0 + Dk * djj)
    cj = C[j_out : j_out + 1, :]
    Ux = mfac * np.hstack([-Dk * cj, Ck])  # u_j = Ux [x; x_k] + Uu u_rest
    Uu = -mfac * Dk * D[j_out : j_out + 1, rest]
    bj = np.vstack([B[:, j_in : j_in + 1], np.zeros((nk, 1))])
    minus_Bk = np.vstack([np.zeros((n, 1)), -Bk])
    yj_x = np.hstack([cj, np.zeros((1, nk))]) + djj * Ux
    yj_u = D[j_out : j_out + 1, rest] + djj * Uu
    A_new = scipy.linalg.block_diag(A, Ak) + bj @ Ux + minus_Bk @ yj_x
    B_new = np.vstack([B[:, rest], np.zeros((nk, len(rest)))]) + bj @ Uu + minus_Bk @ yj_u
    C_new = np.hstack([C, np.zeros((C.shape[0], nk))]) + D[:, j_in : j_in + 1] @ Ux
    D_new = D[:, rest] + D[:, j_in : j_in + 1] @ Uu
    return A_new, B_new, C_new, D_new


def eigenvalues(A) -> np.ndarray:
    return np.linalg.eigvals(A) if A.shape[0] else np.zeros(0, dtype=complex)


# ---------------------------------------------------------------------------------------------
# Nyquist counts


def on_axis(r: np.ndarray) -> np.ndarray:
    return np.abs(r.real) <= AXIS_TOL * np.maximum(1.0, np.abs(r))


def _rhp(r: np.ndarray) -> int:
    return int(np.sum((r.real > 0) & ~on_axis(r)))


@dataclass(frozen=True)
class NyquistCount:
    """Nyquist count of a critical point for F = (numerator roots) / (denominator roots).

    ``encirclements`` is the number of clockwise encirclements of the critical point (Z - P
    with the contour indented to the right of imaginary-axis poles), or None if the plot passes
    through the critical point (F has an uncancelled zero on the imaginary axis).
    ``winding`` is the independent count from the indented contour (None if not computed).
    """

    critical_point: float
    rhp_zeros: int
    rhp_poles: int
    axis_zeros: tuple[complex, ...]
    axis_poles: tuple[complex, ...]
    encirclements: int | None
    winding: int | None

    @property
    def passes_through(self) -> bool:
        return self.encirclements is None


def _cancel_axis(zeros: np.ndarray, poles: np.ndarray):
    """Remove pairs of equal imaginary-axis roots from zeros and poles (multiplicity aware)."""
    zeros, poles = list(zeros), list(poles)
    for z in list(zeros):
        for idx, p in enumerate(poles):
            if abs(z - p) <= 1e-6 * max(1.0, abs(p)):
                zeros.remove(z)
                poles.pop(idx)
                break
    return np.array(zeros, dtype=complex), np.array(poles, dtype=complex)


def nyquist_count(
    num_roots: Sequence[np.ndarray],
    den_roots: Sequence[np.ndarray],
    critical_point: float,
    F=None,
    singular: np.ndarray | None = None,
) -> NyquistCount:
    """Count encirclements of the critical point from the roots of F's factors.

    F(s) - as a function of complex s whose zeros are the critical-point crossings - if given, is
    integrated along the indented contour and its winding number must agree with the count.
    ``singular``: further points where the parts of F cannot be evaluated (e.g. controller
    integrators that cancel in F); imaginary-axis ones are indented too.
    """
    num = np.concatenate([np.asarray(r, dtype=complex).ravel() for r in num_roots] or [np.zeros(0)])
    den = np.concatenate([np.asarray(r, dtype=complex).ravel() for r in den_roots] or [np.zeros(0)])
    az, ap = _cancel_axis(num[on_axis(num)], den[on_axis(den)])
    Z, P = _rhp(num), _rhp(den)
    enc = None if az.size else Z - P
    winding = None
    if F is not None and enc is not None:
        extra = np.zeros(0, dtype=complex) if singular is None else np.asarray(singular, complex)
        winding = _winding(F, num, den, extra)
        if winding != enc:
            raise InputError(
                "plant",
                f"encirclement count is ill-conditioned: pole/zero count {enc}, contour winding"
                f" {winding}",
            )
    return NyquistCount(
        critical_point=critical_point,
        rhp_zeros=Z,
        rhp_poles=P,
        axis_zeros=tuple(complex(z) for z in az),
        axis_poles=tuple(complex(p) for p in ap),
        encirclements=enc,
        winding=winding,
    )


def _winding(F, num: np.ndarray, den: np.ndarray, extra: np.ndarray) -> int:
    roots = np.concatenate([num, den, extra])
    mags = np.abs(roots)
    radius = 4.0 * (mags.max() if mags.size else 1.0) + 10.0
    nonzero = mags[mags > 1e-9 * (mags.max() if mags.size else 0.0)]
    scale = 0.1 * nonzero.min() if nonzero.size else 1.0
    axis = roots[on_axis(roots)]
    centres: list[float] = []
    for r in axis:  # unique imaginary-axis points
        if all(abs(r.imag - c) > 1e-6 * max(1.0, abs(c)) for c in centres):
            centres.append(float(r.imag))
    radii = []
    for c in centres:
        d = np.abs(roots - 1j * c)
        others = d[d > 1e-6 * max(1.0, abs(c))]
        near = others.min() if others.size else radius
        radii.append(min(0.1 * near, 1e-3 * max(1.0, abs(c)), 0.1 * scale))
    return winding_number(F, radius, np.array(centres), np.array(radii), scale=max(scale, 1e-6))


def scalar_d(siso):
    """(A, b, c, d) of a SISO realisation with d as a float."""
    A, b, c, d = siso
    return A, b, c, float(d[0, 0])
