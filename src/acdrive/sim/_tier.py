"""Which loop runs a system, and what it costs to get it: the tiers of the compiled loop.

* **native**: the whole loop as C (``sim._native``: the parts' C from ``sim._ccode``, the text
  the export writes, and one generated driver), compiled by the machine's C compiler in well under a second for a new
  topology, loaded without numba's dispatcher; as fast per step as the specialised loop and,
  under strict math, bit-identical to it. Single runs take it when every part kind has C and a
  C compiler is present.
* **specialised**: the generated loop of one topology (``sim._loop_source``), kernels inlined
  and offsets literal: the fastest per step, but numba compiles it for every new topology
  (seconds to a quarter of a minute), once per machine.
* **generic**: one loop for every topology (``sim._generic``), compiled once per installation,
  reading the topology from tables and calling each part kind's kernels (``sim._kernels``,
  compiled once per kind) through their addresses: no compile for a new topology built from
  part kinds this machine has compiled before; several times slower per step.

``choose`` picks, at ``System.compile()``: the native loop when it can run the system; else
the specialised loop when it is in the cache (a load);
else the generic loop when every part kind's kernels are (a new topology runs at once, and the
specialised loop compiles in a background process for the runs after); else the specialised
loop, compiled now, with a notice that names the kinds without kernels (they compile in the
background, so the next new topology need not wait). A run long enough that the compile pays
(``pays_to_specialise``), a batch, or ``ACDRIVE_LOOP_TIER=specialised`` compiles the
specialised loop in the foreground; ``ACDRIVE_LOOP_TIER=generic`` insists on the generic one,
``ACDRIVE_LOOP_TIER=native`` on the native one. Batches always run numba's loops (one variant per
core, or the lockstep loop across SIMD lanes).
The tiers give bit-identical results: the same operations in the same order, fast-math flags
that allow no reordering, fusing or reciprocals (``acdrive._jit.FAST_MATH_FLAGS``), and the same
sine, cosine and magnitudes in numba and in C (``sim._lane_math``): ``tests/test_tiers.py``,
``tests/test_native_tier.py``, in the default build and under ACDRIVE_STRICT_MATH=1.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

from acdrive.errors import InputError
from acdrive.sim import _codegen as codegen

TIERS = ("auto", "native", "generic", "specialised")


def _run_args() -> tuple:
    from numba import types

    F1, F2 = types.float64[::1], types.float64[:, ::1]
    I1, I2 = types.int64[::1], types.int64[:, ::1]
    return (F1, F1, I1, F1, F1, F1, types.float64, types.float64, types.int64, types.int64,
            types.int64, I1, F2, I2, I2)  # fmt: skip


def __getattr__(name: str):
    """``RUN_ARGS``: argument types of the loops' ``run`` (as ``CompiledSystem.run`` calls it);
    ``GENERIC_RUN_ARGS``: the generic loop's, the topology's tables after them (``sim._tables``).
    Built on first use, so that importing this module does not import numba."""
    if name == "RUN_ARGS":
        return _run_args()
    if name == "GENERIC_RUN_ARGS":
        from numba import types

        return (*_run_args(), *([types.int64[:, ::1]] * 9), types.int64[::1])
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


#: seconds per (sample x substep x part) of the generic loop when none was measured here yet:
#: thread CPU of its run, 1.1e-7 (bodson-ramp), 1.2e-7 (im-foc-speed), 1.4e-7 (a 4-part IM), on
#: the 2-core machine (``benchmarks/compile_profile.py``, docs/design.md)
_GENERIC_RATE_DEFAULT = 1.2e-7
#: seconds of compile per part of the specialised loop when none was measured here yet: thread
#: CPU 0.9 (bodson-ramp, 13 parts), 1.6 (im-foc-speed, 10), 1.9 (a 4-part IM); more under load
_COMPILE_PER_PART_DEFAULT = 1.5


def chosen() -> str:
    """The tier asked for by ACDRIVE_LOOP_TIER (default ``auto``)."""
    tier = os.environ.get("ACDRIVE_LOOP_TIER", "auto") or "auto"
    if tier not in TIERS:
        raise InputError("ACDRIVE_LOOP_TIER", f"must be one of {', '.join(TIERS)}, got {tier!r}")
    return tier


def kinds_of(system) -> list[type]:
    """The part kinds of ``system``, in the order of first appearance."""
    return list(dict.fromkeys(type(p) for p in system.parts))


def kinds_without_kernels(system) -> list[tuple[type, str]]:
    """(kind, why) for every part kind of ``system`` whose kernels the generic loop cannot call
    without compiling them now."""
    from acdrive.sim import _kernels as kernels

    missing = []
    for kind in kinds_of(system):
        try:
            ready = kernels.kind_ready(kind)
        except TypeError as error:  # a kernel the generator cannot name (not module-level)
            missing.append((kind, str(error)))
            continue
        if not ready:
            missing.append((kind, "not compiled on this machine yet"))
    return missing


def expected_specialised_compile(system) -> float:
    """Seconds the specialised loop of ``system`` is expected to take to compile here."""
    n = len(system.parts)
    measured = codegen.expected_time("specialised", n)
    return measured if measured is not None else _COMPILE_PER_PART_DEFAULT * n


def expected_generic_run(system, n_steps: int, substeps: int) -> float:
    """Seconds the generic loop is expected to take for a run of ``n_steps`` samples."""
    rate = codegen.expected_time("generic-run-rate", 1)
    rate = rate if rate is not None else _GENERIC_RATE_DEFAULT
    return rate * n_steps * substeps * len(system.parts)


def record_generic_run(system, n_steps: int, substeps: int, seconds: float) -> None:
    """Keep the generic loop's measured seconds per (sample x substep x part)."""
    work = n_steps * substeps * len(system.parts)
    if work > 0 and seconds > 0.05:  # too short a run measures the call, not the loop
        codegen.record_time("generic-run-rate", 1, seconds / work)


