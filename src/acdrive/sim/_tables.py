"""The tables the generic loop (``sim._generic``) runs one topology from, and the kernels'
addresses in this process."""

from __future__ import annotations

import numpy as np

from acdrive.sim import _kernels as kernels
from acdrive.sim._integrators import INTEGRATORS
from acdrive.sim._loop_source import copy_pairs, profile_parts

METHOD_CODES = {"rk4": 0, "rk6": 1}


class GenericUnavailable(Exception):
    """The generic tier cannot run this topology; the message says why."""


def tables(system, addresses) -> tuple:
    """(SLOT, PROJECT, STATE_OUT, DIRECT, RHS, SAMPLED, MODS, COPY, BREAKS, SIZES) of ``system``;
    ``addresses[(kind, role)]`` is the native address of a kind's role kernel."""
    index = {p.name: i for i, p in enumerate(system.parts)}
    slot = np.zeros((len(system.parts), 8), dtype=np.int64)
    for i, p in enumerate(system.parts):
        s = system.slots[p.name]
        slot[i] = (*s.x, *s.s, *s.u, *s.y)
    copies: list[tuple[int, int]] = []

    def row(part, role, pairs, fast_role=None):
        c0 = len(copies)
        copies.extend(pairs)
        fast = addresses[(type(part), fast_role)] if fast_role else 0
        return (index[part.name], addresses[(type(part), role)], c0, len(copies), fast)

    def table(rows):
        return np.array(rows, dtype=np.int64).reshape(len(rows), 5)

    kinds_with = {role: {k for (k, r) in addresses if r == role} for role in kernels.ROLES}
    project = [row(p, "project", ()) for p in system.continuous
               if type(p) in kinds_with["project"]]  # fmt: skip
    state_out = [row(p, "state_outputs", (), "state_outputs_fast") for p in system.continuous]
    direct = [row(p, "direct_outputs", copy_pairs(system, p, only=p.DIRECT_FROM),
                  "direct_outputs_fast") for p in system.direct]  # fmt: skip
    rhs = []
    for p in system.continuous:
        copied = p.DIRECT_FROM if p in system.direct else ()
        rhs.append(row(p, "rhs", copy_pairs(system, p, skip=copied)))
    sampled = [row(p, "step", copy_pairs(system, p)) for p in system.sampled]
    mods = [row(p, "segments", copy_pairs(system, p)) for p in system.modulators]
    copy = np.array(copies, dtype=np.int64).reshape(len(copies), 2)
    breaks = np.array([(i, p.PARAMS.table_start, len(p.PARAMS.tables))
                       for i, p in profile_parts(system)], dtype=np.int64).reshape(-1, 3)  # fmt: skip
    sizes = np.array(
        [
            INTEGRATORS[system.method][1] + 1,
            max([m.MAX_SEGMENTS for m in system.modulators], default=1),
            max(max([m.OUTPUTS.size() for m in system.modulators], default=1), 1),
            METHOD_CODES[system.method],
        ],
        dtype=np.int64,
    )
    return (slot, table(project), table(state_out), table(direct), table(rhs), table(sampled),
            table(mods), copy, breaks, sizes)  # fmt: skip
