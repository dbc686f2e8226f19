"""The synchronous machine with flux linkages as states and a flux map as its magnetic model.

The equations are ``machines._synchronous_part``'s (voltage equation in rotor coordinates, torque
n_p Im(conj(psi_dq) i_dq), states psi_dq, theta, e_r; power-invariant scaling, motor reference
arrows), with the currents read from the inverse flux map

    i_d = I_d(psi_d, psi_q),   i_q = I_q(psi_d, psi_q)

two 2-D tables on a flux grid, bilinear inside it and clamped at its edges
(``core._tables.table2d_at``): outside the grid the currents of its nearest edge hold, so a run
is only the map's where its fluxes stay on the grid. ``FluxMapSynchronousMachine.from_flux_map``
builds the tables from a map psi(i) on a current grid (``machines._flux_map``: checked for
invertibility and reciprocity, inverted once by Newton's method on its bilinear interpolant).

The voltage equation and the rotor phasor's reset are the synchronous machine's own kernels
(``synchronous_rhs``, ``synchronous_project``): they read R_s and n_p, which this part declares
in the same slots.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from acdrive._jit import jit_fast
from acdrive.core._signals import Layout, Table2D, pack_table2d, real, table2d, unpack_table2d
from acdrive.core._tables import table2d_at, table2d_offset
from acdrive.errors import InputError
from acdrive.machines import _synchronous_part as synchronous
from acdrive.machines._flux_map import FluxMap, bilinear
from acdrive.machines._record import MachinePart
from acdrive.machines._synchronous_part import write_outputs

PARAMS = Layout(
    real("R_s", "ohm", "stator resistance", "positive"),
    real("n_p", "", "pole pairs", "count"),
    table2d("i_d", "A", "d-axis current i_d(psi_d, psi_q), the inverse flux map (power-invariant)"),
    table2d("i_q", "A", "q-axis current i_q(psi_d, psi_q), the inverse flux map (power-invariant)"),
)
assert all(PARAMS.slot(n) == synchronous.PARAMS.slot(n) for n in ("R_s", "n_p"))
_I_D_TABLE = PARAMS.table_start  # the first 2-D table (the layout has no 1-D table)
_PSI_DQ = synchronous.STATES.slot("psi_dq")


@jit_fast
def flux_map_state_outputs(t, x, p, y):
    psi_d, psi_q = x[_PSI_DQ], x[_PSI_DQ + 1]
    i_d = table2d_at(p, _I_D_TABLE, psi_d, psi_q)
    i_q = table2d_at(p, table2d_offset(p, _I_D_TABLE, 1), psi_d, psi_q)
    write_outputs(x, p, y, i_d, i_q)


class FluxMapSynchronousMachine(MachinePart):
    """Synchronous machine (PM, SyRM, PM-SyRM) with flux linkages as states and a flux map as its
    magnetic model: the currents from the inverse map i_d(psi_d, psi_q), i_q(psi_d, psi_q), two
    2-D tables (bilinear, clamped at the grid's edges); the voltage equation of
    ``SynchronousMachine`` (module docstring). Built from a map psi(i) on a current grid by
    ``from_flux_map``."""

    SOURCE = (
        "voltage equation in rotor coordinates with flux states; currents from an inverted flux "
        "map, bilinear on a flux grid (machines._flux_map_part)"
    )

    PARAMS, STATES, INPUTS, OUTPUTS = (
        PARAMS, synchronous.STATES, synchronous.INPUTS, synchronous.OUTPUTS
    )
    INITIAL: ClassVar[dict] = {"e_r": 1.0}
    state_outputs = flux_map_state_outputs
    rhs = synchronous.synchronous_rhs
    project = synchronous.synchronous_project

    @classmethod
    def from_flux_map(
        cls, name: str, flux_map: FluxMap, R_s: float, n_p: int,
        flux_points: tuple[int, int] | None = None,
    ) -> FluxMapSynchronousMachine:  # fmt: skip
        """The machine whose currents invert ``flux_map`` (``FluxMap.inverted``: ``flux_points``
        evenly spaced fluxes per axis over the largest box inside the map's image, the current
        grid's counts if None)."""
        if not isinstance(flux_map, FluxMap):
            raise InputError(
                "flux_map", f"must be a machines.FluxMap, got {type(flux_map).__name__}"
            )
        i_d, i_q = flux_map.inverted(flux_points)
        return cls(name, R_s=R_s, n_p=n_p, i_d=i_d, i_q=i_q)

    def tables(self) -> tuple[Table2D, Table2D]:
        """The inverse map as packed: (i_d table, i_q table)."""
        return (unpack_table2d(pack_table2d(f"{self.name}.i_d", self.values["i_d"])),
                unpack_table2d(pack_table2d(f"{self.name}.i_q", self.values["i_q"])))  # fmt: skip

    def zero_current_flux(self) -> complex:
        """psi_d + j psi_q where the tables give zero current (the magnet's flux linkage), by
        Newton's method on their bilinear interpolants; the grid's nearest point to it if the
        tables hold no zero."""
        t_d, t_q = self.tables()
        psi_d, psi_q = 0.5 * (t_d.x[0] + t_d.x[-1]), 0.5 * (t_d.y[0] + t_d.y[-1])
        for _ in range(60):
            f_d, dd_d, dd_q = bilinear(t_d.x, t_d.y, t_d.values, psi_d, psi_q)
            f_q, dq_d, dq_q = bilinear(t_q.x, t_q.y, t_q.values, psi_d, psi_q)
            det = dd_d * dq_q - dd_q * dq_d
            if det <= 0.0 or abs(f_d) + abs(f_q) == 0.0:
                break
            psi_d = float(np.clip(psi_d - (dq_q * f_d - dd_q * f_q) / det, t_d.x[0], t_d.x[-1]))
            psi_q = float(np.clip(psi_q - (dd_d * f_q - dq_d * f_d) / det, t_d.y[0], t_d.y[-1]))
        return complex(psi_d, psi_q)

    def initial_state(self, **values) -> np.ndarray:
        """As ``Part.initial_state``; psi_dq starts where the current is zero
        (``zero_current_flux``) and e_r follows an initial ``theta`` unless given."""
        if "psi_dq" not in values:
            values["psi_dq"] = self.zero_current_flux()
        if "theta" in values and "e_r" not in values:
            values["e_r"] = complex(np.exp(1j * self.values["n_p"] * float(values["theta"])))
        return super().initial_state(**values)
