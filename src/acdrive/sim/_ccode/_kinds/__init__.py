"""The C of each part kind: registries keyed by the part's class, filled on a kind's first
look-up.

Each entry is generated from the kind's kernels (``sim._ccode._kind_c``; every entry is
``from_kernel``, and ``tests/test_kernel_translation.py`` checks C against kernel bit for bit on
random draws), built-in kinds and a user's own alike, and names what it implements (the class's
``SOURCE``). A sampled kind's entry is a :class:`CStep`: the body of its step function, which
reads its inputs as ``u->name``, its parameters as ``p->name``, its discrete state as
``s->name`` and writes its outputs as ``y->name`` (a complex quantity is an ``acd_complex`` with
``.re`` and ``.im``; a table ``p->name`` has ``.n`` points ``.t[i]``, ``.v[i]``); ``t`` is the
sample instant and ``T_s`` the sample period; it returns the event bits (``ACD_<KIND>_<EVENT>``
masks, from ``EVENTS``). A kind whose kernel is outside the kernel language has no entry; the
refusal names the kernel, its line and the construct (``untranslatable``).

Plant kinds (continuous parts and modulators, for the plant C, ``sim._ccode._plant_source``)
have a second registry of :class:`PlantC` entries: bodies against the structs the generator
declares from the kind's layouts (``p->``, ``x->`` its continuous state, ``u->``, ``y->``,
``dx->`` the derivative of the state; a modulator's ``s->``, ``dt[i]`` and ``v[i]``, the outputs
of segment i).

The registry imports no part kind: the engine names no concrete part to give it C.
"""

from __future__ import annotations

from acdrive.errors import InputError
from acdrive.sim._ccode._pieces import PLANT_ROLES, CStep, CSupport, PlantC

__all__ = ["PLANT_ROLES", "CStep", "CSupport", "PlantC", "c_step_of", "plant_c_of", "register",
           "register_plant", "untranslatable"]


_REGISTRY: dict[type, CStep] = {}
_PLANT_REGISTRY: dict[type, PlantC] = {}


def register(kind: type, step: CStep) -> None:
    """Give part class ``kind`` its C step."""
    _REGISTRY[kind] = step


def register_plant(kind: type, c: PlantC) -> None:
    """Give plant part class ``kind`` (continuous part or modulator) its C."""
    _PLANT_REGISTRY[kind] = c


#: kind -> why its C cannot be generated from its kernels (``sim._ccode._translate``)
_UNTRANSLATABLE: dict[type, str] = {}


def _entry(registry: dict, kind: type):
    """``kind``'s entry in ``registry``, generated from its kernels and registered on its first
    look-up (None: no C, the reason in ``untranslatable``)."""
    entry = registry.get(kind)
    if entry is None and kind not in _UNTRANSLATABLE:
        entry = _generated(registry, kind)
    return entry


def _generated(registry: dict, kind: type):
    """The C of ``kind`` generated from its kernels and registered, or None (the reason kept)."""
    from acdrive.core._parts import SampledPart
    from acdrive.sim._ccode._kind_c import c_plant, c_step
    from acdrive.sim._ccode._translate import UnsupportedKernel

    source = f"{kind.SOURCE or f'{kind.__module__}.{kind.__qualname__}'}, generated from its kernels"
    try:
        if issubclass(kind, SampledPart):
            entry = c_step(kind, source) if registry is _REGISTRY else None
        else:
            entry = c_plant(kind, source) if registry is _PLANT_REGISTRY else None
        if entry is None:
            return None
    except UnsupportedKernel as exc:
        _UNTRANSLATABLE[kind] = str(exc)
        return None
    except Exception as exc:  # noqa: BLE001 (a kernel the translator stumbles on runs in numba)
        _UNTRANSLATABLE[kind] = f"the translator could not read it ({type(exc).__name__}: {exc})"
        return None
    registry[kind] = entry
    return entry


def untranslatable(kind: type) -> str | None:
    """Why ``kind``'s kernels gave no C (None: they did, or were not tried)."""
    return _UNTRANSLATABLE.get(kind)


def _no_c(part, what: str) -> InputError:
    why = untranslatable(type(part))
    return InputError(
        part.name,
        f"part kind {type(part).__name__} has no C implementation, so {what} cannot be "
        f"exported: " + (f"its kernel is outside the kernel language ({why})" if why else
                         "no C is registered for it"),
    )  # fmt: skip


def c_step_of(part) -> CStep:
    """The C step of ``part``'s kind, or an InputError naming the part and the rule."""
    step = _entry(_REGISTRY, type(part))
    if step is None:
        raise _no_c(part, "the chain")
    return step


def plant_c_of(part) -> PlantC:
    """The C of plant ``part``'s kind, or an InputError naming the part and the rule."""
    c = _entry(_PLANT_REGISTRY, type(part))
    if c is None:
        raise _no_c(part, "the plant")
    return c
