"""The catalog of built-in part kinds: every ``core.Part`` subclass exported by the public
namespaces ``acdrive.machines``, ``acdrive.plant`` and ``acdrive.control``.

Found by reading the namespaces' exports (nothing is listed by hand), so a new part appears here,
in ``acdrive parts`` and in the API test as soon as its namespace exports it. Only names that
look like classes (a capital, not all capitals) are imported: constants and functions are left
alone, and the modules that hold only functions are not imported at all.
"""

from __future__ import annotations

import difflib
import importlib

from acdrive.errors import InputError

#: the public namespaces whose part kinds are built-in
NAMESPACES = ("acdrive.machines", "acdrive.plant", "acdrive.control")


def _looks_like_class(name: str) -> bool:
    return name[:1].isupper() and not name.isupper()


def part_kinds() -> dict[str, type]:
    """Built-in part kind name -> class, in namespace order, then alphabetical."""
    from acdrive.core._parts import Part

    found: dict[str, type] = {}
    for package in NAMESPACES:
        module = importlib.import_module(package)
        for name in module.__all__:
            if not _looks_like_class(name):
                continue
            obj = getattr(module, name)
            if isinstance(obj, type) and issubclass(obj, Part):
                found[name] = obj
    return found


def namespace_of(cls: type) -> str:
    """The public namespace a built-in part kind is imported from."""
    for package in NAMESPACES:
        module = importlib.import_module(package)
        if getattr(module, cls.__name__, None) is cls:
            return package
    return cls.__module__


def find_part_kind(name: str, field: str = "part") -> type:
    """The built-in part kind ``name``, else an InputError naming ``field`` with the close names
    (or, if none is close, all of them)."""
    kinds = part_kinds()
    if name in kinds:
        return kinds[name]
    by_lower = {k.lower(): k for k in kinds}
    if name.lower() in by_lower:  # a case slip: name the one meant
        close = [by_lower[name.lower()]]
    else:
        close = difflib.get_close_matches(name, list(kinds), n=4, cutoff=0.6)
    if close:
        raise InputError(field, f"no part kind {name!r}; did you mean {', '.join(close)}?")
    raise InputError(field, f"no part kind {name!r}; the built-in kinds: {', '.join(kinds)}")
