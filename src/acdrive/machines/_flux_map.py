"""A synchronous machine's flux map: the flux linkages psi_d(i_d, i_q), psi_q(i_d, i_q) on a
current grid, its checks, its inversion onto a flux grid, and its file formats.

A finite-element tool gives the map on a rectangular current grid; the flux-state machine
(``machines._flux_map_part``) needs the inverse i_d(psi_d, psi_q), i_q(psi_d, psi_q) on a
rectangular flux grid. ``FluxMap.inverted`` computes it once, at construction:

* the flux grid spans the largest box inside the image of the current grid: psi_d from the
  largest psi_d on the edge i_d = min to the smallest on the edge i_d = max, psi_q likewise
  from the edges i_q = min and i_q = max (``flux_box``), each axis ``points`` evenly spaced;
* at each flux-grid point the currents solve psi(i) = psi_point, psi(i) the *bilinear*
  interpolant of the current-grid map (``core._tables.table2d_at``, here vectorised as
  ``bilinear``), by Newton's method, started from a scattered linear interpolation of the
  inverse (Delaunay triangles of the map's points, ``scipy.interpolate.griddata``), the
  Jacobian of each step the bilinear cell's own derivatives. The result inverts the bilinear map
  to rounding; a linear map is inverted exactly (to rounding) at every grid point.

Checks, before the inversion:

* **invertibility**: the map must increase along its own axes and keep its orientation:
  at every corner of every cell, d psi_d/d i_d > 0, d psi_q/d i_q > 0 and
  det(d psi / d i) > 0 (the cell's bilinear derivatives). A point where this fails is one
  InputError naming the point (the map is not monotone there);
* **reciprocity**: a map from a magnetic energy has d psi_d/d i_q = d psi_q/d i_d (a symmetric
  incremental inductance matrix). The mismatch at each grid node, from central differences
  (one-sided at the edges), relative to the larger of |d psi_d/d i_d| and |d psi_q/d i_q| there,
  above ``RECIPROCITY_TOLERANCE`` is a ``Notice`` naming the worst node (a warning: measured
  maps carry noise, the run still follows the map).

**Scaling.** A map is held in acdrive's power-invariant scaling (``acdrive._frames``). Maps
from finite-element tools are peak-valued (amplitude-invariant): ``FluxMap(..., scaling="peak")``
multiplies currents and fluxes by K = sqrt(3/2) (``frames.K_PEAK``) when it is built.

**CSV file** (``read_flux_map_csv``, ``write_flux_map_csv``): a first line ``# scaling: peak`` or
``# scaling: power-invariant``, a header ``i_d [A],i_q [A],psi_d [Wb],psi_q [Wb]`` (these four
columns, in any order) and one row per grid point: every pair of the distinct i_d and i_q
values exactly once, in any order.

**SyR-e's .mat file** (``read_syre_mat``): the flux map a SyR-e (Politecnico di Torino) flux-map
simulation saves, ``fdfq_idiq_n*.mat``, with the matrices ``Id``, ``Iq``, ``Fd``, ``Fq`` (the
grid as ``meshgrid(id, iq)``: rows along i_q, columns along i_d), peak-valued.
"""

from __future__ import annotations

import csv
import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from acdrive._frames import K_PEAK
from acdrive.core._signals import Table2D, pack_table2d
from acdrive.errors import InputError, Notice

#: the relative reciprocity mismatch above which a map is reported (``Notice``): 5 % of the
#: larger self incremental inductance at the node
RECIPROCITY_TOLERANCE = 0.05
#: the scalings a map may be given in
SCALINGS = ("peak", "power-invariant")
#: the CSV columns: name -> unit
CSV_COLUMNS = {"i_d": "A", "i_q": "A", "psi_d": "Wb", "psi_q": "Wb"}
#: Newton's iterations at most, and the residual (relative to the flux grid's span) it stops at
NEWTON_ITERATIONS, NEWTON_TOLERANCE = 60, 1e-13


