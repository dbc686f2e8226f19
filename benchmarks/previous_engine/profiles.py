"""Piecewise-linear time profiles (supply magnitude and frequency, load torque, references).

A profile is a pair of arrays (times, values): linear interpolation in between, held constant
before the first and after the last point. Compiled code evaluates them with ``profile_at``.
"""

from __future__ import annotations

import numpy as np

from acdrive._jit import jit


@jit
def profile_at(times, values, t):
    """Value of the piecewise-linear profile (times, values) at time ``t``."""
    n = times.shape[0]
    if n == 1 or t <= times[0]:
        return values[0]
    if t >= times[n - 1]:
        return values[n - 1]
    k = np.searchsorted(times, t, side="right") - 1
    dt = times[k + 1] - times[k]
    if dt <= 0.0:
        return values[k + 1]
    return values[k] + (values[k + 1] - values[k]) * (t - times[k]) / dt


def pad_profiles(profiles: list[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """Stack profiles of different lengths into 2-D arrays, repeating each last point.

    Repeated final points (equal times) keep every profile's value unchanged.
    """
    length = max(len(t) for t, _ in profiles)
    times = np.empty((len(profiles), length))
    values = np.empty((len(profiles), length))
    for row, (t, v) in enumerate(profiles):
        n = len(t)
        times[row, :n], values[row, :n] = t, v
        times[row, n:], values[row, n:] = t[-1], v[-1]
    return times, values
