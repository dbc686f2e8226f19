"""The one compilation setting of acdrive's compiled code.

``error_model="numpy"``: floating-point division by zero gives inf/NaN instead of raising (and
costs no check per division); the engine checks the state for non-finite values every sample, so
nothing non-finite goes unnoticed. ``cache=True``: a second run does not pay the compile time.
"""

import os

from numba import njit

#: ACDRIVE_STRICT_MATH=1 compiles the fast-math functions with strict IEEE arithmetic instead: the
#: results then depend only on the order of operations written in the source, not on the
#: compiler's choice of contractions, which is how two implementations are compared bit for bit
#: (benchmarks/compare_engines.py). It has its own cache folder (acdrive/__init__.py).
STRICT_MATH = os.environ.get("ACDRIVE_STRICT_MATH") == "1"

jit = njit(cache=True, error_model="numpy")

#: the plant's right-hand side and its integrator: also fast-math (reassociation, fused
#: multiply-add, no NaN/inf special cases inside); the engine checks finiteness outside it.
jit_fast = njit(cache=True, error_model="numpy", fastmath=not STRICT_MATH)

#: small helpers of the plant's kernels: inlined into the compiled loop at numba-IR level (numba
#: does not inline one compiled function into another by itself; a call per table lookup or per
#: current computation costs more than the arithmetic)
jit_inline = njit(cache=True, error_model="numpy", fastmath=not STRICT_MATH, inline="always")