def bilinear(x, y, values, xq, yq):
    """``core._tables.table2d_at`` for arrays of points: bilinear on the grid (x, y, values),
    each coordinate clamped to its axis first. Also returns the derivatives d/dx, d/dy of the
    cell's bilinear function at the (clamped) points (zero across a clamped coordinate)."""
    x, y, values = np.asarray(x), np.asarray(y), np.asarray(values)
    xq, yq = np.asarray(xq, dtype=float), np.asarray(yq, dtype=float)
    xc, yc = np.clip(xq, x[0], x[-1]), np.clip(yq, y[0], y[-1])
    i = np.clip(np.searchsorted(x, xc, side="right") - 1, 0, x.size - 2)
    j = np.clip(np.searchsorted(y, yc, side="right") - 1, 0, y.size - 2)
    hx, hy = x[i + 1] - x[i], y[j + 1] - y[j]
    f_x, f_y = (xc - x[i]) / hx, (yc - y[j]) / hy
    v_00, v_01 = values[i, j], values[i, j + 1]
    v_10, v_11 = values[i + 1, j], values[i + 1, j + 1]
    a = v_00 + (v_10 - v_00) * f_x
    b = v_01 + (v_11 - v_01) * f_x
    d_x = ((v_10 - v_00) + ((v_11 - v_01) - (v_10 - v_00)) * f_y) / hx
    d_y = (b - a) / hy
    d_x = np.where(xq == xc, d_x, 0.0)
    d_y = np.where(yq == yc, d_y, 0.0)
    return a + (b - a) * f_y, d_x, d_y


