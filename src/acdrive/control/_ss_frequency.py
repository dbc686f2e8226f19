"""Batched frequency responses of state-space models, G(s) = C (s I - A)^-1 B + D over a batch of
models and a grid of points (``evaluate_ss``): what ``LTI``, ``LTIMatrix`` and the ICAD analysis
(Amezquita-Brooks et al. (5)-(10)) evaluate; ``acdrive.analysis._freqresp`` re-exports it.

- modal path: A = V diag(lambda) V^-1 once per model, then G(s) = D + sum_i R_i / (s - lambda_i)
  with residues R_i = (C V)[:, i] (V^-1 B)[i, :]: a handful of operations per point;
- Hessenberg path: H = Q^T A Q once per model, then one Hessenberg solve (s I - H) X = Q^T B per
  point (pivoting between adjacent rows) and G = (C Q) X + D.

The modal path is used when the eigenvector matrix is well conditioned. Points where its terms
cancel (the sum of their sizes exceeds ``CANCEL_LIMIT`` times the size of the result, e.g. an
element of high relative degree far above its poles) are solved directly, all at once (a batched
LU solve of (s I - A) X = B, backward stable like the Hessenberg solve); models with
ill-conditioned V (defective or nearly defective A) are evaluated by the Hessenberg path, which is
as accurate as a dense solve. The compiled modal sum exists twice, threaded over models
(``_modal_sum``) and serial for one model (``_modal_sum_one``), each with its own cache entry.

The per-model part (decomposition, residues, Hessenberg form: ``_PreparedSS``) does not depend on
the points; for a single model it is kept per process, keyed by the bits of A, B, C and D
(``_prepared_model``), so a search that evaluates one model at one point after another pays it
once. A kept preparation gives the same bits as a fresh one.
"""

from __future__ import annotations

import functools

import numpy as np

from acdrive._jit import njit, prange, serial_twin
from acdrive.errors import InputError, call_interruptible

#: Models whose eigenvector matrix has a larger condition number use the Hessenberg path.
EIG_COND_LIMIT = 1e5
#: Points whose modal terms cancel by more than this factor are solved directly (LU).
CANCEL_LIMIT = 1e6


@njit(cache=True, error_model="numpy", parallel=True)
def _modal_sum(s, lam, R, D, limit, out, lost):
    """out[b, k, c] = D[b, c] + sum_i R[b, i, c] / (s[k] - lam[b, i]) (c: flattened entry);
    lost[b, k] flags points where, for some entry, the summed size (|re| + |im|) of the terms
    exceeds ``limit`` times the size of their sum. Models (b) run in parallel on all cores;
    every point's arithmetic is the same as in a serial loop."""
    nb, n, q = R.shape
    for b in prange(nb):
        total = np.empty(q)
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


#: the same loop compiled without threads, for a single model (its own cache entry)
_modal_sum_one = serial_twin(_modal_sum, "_modal_sum_one")


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


def _hessenberg_form(A, B, C, D) -> tuple:
    """One model's data for ``_hessenberg_solve``: H = Q^T A Q and Q^T B, C Q, D, each with a
    leading batch axis of one."""
    import scipy.linalg  # only when a model needs the Hessenberg path

    H, Q = scipy.linalg.hessenberg(A, calc_q=True)
    return (
        np.ascontiguousarray(H)[None],
        (Q.T @ B).astype(complex)[None],
        (C @ Q).astype(complex)[None],
        np.ascontiguousarray(D, dtype=float)[None],
    )


