"""Which loop runs a system, and what it costs to get it: the tiers of the compiled loop.

* **native**: the whole loop as C (``sim._native``: the parts' C generated from their kernels by
  ``sim._ccode``, the text the export writes, and one generated driver), compiled by the
  machine's C compiler in well under a second for a new topology, loaded without numba's
  dispatcher; as fast per step as the specialised loop and bit-identical to it. Single runs take
  it when every part kind's kernels translate to C and a C compiler is present.
* **specialised**: numba's generated loop of one topology (``sim._loop_source``), kernels
  inlined and offsets literal: as fast per step, but numba compiles it for every new topology
  (seconds to a quarter of a minute), once per machine. It runs a system the native loop cannot
  (no C compiler, or a part whose kernel is outside the language the translator takes; the
  notice of its compile names the reason), and every batch (one variant per core, or the
  lockstep loop across SIMD lanes, ``sim._lockstep_source``).

``CompiledSystem`` takes the native loop when it can run the system, else the specialised loop
(a load when it is in the cache). ``ACDRIVE_LOOP_TIER=native`` insists on the native loop (an
error naming the obstacle otherwise), ``ACDRIVE_LOOP_TIER=specialised`` on numba's.
Both loops expand the same Runge-Kutta tableau (``sim._rk_source``) around the same kernels and
give bit-identical results: the same operations in the same order, fast-math flags that allow
no reordering, fusing or reciprocals (``acdrive._jit.FAST_MATH_FLAGS``), and the same sine,
cosine and magnitudes in numba and in C (``sim._lane_math``): ``tests/test_native_tier.py``, in
the default build and under ACDRIVE_STRICT_MATH=1.
"""

from __future__ import annotations

import os

from acdrive.errors import InputError
from acdrive.sim import _codegen as codegen

TIERS = ("auto", "native", "specialised")


def _run_args() -> tuple:
    from numba import types

    F1, F2 = types.float64[::1], types.float64[:, ::1]
    I1, I2 = types.int64[::1], types.int64[:, ::1]
    return (F1, F1, I1, F1, F1, F1, types.float64, types.float64, types.int64, types.int64,
            types.int64, I1, F2, I2, I2)  # fmt: skip


def __getattr__(name: str):
    """``RUN_ARGS``: argument types of the loops' ``run`` (as ``CompiledSystem.run`` calls it),
    built on first use, so that importing this module does not import numba."""
    if name == "RUN_ARGS":
        return _run_args()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


#: seconds of compile per part of the specialised loop when none was measured here yet: thread
#: CPU 0.9 (bodson-ramp, 13 parts), 1.6 (im-foc-speed, 10), 1.9 (a 4-part IM); more under load
_COMPILE_PER_PART_DEFAULT = 1.5


def chosen() -> str:
    """The tier asked for by ACDRIVE_LOOP_TIER (default ``auto``)."""
    tier = os.environ.get("ACDRIVE_LOOP_TIER", "auto") or "auto"
    if tier not in TIERS:
        raise InputError("ACDRIVE_LOOP_TIER", f"must be one of {', '.join(TIERS)}, got {tier!r}")
    return tier


def describe_compile(system, why: str) -> str:
    """The notice of a foreground compile of the specialised loop, with the time measured here
    for a loop of this size."""
    n = len(system.parts)
    measured = codegen.expected_time("specialised", n)
    about = (f"about {measured:.2g} s as measured on this machine for {n} parts; "
             if measured is not None else "")  # fmt: skip
    return (f"compiling the specialised simulation loop for this topology once ({about}later "
            f"runs load it): {why}")  # fmt: skip
