"""Individual channel analysis (ICAD) of 2x2 plants with diagonal controllers.

Ugalde-Loo et al. (1)-(6) and Amezquita-Brooks et al. (5)-(10): for y = G u and u_i = k_i e_i,

- multivariable structure function (MSF)  gamma = g12 g21 / (g11 g22)           (4) / (8)
- diagonal closed loops                  h_i = k_i g_ii / (1 + k_i g_ii)          (5) / (9)
- individual channels                    c_i = k_i g_ii (1 - gamma h_j), i != j   (3) / (7)
- cross coupling                          y_i / r_j = S_i (g_ij / g_jj) h_j, S_i = 1/(1 + c_i)
                                                                                    (6) / (10)

Frequency data are evaluated batched over (speed or parameter set) x frequency from state-space
data (``acdrive.analysis._freqresp``). Channels and coupling use algebraically identical forms
that never divide by g_ii: c_i = k_i (g_ii + k_j det G) / (1 + k_j g_jj) and
y_i/r_j = S_i g_ij k_j / (1 + k_j g_jj).

Exact Nyquist counts. Every Nyquist function used here is a ratio of characteristic
polynomials of state-space realisations, so its right-half-plane (RHP) zeros and poles are
eigenvalues or invariant zeros computed from state-space data:

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

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg
from numba import njit, prange

from acdrive.analysis._freqresp import LTI, check_frequency_grid, evaluate_ss
from acdrive.analysis._margins import (
    LoopMargins,
    StructuralMargin,
    bandwidth,
    loop_margins,
    structural_margin,
    winding_number,
)
from acdrive.analysis._plants import Plant2x2, as_plant
from acdrive.control._lti import PAPER_20, PAPER_PI, as_lti
from acdrive.errors import InputError, call_interruptible, require_finite
from acdrive.machines._induction import IMParams
from acdrive.machines._pmsm import PMSGParams

AXIS_TOL = 1e-9  # |Re s| <= AXIS_TOL * max(1, |s|): root on the imaginary axis
MARKOV_TOL = 1e-10  # relative size below which a Markov parameter counts as zero
INFINITE_EIG = 1e8  # generalised eigenvalues above this times the pencil norm are infinite


# ---------------------------------------------------------------------------------------------
# batched frequency data


@njit(cache=True, error_model="numpy", inline="always")
def _reciprocal(z):
    """1 / z as conj(z) / |z|^2: one real division instead of a complex one (numba's complex
    division branches and divides twice). Where |z|^2 would overflow or underflow, and for
    inf, nan or 0, it is the complex division itself, so only the rounding differs."""
    size2 = z.real * z.real + z.imag * z.imag
    if 1e-300 < size2 < 1e300:
        f = 1.0 / size2
        return complex(z.real * f, -z.imag * f)
    return 1.0 / z


@njit(cache=True, error_model="numpy", parallel=True)
def _icad_kernel(G, k1, k2, gamma, h, c, coupling):
    """Per point: Ugalde-Loo (3)-(6) in the division-safe forms of the module docstring.

    G (rows, K, 2, 2) and the outputs (rows, K[, 2]): a row is one plant (speed) over the
    frequency grid. The controller values k (nk, K) repeat with the period of their rows: row r
    takes k[r % nk] (nk = 1: the same frequency grid at every speed). Rows run in parallel on all
    cores; every output is written once, and each reciprocal is computed once per point."""
    for r in prange(G.shape[0]):
        k1r, k2r = k1[r % k1.shape[0]], k2[r % k2.shape[0]]
        for j in range(G.shape[1]):
            a, b = k1r[j], k2r[j]
            g11, g12, g21, g22 = G[r, j, 0, 0], G[r, j, 0, 1], G[r, j, 1, 0], G[r, j, 1, 1]
            det = g11 * g22 - g12 * g21
            kg1, kg2 = a * g11, b * g22
            r1, r2 = _reciprocal(1.0 + kg1), _reciprocal(1.0 + kg2)  # 1 / (1 + k_i g_ii)
            c1 = a * (g11 + b * det) * r2
            c2 = b * (g22 + a * det) * r1
            gamma[r, j] = (g12 * g21) * _reciprocal(g11 * g22)
            h[r, j, 0], h[r, j, 1] = kg1 * r1, kg2 * r2
            c[r, j, 0], c[r, j, 1] = c1, c2
            coupling[r, j, 0] = g12 * b * r2 * _reciprocal(1.0 + c1)
            coupling[r, j, 1] = g21 * a * r1 * _reciprocal(1.0 + c2)


def _derived(key: str, G, k1, k2, gamma, h, c) -> np.ndarray:
    """The ICAD quantities that follow from the kernel's: kg, gamma_h, S, T (last axis: i)."""
    if key == "kg":
        return np.stack([k1 * G[..., 0, 0], k2 * G[..., 1, 1]], axis=-1)
    if key == "gamma_h":  # gamma h_j for channel i
        return gamma[..., None] * h[..., ::-1]
    if key == "S":
        return 1.0 / (1.0 + c)
    if key == "T":
        return c / (1.0 + c)
    raise KeyError(key)


