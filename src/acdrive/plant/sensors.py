"""Sensors seen by the controller (Bodson section IV-A: encoder, voltage networks)."""

from __future__ import annotations

import numpy as np

from acdrive.jit import jit


@jit
def encoder_angle(theta, offset, counts_per_rev):
    """Incremental-encoder reading: the shaft angle plus an unknown ``offset``, truncated to whole
    counts of 2 pi / counts_per_rev (counts_per_rev <= 0 means an ideal sensor)."""
    reading = theta + offset
    if counts_per_rev <= 0.0:
        return reading
    step = 2.0 * np.pi / counts_per_rev
    return np.floor(reading / step) * step