@dataclass(frozen=True)
class FluxMap:
    """psi_d[k, l], psi_q[k, l] [Wb] at the currents (i_d[k], i_q[l]) [A]: i_d and i_q strictly
    increasing, at least two values each; ``scaling`` "peak" (converted to power-invariant when
    built) or "power-invariant" (module docstring). Checked when built (invertibility an
    InputError, reciprocity a Notice)."""

    i_d: np.ndarray
    i_q: np.ndarray
    psi_d: np.ndarray
    psi_q: np.ndarray
    scaling: str = "power-invariant"

    def __post_init__(self):
        if self.scaling not in SCALINGS:
            raise InputError(
                "flux_map.scaling", f"must be one of {', '.join(SCALINGS)}, got {self.scaling!r}"
            )
        d = Table2D(self.i_d, self.i_q, self.psi_d)
        q = Table2D(self.i_d, self.i_q, self.psi_q)
        packed_d = pack_table2d("flux_map.psi_d", d)
        pack_table2d("flux_map.psi_q", q)
        n_d, n_q = int(packed_d[0]), int(packed_d[1])
        k = 1.0 if self.scaling == "power-invariant" else K_PEAK
        for name, value, shape in (("i_d", self.i_d, (n_d,)), ("i_q", self.i_q, (n_q,)),
                                   ("psi_d", self.psi_d, (n_d, n_q)),
                                   ("psi_q", self.psi_q, (n_d, n_q))):  # fmt: skip
            array = k * np.asarray(value, dtype=float).reshape(shape)
            array.setflags(write=False)
            object.__setattr__(self, name, array)
        object.__setattr__(self, "scaling", "power-invariant")
        self._check_invertible()
        self._check_reciprocal()

    def _check_invertible(self) -> None:
        """InputError naming the first grid point (cell corner) where the map does not increase
        along its axes or turns over (module docstring)."""
        i_d, i_q = self.i_d, self.i_q
        for psi, axis, name in ((self.psi_d, 0, "psi_d"), (self.psi_q, 1, "psi_q")):
            step = np.diff(psi, axis=axis)
            if np.any(step <= 0.0):
                k, l = np.argwhere(step <= 0.0)[0]
                rise = (k + 1, l) if axis == 0 else (k, l + 1)
                along = "i_d" if axis == 0 else "i_q"
                raise InputError(
                    f"flux_map.{name}",
                    f"must increase with {along} (an invertible map): it goes from {psi[k, l]:.6g} "
                    f"to {psi[rise]:.6g} Wb between (i_d, i_q) = ({i_d[k]:.6g}, {i_q[l]:.6g}) A "
                    f"and ({i_d[rise[0]]:.6g}, {i_q[rise[1]]:.6g}) A",
                )
        h_d, h_q = np.diff(i_d)[:, None], np.diff(i_q)[None, :]
        for corner_d in (0, 1):  # the Jacobian of each cell's bilinear function at its corners
            for corner_q in (0, 1):
                a = slice(corner_q, None if corner_q else -1)
                b = slice(corner_d, None if corner_d else -1)
                dd_d = np.diff(self.psi_d, axis=0)[:, a] / h_d
                dq_q = np.diff(self.psi_q, axis=1)[b, :] / h_q
                dd_q = np.diff(self.psi_d, axis=1)[b, :] / h_q
                dq_d = np.diff(self.psi_q, axis=0)[:, a] / h_d
                det = dd_d * dq_q - dd_q * dq_d
                if np.any(det <= 0.0):
                    cell_d, cell_q = np.argwhere(det <= 0.0)[0]
                    k, l = cell_d + corner_d, cell_q + corner_q
                    raise InputError(
                        "flux_map",
                        f"is not invertible at (i_d, i_q) = ({i_d[k]:.6g}, {i_q[l]:.6g}) A: the "
                        "incremental inductance matrix there has determinant "
                        f"{det[cell_d, cell_q]:.3g} H^2 <= 0",
                    )

    def reciprocity(self) -> tuple[float, float, float]:
        """(worst relative mismatch, i_d, i_q at it): |d psi_d/d i_q - d psi_q/d i_d| over the
        larger of |d psi_d/d i_d| and |d psi_q/d i_q|, at every grid node (module docstring)."""
        d_dd, d_dq = np.gradient(self.psi_d, self.i_d, self.i_q)
        d_qd, d_qq = np.gradient(self.psi_q, self.i_d, self.i_q)
        mismatch = np.abs(d_dq - d_qd) / np.maximum(np.abs(d_dd), np.abs(d_qq))
        k, l = np.unravel_index(int(np.argmax(mismatch)), mismatch.shape)
        return float(mismatch[k, l]), float(self.i_d[k]), float(self.i_q[l])

    def _check_reciprocal(self) -> None:
        worst, i_d, i_q = self.reciprocity()
        if worst > RECIPROCITY_TOLERANCE:
            warnings.warn(
                Notice(
                    f"flux map: d psi_d/d i_q and d psi_q/d i_d differ by {100 * worst:.3g} % of "
                    f"the self incremental inductance at (i_d, i_q) = ({i_d:.6g}, {i_q:.6g}) A, "
                    f"the worst node (more than {100 * RECIPROCITY_TOLERANCE:g} %: the map is "
                    "not from a magnetic energy; the run follows it as given)"
                ),
                stacklevel=3,
            )

    def flux_box(self) -> tuple[float, float, float, float]:
        """(psi_d min, psi_d max, psi_q min, psi_q max) of the flux grid: the largest box inside
        the image of the current grid (module docstring)."""
        return (float(np.max(self.psi_d[0, :])), float(np.min(self.psi_d[-1, :])),
                float(np.max(self.psi_q[:, 0])), float(np.min(self.psi_q[:, -1])))  # fmt: skip

    def fluxes(self, i_d, i_q):
        """psi_d, psi_q [Wb] at currents (arrays) by bilinear interpolation of the map."""
        return (bilinear(self.i_d, self.i_q, self.psi_d, i_d, i_q)[0],
                bilinear(self.i_d, self.i_q, self.psi_q, i_d, i_q)[0])  # fmt: skip

    def currents(self, psi_d, psi_q):
        """i_d, i_q [A] (arrays) with ``fluxes(i_d, i_q) = (psi_d, psi_q)``: Newton's method on
        the bilinear map from a scattered linear interpolation of the inverse (module
        docstring). An InputError naming the flux point where it does not converge."""
        from scipy.interpolate import griddata

        psi_d, psi_q = np.broadcast_arrays(np.asarray(psi_d, float), np.asarray(psi_q, float))
        shape = psi_d.shape
        psi_d, psi_q = psi_d.ravel(), psi_q.ravel()
        points = np.column_stack([self.psi_d.ravel(), self.psi_q.ravel()])
        grid_d, grid_q = np.meshgrid(self.i_d, self.i_q, indexing="ij")
        wanted = np.column_stack([psi_d, psi_q])
        i_d = griddata(points, grid_d.ravel(), wanted, method="linear")
        i_q = griddata(points, grid_q.ravel(), wanted, method="linear")
        outside = np.isnan(i_d) | np.isnan(i_q)
        if np.any(outside):
            i_d[outside] = griddata(points, grid_d.ravel(), wanted[outside], method="nearest")
            i_q[outside] = griddata(points, grid_q.ravel(), wanted[outside], method="nearest")
        scale = max(np.ptp(self.psi_d), np.ptp(self.psi_q))
        for _ in range(NEWTON_ITERATIONS):
            f_d, dd_d, dd_q = bilinear(self.i_d, self.i_q, self.psi_d, i_d, i_q)
            f_q, dq_d, dq_q = bilinear(self.i_d, self.i_q, self.psi_q, i_d, i_q)
            r_d, r_q = f_d - psi_d, f_q - psi_q
            if np.max(np.abs(r_d) + np.abs(r_q)) <= NEWTON_TOLERANCE * scale:
                break
            det = dd_d * dq_q - dd_q * dq_d
            det = np.where(det > 0.0, det, np.inf)  # a clamped coordinate: no step
            i_d = np.clip(i_d - (dq_q * r_d - dd_q * r_q) / det, self.i_d[0], self.i_d[-1])
            i_q = np.clip(i_q - (dd_d * r_q - dq_d * r_d) / det, self.i_q[0], self.i_q[-1])
        else:
            k = int(np.argmax(np.abs(r_d) + np.abs(r_q)))
            raise InputError(
                "flux_map",
                f"no current gives (psi_d, psi_q) = ({psi_d[k]:.6g}, {psi_q[k]:.6g}) Wb on the "
                "map (the point is outside the map's image, or the map folds near it)",
            )
        return i_d.reshape(shape), i_q.reshape(shape)

    def inverted(self, points: tuple[int, int] | None = None) -> tuple[Table2D, Table2D]:
        """i_d(psi_d, psi_q) and i_q(psi_d, psi_q) as 2-D tables on the flux grid of
        ``points`` = (n_psi_d, n_psi_q) evenly spaced fluxes over ``flux_box`` (the current
        grid's counts if None)."""
        n_d, n_q = points if points is not None else (self.i_d.size, self.i_q.size)
        for name, n in (("flux_points[0]", n_d), ("flux_points[1]", n_q)):
            if not (isinstance(n, (int, np.integer)) and n >= 2):
                raise InputError(name, f"must be an integer >= 2, got {n!r}")
        d_lo, d_hi, q_lo, q_hi = self.flux_box()
        if not (d_lo < d_hi and q_lo < q_hi):
            raise InputError(
                "flux_map",
                "the image of its current grid holds no box of fluxes "
                f"(psi_d {d_lo:.6g}..{d_hi:.6g} Wb, psi_q {q_lo:.6g}..{q_hi:.6g} Wb)",
            )
        psi_d, psi_q = np.linspace(d_lo, d_hi, n_d), np.linspace(q_lo, q_hi, n_q)
        i_d, i_q = self.currents(*np.meshgrid(psi_d, psi_q, indexing="ij"))
        return Table2D(psi_d, psi_q, i_d), Table2D(psi_d, psi_q, i_q)

    @classmethod
    def of_currents(cls, currents, i_d, i_q) -> FluxMap:
        """The map of a magnetic model given as ``currents(psi_d, psi_q) -> (i_d, i_q)`` (scalar
        power-invariant fluxes in, e.g. ``machines._synchronous_part.magnetic_currents`` bound to
        a part's parameters) on the current grid ``i_d`` x ``i_q``: each point's fluxes by
        Newton's method with a central-difference Jacobian, from the previous point's fluxes."""
        i_d, i_q = np.asarray(i_d, float), np.asarray(i_q, float)
        psi_d, psi_q = np.zeros((i_d.size, i_q.size)), np.zeros((i_d.size, i_q.size))
        guess = np.zeros(2)
        for k, target_d in enumerate(i_d):
            for l, target_q in enumerate(i_q):
                z = guess.copy()
                for _ in range(NEWTON_ITERATIONS):
                    r = np.array(currents(z[0], z[1])) - (target_d, target_q)
                    if abs(r[0]) + abs(r[1]) <= 1e-12 * (1.0 + abs(target_d) + abs(target_q)):
                        break
                    h = 1e-7 * (1.0 + np.abs(z))
                    J = np.empty((2, 2))
                    for m in range(2):
                        e = np.zeros(2)
                        e[m] = h[m]
                        J[:, m] = (np.array(currents(*(z + e))) - currents(*(z - e))) / (2 * h[m])
                    z = z - np.linalg.solve(J, r)
                psi_d[k, l], psi_q[k, l] = z
                guess = z if l < i_q.size - 1 else np.array([psi_d[k, 0], psi_q[k, 0]])
        return cls(i_d, i_q, psi_d, psi_q)


