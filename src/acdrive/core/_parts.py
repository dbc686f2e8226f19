"""Parts: the components a system is built from, each declaring its signals once.

Three kinds, with a hard boundary between the continuous plant and the sampled controller
(GUIDE, "Parts and systems"):

* :class:`ContinuousPart` (machine, mechanics, supply, network): continuous states integrated
  between samples. Kernels, all module-level numba functions with fixed signatures:
  ``state_outputs(t, x, p, y)`` writes the outputs that depend on the state only;
  ``direct_outputs(t, x, u, p, y)`` (optional) writes the rest, reading only the inputs named in
  ``DIRECT_FROM``; ``rhs(t, x, u, p, y, dx)`` writes dx/dt, and may read the part's own
  outputs ``y`` of the same evaluation (computed just before it) instead of recomputing them;
  ``project(x, p)`` (optional) re-normalises redundant states (e.g. unit phasors) at each sample.
* :class:`Modulator` (converter, inverter): turns a sampled command into piecewise-constant plant
  inputs within one sample, ``segments(T_s, u, p, s, dt, v) -> (n, events)`` with segment
  lengths in ``dt[:n]`` (summing to T_s) and output values in ``v[:n, :]``. The averaged converter
  gives one segment; a switching inverter gives several, with exact switching instants.
* :class:`SampledPart` (sensor, estimator, controller): sees samples only,
  ``step(t, T_s, u, p, s, y) -> events`` updates its discrete state ``s`` and writes its
  outputs (``T_s`` is the sample period of the run).

Outputs of sampled parts and modulators are held between samples (zero-order hold); before the
first sample they hold the values of ``held_outputs()`` (zero unless a part says otherwise, e.g. a
relay that starts closed), which a run may override.

Continuous-part kernels run in the integrator, compiled without numba's reference counting for
speed: they must not allocate arrays (``np.zeros``, array arithmetic); numba refuses such a kernel
when the system compiles. Modulators and sampled parts may allocate (better not, for speed).

A part instance has a name (one identifier, unique in its system) and its parameter values,
packed and validated against ``PARAMS`` at construction (an ``InputError`` naming
``<part>.<field>``). Ports are obtained from the declarations (``part.out.v_s``,
``part.inp.v_r``), never typed as strings in a wiring.
"""

from __future__ import annotations

import types
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from acdrive.core import _describe
from acdrive.core._signals import Layout, Var
from acdrive.errors import InputError

EMPTY = Layout()


@dataclass(frozen=True)
class Port:
    """One declared input or output of one part instance."""

    part: Part
    var: Var
    direction: str  # "in" or "out"

    @property
    def path(self) -> str:
        return f"{self.part.name}.{self.var.name}"

    def __repr__(self) -> str:
        return f"<{self.direction}put {self.path} [{self.var.unit or '-'}, {self.var.kind}]>"


class _Ports:
    """Attribute access to a part's ports: ``part.out.i_s``; unknown names raise at once."""

    def __init__(self, part: Part, layout: Layout, direction: str):
        self._part, self._layout, self._direction = part, layout, direction

    def __getattr__(self, name: str) -> Port:
        if name.startswith("_"):
            raise AttributeError(name)
        if name not in self._layout:
            kind = "input" if self._direction == "in" else "output"
            declared = ", ".join(v.name for v in self._layout) or "none"
            raise InputError(
                f"{self._part.name}.{name}",
                f"{self._part.name} has no {kind} {name} (declared: {declared})",
            )
        return Port(self._part, self._layout.var(name), self._direction)

    def __iter__(self):
        return (Port(self._part, v, self._direction) for v in self._layout)

    def __dir__(self):
        return [v.name for v in self._layout]

    def __repr__(self) -> str:
        return _describe.ports_repr(self._part.name, self._layout, self._direction)


class _KindOrInstanceMethod:
    """A method bound to the instance when called on one, else to the class: ``part.describe()``
    shows the values, ``PartKind.describe()`` the defaults."""

    def __init__(self, function):
        self.function = function
        self.__doc__ = function.__doc__

    def __get__(self, instance, owner):
        return types.MethodType(self.function, owner if instance is None else instance)


