"""Kernels whose profile tables all have one point, without the table search.

A part's profile (``core._tables``) is searched by ``table_at``: a loop whose length depends on
the data. In the lockstep loop (``sim._lockstep_source``) a loop inside a kernel keeps the whole
lane loop around it scalar, and the supply's and the shaft's kernels look a table up in every
right-hand side. Most batches keep such a profile constant (one point) in every variant. For a
part whose tables have one point in every variant of a group, the lockstep source calls
``one_point_kernel(kernel)``: the same Python function, compiled with ``table_at`` (called
directly, or through the acdrive helpers it calls) replaced by its one-point form, which returns
the same number bit for bit: a one-point table ``[1, t_0, v_0]`` gives ``v_0`` at every time
(``table_at``'s first branch). ``table_offset`` stays: at a call site its count of tables is a
constant, so its loop unrolls (replacing it too by the fixed offsets of one-point tables was
measured slower; docs/speed.md, "The batch loops").

The replacement goes through ``sim._rebind``, which also reaches the acdrive helpers a kernel
calls; a helper reached as a module attribute (``module.helper``) keeps the search, which is
slower in a lane loop, never wrong.
"""

from __future__ import annotations

from acdrive._jit import jit_inline
from acdrive.core import _tables
from acdrive.sim._rebind import rebound_kernel


@jit_inline
def table_at_one_point(p, offset, t):
    """``table_at`` of a one-point table ``[1, t_0, v_0]`` at ``offset``: ``v_0`` at every t."""
    return p[offset + 2]


#: the rebinding table (``sim._rebind``): ``table_at`` by its one-point form
ONE_POINT = {id(_tables.table_at): table_at_one_point}


def one_point_kernel(function):
    """The Python ``function`` of a kernel (a dispatcher's ``py_func``) with one-point table
    lookups (module docstring); ``function`` itself if it looks no table up."""
    return rebound_kernel(function, ONE_POINT)
