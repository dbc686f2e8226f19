"""Batched frequency responses from state-space data, and SISO LTI controllers.

``evaluate_ss`` computes G(s) = C (s I - A)^-1 B + D for stacks of state-space models (a leading
batch axis, e.g. rotor speed or parameter set) at many complex points s at once, with compiled
(numba) loops over points and no transfer-function polynomials:

- modal path: A = V diag(lambda) V^-1 once per model, then G(s) = D + sum_i R_i / (s - lambda_i)
  with residues R_i = (C V)[:, i] (V^-1 B)[i, :]: a handful of operations per point;
- Hessenberg path: H = Q^T A Q once per model, then one Hessenberg solve (s I - H) X = Q^T B per
  point (pivoting between adjacent rows) and G = (C Q) X + D.

The modal path is used when the eigenvector matrix is well conditioned; points where its terms
cancel (the sum of their sizes exceeds ``CANCEL_LIMIT`` times the size of the result, e.g. an
element of high relative degree far above its poles) and models with ill-conditioned V (defective
or nearly defective A) are evaluated by the Hessenberg path, which is as accurate as a dense solve.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
from numba import njit

from acdrive.errors import InputError, require_finite

#: Models whose eigenvector matrix has a larger condition number use the Hessenberg path.
EIG_COND_LIMIT = 1e5
#: Points whose modal terms cancel by more than this factor use the Hessenberg path.
CANCEL_LIMIT = 1e6


@njit(cache=True, error_model="numpy")
def _modal_sum(s, lam, R, D, limit, out, lost):
    """out[b, k, c] = D[b, c] + sum_i R[b, i, c] / (s[k] - lam[b, i]) (c: flattened entry);
    lost[b, k] flags points where, for some entry, the summed size (|re| + |im|) of the terms
    exceeds ``limit`` times the size of their sum."""
    nb, n, q = R.shape
    total = np.empty(q)
    for b in range(nb):
        for k in range(s.size):
            for c in range(q):
                out[b, k, c] = 0.0
                total[c] = 0.0
            for i in range(n):
                inv = 1.0 / (s[k] - lam[b, i])
                for c in range(q):
                    term = inv * R[b, i, c]
                    out[b, k, c] += term
                    total[c] += abs(term.real) + abs(term.imag)
            flag = False
            for c in range(q):
                v = out[b, k, c]
                if total[c] > limit * (abs(v.real) + abs(v.imag)):
                    flag = True
                out[b, k, c] = v + D[b, c]
            lost[b, k] = flag
    return out


@njit(cache=True, error_model="numpy")
def _hessenberg_solve(s, H, QB, CQ, D, out):
    """out[b, k] = CQ[b] (s[k] I - H[b])^-1 QB[b] + D[b] for upper Hessenberg H[b].

    Singular points (s on an eigenvalue) give inf/nan entries.
    """
    nb, n, _ = H.shape
    m = QB.shape[2]
    p = CQ.shape[1]
    M = np.empty((n, n), dtype=np.complex128)
    X = np.empty((n, m), dtype=np.complex128)
    for b in range(nb):
        for k in range(s.size):
            for i in range(n):
                for j in range(n):
                    M[i, j] = -H[b, i, j]
                M[i, i] += s[k]
                for c in range(m):
                    X[i, c] = QB[b, i, c]
            for i in range(n - 1):  # eliminate the subdiagonal entry M[i+1, i]
                if abs(M[i + 1, i]) > abs(M[i, i]):
                    for j in range(i, n):
                        M[i, j], M[i + 1, j] = M[i + 1, j], M[i, j]
                    for c in range(m):
                        X[i, c], X[i + 1, c] = X[i + 1, c], X[i, c]
                f = M[i + 1, i] / M[i, i]
                for j in range(i + 1, n):
                    M[i + 1, j] -= f * M[i, j]
                for c in range(m):
                    X[i + 1, c] -= f * X[i, c]
            for i in range(n - 1, -1, -1):  # back substitution
                for c in range(m):
                    acc = X[i, c]
                    for j in range(i + 1, n):
                        acc -= M[i, j] * X[j, c]
                    X[i, c] = acc / M[i, i]
            for r in range(p):
                for c in range(m):
                    acc = D[b, r, c] + 0j
                    for j in range(n):
                        acc += CQ[b, r, j] * X[j, c]
                    out[b, k, r, c] = acc
    return out


def _hessenberg_points(A, B, C, D, s) -> np.ndarray:
    """G(s) of one model at points s by the Hessenberg path, shape (k, p, m)."""
    H, Q = scipy.linalg.hessenberg(A, calc_q=True)
    out = np.empty((1, s.size) + D.shape, dtype=complex)
    _hessenberg_solve(
        s,
        np.ascontiguousarray(H)[None],
        (Q.T @ B).astype(complex)[None],
        (C @ Q).astype(complex)[None],
        np.ascontiguousarray(D, dtype=float)[None],
        out,
    )
    return out[0]


def evaluate_ss(A, B, C, D, s) -> np.ndarray:
    """G(s) for batched state-space data.

    A: (..., n, n), B: (..., n, m), C: (..., p, n), D: (..., p, m) (same leading batch shape);
    s: complex points, shape (k,). Returns shape (..., k, p, m).
    """
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    C = np.asarray(C, dtype=float)
    D = np.asarray(D, dtype=float)
    s = np.ascontiguousarray(np.atleast_1d(np.asarray(s, dtype=complex)))
    batch = A.shape[:-2]
    n = A.shape[-1]
    p, m = D.shape[-2:]
    out_shape = batch + (s.size, p, m)
    if n == 0:
        return np.broadcast_to(D[..., None, :, :], out_shape).astype(complex)
    A2 = A.reshape(-1, n, n)
    nb = A2.shape[0]
    B2 = np.broadcast_to(B, batch + (n, m)).reshape(nb, n, m)
    C2 = np.broadcast_to(C, batch + (p, n)).reshape(nb, p, n)
    D2 = np.ascontiguousarray(np.broadcast_to(D, batch + (p, m)).reshape(nb, p, m))
    G = np.empty((nb, s.size, p, m), dtype=complex)
    lam, V = np.linalg.eig(A2)
    cond = np.linalg.cond(V)
    good = np.isfinite(cond) & (cond < EIG_COND_LIMIT)
    if np.any(good):
        Vg = V[good]
        CV = C2[good] @ Vg  # (b, p, n)
        VB = np.linalg.solve(Vg, B2[good].astype(complex))  # (b, n, m)
        R = (CV.transpose(0, 2, 1)[:, :, :, None] * VB[:, :, None, :]).reshape(-1, n, p * m)
        all_good = bool(np.all(good))  # then write straight into G (no copy)
        modal = (
            G.reshape(nb, s.size, p * m)
            if all_good
            else np.empty((R.shape[0], s.size, p * m), complex)
        )
        lost = np.zeros((R.shape[0], s.size), dtype=np.bool_)
        Dg = np.ascontiguousarray(D2[good].reshape(-1, p * m))
        _modal_sum(s, np.ascontiguousarray(lam[good]), R, Dg, CANCEL_LIMIT, modal, lost)
        if not all_good:
            G[good] = modal.reshape(-1, s.size, p, m)
        for gb, b in enumerate(np.flatnonzero(good)):
            pts = np.flatnonzero(lost[gb])
            if pts.size:
                G[b, pts] = _hessenberg_points(A2[b], B2[b], C2[b], D2[b], s[pts])
    for b in np.flatnonzero(~good):
        G[b] = _hessenberg_points(A2[b], B2[b], C2[b], D2[b], s)
    return G.reshape(out_shape)


def check_frequency_grid(w, name: str = "w") -> np.ndarray:
    """Validate a frequency grid [rad/s]: non-empty, finite, strictly positive, increasing."""
    try:
        w = np.atleast_1d(np.asarray(w, dtype=float))
    except (TypeError, ValueError):
        raise InputError(name, "must be an array of frequencies") from None
    if w.ndim != 1 or w.size == 0:
        raise InputError(name, "must be a non-empty 1-D array of frequencies")
    if not np.all(np.isfinite(w)):
        raise InputError(name, "must be finite (no NaN or infinity)")
    if np.any(w <= 0.0):
        raise InputError(name, "frequencies must be > 0 rad/s")
    if np.any(np.diff(w) <= 0.0):
        raise InputError(name, "frequencies must be strictly increasing")
    return w


def freqresp_ss(A, B, C, D, w) -> np.ndarray:
    """G(j w) for batched state-space data on a validated grid w [rad/s]; see ``evaluate_ss``."""
    return evaluate_ss(A, B, C, D, 1j * check_frequency_grid(w))


# ---------------------------------------------------------------------------------------------
# SISO controllers


def _real_section(roots: list[complex]) -> np.ndarray:
    """Monic real polynomial coefficients (highest first) with the given 1 or 2 roots."""
    return np.real(np.poly(roots))


def _group(roots) -> list[list[complex]]:
    """Group roots into real polynomials of degree <= 2: conjugate pairs, then real pairs."""
    roots = [complex(r) for r in roots]
    reals = sorted((r.real for r in roots if abs(r.imag) <= 1e-12 * max(1.0, abs(r))), reverse=True)
    upper = [r for r in roots if r.imag > 1e-12 * max(1.0, abs(r))]
    lower = [r for r in roots if r.imag < -1e-12 * max(1.0, abs(r))]
    if len(upper) != len(lower):
        raise InputError("roots", "complex roots must come in conjugate pairs")
    groups = [[r, r.conjugate()] for r in upper]
    groups += [[reals[i], reals[i + 1]] for i in range(0, len(reals) - 1, 2)]
    if len(reals) % 2:
        groups.append([reals[-1]])
    return groups


def _canonical(num: np.ndarray, den: np.ndarray):
    """Controllable canonical realisation of num/den (den monic, deg num <= deg den)."""
    n = den.size - 1
    num = np.concatenate([np.zeros(n + 1 - num.size), num])
    d = num[0]
    r = num[1:] - d * den[1:]  # strictly proper remainder, highest power first
    A = np.zeros((n, n))
    A[0, :] = -den[1:]
    A[1:, :-1] = np.eye(n - 1)
    B = np.zeros((n, 1))
    B[0, 0] = 1.0
    C = r[None, :]
    return A, B, C, np.array([[d]])


def _series(first, second):
    """State-space of second(s) * first(s) (signal goes through ``first`` then ``second``)."""
    A1, B1, C1, D1 = first
    A2, B2, C2, D2 = second
    n1, n2 = A1.shape[0], A2.shape[0]
    A = np.block([[A1, np.zeros((n1, n2))], [B2 @ C1, A2]])
    B = np.vstack([B1, B2 @ D1])
    C = np.hstack([D2 @ C1, C2])
    return A, B, C, D2 @ D1


@dataclass(frozen=True)
class LTI:
    """A real SISO continuous-time controller k(s) = C (s I - A)^-1 B + D.

    Build it with ``zpk``, ``pi``, ``pi_lag``, ``paper_20`` or ``from_control``.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    name: str = ""

    def __post_init__(self):
        A = np.array(self.A, dtype=float)
        n = round(float(np.sqrt(A.size)))
        if n * n != A.size:
            raise InputError("controller.A", "must be square")
        A = A.reshape(n, n)
        B = np.array(self.B, dtype=float).reshape(n, 1)
        C = np.array(self.C, dtype=float).reshape(1, n)
        D = np.array(self.D, dtype=float).reshape(1, 1)
        for label, arr in (("A", A), ("B", B), ("C", C), ("D", D)):
            if not np.all(np.isfinite(arr)):
                raise InputError(f"controller.{label}", "must be finite")
            arr.setflags(write=False)
        for label, arr in (("A", A), ("B", B), ("C", C), ("D", D)):
            object.__setattr__(self, label, arr)

    # -- constructors ------------------------------------------------------------------------
    @classmethod
    def zpk(cls, zeros, poles, gain: float, name: str = "") -> LTI:
        """k(s) = gain * prod(s - z) / prod(s - p); proper, real (conjugate-paired) data."""
        gain = require_finite("gain", gain)
        zeros = list(np.atleast_1d(np.asarray(zeros, dtype=complex)))
        poles = list(np.atleast_1d(np.asarray(poles, dtype=complex)))
        if not all(np.isfinite(zeros)) or not all(np.isfinite(poles)):
            raise InputError("controller", "zeros and poles must be finite")
        if len(zeros) > len(poles):
            raise InputError("controller", "improper: more zeros than poles")
        # denominators: conjugate pairs and real pairs (degree 2), at most one of degree 1
        pole_groups = sorted(_group(poles), key=len, reverse=True)
        zero_groups = sorted(_group(zeros), key=len, reverse=True)
        sections = [[g, []] for g in pole_groups]
        for zg in zero_groups:  # first-fit; always succeeds for nz <= np (see grouping)
            for sec in sections:
                if len(sec[1]) + len(zg) <= len(sec[0]):
                    sec[1] = sec[1] + zg
                    break
            else:  # pragma: no cover - unreachable by the degree argument
                raise InputError("controller", "cannot realise zeros")
        ss = (np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), np.array([[gain]]))
        for pg, zg in sections:
            num = _real_section(zg) if zg else np.array([1.0])
            ss = _series(ss, _canonical(num, _real_section(pg)))
        return cls(*ss, name=name)

    @classmethod
    def pi(cls, K_P: float, K_I: float, name: str = "") -> LTI:
        """PI controller k(s) = K_P + K_I / s."""
        K_P = require_finite("K_P", K_P)
        K_I = require_finite("K_I", K_I)
        return cls(np.zeros((1, 1)), np.ones((1, 1)), np.array([[K_I]]), np.array([[K_P]]), name)

    @classmethod
    def pi_lag(cls, gain: float, pi_zero: float, lag_zeros, lag_poles, name: str = "") -> LTI:
        """PI x lag of Amezquita-Brooks et al. (22): gain (s + pi_zero)/s * prod(s - z)/prod(s - p)."""
        pi_zero = require_finite("pi_zero", pi_zero)
        zeros = [-pi_zero] + list(np.atleast_1d(lag_zeros))
        poles = [0.0] + list(np.atleast_1d(lag_poles))
        return cls.zpk(zeros, poles, gain, name=name)

    @classmethod
    def paper_20(cls) -> LTI:
        """Controller (20) of Amezquita-Brooks et al.: 326.5 (s+400)^2 (s+1000) / (s (s^2+100s+42500))."""
        return cls.pi_lag(
            326.5, 1000.0, [-400.0, -400.0], [-50 + 200j, -50 - 200j], name="paper-20"
        )

    @classmethod
    def gain(cls, k: float, name: str = "") -> LTI:
        """Static gain k(s) = k."""
        return cls(
            np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), [[require_finite("k", k)]], name
        )

    @classmethod
    def from_control(cls, sys, name: str = "") -> LTI:
        """From a python-control SISO continuous-time TransferFunction or StateSpace."""
        import control

        ss = control.ss(sys)
        if ss.ninputs != 1 or ss.noutputs != 1:
            raise InputError("controller", "must be SISO")
        if ss.dt not in (0, None):
            raise InputError("controller", "must be continuous-time (dt = 0)")
        return cls(ss.A, ss.B, ss.C, ss.D, name=name)

    # -- properties ---------------------------------------------------------------------------
    @property
    def order(self) -> int:
        return self.A.shape[0]

    def poles(self) -> np.ndarray:
        return np.linalg.eigvals(self.A) if self.order else np.zeros(0, dtype=complex)

    def freqresp(self, w) -> np.ndarray:
        """k(j w) on a validated frequency grid w [rad/s]."""
        return self.evaluate(1j * check_frequency_grid(w))

    def evaluate(self, s) -> np.ndarray:
        """k(s) at complex points s (shape (k,))."""
        return evaluate_ss(self.A, self.B, self.C, self.D, s)[:, 0, 0]

    @property
    def is_stable(self) -> bool:
        """All poles strictly in the open left half-plane."""
        return bool(np.all(self.poles().real < 0.0))

    def rhp_poles(self, tol: float = 1e-9) -> np.ndarray:
        """Poles with Re p > tol * max(1, |p|) (open right half-plane)."""
        p = self.poles()
        return p[p.real > tol * np.maximum(1.0, np.abs(p))]