class _PreparedSS:
    """What ``evaluate_ss`` computes once per batch of models, before any point: the modal
    residues of the models with a well-conditioned eigenvector matrix, the Hessenberg form of
    the others (module docstring). ``at(s)`` is G at points s, shape (nb, k, p, m)."""

    def __init__(self, A2, B2, C2, D2):
        n = A2.shape[-1]
        p, m = D2.shape[-2:]
        self.A2, self.B2, self.C2, self.D2 = A2, B2, C2, D2
        lam, V = np.linalg.eig(A2)
        cond = np.linalg.cond(V)
        self.good = good = np.isfinite(cond) & (cond < EIG_COND_LIMIT)
        self.all_good = bool(np.all(good))  # then the modal sum writes straight into G
        self.good_index = np.flatnonzero(good)
        self.R = None
        if self.good_index.size:
            Vg = V[good]
            CV = C2[good] @ Vg  # (b, p, n)
            VB = np.linalg.solve(Vg, B2[good].astype(complex))  # (b, n, m)
            self.R = (CV.transpose(0, 2, 1)[:, :, :, None] * VB[:, :, None, :]).reshape(
                -1, n, p * m
            )
            self.lam = np.ascontiguousarray(lam[good])
            self.Dg = np.ascontiguousarray(D2[good].reshape(-1, p * m))
        self.hessenberg = {
            b: _hessenberg_form(A2[b], B2[b], C2[b], D2[b]) for b in np.flatnonzero(~good)
        }

    def at(self, s) -> np.ndarray:
        nb, n, _ = self.A2.shape
        p, m = self.D2.shape[-2:]
        G = np.empty((nb, s.size, p, m), dtype=complex)
        R = self.R
        if R is not None:
            modal = (
                G.reshape(nb, s.size, p * m)
                if self.all_good
                else np.empty((R.shape[0], s.size, p * m), complex)
            )
            lost = np.zeros((R.shape[0], s.size), dtype=np.bool_)
            # one model (a controller's response): the serial twin, no thread start-up
            modal_sum = _modal_sum if R.shape[0] > 1 else _modal_sum_one
            call_interruptible(modal_sum, s, self.lam, R, self.Dg, CANCEL_LIMIT, modal, lost)
            if not self.all_good:
                G[self.good] = modal.reshape(-1, s.size, p, m)
            gb, k = np.nonzero(lost)
            if gb.size:  # every such point at once: C (s I - A)^-1 B + D by a batched LU solve
                b = self.good_index[gb]
                M = s[k, None, None] * np.eye(n) - self.A2[b]
                X = np.linalg.solve(M, self.B2[b].astype(complex))
                G[b, k] = self.C2[b] @ X + self.D2[b]
        for b, form in self.hessenberg.items():
            out = np.empty((1, s.size, p, m), dtype=complex)
            _hessenberg_solve(s, *form, out)
            G[b] = out[0]
        return G


#: how many single models ``_prepared_model`` keeps, and the most states a kept model has
PREPARED_MODELS = 64
PREPARED_MAX_STATES = 64


@functools.lru_cache(maxsize=PREPARED_MODELS)
def _prepared_model(key: tuple) -> _PreparedSS:
    """The preparation of one model, kept per process: root finding and margins evaluate the
    same plant and controllers at one point after another. ``key``: each matrix's shape and
    bytes (float64), so equal bits give the same preparation and any changed bit a new one."""
    A, B, C, D = (np.frombuffer(data, dtype=float).reshape(shape).copy() for shape, data in key)
    return _PreparedSS(A[None], B[None], C[None], D[None])


def evaluate_ss(A, B, C, D, s) -> np.ndarray:
    """G(s) for batched state-space data.

    A: (..., n, n), B: (..., n, m), C: (..., p, n), D: (..., p, m) (same leading batch shape);
    s: complex points, shape (k,). Returns shape (..., k, p, m). (For a discrete model, s = z.)
    The per-model work (eigen- or Hessenberg decomposition, residues) of a single model is done
    once per process for the same bits of A, B, C, D (``_prepared_model``).
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
    if A.ndim == B.ndim == C.ndim == D.ndim == 2 and n <= PREPARED_MAX_STATES:
        key = tuple((M.shape, np.ascontiguousarray(M).tobytes()) for M in (A, B, C, D))
        return _prepared_model(key).at(s).reshape(out_shape)
    A2 = A.reshape(-1, n, n)
    nb = A2.shape[0]
    B2 = np.broadcast_to(B, batch + (n, m)).reshape(nb, n, m)
    C2 = np.broadcast_to(C, batch + (p, n)).reshape(nb, p, n)
    D2 = np.ascontiguousarray(np.broadcast_to(D, batch + (p, m)).reshape(nb, p, m))
    return _PreparedSS(A2, B2, C2, D2).at(s).reshape(out_shape)


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
