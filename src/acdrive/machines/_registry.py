"""The built-in machines by name: one registry for every command, scenario and report.

* ``bodson-dfim``: the laboratory DFIM of Bodson section III-D / IV-A;
* ``ugalde-im-300w``: the 300 W induction machine of Ugalde-Loo et al.;
* ``delorenzo-im`` and ``delorenzo-im-13``: the DeLorenzo induction machine of Amezquita-Brooks
  et al., from its Appendix and as identified from its matrix (13);
* ``pmsg-2mw``: the 2 MW permanent-magnet generator of Ugalde-Loo et al.

``machine_part`` makes the continuous plant part of a built-in machine (its electrical model; the
inertia and friction go to a ``plant.Shaft``).
"""

from __future__ import annotations

from acdrive._arguments import Instance
from acdrive.errors import InputError
from acdrive.machines._dfim import BODSON_DFIM, DFIMParams
from acdrive.machines._induction import DELORENZO_IM, DELORENZO_IM_13, UGALDE_IM_300W, IMParams
from acdrive.machines._pmsm import PMSG_2MW, PMSGParams

MACHINES: dict[str, IMParams | PMSGParams | DFIMParams] = {
    "ugalde-im-300w": UGALDE_IM_300W,
    "delorenzo-im": DELORENZO_IM,
    "delorenzo-im-13": DELORENZO_IM_13,
    "pmsg-2mw": PMSG_2MW,
    "bodson-dfim": BODSON_DFIM,
}

#: the argument rule of a machine record (acdrive._arguments)
MACHINE_RECORD = Instance(IMParams, PMSGParams, DFIMParams)


def names(kind: type | None = None) -> tuple[str, ...]:
    """Names of the built-in machines, of one parameter class if ``kind`` is given."""
    return tuple(n for n, p in MACHINES.items() if kind is None or isinstance(p, kind))


def machine_params(name: str, kind: type | None = None, field: str = "machine"):
    """Parameters of a built-in machine (of class ``kind`` if given), or an InputError naming
    ``field`` and listing the names that fit."""
    if name in names(kind):
        return MACHINES[name]
    raise InputError(field, f"unknown '{name}', known: {', '.join(names(kind))}")


def machine_part(name: str, part_name: str, field: str = "machine", **extra):
    """The continuous plant part named ``part_name`` of the built-in machine ``name``: a
    ``CageInductionMachine``, ``PermanentMagnetMachine`` or ``DoublyFedMachine``, the part its
    parameter record was generated from; ``extra`` goes to its ``from_params`` (e.g. a DFIM's
    ``V_loss``)."""
    params = machine_params(name, field=field)
    return type(params).PART.from_params(part_name, params, **extra)
