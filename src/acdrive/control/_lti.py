"""Linear time-invariant controllers: one definition for the ICAD analysis and the simulator.

A controller is defined once, as a continuous-time state-space model, and that very object is
what both sides use: ``acdrive.analysis`` (ICAD, Amezquita-Brooks et al. (5)-(10)) evaluates its
frequency response, and :func:`discretise` turns it into the difference equation that the sampled
part ``acdrive.control.StationaryCurrentController`` runs. No numbers are copied between
the two.

* :class:`LTI`: a real SISO k(s) = C (s I - A)^-1 B + D, built with ``tf`` (polynomials), ``zpk``,
  ``pi``, ``pi_lag``, ``gain``, ``paper_20`` or ``from_control``.
* :class:`LTIMatrix`: a p x m controller, either a grid of SISO ``LTI`` entries (``diagonal(k_1,
  k_2)`` for the decentralised controllers of the paper, u_i = k_i e_i) or a general MIMO state
  space (``ss``).
* :func:`discretise`: (A_d, B_d, C_d, D_d) for a sample period T_s by zero-order hold (exact for a
  piecewise-constant controller input) or Tustin, s = c (z - 1)/(z + 1) with c = 2/T_s or, with
  pre-warping at w_0, c = w_0 / tan(w_0 T_s / 2) (then k_d(e^{j w_0 T_s}) = k(j w_0) exactly).
* Built-in controllers of Amezquita-Brooks et al. (section "Built-in controllers" below): (20),
  their PI (K_P = 360, K_I = 9000), the PI family of Fig. 17, the high-integral-gain PI of Fig. 18
  and the inner PI of (22). The ICAD reports and the simulator take them from here.

The batched frequency-response evaluation (``evaluate_ss``) lives here because ``LTI`` needs it;
``acdrive.analysis._freqresp`` re-exports it:

- modal path: A = V diag(lambda) V^-1 once per model, then G(s) = D + sum_i R_i / (s - lambda_i)
  with residues R_i = (C V)[:, i] (V^-1 B)[i, :]: a handful of operations per point;
- Hessenberg path: H = Q^T A Q once per model, then one Hessenberg solve (s I - H) X = Q^T B per
  point (pivoting between adjacent rows) and G = (C Q) X + D.

The modal path is used when the eigenvector matrix is well conditioned. Points where its terms
cancel (the sum of their sizes exceeds ``CANCEL_LIMIT`` times the size of the result, e.g. an
element of high relative degree far above its poles) are solved directly, all at once (a batched
LU solve of (s I - A) X = B, backward stable like the Hessenberg solve); models with
ill-conditioned V (defective or nearly defective A) are evaluated by the Hessenberg path, which is
as accurate as a dense solve.
"""

from __future__ import annotations

import math
import types
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
from numba import njit, prange

from acdrive.errors import InputError, call_interruptible, require_finite

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


def _renamed(function, name):
    """A copy of a plain function under another name. Numba names a function's disk cache after
    its qualified name and does not key it on ``parallel``: two dispatchers compiled from one
    Python function would read and write the same cache entry, and whichever compiled first
    would serve both."""
    twin = types.FunctionType(
        function.__code__, function.__globals__, name, function.__defaults__, function.__closure__
    )
    twin.__qualname__ = name
    twin.__doc__ = function.__doc__
    return twin


#: the same loop compiled without threads, for a single model (its own cache entry)
_modal_sum_one = njit(cache=True, error_model="numpy")(
    _renamed(_modal_sum.py_func, "_modal_sum_one")
)


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
    s: complex points, shape (k,). Returns shape (..., k, p, m). (For a discrete model, s = z.)
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
        # one model (a controller's response): the serial twin, no thread start-up
        modal_sum = _modal_sum if R.shape[0] > 1 else _modal_sum_one
        call_interruptible(
            modal_sum, s, np.ascontiguousarray(lam[good]), R, Dg, CANCEL_LIMIT, modal, lost
        )
        if not all_good:
            G[good] = modal.reshape(-1, s.size, p, m)
        gb, k = np.nonzero(lost)
        if gb.size:  # every such point at once: C (s I - A)^-1 B + D by a batched LU solve
            b = np.flatnonzero(good)[gb]
            M = s[k, None, None] * np.eye(n) - A2[b]
            X = np.linalg.solve(M, B2[b].astype(complex))
            G[b, k] = C2[b] @ X + D2[b]
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


