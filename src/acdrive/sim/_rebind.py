"""A kernel compiled with some of the functions it calls replaced: the seam through which every
generated loop gives its kernels acdrive's elementary functions (``sim._lane_math``, the same in
every tier), and the lockstep loop its one-point table lookups (``sim._one_point``).

A replacement table maps ``id(original)`` to its replacement: a compiled function
(``sim._one_point``: ``table_at`` by its one-point form) or a module (``sim._lane_math``: numpy
by a namespace with sin, cos, abs and sqrt that make no library call).
``rebound_kernel(function, *tables)`` is a copy of the Python ``function`` whose globals hold
the replacements; the acdrive helpers it calls
(compiled functions of acdrive's modules) are copied the same way, recursively, so a
replacement reaches the helper that makes the call. Each copy is compiled with its original's
options, caching aside (a copy made at run time has no file of its own).

A helper reached as a module attribute (``module.helper``) is not rebound, nor is a function
outside acdrive: it keeps the original, which is slower in a lane loop, never wrong.
"""

from __future__ import annotations

import types

from numba import njit
from numba.core.registry import CPUDispatcher

from acdrive._jit import LazyKernel

#: the copies made, per (tables, original): a helper is copied once per table set
_MADE: dict[tuple, object] = {}


def _jit_options(value) -> dict | None:
    """The compile options of a jitted function (acdrive's ``LazyKernel`` or a numba
    dispatcher) but caching; None for anything else."""
    if isinstance(value, LazyKernel):
        options = value._options
    elif isinstance(value, CPUDispatcher):
        options = value.targetoptions
    else:
        return None
    return {k: v for k, v in options.items() if k not in ("cache", "nopython")}


def _rebound(value, replaced: dict, key: tuple):
    """``value`` with the replacements, or None if neither it nor what it calls has any."""
    replacement = replaced.get(id(value))
    if replacement is not None:
        return replacement
    options = _jit_options(value)
    if options is not None and value.py_func.__module__.startswith("acdrive."):
        made = (key, id(value))
        if made not in _MADE:
            _MADE[made] = None  # a recursive helper: searched once
            function = _rebind(value.py_func, replaced, key)
            if function is not None:
                _MADE[made] = njit(**options)(function)
        return _MADE[made]
    return None


def _rebind(function, replaced: dict, key: tuple):
    """A copy of the Python ``function`` whose globals hold the replacements (None if neither
    it nor the acdrive helpers it calls use any of the originals)."""
    changes = {}
    for name in function.__code__.co_names:
        if name in function.__globals__:
            new = _rebound(function.__globals__[name], replaced, key)
            if new is not None:
                changes[name] = new
    if not changes:
        return None
    copy = types.FunctionType(function.__code__, {**function.__globals__, **changes},
                              function.__name__, function.__defaults__, function.__closure__)  # fmt: skip
    copy.__kwdefaults__ = function.__kwdefaults__
    copy.__qualname__ = function.__qualname__
    return copy


def rebound_kernel(function, *tables: dict):
    """The Python ``function`` of a kernel (a dispatcher's ``py_func``) with the replacements of
    ``tables`` (module docstring); ``function`` itself if it uses none of the originals."""
    replaced = {k: v for table in tables for k, v in table.items()}
    key = tuple(sorted(replaced))
    return _rebind(function, replaced, key) or function
