"""Generic linearisation: central-difference Jacobians, Newton's method, and the one-sample map of
a compiled system (``acdrive.sim._compiled``) with its fixed point and Jacobian.

The one-sample map is the compiled loop's own sample, run from Python piece by piece in the
loop's order (``project``, ``plant_outputs``, every ``sample_<i>``, ``modulate``, ``integrate``; the
slow path ``acdrive.sim._reference`` does the same). A study chooses the map's state: a list of
:class:`Coordinate`, each a quantity of one part in the plant state X, the discrete states S or
the held outputs Y, found through the system's slots and the part's layouts (never a
hand-written index), with a frame tag the study uses to re-reference it from one sample to the
next (:meth:`SampleMap.rereference`), so that the map of a time-invariant system is autonomous.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acdrive.core._parts import ContinuousPart, Part

FD_STEP = 1e-6  # relative step of the central differences (truncation ~1e-12, rounding ~1e-10)


def jacobian(f, x: np.ndarray, scales: np.ndarray) -> np.ndarray:
    """Central-difference Jacobian of the vector function ``f`` at ``x``; the step of entry i is
    ``FD_STEP * max(|x_i|, scales_i)``."""
    cols = []
    for i in range(x.size):
        h = FD_STEP * max(abs(x[i]), scales[i])
        xp, xm = x.copy(), x.copy()
        xp[i] += h
        xm[i] -= h
        cols.append((f(xp) - f(xm)) / (2.0 * h))
    return np.column_stack(cols)


def newton(f, x0: np.ndarray, scales: np.ndarray, tol: float = 1e-10, max_iter: int = 30):
    """Solve f(x) = 0 by Newton's method with the central-difference Jacobian; RuntimeError if it
    does not converge within ``max_iter`` iterations."""
    x = x0.copy()
    for _ in range(max_iter):
        r = f(x)
        if np.all(np.abs(r) <= 1e-14 * scales):
            return x
        dx = np.linalg.solve(jacobian(f, x, scales), -r)
        x = x + dx
        if np.all(np.abs(dx) <= tol * np.maximum(np.abs(x), scales)):
            return x
    raise RuntimeError("equilibrium not found (Newton did not converge)")


# ---------------------------------------------------------------------------------------------
# quantities of a compiled system
# ---------------------------------------------------------------------------------------------


def slot(system, part: Part, array: str, name: str) -> int:
    """Index in the system's flat array ``array`` of the quantity ``name`` of ``part``.

    array: "x" (a continuous part's state), "s" (a sampled part's or modulator's discrete state)
    or "y" (an output). A complex quantity occupies the index returned and the next one.
    """
    if array == "y":
        layout = part.OUTPUTS
    elif array == ("x" if isinstance(part, ContinuousPart) else "s"):
        layout = part.STATES
    else:
        raise ValueError(f"the states of {part.name} are not in array {array!r}")
    return getattr(system.slots[part.name], array)[0] + layout.slot(name)


def get_complex(a: np.ndarray, i: int) -> complex:
    return complex(a[i], a[i + 1])


def set_complex(a: np.ndarray, i: int, value: complex) -> None:
    a[i], a[i + 1] = value.real, value.imag


@dataclass(frozen=True)
class Coordinate:
    """One quantity of a compiled system in the state of a one-sample map: ``name`` is
    ``<part>.<quantity>``, at ``index`` of the array ``array`` ("x", "s" or "y"), ``width`` 1 (real)
    or 2 (complex: real then imaginary part); ``frame`` tags how the study re-references it."""

    name: str
    array: str
    index: int
    width: int
    frame: str = ""

    @property
    def names(self) -> tuple[str, ...]:
        return (self.name,) if self.width == 1 else (f"{self.name}.re", f"{self.name}.im")


def coordinate(system, part: Part, array: str, name: str, frame: str = "") -> Coordinate:
    """The :class:`Coordinate` of quantity ``name`` of ``part`` in ``array`` (see :func:`slot`)."""
    layout = part.OUTPUTS if array == "y" else part.STATES
    width = layout.var(name).width
    return Coordinate(f"{part.name}.{name}", array, slot(system, part, array, name), width, frame)


# ---------------------------------------------------------------------------------------------
# the one-sample map of a compiled system
# ---------------------------------------------------------------------------------------------


class SampleMap:
    """z_k -> z_{k+1}: one sample of a compiled system as a map of its ``coordinates``.

    ``load(z)`` resets the arrays ``X``, ``S``, ``Y`` (plant state, discrete states, held outputs;
    modified in place, never replaced) to the study's template ``X0``, ``S0``, ``Y0`` and writes z
    into them at the sample instant t;
    ``__call__`` then runs exactly one sample of the compiled loop on them and returns
    ``read()``: every coordinate after the sample, passed through ``rereference``. The map's
    ``between()`` runs after the sampled parts and before the modulators (e.g. a computation
    delay a study adds to the loop; nothing by default). The map is evaluated at the same t every
    time: it is meant for time-invariant systems (constant profiles).
    """

    #: the map state, in order
    coordinates: tuple[Coordinate, ...] = ()

    def __init__(self, compiled, sample_time: float, substeps: int, t: float = 0.0):
        system, m = compiled.system, compiled.module
        self.compiled, self.system, self.module = compiled, system, m
        self.T, self.substeps, self.t = float(sample_time), int(substeps), float(t)
        self.P, self.PO = system.pack_params()
        self.X, self.S = system.pack_initial()
        self.Y = system.pack_held()
        self.X0, self.S0, self.Y0 = self.X.copy(), self.S.copy(), self.Y.copy()
        self.U = np.zeros(system.sizes["u"])
        self.E = np.zeros(m.N_EVENTS, dtype=np.int64)
        self.DT, self.V = np.zeros((m.N_MOD, m.MAX_SEG)), np.zeros((m.N_MOD, m.MAX_SEG, m.MAX_W))
        self.NSEG = np.zeros(m.N_MOD, dtype=np.int64)
        self.W = np.empty((m.N_W, system.sizes["x"]))
        self.IDX, self.LEFT = np.zeros(m.N_MOD, dtype=np.int64), np.zeros(m.N_MOD)
        self._steps = [getattr(m, f"sample_{i}") for i in range(len(system.sampled))]
        self._planned = None

    def slot(self, part: Part, array: str, name: str) -> int:
        return slot(self.system, part, array, name)

    def coordinate(self, part: Part, array: str, name: str, frame: str = "") -> Coordinate:
        return coordinate(self.system, part, array, name, frame)

    @property
    def names(self) -> tuple[str, ...]:
        """Names of the entries of z (``.re``/``.im`` for the two entries of a complex one)."""
        return tuple(n for c in self.coordinates for n in c.names)

    def vector(self, values: dict) -> np.ndarray:
        """z from ``values[coordinate name]`` (a float, or a complex number for a complex one)."""
        out = []
        for c in self.coordinates:
            v = values[c.name]
            out += [v] if c.width == 1 else [v.real, v.imag]
        return np.array(out, dtype=float)

    def value(self, z: np.ndarray, name: str):
        """The coordinate ``name`` in the map state ``z`` (complex for a complex coordinate)."""
        k = 0
        for c in self.coordinates:
            if c.name == name:
                return z[k] if c.width == 1 else complex(z[k], z[k + 1])
            k += c.width
        raise KeyError(name)

    def _plan(self) -> list:
        """(coordinate, its array, slice) per coordinate, computed once."""
        if self._planned is None or self._planned[0] is not self.coordinates:
            arrays = {"x": self.X, "s": self.S, "y": self.Y}
            plan = [
                (c, arrays[c.array], slice(c.index, c.index + c.width)) for c in self.coordinates
            ]
            self._planned = (self.coordinates, plan)
        return self._planned[1]

    # --- the pieces of one sample, in the compiled loop's order ------------------------------
    def sensors(self) -> None:
        """At t: re-normalise redundant plant states, evaluate the plant outputs with the held
        inputs (what the sensors see)."""
        m = self.module
        m.project(self.X, self.P, self.PO)
        m.plant_outputs(self.t, self.X, self.P, self.PO, self.Y, self.U)

    def sampled_parts(self) -> None:
        """Every sampled part in wiring order (sensors, estimators, controllers)."""
        for i, step in enumerate(self._steps):
            self.E[i] = step(self.t, self.T, self.P, self.PO, self.S, self.Y, self.U)

    def modulate(self) -> None:
        self.module.modulate(self.T, self.P, self.PO, self.S, self.Y, self.U, self.E, self.DT,
                             self.V, self.NSEG)  # fmt: skip

    def integrate(self) -> None:
        """The plant over [t, t + T_s], segment by segment, ``substeps`` RK4 steps each."""
        self.module.integrate(self.t, self.T, self.substeps, self.X, self.P, self.PO, self.Y,
                              self.U, self.W, self.DT, self.V, self.NSEG, self.IDX, self.LEFT)  # fmt: skip

    def run_sample(self, between=None) -> None:
        """One sample of the compiled loop on X, S, Y in place; ``between()``, if given, runs
        after the sampled parts and before the modulators."""
        self.sensors()
        self.sampled_parts()
        if between is not None:
            between()
        self.modulate()
        self.integrate()

    # --- the map -----------------------------------------------------------------------------
    def load(self, z: np.ndarray) -> int:
        """Template arrays with the coordinates set from ``z``; returns the entries used."""
        self.X[:], self.S[:], self.Y[:] = self.X0, self.S0, self.Y0
        k = 0
        for c, a, at in self._plan():
            a[at] = z[k : k + c.width]
            k += c.width
        return k

    def between(self) -> None:
        """Hook after the sampled parts, before the modulators (nothing by default)."""

    def rereference(self, c: Coordinate, value):
        """Coordinate ``c``'s ``value`` (float or complex) after the sample, in the frame in which
        the next sample is loaded (the identity by default)."""
        return value

    def read(self) -> np.ndarray:
        """Every coordinate after the sample, re-referenced."""
        out = []
        for c, a, _ in self._plan():
            if c.width == 1:
                out.append(self.rereference(c, a[c.index]))
            else:
                v = self.rereference(c, complex(a[c.index], a[c.index + 1]))
                out += [v.real, v.imag]
        return np.array(out)

    def __call__(self, z: np.ndarray) -> np.ndarray:
        self.load(z)
        self.run_sample(self.between)
        return self.read()

    # --- hand-over to a full run -------------------------------------------------------------
    def initial_and_held(self) -> tuple[dict, dict]:
        """The arrays X, S, Y as last loaded, in the form ``CompiledSystem.run`` takes
        (``initial[part] = {state: value}``, ``held[part] = {output: value}``)."""
        initial, held = {}, {}
        for part in self.system.parts:
            sl = self.system.slots[part.name]
            if isinstance(part, ContinuousPart):
                initial[part.name] = part.STATES.unpack(self.X[sl.x[0] : sl.x[1]])
                continue
            initial[part.name] = part.STATES.unpack(self.S[sl.s[0] : sl.s[1]])
            held[part.name] = part.OUTPUTS.unpack(self.Y[sl.y[0] : sl.y[1]])
        return initial, held


def fixed_point(sample_map: SampleMap, guess: np.ndarray, scales: np.ndarray):
    """(z0, F): the fixed point z0 = map(z0) (Newton from ``guess``) and the central-difference
    Jacobian F of the map there; the eigenvalues of F are the z-plane poles of the sampled loop."""
    z0 = newton(lambda z: sample_map(z) - z, guess, scales)
    return z0, jacobian(sample_map, z0, scales)
