"""Discretisation of a linear controller (``discretise``): (A_d, B_d, C_d, D_d) for a sample period
T_s by zero-order hold (exact for a piecewise-constant controller input) or Tustin, s = c (z -
1)/(z + 1) with c = 2/T_s or, with pre-warping at w_0, c = w_0 / tan(w_0 T_s / 2) (then
k_d(e^{j w_0 T_s}) = k(j w_0) exactly). The result, ``DiscreteLTI``, is what the sampled part
``acdrive.control.StationaryCurrentController`` runs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from acdrive.control._lti import LTI, to_control_ss
from acdrive.control._lti_matrix import LTIMatrix
from acdrive.errors import InputError

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
        return to_control_ss(self.Ad, self.Bd, self.Cd, self.Dd, self.T_s, self.source.name)

    @property
    def order(self) -> int:
        return self.Ad.shape[0]

    @property
    def shape(self) -> tuple[int, int]:
        return self.Dd.shape

    def evaluate(self, z) -> np.ndarray:
        """k_d(z) = C_d (z I - A_d)^-1 B_d + D_d at complex points z: shape (k, p, m)."""
        from acdrive.control._ss_frequency import evaluate_ss

        return evaluate_ss(self.Ad, self.Bd, self.Cd, self.Dd, z)

    def freqresp(self, w) -> np.ndarray:
        """k_d(e^{j w T_s}) on a frequency grid w [rad/s]; shape (k,) for an ``LTI`` source, as
        ``LTI.freqresp``, else (k, p, m)."""
        from acdrive.control._ss_frequency import check_frequency_grid

        g = self.evaluate(np.exp(1j * check_frequency_grid(w) * self.T_s))
        return g[:, 0, 0] if isinstance(self.source, LTI) else g


def tustin_constant(T_s: float, prewarp: float | None = None) -> float:
    """c of the substitution s = c (z - 1)/(z + 1): 2/T_s, or w_0 / tan(w_0 T_s / 2) when
    pre-warped at w_0 (then z = e^{j w_0 T_s} maps to s = j w_0 exactly)."""
    if prewarp is None:
        return 2.0 / T_s
    return prewarp / math.tan(0.5 * prewarp * T_s)


def _closed_form(A, B, C, D, T_s: float, method: str, prewarp):
    """(A_d, B_d, C_d, D_d) by the closed forms of ``discretise`` (its InputErrors included)."""
    n, m = B.shape
    if method == "zoh":
        M = np.zeros((n + m, n + m))
        M[:n, :n] = A * T_s
        M[:n, n:] = B * T_s
        with np.errstate(all="ignore"):
            import scipy.linalg  # imported where used: a run that discretises nothing skips it

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
        # scipy's LU, imported here (0.2 CPU-s) and not by a run that discretises nothing: numpy's
        # solve (another LAPACK build, and a transposed factorisation for Cd) differs in the last
        # bits on some matrices, which a closed loop with switching carries to 1e-9 of a peak
        import scipy.linalg

        lu = scipy.linalg.lu_factor(Msys) if n else None
        Ad = scipy.linalg.lu_solve(lu, eye + (0.5 * h) * A) if n else np.zeros((0, 0))
        Bd = h * scipy.linalg.lu_solve(lu, B) if n else np.zeros((0, m))
        Cd = scipy.linalg.lu_solve(lu, C.T, trans=1).T if n else np.zeros((C.shape[0], 0))
        Dd = D + 0.5 * (C @ Bd)
    return Ad, Bd, Cd, Dd


#: the memo of ``_closed_form``'s results on disk (``_cached_closed_form``); the version names
#: the algorithm: a change of it starts a new memo
_MEMO = "discretised"
_MEMO_VERSION = b"closed forms v1: scipy expm (zoh), scipy LU (tustin)"


def _cached_closed_form(A, B, C, D, T_s: float, method: str, prewarp):
    """``_closed_form``, its result kept on disk keyed by every bit of its inputs, so that a
    later process reads the same matrices without importing scipy (0.2 to 0.45 CPU-s, most of a
    warm run of a drive whose controllers are discretised; acdrive's cache folder is keyed by its
    sources, ``acdrive._cache``). A memo that cannot be read is computed and written again."""
    import hashlib

    digest = hashlib.sha256(_MEMO_VERSION)
    for a in (A, B, C, D):
        a = np.ascontiguousarray(a, dtype=float)
        digest.update(repr(a.shape).encode() + a.tobytes())
    digest.update(repr((float(T_s), method, prewarp)).encode())
    try:
        from acdrive._cache import cache_folder

        path = cache_folder(_MEMO, "acdrive") / f"{digest.hexdigest()[:32]}.npz"
    except OSError:
        return _closed_form(A, B, C, D, T_s, method, prewarp)
    try:
        with np.load(path) as found:
            return tuple(np.array(found[k]) for k in ("Ad", "Bd", "Cd", "Dd"))
    except (OSError, ValueError, KeyError, EOFError):
        pass  # not there yet, or damaged: computed and written (again)
    result = _closed_form(A, B, C, D, T_s, method, prewarp)
    _write_memo(path, result)
    return result


def _write_memo(path, result) -> None:
    import os
    import tempfile

    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
        with os.fdopen(fd, "wb") as handle:
            np.savez(handle, **dict(zip(("Ad", "Bd", "Cd", "Dd"), result, strict=True)))
        os.replace(tmp, path)
    except OSError:
        pass  # a memo is an optimisation: a read-only cache folder computes every time


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
    n = B.shape[0]
    Ad, Bd, Cd, Dd = _cached_closed_form(A, B, C, D, T_s, method, prewarp)
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
