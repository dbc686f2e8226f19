"""The pieces a part kind's C is made of: a support piece (``CSupport``), the C of a sampled kind's
step (``CStep``) and of a plant kind (``PlantC``), a kind's C name, and the support pieces every
generated file may draw on (the piecewise-linear table of ``core._tables`` and ``tanh`` in either
precision). The registry (``sim._ccode._kinds``) and the generator of a kind's C from its kernels
(``sim._ccode._translate``) both build on them."""

from __future__ import annotations

import re
from dataclasses import dataclass


def kind_name(cls: type) -> str:
    """CamelCase class name -> snake_case C name: SpeedEstimator -> speed_estimator,
    PMSpeedPI -> pm_speed_pi."""
    return re.sub(r"(?<=[a-z0-9])(?=[A-Z])|(?<=[A-Z])(?=[A-Z][a-z])", "_", cls.__name__).lower()


@dataclass(frozen=True)
class CSupport:
    """A piece of C (static functions, macros) that step bodies may call; ``needs`` lists the
    pieces it calls in turn. A kind's ``support`` and a piece's ``needs`` say where a file may
    draw its helpers from; the file holds, once whatever the number of kinds that use it, each
    definition of them its code calls, and no other (``sim._ccode._helpers``)."""

    name: str
    code: str
    needs: tuple[CSupport, ...] = ()


@dataclass(frozen=True)
class CStep:
    """The C of one part kind's step: ``body`` (statements, returning the event bits; or a
    function of the part instance giving them, for a kind whose layout is set per instance,
    such as a controller of any order), ``support`` (what it calls) and ``source`` (paper and
    equations it implements)."""

    body: object
    source: str
    support: tuple[CSupport, ...] = ()
    #: True when ``body`` is generated from the kind's kernel (``sim._ccode._translate``)
    from_kernel: bool = False


@dataclass(frozen=True)
class PlantC:
    """The C of one plant kind. A continuous part: ``state_outputs`` (writes ``y`` from ``x``),
    ``direct_outputs`` (for a kind with direct outputs: writes them from ``x`` and the inputs
    ``u`` it declares in ``DIRECT_FROM``), ``rhs`` (writes ``dx``; may read ``u`` and its own
    ``y`` of the same evaluation; None for a part without states), ``project`` (re-normalises
    redundant states ``x`` at each sample, for a kind with a ``project`` kernel). A modulator:
    ``segments`` (writes ``*n`` segments ``dt[i]``, ``v[i]``, returns the event bits). Each
    body is a text, or a function of the part instance giving it (a kind whose inputs are set
    per instance, such as a bus of n machines). ``source``: paper and equations; ``support``:
    what they call."""

    source: str
    state_outputs: object = None
    rhs: object = None
    segments: object = None
    project: object = None
    direct_outputs: object = None
    support: tuple[CSupport, ...] = ()
    #: True when the bodies are generated from the kind's kernels (``sim._ccode._translate``)
    from_kernel: bool = False

    def role(self, name: str, part) -> str | None:
        """The body of kernel role ``name`` for ``part`` (None: the kind has no such body)."""
        body = getattr(self, name)
        return body(part) if callable(body) else body

    def body(self, part) -> str:
        """All bodies of ``part`` as one text (``_c_source.kind_types`` compares the instances'
        C)."""
        return "\n".join(self.role(r, part) or "" for r in PLANT_ROLES)


#: the kernel roles of a plant kind, in the order the generated file defines them
PLANT_ROLES = ("state_outputs", "direct_outputs", "rhs", "segments", "project")