class Part:
    """Base of every part. Subclasses set the layouts, the kernels and ``DEFAULTS``."""

    KIND = ""
    PARAMS: Layout = EMPTY
    STATES: Layout = EMPTY
    INPUTS: Layout = EMPTY
    OUTPUTS: Layout = EMPTY
    #: parameter defaults (name -> value); a parameter without default must be given
    DEFAULTS: ClassVar[dict] = {}
    #: initial state defaults (name -> value); every state not listed starts at zero
    INITIAL: ClassVar[dict] = {}
    #: names of the event bits the kernels return (bit i is EVENTS[i])
    EVENTS: tuple[str, ...] = ()
    #: layouts the constructor sets per instance (attribute -> what decides them, e.g.
    #: ``{"INPUTS": "one i_s, a, b per machine (n_machines)"}``), told as such by ``describe()``
    PER_INSTANCE: ClassVar[dict] = {}
    #: the paper and equations (or the model) the kind's kernels implement, named in the C
    #: generated from them (``sim._ccode``)
    SOURCE: ClassVar[str] = ""

    def __init_subclass__(cls, **kwargs):
        """Append the declarations table to the class docstring (``help()``, API reference)."""
        super().__init_subclass__(**kwargs)
        cls._own_doc = _describe.own_doc(cls)
        cls.__doc__ = _describe.class_docstring(cls)
        # None: an own constructor's signature is its own, not a parent's generated one
        cls.__signature__ = _describe.signature(cls) if cls.__init__ is Part.__init__ else None

    def __init__(self, name: str, **params):
        if not isinstance(name, str) or not name.isidentifier():
            raise InputError("name", f"a part name must be an identifier, got {name!r}")
        self.name = name
        self.values = {**self.DEFAULTS, **params}
        self.p = self.PARAMS.pack(name, self.values)
        self.check()
        self.out = _Ports(self, self.OUTPUTS, "out")
        self.inp = _Ports(self, self.INPUTS, "in")

    def check(self) -> None:
        """Cross-field rules on ``self.values`` (raise ``InputError`` naming ``<part>.<field>``);
        rules on single values are declared with the parameter (``Var.rule``)."""

    def check_run(self, sample_time: float) -> None:
        """Rules that involve the run's control sample time (raise ``InputError`` naming the
        field), e.g. a PWM period that must be a whole number of samples; checked before every
        run."""

    def initial_state(self, **values) -> np.ndarray:
        """Packed initial state: ``INITIAL`` defaults, then ``values``, zero elsewhere."""
        merged = {v.name: 0.0 for v in self.STATES}
        merged.update(self.INITIAL)
        merged.update(values)
        return self.STATES.pack(f"{self.name} initial state", merged)

    def held_outputs(self) -> dict:
        """Output values held before the first sample (sampled parts and modulators only):
        output name -> value; outputs not listed hold zero."""
        return {}

    def with_params(self, **changes) -> Part:
        """A copy with some parameters changed (validated again)."""
        clone = object.__new__(type(self))
        clone.__dict__.update(self.__dict__)
        Part.__init__(clone, self.name, **{**self.values, **changes})
        return clone

    def kernels(self) -> dict:
        """Kernel role -> numba function, for the code generator."""
        raise NotImplementedError

    @_KindOrInstanceMethod
    def describe(self) -> _describe.PartDescription:
        """The declarations as a table (parameters with value or default, unit, kind and rule;
        states; inputs; outputs): ``part.describe()`` for an instance's values,
        ``PartKind.describe()`` for a kind's defaults. Printing it (or the REPL) shows the
        aligned table; its ``sections`` hold the rows."""
        return _describe.describe(self)

    def __repr__(self) -> str:
        return _describe.part_repr(self)


class ContinuousPart(Part):
    KIND = "continuous"
    #: inputs that ``direct_outputs`` reads (its outputs depend on them within one evaluation)
    DIRECT_FROM: tuple[str, ...] = ()
    #: outputs written by ``direct_outputs`` (the rest by ``state_outputs``)
    DIRECT_OUTPUTS: tuple[str, ...] = ()
    state_outputs = None
    direct_outputs = None
    rhs = None
    project = None

    def kernels(self) -> dict:
        cls = type(self)  # class access: a numba function is not bound to the instance
        found = {"state_outputs": cls.state_outputs, "rhs": cls.rhs}
        if cls.direct_outputs is not None:
            found["direct_outputs"] = cls.direct_outputs
        if cls.project is not None:
            found["project"] = cls.project
        return found


class Modulator(Part):
    KIND = "modulator"
    #: largest number of segments one sample can need
    MAX_SEGMENTS = 1
    segments = None

    def kernels(self) -> dict:
        return {"segments": type(self).segments}


class SampledPart(Part):
    KIND = "sampled"
    step = None

    def kernels(self) -> dict:
        return {"step": type(self).step}
