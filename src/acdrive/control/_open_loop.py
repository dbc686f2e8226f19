"""Open-loop voltage commands as sampled parts: a three-phase program and a complex table.

``VoltageProgram``: v_ref = sqrt(3/2) V_pk(t) e^{j theta}, theta advanced at each sample by the
trapezoidal integral of 2 pi f over the last period (Bodson (8) scaling), for V/f tests.
``ComplexProgram``: v_ref(t) = re(t) + j im(t) from two tables, e.g. rotor voltages in rotor
coordinates for a DFIM test, or zero for a shorted rotor.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from acdrive._frames import K_PEAK as SQRT_3_2
from acdrive._jit import jit
from acdrive.core._parts import SampledPart
from acdrive.core._profile import Profile
from acdrive.core._signals import Layout, cplx, real, table
from acdrive.core._tables import table_at, table_offset

PROGRAM_PARAMS = Layout(
    table("V_pk", "V", "peak line-to-neutral voltage profile"),
    table("f", "Hz", "frequency profile"),
)
PROGRAM_STATES = Layout(
    real("theta", "rad", "voltage angle"),
    real("t_prev", "s", "time of the previous sample"),
    real("started", "", "1 once the first sample has run"),
)
COMMAND = Layout(cplx("v_ref", "V", "commanded voltage space vector"))
_TABLES = PROGRAM_PARAMS.table_start
_THETA, _T_PREV, _STARTED = (PROGRAM_STATES.slot(n) for n in ("theta", "t_prev", "started"))
_V_REF = COMMAND.slot("v_ref")


@jit
def program_step(t, T_s, u, p, s, y):
    f_at = table_offset(p, _TABLES, 1)
    if s[_STARTED] != 0.0:
        f_mean = 0.5 * (table_at(p, f_at, s[_T_PREV]) + table_at(p, f_at, t))
        s[_THETA] += 2.0 * np.pi * f_mean * (t - s[_T_PREV])
    s[_T_PREV], s[_STARTED] = t, 1.0
    v = SQRT_3_2 * table_at(p, _TABLES, t) * complex(np.cos(s[_THETA]), np.sin(s[_THETA]))
    y[_V_REF], y[_V_REF + 1] = v.real, v.imag
    return 0


class VoltageProgram(SampledPart):
    """Three-phase voltage command of given amplitude and frequency profiles (open loop)."""

    SOURCE = (
        "open-loop three-phase voltage program, Bodson (8) scaling "
        "(control._open_loop.program_step)"
    )

    PARAMS, STATES, OUTPUTS = PROGRAM_PARAMS, PROGRAM_STATES, COMMAND
    DEFAULTS: ClassVar[dict] = {"f": 50.0}
    step = program_step


TABLE_PARAMS = Layout(
    table("re", "V", "real part of the command"),
    table("im", "V", "imaginary part of the command"),
)
_RE = TABLE_PARAMS.table_start


@jit
def complex_program_step(t, T_s, u, p, s, y):
    y[_V_REF] = table_at(p, _RE, t)
    y[_V_REF + 1] = table_at(p, table_offset(p, _RE, 1), t)
    return 0


class ComplexProgram(SampledPart):
    """A complex voltage command from two tables (default zero: a shorted winding)."""

    SOURCE = "a complex command from two tables (control._open_loop.complex_program_step)"

    PARAMS, OUTPUTS = TABLE_PARAMS, COMMAND
    DEFAULTS: ClassVar[dict] = {"re": 0.0, "im": 0.0}
    step = complex_program_step

    @classmethod
    def from_function(cls, name, function, times) -> ComplexProgram:
        """Tabulate a Python function of time (complex volts) at ``times``."""
        times = np.asarray(times, dtype=float)
        values = np.array([complex(function(t)) for t in times])
        return cls(name, re=Profile(times, values.real), im=Profile(times, values.imag))
