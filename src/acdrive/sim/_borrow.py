"""Borrowed views of float arrays for the generated loop: no reference counting per slice.

Every slice a compiled function takes (``X[3:10]`` for one part's states) is a new array view, and
numba counts references to the owner's memory with atomic operations when a view is made and
dropped. The generated loop slices the system arrays for every part at every right-hand-side
evaluation, so those atomics would cost more than the physics. ``borrowed(a)`` is an array over
the same memory without an owner: its slices need no counting. The caller must keep ``a`` alive
for as long as the borrowed array is used (the generated ``run`` uses the owners after its loop).
"""

from __future__ import annotations

import numpy as np
from numba import carray, njit, types
from numba.core import cgutils
from numba.extending import intrinsic


@intrinsic
def _pointer(typingctx, address):
    """The integer ``address`` as a void pointer."""
    signature = types.voidptr(address)

    def codegen(context, builder, sig, args):
        return builder.inttoptr(args[0], cgutils.voidptr_t)

    return signature, codegen


@njit(cache=True)
def borrowed(a):
    """A float64 array over the memory of ``a`` (C-contiguous) that owns nothing."""
    return carray(_pointer(a.ctypes.data), a.shape, np.float64)