DERIVED = ("kg", "gamma_h", "S", "T")


def _kernel_outputs(G, k1, k2):
    """Run the kernel on broadcast inputs; returns (G, k1, k2, gamma, h, c, coupling)."""
    G = np.asarray(G, dtype=complex)
    k1, k2 = np.asarray(k1, dtype=complex), np.asarray(k2, dtype=complex)
    shape = np.broadcast_shapes(G.shape[:-2], k1.shape, k2.shape)
    N = int(np.prod(shape))
    K = shape[-1] if shape else 1  # a row: the last axis (the frequency grid)
    rows = int(np.prod(shape[:-1]))
    G_rows = np.ascontiguousarray(np.broadcast_to(G, shape + (2, 2))).reshape(rows, K, 2, 2)

    def periodic(k):
        """k as the kernel takes it, rows of K values: its own values if they repeat along the
        leading axes (the frequency grid of every speed), else broadcast to every point."""
        if k.ndim >= 1 and shape[len(shape) - k.ndim :] == k.shape:
            return np.ascontiguousarray(k).reshape(-1, K)
        return np.ascontiguousarray(np.broadcast_to(k, shape)).reshape(rows, K)

    # all outputs in one allocation, each a contiguous part: a single block of fresh pages
    block = np.empty(7 * N, dtype=complex)
    gamma = block[:N].reshape(rows, K)
    h, c, coupling = (
        block[(2 * i + 1) * N : (2 * i + 3) * N].reshape(rows, K, 2) for i in range(3)
    )
    if N:
        call_interruptible(_icad_kernel, G_rows, periodic(k1), periodic(k2), gamma, h, c, coupling)
    two = shape + (2,)
    k1, k2 = np.broadcast_to(k1, shape), np.broadcast_to(k2, shape)
    G = G_rows.reshape(shape + (2, 2))
    return G, k1, k2, gamma.reshape(shape), h.reshape(two), c.reshape(two), coupling.reshape(two)


def icad_quantities(G: np.ndarray, k1: np.ndarray, k2: np.ndarray) -> dict[str, np.ndarray]:
    """ICAD frequency data from plant values G (..., 2, 2) and controller values k1, k2 (...):
    the quantities of Ugalde-Loo et al. (1)-(6) = Amezquita-Brooks et al. (5)-(10).

    G[..., 0, 0], k1 and k2 are broadcast together; the results have that broadcast shape
    (channel arrays with a further last axis of length 2):
    gamma, kg (k_i g_ii), h (h_i), gamma_h (gamma h_j for channel i), c (c_i), S (1/(1+c_i)),
    coupling (y_i / r_j), T (c_i/(1+c_i)).
    """
    G, k1, k2, gamma, h, c, coupling = _kernel_outputs(G, k1, k2)
    out = {"gamma": gamma, "h": h, "c": c, "coupling": coupling}
    for key in DERIVED:
        out[key] = _derived(key, G, k1, k2, gamma, h, c)
    return out


