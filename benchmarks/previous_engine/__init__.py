"""The previous hand-wired DFIM engine, frozen: the same-run baseline of the benchmarks.

acdrive's DFIM drive used to be one compiled loop with hand-numbered arrays (``sim/engine.py``,
``plant/dfim_bus.py``, the array controller of ``control/_dfim.py`` and ``build_arrays`` of
``sim/_setup.py``, as of commit 78310a8). The package now runs the drive built from parts
(``acdrive.drives.dfim._drive``); this copy of the previous engine is kept here, outside the package,
only so that ``benchmarks/compare_engines.py`` (equivalence) and ``benchmarks/bench_system.py``
(speed) can measure the new engine against it in the same run. The physics functions it calls
(``acdrive.machines._dfim``, ``acdrive.control._speed``, ...) are the package's own.
"""

from .arrays import simulate_previous_engine

__all__ = ["simulate_previous_engine"]
