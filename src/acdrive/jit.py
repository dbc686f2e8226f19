"""The one compilation setting of acdrive's compiled code.

``error_model="numpy"``: floating-point division by zero gives inf/NaN instead of raising (and
costs no check per division); the engine checks the state for non-finite values every sample, so
nothing non-finite goes unnoticed. ``cache=True``: a second run does not pay the compile time.
"""

from numba import njit

jit = njit(cache=True, error_model="numpy")

#: the plant's right-hand side and its integrator: also fast-math (reassociation, fused
#: multiply-add, no NaN/inf special cases inside); the engine checks finiteness outside it.
jit_fast = njit(cache=True, error_model="numpy", fastmath=True)