@dataclass(frozen=True)
class ICADResponse:
    """ICAD frequency data over a (plant, frequency) grid.

    Shapes: w (nw,); speeds (ns,) (nan for plants without a speed); G (ns, nw, 2, 2);
    k (2, nw); gamma (ns, nw); h, c, coupling and the derived kg, gamma_h, S, T (ns, nw, 2),
    where index i of the last axis is channel i+1 (gamma_h[..., i] = gamma h_j with j != i;
    coupling[..., i] = y_i/r_j). kg, gamma_h, S and T are computed on first access.
    """

    w: np.ndarray
    speeds: np.ndarray
    G: np.ndarray
    k: np.ndarray
    gamma: np.ndarray
    h: np.ndarray
    c: np.ndarray
    coupling: np.ndarray

    def _get(self, key: str) -> np.ndarray:
        cache = self.__dict__.setdefault("_derived_cache", {})
        if key not in cache:
            cache[key] = _derived(key, self.G, self.k[0], self.k[1], self.gamma, self.h, self.c)
        return cache[key]

    @property
    def kg(self) -> np.ndarray:
        return self._get("kg")

    @property
    def gamma_h(self) -> np.ndarray:
        return self._get("gamma_h")

    @property
    def S(self) -> np.ndarray:
        return self._get("S")

    @property
    def T(self) -> np.ndarray:
        return self._get("T")


