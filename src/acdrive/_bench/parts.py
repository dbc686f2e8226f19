"""A benchmark-only sampled part: a precomputed command sequence, one value per sample.

``HeldSequence`` outputs values[k] at the k-th sample it runs (the last value once the sequence
is exhausted), read by index from a counter in its state: O(1) per sample, reading the
parameter array front to back. ``control.ComplexProgram`` gives the same command from
a time table (a staircase with its steps between the sample instants) but searches the table at
every sample: over
10,000 samples and two tables that search, and its cache misses, took about a quarter of the
open-loop DFIM's time per step (0.80 against 1.05 million steps/s with a one-point table). A
peer reading its action array step by step (GEM's users do) does the same work as this part.
"""

from __future__ import annotations

import numpy as np

from acdrive._jit import jit
from acdrive.core._parts import SampledPart
from acdrive.core._profile import Profile
from acdrive.core._signals import Layout, cplx, real, table
from acdrive.core._tables import table_offset

SEQ_PARAMS = Layout(
    table("re", "V", "real parts, one per sample (the table's times are the sample indices)"),
    table("im", "V", "imaginary parts, one per sample"),
)
SEQ_STATES = Layout(real("k", "", "index of the next sample"))
SEQ_OUTPUTS = Layout(cplx("v_ref", "V", "the command of this sample"))
_RE = SEQ_PARAMS.table_start


@jit
def sequence_step(t, T_s, u, p, s, y):
    """values[k] of both tables, k the state counter (held at the last value), then k + 1."""
    n = int(p[_RE])
    k = int(s[0])
    k = min(k, n - 1)
    im = table_offset(p, _RE, 1)
    y[0] = p[_RE + 1 + n + k]
    y[1] = p[im + 1 + n + k]
    s[0] += 1.0
    return 0


class HeldSequence(SampledPart):
    """``HeldSequence(name, values)``: the complex command values[k] at the k-th sample."""

    PARAMS, STATES, OUTPUTS = SEQ_PARAMS, SEQ_STATES, SEQ_OUTPUTS
    step = sequence_step

    def __init__(self, name: str, values=None, **params):
        if values is not None:
            values = np.asarray(values, dtype=complex)
            index = np.arange(values.size, dtype=float)
            params = {
                "re": Profile(index, values.real),
                "im": Profile(index, values.imag),
                **params,
            }
        super().__init__(name, **params)
