"""Shaft parts: a free shaft with load and friction, or a speed prescribed as a profile.

Free shaft (Bodson (26), Amezquita-Brooks et al. (2) in mechanical speed):

    J dw/dt = tau_e - tau_L(t) - (B + k_b(t)) w - tau_c tanh(w / W_COULOMB),   d theta/dt = w

tau_e drives the shaft (a machine's motoring torque); everything else opposes positive speed:
the active load-torque profile tau_L(t) (a turbine driving a generator is a negative load), the
viscous friction B w, the passive eddy-current brake k_b(t) w and the Coulomb friction, smoothed
over W_COULOMB so the right-hand side stays smooth for the integrator. The brake is passive (it
only dissipates, k_b >= 0) and its coefficient follows a profile (the ``brake`` table, N m s/rad,
zero by default), so a brake is applied or released at a given time: a step of the coefficient
is a vertical step of the table. A free shaft with a constant brake and no other torque decays
as w(t) = w(0) exp(-(B + k_b) t / J).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from acdrive._jit import jit_fast, jit_inline
from acdrive.core._parts import ContinuousPart
from acdrive.core._signals import Layout, pack_table, real, table
from acdrive.core._tables import table_at, table_offset
from acdrive.errors import InputError

#: speed scale of the smooth Coulomb friction tau_c tanh(w / W_COULOMB) [rad/s]
W_COULOMB = 0.5

SHAFT_PARAMS = Layout(
    real("J", "kg m^2", "inertia of rotor and load", "positive"),
    real("B", "N m s/rad", "viscous friction coefficient", "nonnegative"),
    real("tau_c", "N m", "Coulomb friction torque", "nonnegative"),
    table("load", "N m", "active load torque profile, opposing positive speed"),
    # appended after ``load``: the layout of the earlier parameters is unchanged
    table("brake", "N m s/rad", "eddy-current brake coefficient profile (>= 0), torque -k_b w"),
)
SHAFT_STATES = Layout(
    real("w", "rad/s", "mechanical speed"),
    real("theta", "rad", "mechanical angle"),
)
SHAFT_INPUTS = Layout(real("tau_e", "N m", "electromagnetic torque"))
SHAFT_OUTPUTS = Layout(
    real("w", "rad/s", "mechanical speed"),
    real("theta", "rad", "mechanical angle"),
)
_J, _B, _TAU_C = (SHAFT_PARAMS.slot(n) for n in ("J", "B", "tau_c"))
_LOAD = SHAFT_PARAMS.table_start
_W, _THETA = SHAFT_STATES.slot("w"), SHAFT_STATES.slot("theta")
_TAU_E = SHAFT_INPUTS.slot("tau_e")
_Y_W, _Y_THETA = SHAFT_OUTPUTS.slot("w"), SHAFT_OUTPUTS.slot("theta")


@jit_inline
def load_torque(p, w, t):
    """tau_L(t) + B w + tau_c tanh(w / W_COULOMB): the load and the friction (the brake is
    ``brake_torque``; together they are everything that opposes the motor)."""
    tau = table_at(p, _LOAD, t) + p[_B] * w
    if p[_TAU_C] != 0.0:
        tau += p[_TAU_C] * np.tanh(w / W_COULOMB)
    return tau


@jit_inline
def brake_coefficient(p, t):
    """k_b(t) [N m s/rad], the eddy-current brake's coefficient profile."""
    return table_at(p, table_offset(p, _LOAD, 1), t)


@jit_inline
def brake_torque(p, w, t):
    """k_b(t) w: the passive eddy-current brake's torque against the speed."""
    return brake_coefficient(p, t) * w


@jit_fast
def shaft_state_outputs(t, x, p, y):
    y[_Y_W], y[_Y_THETA] = x[_W], x[_THETA]


@jit_fast
def shaft_rhs(t, x, u, p, y, dx):
    dx[_W] = (u[_TAU_E] - load_torque(p, x[_W], t)) / p[_J]
    k_b = brake_coefficient(p, t)
    if k_b != 0.0:  # a separate term: with k_b = 0 the arithmetic is the brake-free shaft's
        dx[_W] -= k_b * x[_W] / p[_J]
    dx[_THETA] = x[_W]


class Shaft(ContinuousPart):
    """Free shaft with inertia, viscous and Coulomb friction, a load-torque profile and an
    eddy-current brake whose coefficient follows a profile (module docstring)."""

    SOURCE = (
        "Bodson (26): J dw/dt = tau_e - tau_L(t) - (B + k_b(t)) w - tau_c tanh(w / W_COULOMB) "
        "(plant._mechanics)"
    )

    PARAMS, STATES, INPUTS, OUTPUTS = SHAFT_PARAMS, SHAFT_STATES, SHAFT_INPUTS, SHAFT_OUTPUTS
    DEFAULTS: ClassVar[dict] = {"B": 0.0, "tau_c": 0.0, "load": 0.0, "brake": 0.0}
    state_outputs = shaft_state_outputs
    rhs = shaft_rhs

    def check(self):
        field = f"{self.name}.brake"
        brake = pack_table(field, self.values["brake"])
        n = int(brake[0])
        if (brake[1 + n :] < 0.0).any():
            raise InputError(field, "a passive brake's coefficient must be >= 0 at every point")


SPEED_PARAMS = Layout(table("w", "rad/s", "prescribed mechanical speed profile"))
SPEED_STATES = Layout(real("theta", "rad", "mechanical angle"))
_P_W = SPEED_PARAMS.table_start
_S_THETA = SPEED_STATES.slot("theta")


@jit_fast
def speed_state_outputs(t, x, p, y):
    y[_Y_W] = table_at(p, _P_W, t)
    y[_Y_THETA] = x[_S_THETA]


@jit_fast
def speed_rhs(t, x, u, p, y, dx):
    dx[_S_THETA] = table_at(p, _P_W, t)


class PrescribedSpeed(ContinuousPart):
    """Shaft held at a speed profile (a dynamometer): outputs w(t) and its angle."""

    SOURCE = "a shaft held at a speed profile (plant._mechanics.speed_state_outputs, speed_rhs)"

    PARAMS, STATES, OUTPUTS = SPEED_PARAMS, SPEED_STATES, SHAFT_OUTPUTS
    state_outputs = speed_state_outputs
    rhs = speed_rhs
