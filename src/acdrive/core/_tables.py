"""Piecewise-linear tables stored inside a part's flat parameter array (see ``core._signals``).

A table occupies ``[n, t_0 .. t_{n-1}, v_0 .. v_{n-1}]``; tables follow one another after the
fixed parameters, so the k-th table starts where the (k-1)-th ends.
"""

from __future__ import annotations

from acdrive._jit import jit_inline


@jit_inline
def table_offset(p, first, k):
    """Start slot of the k-th table (0-based) when the first table starts at ``first``."""
    offset = first
    for _ in range(k):
        offset += 1 + 2 * int(p[offset])
    return offset


@jit_inline
def table_at(p, offset, t):
    """Value at time ``t`` of the table starting at slot ``offset``: linear between points, held
    before the first and after the last point (a vertical step where two times are equal)."""
    n = int(p[offset])
    t0 = offset + 1
    v0 = offset + 1 + n
    if n == 1 or t <= p[t0]:
        return p[v0]
    if t >= p[t0 + n - 1]:
        return p[v0 + n - 1]
    lo, hi = 0, n - 1  # invariant: p[t0 + lo] <= t < p[t0 + hi]
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if p[t0 + mid] <= t:
            lo = mid
        else:
            hi = mid
    dt = p[t0 + hi] - p[t0 + lo]
    if dt <= 0.0:
        return p[v0 + hi]
    return p[v0 + lo] + (p[v0 + hi] - p[v0 + lo]) * (t - p[t0 + lo]) / dt


#: the time ``table_next_time`` gives when no point follows: finite, so that code compiled on
#: the assumption of finite values (``acdrive._jit.FAST_MATH_FLAGS``) may compare with it; the
#: same stand-in as the kernels' "no limit"
NO_BREAK = 1e300


@jit_inline
def table_next_time(p, offset, t):
    """The first point time later than ``t`` of the table at ``offset`` (``NO_BREAK`` if none;
    a one-point table is a constant and has none). Every point is a breakpoint of the profile:
    a corner of the piecewise-linear line, or a vertical step where two times are equal."""
    n = int(p[offset])
    t0 = offset + 1
    if n == 1 or t >= p[t0 + n - 1]:
        return NO_BREAK
    if t < p[t0]:
        return p[t0]
    lo, hi = 0, n - 1  # invariant: p[t0 + lo] <= t < p[t0 + hi]
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if p[t0 + mid] <= t:
            lo = mid
        else:
            hi = mid
    return p[t0 + hi]


@jit_inline
def tables_next_time(p, first, count, t):
    """The first point time later than ``t`` of the ``count`` tables from slot ``first`` on
    (``NO_BREAK`` if none)."""
    earliest = NO_BREAK
    offset = first
    for _ in range(count):
        later = table_next_time(p, offset, t)
        if later < earliest:
            earliest = later
        offset += 1 + 2 * int(p[offset])
    return earliest
