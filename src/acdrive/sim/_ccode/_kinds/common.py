"""C support shared by several kinds: limits of a space vector and of a real, the wrapped angle,
the speed PI (25), the piecewise-linear table; each mirrors its numba function."""

from __future__ import annotations

from acdrive._frames import LIMIT_RTOL
from acdrive.sim._ccode._kinds import CSupport

#: _frames.beyond_limit's tolerance: a magnitude a few ulps above its limit is at it
LIMIT_RTOL_C = CSupport(
    "limit_rtol", f"#define ACD_LIMIT_RTOL ACD_R({LIMIT_RTOL!r}) /* _frames.LIMIT_RTOL */\n"
)

#: _frames.clip_magnitude
CLIP_MAGNITUDE = CSupport(
    "clip_magnitude",
    """
/* x scaled back to magnitude limit if |x| is beyond it (then *limited = 1) */
static acd_complex acd_clip_magnitude(acd_complex x, ACDRIVE_REAL limit, int *limited)
{
    ACDRIVE_REAL magnitude = acd_cabs(x);
    if (!(magnitude > limit + ACD_LIMIT_RTOL * limit)) {
        *limited = 0;
        return x;
    }
    *limited = 1;
    return acd_cscale(limit / magnitude, x);
}
""",
    needs=(LIMIT_RTOL_C,),
)

SPEED_PI = CSupport(
    "speed_pi",
    r"""
/* one sample of the speed PI (25) with conditional integration (control._speed.speed_pi):
   returns the torque command, advances *e_int only while inside [tau_lo, tau_hi] */
static ACDRIVE_REAL acd_speed_pi(ACDRIVE_REAL K_P, ACDRIVE_REAL K_I, ACDRIVE_REAL K_F,
                                 ACDRIVE_REAL *e_int, ACDRIVE_REAL w_ref, ACDRIVE_REAL w,
                                 ACDRIVE_REAL tau_lo, ACDRIVE_REAL tau_hi, ACDRIVE_REAL T_s,
                                 int *clipped)
{
    ACDRIVE_REAL tau = K_F * K_P * w_ref - K_P * w + K_I * *e_int;
    *clipped = 1;
    if (tau > tau_hi) {
        return tau_hi;
    }
    if (tau < tau_lo) {
        return tau_lo;
    }
    *clipped = 0;
    *e_int = *e_int + T_s * (w_ref - w);
    return tau;
}
""",
)

WRAP = CSupport(
    "wrap",
    r"""
/* an angle wrapped into [-pi, pi) */
static ACDRIVE_REAL acd_wrap(ACDRIVE_REAL angle)
{
    return acd_pymod(angle + ACD_PI, ACD_R(2.0) * ACD_PI) - ACD_PI;
}
""",
)

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

#: control._foc._clip: x clipped to [-limit, limit]
CLIP = CSupport(
    "clip",
    r"""
/* x clipped to [-limit, limit] (*limited = 1 if it was outside) */
static ACDRIVE_REAL acd_clip(ACDRIVE_REAL x, ACDRIVE_REAL limit, int *limited)
{
    *limited = 1;
    if (x > limit) {
        return limit;
    }
    if (x < -limit) {
        return -limit;
    }
    *limited = 0;
    return x;
}
""",
)