def write_flux_map_csv(flux_map: FluxMap, path, scaling: str = "power-invariant") -> Path:
    """``flux_map`` as a CSV file (module docstring) in ``scaling``; every number as Python's
    shortest repr, so reading it back gives the same floats."""
    if scaling not in SCALINGS:
        raise InputError("scaling", f"must be one of {', '.join(SCALINGS)}, got {scaling!r}")
    k = 1.0 if scaling == "power-invariant" else 1.0 / K_PEAK
    path = Path(path)
    with path.open("w", newline="") as f:
        f.write(f"# scaling: {scaling}\n")
        writer = csv.writer(f)
        writer.writerow([f"{n} [{u}]" for n, u in CSV_COLUMNS.items()])
        for a, i_d in enumerate(flux_map.i_d):
            for b, i_q in enumerate(flux_map.i_q):
                row = (i_d, i_q, flux_map.psi_d[a, b], flux_map.psi_q[a, b])
                writer.writerow([repr(float(k * x)) for x in row])
    return path


def read_flux_map_csv(path) -> FluxMap:
    """The flux map in the CSV file ``path`` (module docstring); a malformed file is one
    InputError naming the file, its line and the rule."""
    path = Path(path)
    where = str(path)
    try:
        lines = path.read_text().splitlines()
    except OSError as exc:
        raise InputError(where, f"cannot be read ({exc.strerror})") from None
    if not lines or not lines[0].startswith("#"):
        raise InputError(f"{where}:1", f"must be '# scaling: {' or '.join(SCALINGS)}'")
    key, _, scaling = lines[0].lstrip("#").partition(":")
    scaling = scaling.strip()
    if key.strip() != "scaling" or scaling not in SCALINGS:
        raise InputError(
            f"{where}:1", f"must be '# scaling: {' or '.join(SCALINGS)}', got {lines[0]!r}"
        )
    rows = list(csv.reader(lines[1:]))
    wanted = [f"{n} [{u}]" for n, u in CSV_COLUMNS.items()]
    if not rows:
        raise InputError(f"{where}:2", f"must be the header {','.join(wanted)}")
    header = [c.strip() for c in rows[0]]
    if sorted(header) != sorted(wanted):
        raise InputError(
            f"{where}:2",
            f"the header must name the columns {', '.join(wanted)}, got {', '.join(header)}",
        )
    order = [header.index(w) for w in wanted]
    data = []
    for number, row in enumerate(rows[1:], start=3):
        if not row:
            continue
        try:
            values = [float(row[c]) for c in order]
        except (ValueError, IndexError):
            raise InputError(f"{where}:{number}", f"must be {len(wanted)} numbers") from None
        if not all(math.isfinite(v) for v in values):
            raise InputError(f"{where}:{number}", "must be finite numbers")
        data.append(values)
    data = np.array(data).reshape(-1, 4)
    i_d, i_q = np.unique(data[:, 0]), np.unique(data[:, 1])
    psi_d = np.full((i_d.size, i_q.size), np.nan)
    psi_q = np.full_like(psi_d, np.nan)
    a, b = np.searchsorted(i_d, data[:, 0]), np.searchsorted(i_q, data[:, 1])
    seen = np.zeros(psi_d.shape, dtype=int)
    np.add.at(seen, (a, b), 1)
    if np.any(seen != 1):
        k, l = np.argwhere(seen != 1)[0]
        count = "twice or more" if seen[k, l] > 1 else "not at all"
        raise InputError(
            where,
            f"must hold every grid point once: (i_d, i_q) = ({i_d[k]:g}, {i_q[l]:g}) A is "
            f"there {count}",
        )
    psi_d[a, b], psi_q[a, b] = data[:, 2], data[:, 3]
    return FluxMap(i_d, i_q, psi_d, psi_q, scaling=scaling)


