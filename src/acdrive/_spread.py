"""Numbers of limit-cycling runs, printed only to the precision that survives the platform.

A run that limit-cycles is sensitive to the last bit of its arithmetic: the compiled loop uses
fast math, so another CPU or library version gives another trajectory, and its averages differ
in the last printed digits. Such a number is printed as the mean over its window rounded to the
*spread* of that mean, measured over ``SUBWINDOWS`` consecutive sub-windows (the standard
deviation of the sub-window means over the square root of their number, the standard error):
the rounding step is the power of ten at or above the spread, so that the printed digits are
those the oscillation does not move. The step itself can still change between platforms when a
spread lies near a power of ten. A deterministic
run (no limit cycle) keeps its usual format.
"""

from __future__ import annotations

import math

import numpy as np

#: Number of consecutive sub-windows over which a limit-cycle average's spread is measured (32:
#: the spread estimate itself then scatters by about 13 %, so its power of ten rarely flips).
SUBWINDOWS = 32


def subwindow_means(x, n: int = SUBWINDOWS) -> np.ndarray:
    """Means of ``x`` over ``n`` consecutive, nearly equal parts (fewer if ``x`` is shorter)."""
    x = np.asarray(x, dtype=float)
    parts = [p for p in np.array_split(x, min(n, x.size)) if p.size]
    return np.array([float(np.mean(p)) for p in parts])


def mean_and_spread(x, n: int = SUBWINDOWS) -> tuple[float, float]:
    """(mean of ``x``, spread of that mean): the sample standard deviation of its ``n``
    sub-window means divided by sqrt(n), the standard error of the whole window's mean (how far
    another trajectory of the same limit cycle moves it); 0 with fewer than two sub-windows."""
    x = np.asarray(x, dtype=float)
    if x.size == 0:
        return math.nan, math.nan
    means = subwindow_means(x, n)
    spread = float(np.std(means, ddof=1) / math.sqrt(means.size)) if means.size > 1 else 0.0
    return float(np.mean(x)), spread


def mean_and_spread_over_stretches(x, stretches, n: int = SUBWINDOWS) -> tuple[float, float]:
    """(mean of ``x`` over all ``stretches`` (slices), spread of that mean): each stretch, a
    steady operating point of its own, is cut into ``n`` sub-windows; the RMS deviation of the
    sub-window means from their own stretch's mean (sample-corrected), so that different
    operating points do not count, divided by the square root of the number of sub-windows:
    the standard error of the mean (``mean_and_spread``). (nan, nan) without samples."""
    x = np.asarray(x, dtype=float)
    parts = [x[s] for s in stretches if x[s].size]
    if not parts:
        return math.nan, math.nan
    deviations, dof = [], 0
    for part in parts:
        means = subwindow_means(part, n)
        deviations.extend(means - float(np.mean(part)))
        dof += means.size - 1
    spread = (
        math.sqrt(float(np.sum(np.square(deviations))) / dof / len(deviations)) if dof > 0 else 0.0
    )
    return float(np.mean(np.concatenate(parts))), spread


def peak_spread(x, n: int = SUBWINDOWS) -> float:
    """Sample standard deviation of the largest value of ``x`` in each of ``n`` consecutive
    sub-windows: how much a largest value over a limit cycle moves with the window."""
    x = np.asarray(x, dtype=float)
    parts = [p for p in np.array_split(x, min(n, x.size)) if p.size]
    peaks = np.array([float(np.max(p)) for p in parts])
    return float(np.std(peaks, ddof=1)) if peaks.size > 1 else 0.0


def rounding_step(spread: float) -> float:
    """The power of ten at or above ``spread`` (0 for a zero or undefined spread)."""
    if not math.isfinite(spread) or spread <= 0.0:
        return 0.0
    return 10.0 ** math.ceil(math.log10(spread))


def round_to_spread(
    value: float,
    spread: float,
    fmt: str = ".2f",
    sign: bool = False,
    leading_digit: bool = False,
    show_step: bool = False,
) -> str:
    """``value`` rounded to the significance its ``spread`` allows: to the multiple of
    ``rounding_step(spread)`` nearest to it, with as many decimals as that step has; formatted
    with ``fmt`` when the spread is zero (a deterministic number). ``sign``: print '+' on
    non-negative numbers. ``leading_digit``: never round coarser than the value's leading digit
    (for a largest value or an RMS, which a step above it would print as 0). ``show_step``:
    append the rounding step, "(+-step)"."""
    plus = "+" if sign else ""
    if not math.isfinite(value):
        return "n/a"
    step = rounding_step(spread)
    if step and leading_digit and value != 0.0:
        step = min(step, 10.0 ** math.floor(math.log10(abs(value))))
    if step == 0.0:
        return f"{value:{plus}{fmt}}"
    decimals = max(0, -round(math.log10(step)))
    rounded = round(value / step) * step
    if rounded == 0.0:
        rounded = 0.0  # no "-0"
    text = f"{rounded:{plus}.{decimals}f}"
    return text + (f" (+-{step:.{decimals}f})" if show_step else "")


def order_of_magnitude(count: float) -> str:
    """A count known only to its order of magnitude: '0', or '~10^k' with k the nearest integer
    to log10(count)."""
    if count <= 0:
        return "0"
    return f"~1e{round(math.log10(count))}"