def _polynomial(field_name: str, coefficients) -> np.ndarray:
    """Real finite polynomial coefficients (highest power first), leading zeros removed."""
    try:
        c = np.atleast_1d(np.asarray(coefficients, dtype=float))
    except (TypeError, ValueError):
        raise InputError(field_name, "must be a sequence of real coefficients") from None
    if c.ndim != 1:
        raise InputError(field_name, "must be a 1-D sequence of coefficients, highest power first")
    if not np.all(np.isfinite(c)):
        raise InputError(field_name, "coefficients must be finite")
    nonzero = np.flatnonzero(c)
    return c[nonzero[0] :] if nonzero.size else np.zeros(0)


@dataclass(frozen=True)
class LTI:
    """A real SISO continuous-time controller k(s) = C (s I - A)^-1 B + D.

    Build it with ``tf``, ``zpk``, ``pi``, ``pi_lag``, ``gain``, ``paper_20`` or
    ``from_control``. The arrays are read-only: an ``LTI`` is shared, never copied, between the
    ICAD analysis and the simulator.
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
    def tf(cls, num, den, name: str = "") -> LTI:
        """k(s) = num(s) / den(s), coefficients highest power first; proper (deg num <= deg den).

        Realised in controllable canonical form; leading zero coefficients are ignored.
        """
        num = _polynomial("controller.num", num)
        den = _polynomial("controller.den", den)
        if den.size == 0:
            raise InputError("controller.den", "must not be the zero polynomial")
        if num.size > den.size:
            raise InputError(
                "controller.num",
                f"improper transfer function: degree of num ({num.size - 1}) exceeds degree of "
                f"den ({den.size - 1}); a realisable controller has deg num <= deg den",
            )
        if num.size == 0:
            num = np.zeros(1)
        num, den = num / den[0], den / den[0]
        if den.size == 1:
            return cls.gain(float(num[-1]), name=name)
        return cls(*_canonical(num, den), name=name)

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
        """PI controller k(s) = K_P + K_I / s (state: the integral of the error)."""
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
        """Controller (20) of Amezquita-Brooks et al.: 326.5 (s+400)^2 (s+1000) / (s (s^2+100s+42500)).

        The one built-in instance (``PAPER_20``): every call returns the same object, so the ICAD
        reports and the simulator share it."""
        return PAPER_20

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

    def to_control(self):
        """This controller as a python-control ``StateSpace`` (continuous time; needs the optional
        ``control`` extra). ``control.tf(k.to_control())`` gives the transfer function."""
        return _to_control_ss(self.A, self.B, self.C, self.D, 0, self.name)

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


# ---------------------------------------------------------------------------------------------
# MIMO controllers


def _to_control_ss(A, B, C, D, dt, name: str):
    """A python-control ``StateSpace`` of (A, B, C, D) at sampling time ``dt`` (0: continuous);
    python-control is an optional dependency, so its absence is an input error naming it."""
    try:
        import control
    except ImportError:  # pragma: no cover - depends on the environment
        raise InputError(
            "control", "python-control is not installed (pip install 'acdrive[control]')"
        ) from None
    n = np.asarray(A).shape[0]
    p, m = np.asarray(D).shape
    # python-control wants (n x m) B and (p x n) C even when n = 0
    B = np.asarray(B, dtype=float).reshape(n, m)
    C = np.asarray(C, dtype=float).reshape(p, n)
    kwargs = {"name": name} if name else {}
    return control.ss(np.asarray(A, dtype=float).reshape(n, n), B, C, D, dt, **kwargs)


def as_lti(controller, field_name: str = "controller") -> LTI:
    """An ``LTI`` from an ``LTI`` (returned as it is) or a python-control SISO continuous-time
    ``TransferFunction`` / ``StateSpace``; anything else is an ``InputError`` naming the field."""
    if isinstance(controller, LTI):
        return controller
    try:
        import control
    except ImportError:  # pragma: no cover - depends on the environment
        control = None
    if control is not None and isinstance(controller, control.LTI):
        try:
            return LTI.from_control(controller, name=getattr(controller, "name", "") or "")
        except InputError as exc:
            raise InputError(field_name, exc.rule) from None
    raise InputError(
        field_name,
        "must be an LTI controller or a python-control TransferFunction/StateSpace, got "
        f"{type(controller).__name__}",
    )


def _matrix(field_name: str, value, shape: tuple[int | None, int | None]) -> np.ndarray:
    """A finite real 2-D array of the given shape (None: any size), read-only."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(field_name, "must be a real matrix") from None
    if arr.ndim != 2:
        raise InputError(field_name, f"must be a 2-D matrix, got {arr.ndim} dimension(s)")
    for axis, want in enumerate(shape):
        if want is not None and arr.shape[axis] != want:
            raise InputError(
                field_name,
                f"has shape {arr.shape[0]} x {arr.shape[1]}; "
                f"{'rows' if axis == 0 else 'columns'} must be {want}",
            )
    if not np.all(np.isfinite(arr)):
        raise InputError(field_name, "must be finite")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class LTIMatrix:
    """A real p x m continuous-time controller u = K(s) e, K(s) = C (s I - A)^-1 B + D.

    Built from SISO entries (``grid``, ``diagonal``: ``entries`` then holds the very ``LTI``
    objects, e.g. the k_1, k_2 that the ICAD analysis takes, and ``K[i, j]`` returns them) or as
    a general MIMO state space (``ss``; no entries). The realisation of a grid stacks the states
    of its entries, row by row.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    entries: tuple | None = field(default=None, repr=False)
    name: str = ""

    def __post_init__(self):
        A = _matrix("controller.A", self.A, (None, None))
        n = A.shape[0]
        if A.shape[1] != n:
            raise InputError("controller.A", f"must be square, got {A.shape[0]} x {A.shape[1]}")
        D = _matrix("controller.D", self.D, (None, None))
        p, m = D.shape
        if p == 0 or m == 0:
            raise InputError("controller.D", "needs at least one output and one input")
        object.__setattr__(self, "A", A)
        object.__setattr__(self, "B", _matrix("controller.B", self.B, (n, m)))
        object.__setattr__(self, "C", _matrix("controller.C", self.C, (p, n)))
        object.__setattr__(self, "D", D)

    # -- constructors ------------------------------------------------------------------------
    @classmethod
    def ss(cls, A, B, C, D, name: str = "") -> LTIMatrix:
        """General MIMO state space: A n x n, B n x m, C p x n, D p x m (n may be 0)."""
        D = np.atleast_2d(np.asarray(D, dtype=float))
        A = np.asarray(A, dtype=float)
        A = np.atleast_2d(A) if A.size else np.zeros((0, 0))
        n = A.shape[0]
        B = np.asarray(B, dtype=float)
        B = np.atleast_2d(B) if B.size else np.zeros((n, D.shape[1]))
        C = np.asarray(C, dtype=float)
        C = np.atleast_2d(C) if C.size else np.zeros((D.shape[0], n))
        return cls(A, B, C, D, name=name)

    @classmethod
    def from_control(cls, sys, name: str = "") -> LTIMatrix:
        """From a python-control continuous-time ``StateSpace`` or ``TransferFunction`` (any
        number of inputs and outputs)."""
        import control

        ss = control.ss(sys)
        if ss.dt not in (0, None):
            raise InputError("controller", "must be continuous-time (dt = 0)")
        return cls.ss(ss.A, ss.B, ss.C, ss.D, name=name or getattr(sys, "name", "") or "")

    def to_control(self):
        """This controller as a python-control ``StateSpace`` (continuous time)."""
        return _to_control_ss(self.A, self.B, self.C, self.D, 0, self.name)

    @classmethod
    def grid(cls, rows, name: str = "") -> LTIMatrix:
        """K(s) with entries K[i][j] = ``rows[i][j]``: an ``LTI``, a number (static gain) or None
        (zero). The ``LTI`` entries are kept as they are (same objects)."""
        if not isinstance(rows, (list, tuple)) or not rows:
            raise InputError("controller", "must be a non-empty list of rows of SISO entries")
        width = None
        kept = []
        for i, row in enumerate(rows):
            if not isinstance(row, (list, tuple)) or not row:
                raise InputError(f"controller[{i}]", "must be a non-empty row of entries")
            if width is None:
                width = len(row)
            elif len(row) != width:
                raise InputError(
                    f"controller[{i}]", f"has {len(row)} entries; every row must have {width}"
                )
            out_row = []
            for j, entry in enumerate(row):
                if entry is None or isinstance(entry, LTI):
                    out_row.append(entry)
                elif isinstance(entry, (int, float)) and not isinstance(entry, bool):
                    out_row.append(None if entry == 0 else LTI.gain(entry))
                else:
                    raise InputError(
                        f"controller[{i}][{j}]",
                        f"must be an LTI, a number or None, got {type(entry).__name__}",
                    )
            kept.append(tuple(out_row))
        p, m = len(kept), width
        blocks = [(i, j, k) for i, row in enumerate(kept) for j, k in enumerate(row) if k]
        n = sum(k.order for _, _, k in blocks)
        A, B, C, D = np.zeros((n, n)), np.zeros((n, m)), np.zeros((p, n)), np.zeros((p, m))
        at = 0
        for i, j, k in blocks:
            sl = slice(at, at + k.order)
            A[sl, sl] = k.A
            B[sl, j] = k.B[:, 0]
            C[i, sl] = k.C[0, :]
            D[i, j] = k.D[0, 0]
            at += k.order
        return cls(A, B, C, D, entries=tuple(kept), name=name)

    @classmethod
    def diagonal(cls, *ks: LTI, name: str = "") -> LTIMatrix:
        """diag(k_1, ..., k_n): decentralised control u_i = k_i e_i (Amezquita-Brooks et al. (5),
        no decoupling); ``diagonal(k, k)`` applies the same controller to both axes."""
        if not ks:
            raise InputError("controller", "diagonal needs at least one entry")
        for i, k in enumerate(ks):
            if not isinstance(k, LTI):
                raise InputError(f"controller[{i}]", f"must be an LTI, got {type(k).__name__}")
        size = len(ks)
        return cls.grid(
            [[ks[i] if i == j else None for j in range(size)] for i in range(size)], name
        )

    @classmethod
    def of(cls, controller) -> LTIMatrix:
        """``controller`` as a matrix: an ``LTIMatrix`` as it is, an ``LTI`` as a 1 x 1 grid."""
        if isinstance(controller, LTIMatrix):
            return controller
        if isinstance(controller, LTI):
            return cls.grid([[controller]], name=controller.name)
        raise InputError(
            "controller", f"must be an LTI or an LTIMatrix, got {type(controller).__name__}"
        )

    # -- properties ---------------------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, int]:
        """(outputs, inputs)."""
        return self.D.shape

    @property
    def order(self) -> int:
        return self.A.shape[0]

    def __getitem__(self, index) -> LTI | None:
        """The SISO entry K[i, j] of a grid (the same object it was built from; None: zero)."""
        if self.entries is None:
            raise InputError("controller", "a general state-space matrix has no SISO entries")
        i, j = index
        return self.entries[i][j]

    @property
    def is_diagonal(self) -> bool:
        """A square grid with zero off-diagonal entries."""
        p, m = self.shape
        return (
            self.entries is not None
            and p == m
            and all(self.entries[i][j] is None for i in range(p) for j in range(m) if i != j)
        )

    def diagonal_entries(self) -> tuple[LTI, ...]:
        """(k_1, ..., k_n) of a diagonal grid (the objects ICAD's ``analyse(plant, k_1, k_2)``
        takes); a zero diagonal entry is returned as a zero gain."""
        if not self.is_diagonal:
            raise InputError("controller", "is not a diagonal grid of SISO entries")
        return tuple(
            self.entries[i][i] if self.entries[i][i] is not None else LTI.gain(0.0)
            for i in range(self.shape[0])
        )

    def poles(self) -> np.ndarray:
        return np.linalg.eigvals(self.A) if self.order else np.zeros(0, dtype=complex)

    @property
    def is_stable(self) -> bool:
        return bool(np.all(self.poles().real < 0.0))

    def evaluate(self, s) -> np.ndarray:
        """K(s) at complex points s: shape (k, p, m)."""
        return evaluate_ss(self.A, self.B, self.C, self.D, s)

    def freqresp(self, w) -> np.ndarray:
        """K(j w) on a validated frequency grid w [rad/s]: shape (k, p, m)."""
        return self.evaluate(1j * check_frequency_grid(w))


# ---------------------------------------------------------------------------------------------
# Discretisation

METHODS = ("zoh", "tustin")
#: A continuous pole counts as stable for the discretisation check when Re(p) T_s < -STABLE_TOL
#: (its discrete image then differs from the unit circle by far more than rounding).
STABLE_TOL = 1e-10


def _frozen(method: str, label: str, arr) -> np.ndarray:
    arr = np.ascontiguousarray(arr, dtype=float)
    if not np.all(np.isfinite(arr)):
        raise InputError("T_s", f"the {method} closed form gives a non-finite {label}")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class DiscreteLTI:
    """x_{k+1} = A_d x_k + B_d e_k, u_k = C_d x_k + D_d e_k at period ``T_s``, from ``source``
    (the continuous ``LTI`` or ``LTIMatrix`` itself, not a copy) by ``method``. Unpacks as
    ``Ad, Bd, Cd, Dd = discretise(...)``."""

    Ad: np.ndarray
    Bd: np.ndarray
    Cd: np.ndarray
    Dd: np.ndarray
    T_s: float
    method: str
    prewarp: float | None
    source: LTI | LTIMatrix = field(repr=False)

    def __iter__(self):
        return iter((self.Ad, self.Bd, self.Cd, self.Dd))

    def to_control(self):
        """This discrete controller as a python-control ``StateSpace`` with ``dt = T_s``."""
        return _to_control_ss(self.Ad, self.Bd, self.Cd, self.Dd, self.T_s, self.source.name)

    @property
    def order(self) -> int:
        return self.Ad.shape[0]

    @property
    def shape(self) -> tuple[int, int]:
        return self.Dd.shape

    def evaluate(self, z) -> np.ndarray:
        """k_d(z) = C_d (z I - A_d)^-1 B_d + D_d at complex points z: shape (k, p, m)."""
        return evaluate_ss(self.Ad, self.Bd, self.Cd, self.Dd, z)

    def freqresp(self, w) -> np.ndarray:
        """k_d(e^{j w T_s}) on a frequency grid w [rad/s]; shape (k,) for an ``LTI`` source, as
        ``LTI.freqresp``, else (k, p, m)."""
        g = self.evaluate(np.exp(1j * check_frequency_grid(w) * self.T_s))
        return g[:, 0, 0] if isinstance(self.source, LTI) else g


def tustin_constant(T_s: float, prewarp: float | None = None) -> float:
    """c of the substitution s = c (z - 1)/(z + 1): 2/T_s, or w_0 / tan(w_0 T_s / 2) when
    pre-warped at w_0 (then z = e^{j w_0 T_s} maps to s = j w_0 exactly)."""
    if prewarp is None:
        return 2.0 / T_s
    return prewarp / math.tan(0.5 * prewarp * T_s)


def discretise(controller, T_s: float, method: str = "tustin", prewarp=None) -> DiscreteLTI:
    """Discrete state space of ``controller`` (an ``LTI`` or ``LTIMatrix``) at period ``T_s``.

    ``method="zoh"``: the controller input held over each period (exact sampling of the
    continuous controller fed by a staircase), A_d = e^{A T_s}, B_d = int_0^{T_s} e^{A t} dt B
    (one matrix exponential of [[A, B], [0, 0]] T_s), C_d = C, D_d = D.

    ``method="tustin"``: s = c (z - 1)/(z + 1) (``tustin_constant``; ``prewarp`` = w_0 [rad/s],
    0 < w_0 < pi / T_s, keeps k_d(e^{j w_0 T_s}) = k(j w_0)); with h = 2/c and M = I - (h/2) A:
    A_d = M^-1 (I + (h/2) A), B_d = h M^-1 B, C_d = C M^-1, D_d = D + (1/2) C B_d. For the PI
    K_P + K_I / s this is u_k = u_{k-1} + K_P (e_k - e_{k-1}) + K_I (h/2) (e_k + e_{k-1}).

    InputError (naming the field) when: T_s is not a positive number; the method is unknown;
    ``prewarp`` is given for ZOH or lies outside (0, pi/T_s); the closed form fails (M singular:
    a controller pole at s = c; a non-finite matrix exponential); or the discretisation is
    unstable where the controller is not: fewer eigenvalues of A_d strictly inside the unit
    circle than poles of the controller strictly in the left half-plane (a stable controller
    must give max |eig(A_d)| < 1).
    """
    K = controller if isinstance(controller, (LTI, LTIMatrix)) else LTIMatrix.of(controller)
    if isinstance(T_s, bool) or not isinstance(T_s, (int, float, np.floating)):
        raise InputError("T_s", f"must be a number, got {type(T_s).__name__}")
    T_s = float(T_s)
    if not (math.isfinite(T_s) and T_s > 0.0):
        raise InputError("T_s", f"must be a finite sample period > 0 s, got {T_s:g}")
    if method not in METHODS:
        raise InputError("method", f"must be one of {', '.join(METHODS)}, got {method!r}")
    if prewarp is not None:
        if method != "tustin":
            raise InputError("prewarp", "pre-warping applies to the Tustin method only")
        if isinstance(prewarp, bool) or not isinstance(prewarp, (int, float, np.floating)):
            raise InputError("prewarp", f"must be a number [rad/s], got {type(prewarp).__name__}")
        prewarp = float(prewarp)
        nyquist = math.pi / T_s
        if not (math.isfinite(prewarp) and 0.0 < prewarp < nyquist):
            raise InputError(
                "prewarp",
                f"must lie in (0, pi/T_s) = (0, {nyquist:.6g}) rad/s, got {prewarp:g}",
            )
    A, B, C, D = K.A, K.B, K.C, K.D
    n, m = B.shape
    if method == "zoh":
        M = np.zeros((n + m, n + m))
        M[:n, :n] = A * T_s
        M[:n, n:] = B * T_s
        with np.errstate(all="ignore"):
            E = scipy.linalg.expm(M)
        Ad, Bd, Cd, Dd = E[:n, :n], E[:n, n:], C.copy(), D.copy()
        if not (np.all(np.isfinite(Ad)) and np.all(np.isfinite(Bd))):
            raise InputError(
                "T_s",
                "the ZOH closed form e^{A T_s} overflows: the controller has a pole with "
                "Re(p) T_s far above 1",
            )
    else:
        c = tustin_constant(T_s, prewarp)
        h = 2.0 / c
        eye = np.eye(n)
        Msys = eye - (0.5 * h) * A
        if n and (
            not np.all(np.isfinite(Msys)) or np.linalg.cond(Msys) > 1.0 / np.finfo(float).eps
        ):
            raise InputError(
                "T_s",
                f"the Tustin closed form fails: I - A/c is singular (c = {c:.6g} 1/s), the "
                "controller has a pole at s = c; change T_s or prewarp",
            )
        lu = scipy.linalg.lu_factor(Msys) if n else None
        Ad = scipy.linalg.lu_solve(lu, eye + (0.5 * h) * A) if n else np.zeros((0, 0))
        Bd = h * scipy.linalg.lu_solve(lu, B) if n else np.zeros((0, m))
        Cd = scipy.linalg.lu_solve(lu, C.T, trans=1).T if n else np.zeros((C.shape[0], 0))
        Dd = D + 0.5 * (C @ Bd)
    if n:
        # poles decisively in the left half-plane at this period (Re(p) T_s < -STABLE_TOL; an
        # integrator or a pole that rounds onto the axis is not counted)
        stable_c = int(np.sum(np.linalg.eigvals(A).real * T_s < -STABLE_TOL))
        radii = np.abs(np.linalg.eigvals(Ad))
        stable_d = int(np.sum(radii < 1.0))
        if stable_d < stable_c:
            raise InputError(
                "T_s",
                f"the {method} discretisation is unstable where the controller is stable: "
                f"{stable_c} pole(s) in the open left half-plane but only {stable_d} eigenvalue(s)"
                f" of A_d inside the unit circle (max |eig(A_d)| = {radii.max():.17g} >= 1); "
                "a stable pole must map strictly inside the unit circle",
            )
    Ad, Bd, Cd, Dd = (
        _frozen(method, label, a) for label, a in zip(("Ad", "Bd", "Cd", "Dd"), (Ad, Bd, Cd, Dd))
    )
    return DiscreteLTI(Ad, Bd, Cd, Dd, T_s, method, prewarp, K)


# ---------------------------------------------------------------------------------------------
# Built-in controllers (Amezquita-Brooks et al.): the single definitions

#: Controller (20) = (22): 326.5 (s + 1000)/s * (s + 400)^2 / (s^2 + 100 s + 42500), the PI
#: (s + 1000)/s cascaded with the lag (s + 400)^2 / ((s + 50)^2 + 200^2).
PAPER_20 = LTI.pi_lag(326.5, 1000.0, [-400.0, -400.0], [-50 + 200j, -50 - 200j], name="paper-20")

#: The stationary-frame PI of sec. VI-D, K_P = 360, K_I = 9000 (crossover of (20), PM >= 45 deg),
#: applied without decoupling or back-EMF compensation (sec. VI).
PAPER_PI = LTI.pi(360.0, 9000.0, name="paper-pi")

#: The inner PI of (22): 326.5 (s + 1000)/s = K_P 326.5, K_I 326 500 (Fig. 19, 20).
PI_OF_22 = LTI.pi_lag(326.5, 1000.0, [], [], name="PI of (22)")

#: Integral gains of the PI family of Fig. 17 (sec. VII), lowest first.
FIG17_K_I = (3e3, 9e3, 3e4, 1e5, 3e5, 6e5, 9e5)
#: Their proportional gains: for each K_I, K_P such that the individual channel c_i (7) with the
#: PI on both loops crosses 0 dB at the crossover of (20) (3343.7 rad/s), DeLorenzo IM with the
#: parameters of (13) at w_r = 375 rad/s (sec. VII: "initially setting integral gain K_I and then
#: adjusting proportional gain K_P so that the desired crossover frequency is obtained"). Solved
#: by brentq (xtol 1e-9) in acdrive._report.icad.pi_comparison, which re-solves and checks them.
FIG17_K_P = (
    346.82834346910863,
    346.81905073525684,
    346.7133968461226,
    345.53752834051744,
    335.0232587104563,
    296.8008365377555,
    218.72536669274623,
)
#: The PI family of Fig. 17 (K_I rising).
FIG17_PI_FAMILY = tuple(
    LTI.pi(kp, ki, name=f"PI K_I = {ki:.0e}") for kp, ki in zip(FIG17_K_P, FIG17_K_I, strict=True)
)
#: The high-integral-gain PI of Fig. 18: the highest-gain member of the family (K_I = 9e5).
FIG18_PI = FIG17_PI_FAMILY[-1]

#: Every built-in controller by name (the same objects as the constants above).
BUILTIN = {
    "paper-20": PAPER_20,
    "paper-pi": PAPER_PI,
    "paper-22-pi": PI_OF_22,
    **{f"fig17-pi-{ki:.0e}".replace("e+0", "e"): k for ki, k in zip(FIG17_K_I, FIG17_PI_FAMILY)},
    "fig18-pi": FIG18_PI,
}


def builtin(name: str) -> LTI:
    """The built-in controller ``name`` (see ``BUILTIN``); the shared object, not a copy."""
    try:
        return BUILTIN[name]
    except (KeyError, TypeError):
        raise InputError(
            "controller", f"unknown built-in '{name}', known: {', '.join(BUILTIN)}"
        ) from None
