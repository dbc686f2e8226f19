"""Controllers exported as C99 and run in acdrive's loop (software in the loop).

``to_c(system, sample_time, initial, held)`` writes the sampled controller chains of a system
as one header and one source (the engine's C generator, ``acdrive.sim._ccode._c_source``, which
the native tier of the loop compiles too); ``run_in_loop`` compiles them with the system's C
compiler and runs them in place of the compiled sampled parts (``acdrive.export._sil``);
``target_report(targets)`` (a case or a scenario) and ``board_cost(compiled, export, ...)`` (any
system's export) cross-compile the float build for a Cortex-M4F and count its instructions per
step on QEMU's board model (``acdrive.export._cost``, ``_target``). docs/guide/export.md
describes the files and the checks.
"""

from acdrive._arguments import FLAG, POSITIVE, TEXT, Instance, Table, Text, checked
from acdrive.export._cost import board_cost, target_report
from acdrive.export._sil import run_in_loop
from acdrive.sim._ccode import _c_source
from acdrive.sim._ccode._c_source import CExport

#: the engine's generator (``acdrive.sim._ccode._c_source.to_c``) with its arguments checked
to_c = checked(
    system=Instance(
        "acdrive.sim._system:System",
        what="a System (acdrive.sim.System): the export reads the chain's inputs and commands "
        "from the System's wiring, which a list of parts has not; build one from the parts first",
    ),
    sample_time=POSITIVE,
    initial=Table(Table(empty=True), empty=True, optional=True),
    held=Table(Table(empty=True), empty=True, optional=True),
    name=TEXT,
    description=Text(empty=True),
    open_loop=FLAG,
    values=FLAG,
)(_c_source.to_c)

__all__ = ["CExport", "board_cost", "run_in_loop", "target_report", "to_c"]