def pays_to_specialise(system, n_steps: int, substeps: int) -> bool:
    """Whether compiling the specialised loop now costs less than the generic loop's extra time
    on a run of ``n_steps`` samples (the generic loop is several times slower per step)."""
    return expected_generic_run(system, n_steps, substeps) > expected_specialised_compile(system)


def describe_compile(system, why: str) -> str:
    """The notice of a foreground compile of the specialised loop, with the time measured here
    for a loop of this size."""
    n = len(system.parts)
    measured = codegen.expected_time("specialised", n)
    about = (f"about {measured:.2g} s as measured on this machine for {n} parts; "
             if measured is not None else "")  # fmt: skip
    return (f"compiling the specialised simulation loop for this topology once ({about}later "
            f"runs load it): {why}")  # fmt: skip


def compile_generic_tier(system) -> float:
    """Compile now, in this process, what the generic loop needs to run ``system`` (its part
    kinds' kernels and the generic loop itself, each loaded instead if cached): what the
    background compile does after a fallback, for a caller that must not leave a process
    behind (a benchmark). Returns the seconds spent compiling."""
    from acdrive.sim import _generic
    from acdrive.sim import _kernels as kernels

    total = 0.0
    for kind in kinds_of(system):
        total += kernels.addresses(kind)[1]
    seconds, compiled = codegen.compile_for(_generic.run, __getattr__("GENERIC_RUN_ARGS"))
    return total + (seconds if compiled else 0.0)


def background_enabled() -> bool:
    return os.environ.get("ACDRIVE_BACKGROUND_COMPILE", "1") != "0"


def start_background(kinds=(), generic=False, specialised_source=None,
                     size=0) -> subprocess.Popen | None:  # fmt: skip
    """Compile in a background process (``sim._background``): the kernels of ``kinds``, the
    generic loop, the specialised loop of ``specialised_source`` (a generated module's text), so
    that later runs load them. Returns the process, or None when switched off
    (ACDRIVE_BACKGROUND_COMPILE=0) or nothing is to do."""
    job = {
        "kinds": [[k.__module__, k.__qualname__] for k in kinds if k.__module__ != "__main__"],
        "generic": bool(generic),
        "specialised": str(codegen.module_path(specialised_source)) if specialised_source else None,
        "size": int(size),
    }
    if not background_enabled() or not (job["kinds"] or job["generic"] or job["specialised"]):
        return None
    if specialised_source:
        codegen.load_module(specialised_source)  # the file exists before the child reads it
    return subprocess.Popen(
        [sys.executable, "-m", "acdrive.sim._background", json.dumps(job)],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,  # an interrupt of the user's command does not reach it
    )
