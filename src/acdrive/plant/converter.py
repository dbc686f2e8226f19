"""Rotor-side voltage-source converter, averaged model.

The converter applies the commanded rotor voltage, held over the sample period (zero-order
hold), within the linear range of space-vector modulation: a phase-voltage peak of V_dc / sqrt(3),
i.e. a space-vector magnitude of sqrt(3/2) V_dc / sqrt(3) = V_dc / sqrt(2) (Bodson (8)). A command
beyond it is scaled back along its own direction.
"""

from __future__ import annotations

import numpy as np

from acdrive.jit import jit


def max_voltage_magnitude(v_dc: float) -> float:
    """Largest space-vector magnitude the converter applies from DC-link voltage ``v_dc``."""
    return v_dc / np.sqrt(2.0)


@jit
def converter_output(v_command, v_max):
    """(applied voltage, saturated) for a complex command and magnitude limit ``v_max``."""
    magnitude = np.abs(v_command)
    if magnitude <= v_max:
        return v_command, False
    return v_command * (v_max / magnitude), True
