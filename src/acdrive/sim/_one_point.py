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
measured slower; docs/design.md, "Lockstep").

A helper reached as a module attribute (``module.helper``) is not rebound: it keeps the search,
which is slower in a lane loop, never wrong.
"""

from __future__ import annotations

import types

from numba import njit
from numba.core.registry import CPUDispatcher

from acdrive._jit import LazyKernel, jit_inline
from acdrive.core import _tables


@jit_inline
def table_at_one_point(p, offset, t):
    """``table_at`` of a one-point table ``[1, t_0, v_0]`` at ``offset``: ``v_0`` at every t."""
    return p[offset + 2]


_REPLACED = {id(_tables.table_at): table_at_one_point}
_MADE: dict[int, object] = {}


def _rebound(value):
    """``value`` with one-point lookups, or None if it makes no table lookup."""
    replacement = _REPLACED.get(id(value))
    if replacement is not None:
        return replacement
    options = _jit_options(value)
    if options is not None and value.py_func.__module__.startswith("acdrive."):
        if id(value) not in _MADE:
            _MADE[id(value)] = None  # a recursive helper: searched once
            function = _rebind(value.py_func)
            if function is not None:
                _MADE[id(value)] = njit(**options)(function)
        return _MADE[id(value)]
    return None


def _jit_options(value) -> dict | None:
    """The compile options of a jitted function (acdrive's ``LazyKernel`` or a numba
    dispatcher) but caching (a copy made at run time has no file of its own); None otherwise."""
    if isinstance(value, LazyKernel):
        options = value._options
    elif isinstance(value, CPUDispatcher):
        options = value.targetoptions
    else:
        return None
    return {k: v for k, v in options.items() if k != "cache"}


def _rebind(function):
    """A copy of the Python ``function`` whose globals give one-point lookups (None if neither
    it nor the acdrive helpers it calls look a table up)."""
    changes = {}
    for name in function.__code__.co_names:
        if name in function.__globals__:
            new = _rebound(function.__globals__[name])
            if new is not None:
                changes[name] = new
    if not changes:
        return None
    copy = types.FunctionType(function.__code__, {**function.__globals__, **changes},
                              function.__name__, function.__defaults__, function.__closure__)  # fmt: skip
    copy.__kwdefaults__ = function.__kwdefaults__
    copy.__qualname__ = function.__qualname__
    return copy


def one_point_kernel(function):
    """The Python ``function`` of a kernel (a dispatcher's ``py_func``) with one-point table
    lookups (module docstring); ``function`` itself if it looks no table up."""
    return _rebind(function) or function
