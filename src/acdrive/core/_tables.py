"""Piecewise-linear tables stored inside a part's flat parameter array (see ``core._signals``).

A table occupies ``[n, t_0 .. t_{n-1}, v_0 .. v_{n-1}]``; tables follow one another after the
fixed parameters, so the k-th table starts where the (k-1)-th ends. 2-D tables
``[n_x, n_y, x.., y.., values]`` follow the tables the same way.
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


@jit_inline
def table2d_offset(p, first, k):
    """Start slot of the k-th 2-D table (0-based) when the first 2-D table starts at ``first``
    (``[n_x, n_y, x.., y.., values]`` each, ``core._signals``)."""
    offset = first
    for _ in range(k):
        n_x = int(p[offset])
        n_y = int(p[offset + 1])
        offset += 2 + n_x + n_y + n_x * n_y
    return offset


@jit_inline
def table2d_at(p, offset, x, y):
    """Bilinear interpolation at (x, y) of the 2-D table starting at slot ``offset``; a point
    outside the grid is first clamped to it (each coordinate to its axis's range), so the edge
    values are held outside. In the cell x_i <= x <= x_{i+1}, y_j <= y <= y_{j+1}, with
    f_x = (x - x_i) / (x_{i+1} - x_i) and f_y likewise: v = a + (b - a) f_y with
    a = v_ij + (v_{i+1,j} - v_ij) f_x and b = v_{i,j+1} + (v_{i+1,j+1} - v_{i,j+1}) f_x."""
    n_x = int(p[offset])
    n_y = int(p[offset + 1])
    x0 = offset + 2
    y0 = x0 + n_x
    v0 = y0 + n_y
    if x < p[x0]:
        x = p[x0]
    if x > p[x0 + n_x - 1]:
        x = p[x0 + n_x - 1]
    if y < p[y0]:
        y = p[y0]
    if y > p[y0 + n_y - 1]:
        y = p[y0 + n_y - 1]
    lo, hi = 0, n_x - 1  # invariant: x_lo <= x <= x_hi, the cell [lo, lo + 1] at the end
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if p[x0 + mid] <= x:
            lo = mid
        else:
            hi = mid
    i = lo
    lo, hi = 0, n_y - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if p[y0 + mid] <= y:
            lo = mid
        else:
            hi = mid
    j = lo
    f_x = (x - p[x0 + i]) / (p[x0 + i + 1] - p[x0 + i])
    f_y = (y - p[y0 + j]) / (p[y0 + j + 1] - p[y0 + j])
    v_00 = p[v0 + i * n_y + j]
    v_01 = p[v0 + i * n_y + j + 1]
    v_10 = p[v0 + (i + 1) * n_y + j]
    v_11 = p[v0 + (i + 1) * n_y + j + 1]
    a = v_00 + (v_10 - v_00) * f_x
    b = v_01 + (v_11 - v_01) * f_x
    return a + (b - a) * f_y