def stack_plants(plants) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(A, B, C, D, speeds) stacked over a sequence of plants with the same number of states."""
    if isinstance(plants, Plant2x2) or not isinstance(plants, Sequence):
        plants = [plants]
    plants = [as_plant(p) for p in plants]
    if not plants:
        raise InputError("plants", "must not be empty")
    n = plants[0].n_states
    if any(p.n_states != n for p in plants):
        raise InputError("plants", "must all have the same number of states")
    speeds = np.array([np.nan if p.speed is None else p.speed for p in plants])
    return (
        np.stack([p.A for p in plants]),
        np.stack([p.B for p in plants]),
        np.stack([p.C for p in plants]),
        np.stack([p.D for p in plants]),
        speeds,
    )


def icad_response_arrays(A, B, C, D, k1: LTI, k2: LTI, w, speeds=None) -> ICADResponse:
    """``icad_response`` on stacked state-space arrays A (ns, n, n), B (ns, n, 2), ..."""
    w = check_frequency_grid(w)
    G = evaluate_ss(A, B, C, D, 1j * w)
    if G.shape[-2:] != (2, 2):
        raise InputError("plant", f"must be 2x2, got {G.shape[-2]}x{G.shape[-1]}")
    k1, k2 = as_lti(k1, "k1"), as_lti(k2, "k2")  # python-control objects are welcome too
    k1w = k1.freqresp(w)
    kv = np.stack([k1w, k1w if k2 is k1 else k2.freqresp(w)])
    _, _, _, gamma, h, c, coupling = _kernel_outputs(G, kv[0], kv[1])
    ns = G.shape[0]
    speeds = np.full(ns, np.nan) if speeds is None else np.asarray(speeds, dtype=float)
    return ICADResponse(w=w, speeds=speeds, G=G, k=kv, gamma=gamma, h=h, c=c, coupling=coupling)


def icad_response(plants, k1: LTI, k2: LTI, w) -> ICADResponse:
    """Batched ICAD frequency data for one plant or a sequence of plants on grid w [rad/s]."""
    A, B, C, D, speeds = stack_plants(plants)
    return icad_response_arrays(A, B, C, D, k1, k2, w, speeds)


# ---------------------------------------------------------------------------------------------
# roots from state-space data


def _markov_zero(A, b, c, d) -> bool:
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


def _relative_degree(A, b, c, d) -> int | None:
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


def _eig(A) -> np.ndarray:
    return np.linalg.eigvals(A) if A.shape[0] else np.zeros(0, dtype=complex)


# ---------------------------------------------------------------------------------------------
# Nyquist counts


def _on_axis(r: np.ndarray) -> np.ndarray:
    return np.abs(r.real) <= AXIS_TOL * np.maximum(1.0, np.abs(r))


def _rhp(r: np.ndarray) -> int:
    return int(np.sum((r.real > 0) & ~_on_axis(r)))


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
    az, ap = _cancel_axis(num[_on_axis(num)], den[_on_axis(den)])
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
    axis = roots[_on_axis(roots)]
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
            rd[i, j] = _relative_degree(*_scalar_d(plant.siso(i, j)))
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


def _siso_zeros(plant: Plant2x2, i: int, j: int) -> np.ndarray:
    A, b, c, d = plant.siso(i, j)
    return invariant_zeros(A, b, c, d)


def structure_conditions(plant, *, verify: bool = True) -> StructureConditions:
    """Check conditions i-iv for a 2x2 plant (exact counts; ``verify`` adds the contour check)."""
    plant = as_plant(plant)
    poles = plant.poles()
    cond_i = bool(np.all(poles.real < 0) and not np.any(_on_axis(poles)))
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
    z11, z22 = _siso_zeros(plant, 0, 0), _siso_zeros(plant, 1, 1)
    z12, z21 = _siso_zeros(plant, 0, 1), _siso_zeros(plant, 1, 0)
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
    cond_ii = not np.any((gamma_poles.real > 0) | _on_axis(gamma_poles))
    ev = _Evaluator(plant, None, None)
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


# ---------------------------------------------------------------------------------------------
# channel analysis


class _Evaluator:
    """Point evaluation of the ICAD functions of one plant at complex s."""

    def __init__(self, plant: Plant2x2, k1: LTI | None, k2: LTI | None):
        self.plant, self.k = plant, (k1, k2)

    def G(self, s):
        p = self.plant
        return evaluate_ss(p.A, p.B, p.C, p.D, s)

    def gamma(self, s):
        G = self.G(s)
        with np.errstate(divide="ignore", invalid="ignore"):
            return G[:, 0, 1] * G[:, 1, 0] / (G[:, 0, 0] * G[:, 1, 1])

    def all(self, s):
        return icad_quantities(self.G(s), self.k[0].evaluate(s), self.k[1].evaluate(s))

    def of_w(self, key: str, i: int | None = None):
        """Function of real frequency w returning quantity ``key`` (channel i, 0-based)."""

        def f(w):
            q = self.all(1j * np.asarray(w, dtype=float))[key]
            return q if i is None else q[..., i]

        return f


@dataclass(frozen=True)
class ChannelAnalysis:
    """Channel i of the ICAD decomposition (1-based ``index``).

    ``margins``: of c_i (critical point -1); ``kg_margins``: of k_i g_ii (the loop of h_i);
    ``bandwidth_rad_s``: -3 dB bandwidth of c_i/(1 + c_i); ``channel_count``: c_i around -1;
    ``kg_count``: k_i g_ii around -1; ``gamma_h_count``: gamma h_j around +1;
    ``structural``: structural gain margin of gamma h_j; ``coupling_peak_db``: peak |y_i / r_j|.
    ``h_stable`` / ``channel_stable``: h_i and the closed loop of c_i are stable (eigenvalues).
    """

    index: int
    margins: LoopMargins
    kg_margins: LoopMargins
    bandwidth_rad_s: float
    channel_count: NyquistCount
    kg_count: NyquistCount
    gamma_h_count: NyquistCount
    structural: StructuralMargin
    coupling_peak_db: float
    h_stable: bool
    channel_stable: bool


@dataclass(frozen=True)
class ICADAnalysis:
    """Full ICAD of one plant with a diagonal controller on a frequency grid.

    ``b1``: both channels and both h_i closed loops are stable (Amezquita-Brooks et al. (b.1)
    without a margin threshold); ``b2``: neither gamma nor gamma h_j encircles or passes through
    (1, 0) ((b.2) without a proximity threshold; see ``structural`` and channel margins).
    """

    plant: Plant2x2
    conditions: StructureConditions
    structural: StructuralMargin  # of gamma
    channels: tuple[ChannelAnalysis, ChannelAnalysis]
    closed_loop_poles: np.ndarray
    closed_loop_stable: bool
    b1: bool
    b2: bool
    response: ICADResponse

    @property
    def coupling_peak_db(self) -> float:
        return worst((ch.coupling_peak_db for ch in self.channels), max)


def check_controller(k, name: str) -> LTI:
    """Require a controller without open right-half-plane poles (integrators are allowed); a
    python-control SISO ``TransferFunction`` or ``StateSpace`` is taken as its ``LTI``."""
    k = as_lti(k, name)
    bad = k.rhp_poles()
    if bad.size:
        raise InputError(
            name,
            f"has right-half-plane pole(s) {', '.join(f'{p:.4g}' for p in bad)}; the channel"
            " analysis needs a stable controller (imaginary-axis poles are allowed)",
        )
    return k


def default_grid(plant: Plant2x2, k1: LTI, k2: LTI, n: int = 4000) -> np.ndarray:
    """Log-spaced grid from 1/100 of the slowest to 100 x the fastest plant/controller root."""
    roots = [plant.poles(), k1.poles(), k2.poles(), invariant_zeros(k1.A, k1.B, k1.C, k1.D)]
    if plant.speed:
        roots.append(np.array([plant.speed]))
    r = np.abs(np.concatenate(roots))
    r = r[r > 0]
    lo, hi = (r.min() / 100.0, r.max() * 300.0) if r.size else (1e-2, 1e3)
    ev = _Evaluator(plant, k1, k2)
    for _ in range(8):  # extend until both loops k_i g_ii are well below 0 dB at the top
        with np.errstate(all="ignore"):
            kg = ev.all(np.array([1j * hi]))["kg"]
        if np.all(np.abs(kg) < 0.05):
            break
        hi *= 10.0
    return np.logspace(np.log10(lo), np.log10(hi), n)


def analyse(plant, k1: LTI, k2: LTI, w=None, *, verify: bool = True) -> ICADAnalysis:
    """ICAD of a 2x2 plant with diagonal controller diag(k1, k2).

    Conditions i-iv (exact counts), structural margins of gamma and gamma h_j, channel and
    k_i g_ii margins, bandwidths and coupling peaks on grid ``w`` (default ``default_grid``).
    ``verify`` cross-checks every encirclement count with a contour winding number.
    """
    plant = as_plant(plant)
    k1, k2 = check_controller(k1, "k1"), check_controller(k2, "k2")
    w = default_grid(plant, k1, k2) if w is None else check_frequency_grid(w)
    cond = structure_conditions(plant, verify=verify)
    ev = _Evaluator(plant, k1, k2)
    A, B, C, D = plant.A, plant.B, plant.C, plant.D
    ks = (k1, k2)
    loops = [close_loop(A, B, C, D, i, i, ks[i]) for i in range(2)]  # loop i closed
    phi = [_eig(lp[0]) for lp in loops]
    full = close_loop(*loops[1], 0, 0, k1)  # loop 2 then loop 1 (remaining input is u_1)
    phi_cl = _eig(full[0])
    poles = cond.plant_poles
    dk = [k.poles() for k in ks]
    sing = np.concatenate([poles, dk[0], dk[1]])
    gdc = _dc(ev)
    channels = []
    for i in range(2):
        j = 1 - i
        Aj, Bj, Cj, Dj = loops[j]  # plant with loop j closed, remaining input u_i
        zeta = invariant_zeros(Aj, Bj, Cj[i : i + 1, :], Dj[i : i + 1, :])
        nii = _siso_zeros(plant, i, i)

        def f_c(s, i=i):
            return 1.0 + ev.all(s)["c"][..., i]

        def f_kg(s, i=i):
            return 1.0 + ev.all(s)["kg"][..., i]

        def f_gh(s, i=i):
            return 1.0 - ev.all(s)["gamma_h"][..., i]

        c_count = nyquist_count([phi_cl], [phi[j], dk[i]], -1.0, f_c if verify else None, sing)
        kg_count = nyquist_count([phi[i]], [poles, dk[i]], -1.0, f_kg if verify else None, sing)
        if cond.gamma_identically_zero:
            gh_count = NyquistCount(1.0, 0, 0, (), (), 0, None)
        else:
            gh_count = nyquist_count(
                [zeta, poles], [nii, phi[j]], 1.0, f_gh if verify else None, sing
            )
        T = ev.of_w("T", i)
        channels.append(
            ChannelAnalysis(
                index=i + 1,
                margins=loop_margins(ev.of_w("c", i), w),
                kg_margins=loop_margins(ev.of_w("kg", i), w),
                bandwidth_rad_s=bandwidth(T, w, dc_gain=_dc_T(ev, i)),
                channel_count=c_count,
                kg_count=kg_count,
                gamma_h_count=gh_count,
                structural=structural_margin(ev.of_w("gamma_h", i), w, _dc_gh(ev, i)),
                coupling_peak_db=-math.inf
                if _markov_zero(*_scalar_d(plant.siso(i, j)))
                else _db(np.nanmax(np.abs(ev.of_w("coupling", i)(w)))),
                h_stable=_stable(phi[i]),
                channel_stable=_stable(phi_cl) and _stable(phi[j]),
            )
        )
    response = icad_response(plant, k1, k2, w)
    cl_stable = _stable(phi_cl)
    b1 = all(ch.h_stable and ch.channel_stable for ch in channels)
    b2 = cond.iv and all(ch.gamma_h_count.encirclements == 0 for ch in channels)
    return ICADAnalysis(
        plant=plant,
        conditions=cond,
        structural=structural_margin(lambda x: ev.gamma(1j * np.asarray(x)), w, gdc),
        channels=(channels[0], channels[1]),
        closed_loop_poles=phi_cl,
        closed_loop_stable=cl_stable,
        b1=b1,
        b2=b2,
        response=response,
    )


def _scalar_d(siso):
    A, b, c, d = siso
    return A, b, c, float(d[0, 0])


def _db(x: float) -> float:
    return 20.0 * math.log10(x) if x > 0 else -math.inf


def _stable(roots: np.ndarray) -> bool:
    return bool(np.all(roots.real < 0) and not np.any(_on_axis(roots)))


def _finite_at_zero(values) -> complex | None:
    v = complex(values[0])
    return v if np.isfinite(v) else None


def _dc(ev: _Evaluator) -> complex | None:
    """gamma(0) if the plant has no pole at s = 0."""
    if np.any(np.abs(ev.plant.poles()) < 1e-12):
        return None
    with np.errstate(all="ignore"):
        return _finite_at_zero(ev.gamma(np.zeros(1)))


def _dc_T(ev: _Evaluator, i: int) -> float | None:
    """|T_i(0)| of c_i/(1+c_i) as a limit (evaluated just off s = 0 to pass integrators)."""
    s = np.array([1e-9 * max(1.0, float(np.max(np.abs(ev.plant.poles()), initial=1.0)))]) * 1j
    v = ev.all(s)["T"][0, i]
    return float(abs(v)) if np.isfinite(v) else None


def _dc_gh(ev: _Evaluator, i: int) -> complex | None:
    s = np.array([1e-9 * max(1.0, float(np.max(np.abs(ev.plant.poles()), initial=1.0)))]) * 1j
    v = ev.all(s)["gamma_h"][0, i]
    return complex(v.real, 0.0) if np.isfinite(v) else None


# ---------------------------------------------------------------------------------------------
# sweeps


@dataclass(frozen=True)
class SweepSummary:
    """Worst case of each ICAD figure over a set of analyses (speeds or perturbed plants)."""

    speeds: np.ndarray
    all_conditions: bool  # i-iv hold for every member
    closed_loop_stable: bool
    structural_gm_db: float  # min over members of the gamma structural margin
    structural_gm_h_db: float  # min over members and channels of the gamma h_j margin
    pm_deg: float  # min channel phase margin
    gm_db: float  # min channel upward gain margin
    kg_pm_deg: float
    kg_gm_db: float
    bandwidth_rad_s: float  # min channel bandwidth
    crossover_rad_s: float  # min channel crossover
    coupling_peak_db: float  # max coupling


def worst(values, fn=min) -> float:
    """min (or ``fn``) of figures; nan if any is nan (an undefined figure is never skipped)."""
    arr = np.asarray(list(values), dtype=float)
    return math.nan if np.isnan(arr).any() else float(fn(arr))


def summarize(analyses: Sequence[ICADAnalysis]) -> SweepSummary:
    """Worst-case figures over a sequence of analyses."""
    if not analyses:
        raise InputError("analyses", "must not be empty")
    chans = [ch for a in analyses for ch in a.channels]
    return SweepSummary(
        speeds=np.array([np.nan if a.plant.speed is None else a.plant.speed for a in analyses]),
        all_conditions=all(
            a.conditions.i and a.conditions.ii and a.conditions.iii and a.conditions.iv
            for a in analyses
        ),
        closed_loop_stable=all(a.closed_loop_stable for a in analyses),
        structural_gm_db=worst(a.structural.gm_db for a in analyses),
        structural_gm_h_db=worst(ch.structural.gm_db for ch in chans),
        pm_deg=worst(ch.margins.pm_deg for ch in chans),
        gm_db=worst(ch.margins.gm_db for ch in chans),
        kg_pm_deg=worst(ch.kg_margins.pm_deg for ch in chans),
        kg_gm_db=worst(ch.kg_margins.gm_db for ch in chans),
        bandwidth_rad_s=worst(ch.bandwidth_rad_s for ch in chans),
        crossover_rad_s=worst(ch.margins.crossover_rad_s for ch in chans),
        coupling_peak_db=worst((ch.coupling_peak_db for ch in chans), max),
    )


def sweep(plants: Sequence, k1: LTI, k2: LTI, w=None, *, verify: bool = False):
    """``analyse`` over plants (e.g. ``plants_for(machine, speeds)``); returns (list, summary)."""
    analyses = [analyse(p, k1, k2, w, verify=verify) for p in plants]
    return analyses, summarize(analyses)


# ---------------------------------------------------------------------------------------------
# closed forms of the papers


def im_msf_closed_form(p: IMParams, w_r: float, w) -> np.ndarray:
    """gamma(j w) of the IM, Ugalde-Loo et al. (60)-(61) (real numerator over d_gamma^2)."""
    w_r = require_finite("w_r", w_r)
    w = np.asarray(w, dtype=float)
    re, im = im_dgamma_re_im(p, w_r, w)
    Lr, Lm, Rr = p.L_r, p.L_m, p.R_r
    return Lr**2 * Lm**4 * Rr**2 * w_r**2 * w**2 / (re + 1j * im) ** 2


def im_dgamma_re_im(p: IMParams, w_r: float, w):
    """(Re, Im) of d_gamma(j w), Ugalde-Loo et al. (61), the denominator of the IM's
    multivariable structure function (60); ``w`` a number or an array."""
    sig, Ls, Lr, Lm, Rs, Rr = p.sigma, p.L_s, p.L_r, p.L_m, p.R_s, p.R_r
    re = (
        -(Lr**3) * Rs * w_r**2
        + 2 * w**2 * sig * Ls * Lr**2 * Rr
        + w**2 * Lr**3 * Rs
        - Lr * Rs * Rr**2
        + w**2 * Lr * Lm**2 * Rr
    )
    im = (
        -w * sig * Ls * Lr**3 * w_r**2
        + w**3 * sig * Ls * Lr**3
        - w * sig * Ls * Lr * Rr**2
        - 2 * w * Lr**2 * Rs * Rr
        - w * Lm**2 * Rr**2
    )
    return re, im


def im_msf_at_rotor_speed(p: IMParams, w_r: float) -> complex:
    """gamma(j w_r) of the IM, Amezquita-Brooks et al. (14)."""
    w_r = require_finite("w_r", w_r)
    sig, Ls, Lr, Lm, Rs, Rr = p.sigma, p.L_s, p.L_r, p.L_m, p.R_s, p.R_r
    re = 2 * w_r**2 * sig * Ls * Lr**2 + w_r**2 * Lr * Lm**2 - Lr * Rs * Rr
    im = -w_r * sig * Ls * Lr * Rr - 2 * w_r * Lr**2 * Rs - w_r * Lm**2 * Rr
    return Lr**2 * Lm**4 * w_r**4 / complex(re, im) ** 2


def im_msf_magnitude_at_rotor_speed(p: IMParams, w_r: float) -> float:
    """|gamma(j w_r)| of the IM, Amezquita-Brooks et al. (18)."""
    w_r = require_finite("w_r", w_r)
    sig, Ls, Lr, Lm, Rs, Rr = p.sigma, p.L_s, p.L_r, p.L_m, p.R_s, p.R_r
    re = 2 * w_r**2 * sig * Ls * Lr**2 + w_r**2 * Lr * Lm**2 - Lr * Rs * Rr
    im = -w_r * sig * Ls * Lr * Rr - 2 * w_r * Lr**2 * Rs - w_r * Lm**2 * Rr
    return Lr**2 * Lm**4 * w_r**4 / math.sqrt((re**2 - im**2) ** 2 + 4 * re**2 * im**2)


def im_msf_positive_crossing(p: IMParams, w_r: float) -> tuple[float, float]:
    """(w, gamma(j w)) where the IM's MSF crosses the positive real axis (w_r != 0).

    Ugalde-Loo (61), (72)-(73): gamma(jw) = num / d^2 with d = re + j im is real positive where
    im = 0, w != 0. Solving im = 0 gives w^2 = [Psi (w_r^2 L_r^2 + R_r^2) + Upsilon]/(Psi L_r^2)
    with Psi = sigma L_s L_r, Upsilon = 2 L_r^2 R_s R_r + L_m^2 R_r^2. The printed F(3) of (73)
    divides by Psi^2 instead of Psi L_r and has 2 L_r R_s R_r in Upsilon; both are dimensionally
    inconsistent misprints (the printed F(2), where re = 0, is right).
    """
    w_r = require_finite("w_r", w_r)
    if w_r == 0.0:
        raise InputError("w_r", "gamma is identically zero at standstill (no crossing)")
    sig, Ls, Lr, Lm, Rs, Rr = p.sigma, p.L_s, p.L_r, p.L_m, p.R_s, p.R_r
    psi = sig * Ls * Lr
    upsilon = 2 * Lr**2 * Rs * Rr + Lm**2 * Rr**2
    w = math.sqrt(psi * (psi * (w_r**2 * Lr**2 + Rr**2) + upsilon)) / (psi * Lr)
    return w, float(im_msf_closed_form(p, w_r, np.array([w]))[0].real)


def gm_min(p: IMParams) -> float:
    """Structural gain-margin lower bound G_M,min of the IM, Amezquita-Brooks et al. (19)."""
    sig, Ls, Lr, Lm = p.sigma, p.L_s, p.L_r, p.L_m
    return (
        Lr**2 * Lm**4 / (Lr**2 * Lm**4 + 4 * sig * Lr**3 * Ls * Lm**2 + 4 * sig**2 * Lr**4 * Ls**2)
    )


def pmsg_msf(p: PMSGParams, w_r: float, s) -> np.ndarray:
    """gamma(s) of the PMSG, Ugalde-Loo et al. (18): -L_d L_q w_r^2 / ((L_q s + R_s)(L_d s + R_s))."""
    w_r = require_finite("w_r", w_r)
    s = np.asarray(s, dtype=complex)
    return -p.L_d * p.L_q * w_r**2 / ((p.L_q * s + p.R_s) * (p.L_d * s + p.R_s))


# ---------------------------------------------------------------------------------------------
# built-in controllers

#: Bodson's current-loop bandwidth a_D,CUR = 2 pi 500 Hz (section IV-A), reused as the default
#: bandwidth of the internal-model PI below.
A_CUR_DEFAULT = 3142.0

CONTROLLER_NAMES = ("paper-20", "paper-pi", "imc-pi")


def imc_pi(params, a: float = A_CUR_DEFAULT) -> LTI:
    """Internal-model PI K_P = L' a, K_I = R' a for the first-order model 1/(L' s + R').

    Bodson (49) with R_T = R_R: (L', R') = (sigma L_r, R_r) for the DFIM rotor current; by the
    same rule (sigma L_s, R_s) for the IM stator current and (L_d, R_s) for the PMSG.
    """
    from acdrive.machines._dfim import DFIMParams

    a = require_finite("bandwidth", a)
    if a <= 0:
        raise InputError("bandwidth", "must be > 0 rad/s")
    if isinstance(params, IMParams):
        L, R = params.sigma * params.L_s, params.R_s
    elif isinstance(params, PMSGParams):
        L, R = params.L_d, params.R_s
    elif isinstance(params, DFIMParams):
        L, R = params.sigma * params.L_r, params.R_r
    else:
        raise InputError("params", f"unsupported machine parameters {type(params).__name__}")
    return LTI.pi(L * a, R * a, name="imc-pi")


def controller_for(name: str, params=None, a: float = A_CUR_DEFAULT) -> LTI:
    """Built-in controller by name: ``paper-20`` (Amezquita-Brooks et al. (20)), ``paper-pi``
    (their PI, K_P = 360, K_I = 9000) or ``imc-pi`` (``imc_pi`` for the machine ``params``).
    The paper's controllers are the shared built-in objects of ``acdrive.control._lti``."""
    if name == "paper-20":
        return PAPER_20
    if name == "paper-pi":
        return PAPER_PI
    if name == "imc-pi":
        if params is None:
            raise InputError("controller", "imc-pi needs machine parameters")
        return imc_pi(params, a)
    raise InputError("controller", f"unknown '{name}', known: {', '.join(CONTROLLER_NAMES)}")


def default_controller_name(params) -> str:
    """paper-20 for induction motors (it was designed for one), imc-pi otherwise."""
    return "paper-20" if isinstance(params, IMParams) else "imc-pi"
