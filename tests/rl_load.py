"""A balanced star-connected R-L load as a part declared outside acdrive, for the tests that feed
one (``test_inverter``: through the SVPWM inverter; ``test_drive_plugin``: a toy drive)."""

from __future__ import annotations

from acdrive._jit import jit_fast
from acdrive.core import ContinuousPart, Layout, cplx, real

RL_PARAMS = Layout(
    real("R", "ohm", "resistance per phase", "positive"),
    real("L", "H", "inductance per phase", "positive"),
)
RL_STATES = Layout(cplx("i", "A", "load current"))
RL_INPUTS = Layout(cplx("v", "V", "phase-to-neutral voltage"))
RL_OUTPUTS = Layout(cplx("i_s", "A", "load current"))


@jit_fast
def rl_state_outputs(t, x, p, y):
    y[0], y[1] = x[0], x[1]


@jit_fast
def rl_rhs(t, x, u, p, y, dx):
    dx[0] = (u[0] - p[0] * x[0]) / p[1]
    dx[1] = (u[1] - p[0] * x[1]) / p[1]


class RLLoad(ContinuousPart):
    """Balanced star-connected R-L load: L di/dt = v - R i (space vectors)."""

    PARAMS, STATES, INPUTS, OUTPUTS = RL_PARAMS, RL_STATES, RL_INPUTS, RL_OUTPUTS
    state_outputs = rl_state_outputs
    rhs = rl_rhs