#: core._tables.table_next_time: the first point time later than t (ACD_HUGE, the kernels'
#: NO_BREAK, if none; a one-point table is a constant and has none)
TABLE_NEXT_TIME = CSupport(
    "table_next_time",
    r"""
static ACDRIVE_REAL acd_table_next_time(int n, const ACDRIVE_REAL *times, ACDRIVE_REAL t)
{
    int lo = 0, hi = n - 1, pass;
    if (n == 1 || t >= times[n - 1]) {
        return ACD_HUGE;
    }
    if (t < times[0]) {
        return times[0];
    }
    for (pass = 0; pass < 32 && hi - lo > 1; ++pass) { /* times[lo] <= t < times[hi] */
        int mid = (lo + hi) / 2;
        if (times[mid] <= t) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return times[hi];
}
""",
)

#: core._tables.table_at: linear between points, held outside, a vertical step where two times
#: are equal. The bisection halves [lo, hi] each pass: 32 passes cover any table an int counts.
TABLE_AT = CSupport(
    "table_at",
    r"""
static ACDRIVE_REAL acd_table_at(int n, const ACDRIVE_REAL *times, const ACDRIVE_REAL *values,
                                 ACDRIVE_REAL t)
{
    int lo = 0, hi = n - 1, pass;
    ACDRIVE_REAL dt;
    if (n == 1 || t <= times[0]) {
        return values[0];
    }
    if (t >= times[n - 1]) {
        return values[n - 1];
    }
    for (pass = 0; pass < 32 && hi - lo > 1; ++pass) { /* times[lo] <= t < times[hi] */
        int mid = (lo + hi) / 2;
        if (times[mid] <= t) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    dt = times[hi] - times[lo];
    if (dt <= ACD_R(0.0)) {
        return values[hi];
    }
    return values[lo] + (values[hi] - values[lo]) * (t - times[lo]) / dt;
}
""",
)

#: core._tables.table2d_at: bilinear in the grid, each coordinate clamped to its axis first; the
#: same operations in the same order. 32 bisection passes cover any axis an int counts.
TABLE2D_AT = CSupport(
    "table2d_at",
    r"""
static ACDRIVE_REAL acd_table2d_at(int nx, int ny, const ACDRIVE_REAL *xs,
                                   const ACDRIVE_REAL *ys, const ACDRIVE_REAL *v, ACDRIVE_REAL x,
                                   ACDRIVE_REAL y)
{
    int lo, hi, i, j, pass;
    ACDRIVE_REAL fx, fy, v00, v01, v10, v11, a, b;
    if (x < xs[0]) {
        x = xs[0];
    }
    if (x > xs[nx - 1]) {
        x = xs[nx - 1];
    }
    if (y < ys[0]) {
        y = ys[0];
    }
    if (y > ys[ny - 1]) {
        y = ys[ny - 1];
    }
    lo = 0;
    hi = nx - 1;
    for (pass = 0; pass < 32 && hi - lo > 1; ++pass) { /* xs[lo] <= x <= xs[hi] */
        int mid = (lo + hi) / 2;
        if (xs[mid] <= x) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    i = lo;
    lo = 0;
    hi = ny - 1;
    for (pass = 0; pass < 32 && hi - lo > 1; ++pass) { /* ys[lo] <= y <= ys[hi] */
        int mid = (lo + hi) / 2;
        if (ys[mid] <= y) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    j = lo;
    fx = (x - xs[i]) / (xs[i + 1] - xs[i]);
    fy = (y - ys[j]) / (ys[j + 1] - ys[j]);
    v00 = v[i * ny + j];
    v01 = v[i * ny + j + 1];
    v10 = v[(i + 1) * ny + j];
    v11 = v[(i + 1) * ny + j + 1];
    a = v00 + (v10 - v00) * fx;
    b = v01 + (v11 - v01) * fx;
    return a + (b - a) * fy;
}
""",
)

#: tanh by precision (newlib's libm has both), for the shaft's Coulomb friction (np.tanh of a kernel)
TANH = CSupport(
    "tanh",
    """
#ifdef ACDRIVE_FLOAT
#define ACD_TANH tanhf
#else
#define ACD_TANH tanh
#endif
""",
)
