"""Voltage sources as continuous parts: the three-phase supply (Bodson (8) scaling), balanced or
with per-phase magnitudes, and a DC source (e.g. a converter's DC link).

``ThreePhaseSource``: v = sqrt(3/2) V_pk(t) e^{j theta_g},  d theta_g/dt = 2 pi f(t): a balanced
source with peak line-to-neutral voltage and frequency profiles. The phasor u_g = e^{j theta_g} is
carried as a state (du_g/dt = j 2 pi f u_g) so the right-hand side needs no trigonometry;
``project`` resets it from theta_g at every sample so it never leaves the unit circle.

``UnbalancedSource``: the same source with a magnitude scale per phase, k_a(t), k_b(t), k_c(t):
the phase EMFs are e_x = k_x(t) V_pk(t) cos(theta_g - phi_x), phi_x = 0, 2 pi/3, 4 pi/3, and the
space vector is their transform (1), sqrt(2/3) (e_a + alpha e_b + alpha^2 e_c). The star point
is isolated, so a zero-sequence EMF drives no current and (1) drops it. With k_a = k_b = k_c = 1
it is the balanced source; with one phase's EMF at zero (a collapsed source phase) the vector has
a positive-sequence part of 2/3 and a negative-sequence part of 1/3 of the balanced magnitude.
This models the source's EMF collapsing, not an open conductor: an open line forces that phase's
current to zero, a constraint on the machine that the space-vector model does not express.

``DCSource``: a DC voltage following a profile (no states), e.g. a converter's DC link.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from acdrive._frames import K_PEAK as SQRT_3_2
from acdrive._frames import abc_to_complex_nb, complex_to_abc_nb
from acdrive._jit import jit_fast
from acdrive.core._parts import ContinuousPart
from acdrive.core._signals import Layout, cplx, real, table
from acdrive.core._tables import table_at, table_offset

PARAMS = Layout(
    table("V_pk", "V", "peak line-to-neutral voltage profile", "nonnegative"),
    table("f", "Hz", "frequency profile", "positive"),
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

    SOURCE = (
        "balanced three-phase source: v = sqrt(3/2) V_pk(t) u_g, du_g/dt = j 2 pi f(t) u_g "
        "(plant._sources)"
    )

    PARAMS, STATES, OUTPUTS = PARAMS, STATES, OUTPUTS
    DEFAULTS: ClassVar[dict] = {"f": 50.0}
    INITIAL: ClassVar[dict] = {"u_g": 1.0}
    state_outputs = source_state_outputs
    rhs = source_rhs
    project = source_project


# --- per-phase magnitudes ---------------------------------------------------------------------

UNBALANCED_PARAMS = Layout(
    *PARAMS,  # V_pk and f first: the balanced source's kernels find them at the same offsets
    table("k_a", "", "phase a EMF magnitude as a fraction of V_pk (profile)", "fraction"),
    table("k_b", "", "phase b EMF magnitude as a fraction of V_pk (profile)", "fraction"),
    table("k_c", "", "phase c EMF magnitude as a fraction of V_pk (profile)", "fraction"),
)


@jit_fast
def unbalanced_state_outputs(t, x, p, y):
    """The transform (1) of the scaled phase EMFs (module docstring). The balanced EMFs are the
    phase values (2) of sqrt(3/2) V_pk u_g (so the right-hand side needs no trigonometry)."""
    balanced = SQRT_3_2 * table_at(p, _TABLES, t) * complex(x[_U], x[_U + 1])
    e_a, e_b, e_c = complex_to_abc_nb(balanced, 0.0)
    k_a = table_offset(p, _TABLES, 2)
    k_b = table_offset(p, k_a, 1)
    k_c = table_offset(p, k_b, 1)
    v = abc_to_complex_nb(
        table_at(p, k_a, t) * e_a, table_at(p, k_b, t) * e_b, table_at(p, k_c, t) * e_c, 0.0
    )
    y[_Y_V], y[_Y_V + 1] = v.real, v.imag


class UnbalancedSource(ThreePhaseSource):
    """Three-phase source with a magnitude profile per phase (``k_a``, ``k_b``, ``k_c``, default
    1), e.g. one phase's EMF collapsing to zero for a while (module docstring): the balanced
    source's states, angle and frequency, with the phase EMFs scaled before the transform (1)."""

    PARAMS = UNBALANCED_PARAMS
    DEFAULTS: ClassVar[dict] = {"f": 50.0, "k_a": 1.0, "k_b": 1.0, "k_c": 1.0}
    state_outputs = unbalanced_state_outputs


# --- DC source --------------------------------------------------------------------------------

DC_PARAMS = Layout(table("V", "V", "DC voltage profile", "nonnegative"))
DC_OUTPUTS = Layout(real("v_dc", "V", "DC voltage"))
_DC_TABLE = DC_PARAMS.table_start
_Y_V_DC = DC_OUTPUTS.slot("v_dc")


@jit_fast
def dc_state_outputs(t, x, p, y):
    y[_Y_V_DC] = table_at(p, _DC_TABLE, t)


@jit_fast
def dc_rhs(t, x, u, p, y, dx):
    pass  # no states


class DCSource(ContinuousPart):
    """A DC voltage following a profile ``V`` (e.g. a converter's DC link, with a drop)."""

    SOURCE = "DC source: the voltage profile (plant._sources.dc_state_outputs)"

    PARAMS, OUTPUTS = DC_PARAMS, DC_OUTPUTS
    state_outputs = dc_state_outputs
    rhs = dc_rhs
