"""C support of the generated kernels and the plant's loop: the piecewise-linear table (its value
and its next point, mirroring ``core._tables``) and tanh in either precision."""

from __future__ import annotations

from acdrive.sim._ccode._kinds import CSupport

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
