"""One sample of computation delay as a sampled part.

A digital controller that computes its command during the sample period applies it at the next
sample instant: the converter sees the command of the previous sample. ``ComputationDelay`` placed
between a controller output and the modulator input models that (the DFIM drive puts one between
its controller and rotor converter when ``controller.computation_delay_samples = 1``, and its
linearisation, ``drives.dfim._linearisation._stability``, runs that same part). The delayed signal is declared
per instance (unit and kind), so one part serves any wire.
"""

from __future__ import annotations

from typing import ClassVar

from acdrive._jit import jit
from acdrive.core._parts import SampledPart
from acdrive.core._signals import Layout, cplx, real
from acdrive.errors import InputError


@jit
def delay_step(t, T_s, u, p, s, y):
    """Output the value stored at the previous sample, store the present input."""
    for i in range(u.shape[0]):
        y[i] = s[i]
        s[i] = u[i]
    return 0


class ComputationDelay(SampledPart):
    """``ComputationDelay(name, unit="V", kind="complex")``: the output is the input of the
    previous sample (zero, or ``initial=`` the first held value, before that)."""

    SOURCE = "one sample of computation delay (control._delay)"

    step = delay_step
    PER_INSTANCE: ClassVar[dict] = {
        "STATES": "stored, of the unit and kind given",
        "INPUTS": "x, of the unit and kind given (default V, complex)",
        "OUTPUTS": "x, the input of the previous sample (same unit and kind)",
    }

    def __init__(self, name: str, unit: str = "V", kind: str = "complex", initial=0.0):
        if kind not in ("real", "complex"):
            raise InputError(f"{name}.kind", 'must be "real" or "complex"')
        declare = cplx if kind == "complex" else real
        self.INPUTS = Layout(declare("x", unit, "signal to delay"))
        self.OUTPUTS = Layout(declare("x", unit, "the input of the previous sample"))
        self.STATES = Layout(declare("stored", unit, "the input kept for the next sample"))
        self._initial = initial
        super().__init__(name)

    def initial_state(self, **values):
        return super().initial_state(**{"stored": self._initial, **values})

    def held_outputs(self) -> dict:
        return {"x": self._initial}