def read_syre_mat(path) -> FluxMap:
    """The flux map of a SyR-e ``fdfq_idiq`` .mat file (module docstring: ``Id``, ``Iq``,
    ``Fd``, ``Fq`` on ``meshgrid(id, iq)``, peak-valued)."""
    from scipy.io import loadmat

    where = str(path)
    try:
        content = loadmat(path)
    except (OSError, ValueError) as exc:
        raise InputError(where, f"cannot be read as a .mat file ({exc})") from None
    missing = [n for n in ("Id", "Iq", "Fd", "Fq") if n not in content]
    if missing:
        raise InputError(
            where, f"must hold SyR-e's matrices Id, Iq, Fd, Fq ({', '.join(missing)} missing)"
        )
    Id, Iq, Fd, Fq = (np.asarray(content[n], dtype=float) for n in ("Id", "Iq", "Fd", "Fq"))
    if not (Id.shape == Iq.shape == Fd.shape == Fq.shape and Id.ndim == 2):
        raise InputError(where, "Id, Iq, Fd, Fq must be matrices of one shape")
    if not (np.all(Id == Id[:1, :]) and np.all(Iq == Iq[:, :1])):
        raise InputError(where, "Id must vary along columns and Iq along rows (meshgrid(id, iq))")
    return FluxMap(Id[0, :], Iq[:, 0], Fd.T, Fq.T, scaling="peak")
