"""The C implementation of each part kind: registries keyed by the part's class.

Each entry is a :class:`CStep`: the body of the kind's step function in C and the support code
it calls. A kind whose kernel is in the kernel language has its C generated from the kernel
(``sim._ccode._translate.c_step``, ``from_kernel``; ``tests/test_kernel_translation.py`` checks
C against kernel bit for bit on random draws); the others carry a hand-written body, a second
implementation of the kernel kept equal to it by the software-in-the-loop and native-tier tests
(``tests/test_export_sil.py``, ``tests/test_native_tier.py``). The generator writes the function's
signature from the kind's declarations, so the body reads its inputs as ``u->name``, its
parameters as ``p->name``, its discrete state as ``s->name`` and writes its outputs as
``y->name`` (a complex quantity is an ``acd_complex`` with ``.re`` and ``.im``; a table
``p->name`` has ``.n`` points ``.t[i]``, ``.v[i]``); ``t`` is the sample instant and ``T_s`` the
sample period; it returns the event bits (``ACD_<KIND>_<EVENT>`` masks, from ``EVENTS``).

A kind is looked up by its exact class. A class with no entry (a user's own part, a subclass)
gets its C generated from its kernels on its first look-up (``sim._ccode._translate``) and
registered; a kernel outside the kernel language leaves it without C, and the refusal names
the kernel, its line and the construct.

Plant kinds (continuous parts and modulators, for the plant C, ``sim._ccode._plant_source``)
have a second registry of :class:`PlantC` entries, the same seam: bodies written against the
structs the generator declares from the kind's layouts (``p->``, ``x->`` its continuous state,
``u->``, ``y->``, ``dx->`` the derivative of the state; a modulator's ``s->``, ``dt[i]`` and
``v[i]``, the outputs of segment i).

Where the C is written: the engine's own kinds (the parts of ``core``, ``plant``, ``machines`` and
``control``) in the modules of this package, registered on the first look-up; a kind defined
above the engine (a drive's own controller) in a module of its own package, which its class
names as ``C_MODULE`` (``Part.C_MODULE``): a look-up that finds no entry for the class imports
that module, whose import registers the kind. The registry names no such module itself.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass

from acdrive.errors import InputError


@dataclass(frozen=True)
class CSupport:
    """A piece of C (static functions, macros) that step bodies may call; ``needs`` lists the
    pieces it calls in turn. A kind's ``support`` and a piece's ``needs`` say where a file may
    draw its helpers from; the file holds, once whatever the number of kinds that use it, each
    definition of them its code calls, and no other (``sim._ccode._helpers``)."""

    name: str
    code: str
    needs: tuple[CSupport, ...] = ()


@dataclass(frozen=True)
class CStep:
    """The C of one part kind's step: ``body`` (statements, returning the event bits; or a
    function of the part instance giving them, for a kind whose layout is set per instance,
    such as a controller of any order), ``support`` (what it calls) and ``source`` (paper and
    equations it implements)."""

    body: object
    source: str
    support: tuple[CSupport, ...] = ()
    #: True when ``body`` is generated from the kind's kernel (``sim._ccode._translate``)
    from_kernel: bool = False


@dataclass(frozen=True)
class PlantC:
    """The C of one plant kind. A continuous part: ``state_outputs`` (writes ``y`` from ``x``),
    ``direct_outputs`` (for a kind with direct outputs: writes them from ``x`` and the inputs
    ``u`` it declares in ``DIRECT_FROM``), ``rhs`` (writes ``dx``; may read ``u`` and its own
    ``y`` of the same evaluation; None for a part without states), ``project`` (re-normalises
    redundant states ``x`` at each sample, for a kind with a ``project`` kernel). A modulator:
    ``segments`` (writes ``*n`` segments ``dt[i]``, ``v[i]``, returns the event bits). Each
    body is a text, or a function of the part instance giving it (a kind whose inputs are set
    per instance, such as a bus of n machines). ``source``: paper and equations; ``support``:
    what they call."""

    source: str
    state_outputs: object = None
    rhs: object = None
    segments: object = None
    project: object = None
    direct_outputs: object = None
    support: tuple[CSupport, ...] = ()
    #: True when the bodies are generated from the kind's kernels (``sim._ccode._translate``)
    from_kernel: bool = False

    def role(self, name: str, part) -> str | None:
        """The body of kernel role ``name`` for ``part`` (None: the kind has no such body)."""
        body = getattr(self, name)
        return body(part) if callable(body) else body

    def body(self, part) -> str:
        """All bodies of ``part`` as one text (``_c_source.kind_types`` compares the instances'
        C)."""
        return "\n".join(self.role(r, part) or "" for r in PLANT_ROLES)


#: the kernel roles of a plant kind, in the order the generated file defines them
PLANT_ROLES = ("state_outputs", "direct_outputs", "rhs", "segments", "project")


#: the modules whose import registers the engine's own kinds (imported on the first look-up)
_MODULES = (
    "acdrive.sim._ccode._kinds.sensors",
    "acdrive.sim._ccode._kinds.bodson",
    "acdrive.sim._ccode._kinds.foc",
    "acdrive.sim._ccode._kinds.plant",
)
_REGISTRY: dict[type, CStep] = {}
_PLANT_REGISTRY: dict[type, PlantC] = {}
_loaded = False


def register(kind: type, step: CStep) -> None:
    """Give part class ``kind`` its C step."""
    _REGISTRY[kind] = step


def register_plant(kind: type, c: PlantC) -> None:
    """Give plant part class ``kind`` (continuous part or modulator) its C."""
    _PLANT_REGISTRY[kind] = c


def _load() -> None:
    global _loaded
    if not _loaded:
        for module in _MODULES:
            importlib.import_module(module)
        _loaded = True


#: kind -> why its C cannot be generated from its kernels (``sim._ccode._translate``)
_UNTRANSLATABLE: dict[type, str] = {}


def _entry(registry: dict, kind: type):
    """``kind``'s entry in ``registry``, after importing the module the class names as
    ``C_MODULE`` if it has none yet; a kind with neither (a user's own part) gets its C
    generated from its kernels and registered (None: no C, the reason in ``untranslatable``)."""
    entry = registry.get(kind)
    module = getattr(kind, "C_MODULE", None)
    if entry is None and module:
        importlib.import_module(module)
        entry = registry.get(kind)
    if entry is None and kind not in _UNTRANSLATABLE:
        entry = _generated(registry, kind)
    return entry


def _generated(registry: dict, kind: type):
    """The C of ``kind`` generated from its kernels and registered, or None (the reason kept)."""
    from acdrive.core._parts import SampledPart
    from acdrive.sim._ccode._translate import UnsupportedKernel, c_plant, c_step

    source = f"{kind.__module__}.{kind.__qualname__}, generated from its kernels"
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
    _load()
    step = _entry(_REGISTRY, type(part))
    if step is None:
        raise _no_c(part, "the chain")
    return step


def plant_c_of(part) -> PlantC:
    """The C of plant ``part``'s kind, or an InputError naming the part and the rule."""
    _load()
    c = _entry(_PLANT_REGISTRY, type(part))
    if c is None:
        raise _no_c(part, "the plant")
    return c


def exportable_kinds() -> list[str]:
    """Names of the part kinds whose C step is registered: the engine's own, and a kind with a
    ``C_MODULE`` once that module has been imported (a look-up of one of its parts does)."""
    _load()
    return sorted(k.__name__ for k in _REGISTRY)
