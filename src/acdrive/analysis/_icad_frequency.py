"""ICAD quantities on frequency grids, batched over (speed or parameter set) x frequency from
state-space data (``acdrive.analysis._freqresp``), and their point evaluation at complex s.

Ugalde-Loo et al. (1)-(6) and Amezquita-Brooks et al. (5)-(10): for y = G u and u_i = k_i e_i,

- multivariable structure function (MSF)  gamma = g12 g21 / (g11 g22)           (4) / (8)
- diagonal closed loops                  h_i = k_i g_ii / (1 + k_i g_ii)          (5) / (9)
- individual channels                    c_i = k_i g_ii (1 - gamma h_j), i != j   (3) / (7)
- cross coupling                          y_i / r_j = S_i (g_ij / g_jj) h_j, S_i = 1/(1 + c_i)
                                                                                    (6) / (10)

Channels and coupling use algebraically identical forms that never divide by g_ii:
c_i = k_i (g_ii + k_j det G) / (1 + k_j g_jj) and y_i/r_j = S_i g_ij k_j / (1 + k_j g_jj).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from acdrive._arguments import Array, Either, Items, checked
from acdrive._jit import njit, prange, serial_twin
from acdrive.analysis._freqresp import LTI, check_frequency_grid, evaluate_ss
from acdrive.analysis._plants import PLANT, Plant2x2, as_plant
from acdrive.control._lti import CONTROLLER, as_lti
from acdrive.errors import InputError, call_interruptible

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
    cores; every output is written once, and each reciprocal is computed once per point. A call
    with one row or fewer than ``PARALLEL_MIN_POINTS`` points runs the serial twin
    (``_icad_kernel_serial``), whose every point is the same arithmetic."""
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


#: the same kernel without threads (its own cache entry, ``_jit.serial_twin``)
_icad_kernel_serial = serial_twin(_icad_kernel, "_icad_kernel_serial")

#: the fewest points a call must have to run its rows in parallel. A point costs about 30 ns on
#: one core; starting a parallel region cost 60 CPU-us and more, milliseconds when other
#: processes shared the cores (the OpenMP workers wake, and spin after it ends), so a call of
#: fewer points (0.3 ms of work) runs on the calling thread.
PARALLEL_MIN_POINTS = 10_000


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
        # one row (a point evaluation) or a small grid: no parallel region
        kernel = _icad_kernel if rows > 1 and N >= PARALLEL_MIN_POINTS else _icad_kernel_serial
        call_interruptible(kernel, G_rows, periodic(k1), periodic(k2), gamma, h, c, coupling)
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


@checked(
    w=Array(1, finite=False, empty=True), speeds=Array(1, finite=False, empty=True),
    G=Array(4, complex=True, finite=False, empty=True),
    k=Array(2, complex=True, finite=False, empty=True),
    gamma=Array(2, complex=True, finite=False, empty=True),
    h=Array(3, complex=True, finite=False, empty=True),
    c=Array(3, complex=True, finite=False, empty=True),
    coupling=Array(3, complex=True, finite=False, empty=True),
)
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


@checked(plants=Either(PLANT, Items(PLANT)), k1=CONTROLLER, k2=CONTROLLER, w=Array(1, low=0.0))
def icad_response(plants, k1: LTI, k2: LTI, w) -> ICADResponse:
    """Batched ICAD frequency data for one plant or a sequence of plants on grid w [rad/s]."""
    A, B, C, D, speeds = stack_plants(plants)
    return icad_response_arrays(A, B, C, D, k1, k2, w, speeds)


class PointEvaluator:
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


# ---------------------------------------------------------------------------------------------
# crossings of the positive real axis by the MSF

#: Frequencies [rad/s] on which ``msf_positive_real_crossing`` looks for crossings.
MSF_CROSSING_GRID = np.logspace(-1, 5, 3000)


def _msf_at(plant: Plant2x2, w: np.ndarray) -> np.ndarray:
    G = evaluate_ss(plant.A, plant.B, plant.C, plant.D, 1j * np.asarray(w, dtype=float))
    return G[:, 0, 1] * G[:, 1, 0] / (G[:, 0, 0] * G[:, 1, 1])


@checked(plant=PLANT, w=Array(1, low=0.0))
def msf_positive_real_crossing(plant, w=MSF_CROSSING_GRID) -> tuple[float, float]:
    """(x_max, frequency [rad/s]) of the largest crossing x > 0 of the positive real axis by the
    MSF gamma (4) of ``plant`` for s = jw, w > 0: the conditions of Ugalde-Loo et al. ask that
    gamma does not reach (1, 0), so x_max < 1 there. Crossings are found as sign changes of
    Im gamma on the grid ``w`` and refined by bisection (brentq); (0, nan) if there is none."""
    plant = as_plant(plant)
    w = check_frequency_grid(w)
    gam = _msf_at(plant, w)
    idx = np.flatnonzero((np.sign(gam.imag[:-1]) != np.sign(gam.imag[1:])) & (gam.real[:-1] > 0))
    best = (0.0, float("nan"))
    for i in idx:
        wx = brentq(lambda x: float(_msf_at(plant, [x])[0].imag), w[i], w[i + 1], xtol=1e-10)
        x = float(_msf_at(plant, [wx])[0].real)
        if x > best[0]:
            best = (x, wx)
    return best
