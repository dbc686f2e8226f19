"""Three-phase voltage source as a continuous part (Bodson (8) scaling).

v = sqrt(3/2) V_pk(t) e^{j theta_g},  d theta_g/dt = 2 pi f(t): a balanced source with peak
line-to-neutral voltage and frequency profiles. The phasor u_g = e^{j theta_g} is carried as a
state (du_g/dt = j 2 pi f u_g) so the right-hand side needs no trigonometry; ``project`` resets it
from theta_g at every sample so it never leaves the unit circle.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from acdrive.core.parts import ContinuousPart
from acdrive.core.signals import Layout, cplx, real, table
from acdrive.core.tables import table_at, table_offset
from acdrive.frames import K_PEAK as SQRT_3_2
from acdrive.jit import jit_fast

PARAMS = Layout(
    table("V_pk", "V", "peak line-to-neutral voltage profile"),
    table("f", "Hz", "frequency profile"),
)
STATES = Layout(
    real("theta_g", "rad", "source angle"),
    cplx("u_g", "", "unit phasor e^{j theta_g}"),
)
OUTPUTS = Layout(cplx("v", "V", "source voltage space vector, stationary frame"))
_TABLES = PARAMS.table_start
_THETA, _U = STATES.slot("theta_g"), STATES.slot("u_g")
_Y_V = OUTPUTS.slot("v")


@jit_fast
def source_project(x, p):
    x[_U], x[_U + 1] = np.cos(x[_THETA]), np.sin(x[_THETA])


@jit_fast
def source_state_outputs(t, x, p, y):
    v = SQRT_3_2 * table_at(p, _TABLES, t) * complex(x[_U], x[_U + 1])
    y[_Y_V], y[_Y_V + 1] = v.real, v.imag


@jit_fast
def source_rhs(t, x, u, p, y, dx):
    w_g = 2.0 * np.pi * table_at(p, table_offset(p, _TABLES, 1), t)
    du = 1j * w_g * complex(x[_U], x[_U + 1])
    dx[_THETA], dx[_U], dx[_U + 1] = w_g, du.real, du.imag


class ThreePhaseSource(ContinuousPart):
    """Balanced three-phase source with magnitude and frequency profiles."""

    PARAMS, STATES, OUTPUTS = PARAMS, STATES, OUTPUTS
    DEFAULTS: ClassVar[dict] = {"f": 50.0}
    INITIAL: ClassVar[dict] = {"u_g": 1.0}
    state_outputs = source_state_outputs
    rhs = source_rhs
    project = source_project
