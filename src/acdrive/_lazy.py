"""Lazy public namespaces for acdrive's subpackages (PEP 562).

A subpackage's ``__init__`` lists its public names and the module each lives in; the module is
imported on first access of the name. Importing ``acdrive.machines._dfim`` therefore does not
import every other machine module (nor numba), the import order between subpackages cannot form a
cycle, and ``from acdrive.machines import DFIMParams`` works as users expect.
"""

from __future__ import annotations

import importlib


def namespace(package: str, exports: dict[str, str]):
    """``(__all__, __getattr__, __dir__)`` for ``package`` whose public names are ``exports``:
    name -> module (relative to the package, e.g. ``".dfim"``)."""
    names = sorted(exports)

    def __getattr__(name: str):
        try:
            module = exports[name]
        except KeyError:
            raise AttributeError(f"module {package!r} has no attribute {name!r}") from None
        return getattr(importlib.import_module(module, package), name)

    def __dir__():
        return names

    return names, __getattr__, __dir__
