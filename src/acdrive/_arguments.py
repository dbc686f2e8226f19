"""The arguments of the public Python API, checked before any work.

A public function or class states one rule per parameter with ``checked``::

    @checked(log=Instance(StandstillLog), base_frequency=POSITIVE, seed=SEED)
    def fit_impedance(log, base_frequency, seed=0): ...

Every call then binds its arguments to the signature and checks each argument it was given
against its parameter's rule, in the signature's order, before the body runs; the first argument
that breaks its rule raises ``InputError("<parameter>", "<rule>, got <what>")``, naming the
Python parameter (an item of a sequence as ``name[i]``, of a table as ``name['key']``). Defaults
are not checked (they are the function's own), nor are the calls a checked function makes to
other checked functions while it runs (its own intermediate values: a fit's trial parameters, a
record it builds), which would cost time in inner loops and could name an argument the user
never gave; a dispatcher that hands its other arguments on declares itself with ``forwarding``.
A parameter without a rule is a programming error, refused when the module is imported, so no
public argument goes unchecked. On a class the rules apply to ``__init__`` (a dataclass's
fields). ``rules_of`` returns the rules of a checked callable; the CLI, which names its flags
instead, renames the fields with ``acdrive.errors.named_as``.

A rule says what it accepts: ``None`` only if ``optional``; NaN or infinity never (but for an
``Array(finite=False)`` of results); a negative number only without a lower bound; an empty
text, sequence, table or array only if ``empty``.
"""

from __future__ import annotations

import contextvars
import functools
import importlib
import inspect
import math
import numbers
import os
from collections.abc import Mapping

import numpy as np

from acdrive.errors import InputError

__all__ = [
    "COUNT", "COUNT0", "FLAG", "FRACTION", "NONNEGATIVE", "PATH", "POSITIVE", "REAL", "RESULT",
    "SEED", "TEXT", "Anything", "Array", "Attributes", "Either", "FilePath", "Flag", "Function",
    "Instance", "Items", "Number", "Table", "Text", "check_call", "checked", "forwarding",
    "optional", "rules_of",
]  # fmt: skip

#: the attribute a checked callable (or a checked class's ``__init__``) keeps its rules in
RULES = "__acdrive_arguments__"


def _shown(value) -> str:
    """What a refused value was, short: a float as ``:g`` formats it, else its repr when short,
    else its type."""
    text = f"{value:g}" if isinstance(value, float) else repr(value)
    return text if len(text) <= 40 else f"a value of type {type(value).__name__}"


def _finite(value) -> bool:
    """``math.isfinite`` of a real number; an exact one too large for a float is finite."""
    try:
        return math.isfinite(value)
    except OverflowError:
        return True


class Rule:
    """What one argument must be. ``check(name, value)`` raises ``InputError(name, ...)``."""

    def __init__(self, *, optional: bool = False):
        self.optional = optional

    #: what the rule accepts (the contract the API test drives)
    accepts_nan = False
    accepts_negative = False
    accepts_empty = False

    @property
    def accepts_none(self) -> bool:
        return self.optional

    def describe(self) -> str:
        raise NotImplementedError

    def refuse(self, name: str, value, why: str | None = None):
        raise InputError(name, f"must be {self.describe()}, got {why or _shown(value)}")

    def check(self, name: str, value) -> None:
        if value is None:
            if not self.optional:
                self.refuse(name, value)
            return
        self.check_value(name, value)

    def check_value(self, name: str, value) -> None:
        raise NotImplementedError


class Number(Rule):
    """A real number (an integer with ``integer``), finite unless ``finite=False`` (a computed
    result's), within [``low``, ``high``]; with ``above`` the lower bound is excluded."""

    def __init__(self, low: float | None = None, high: float | None = None, *, above: bool = False,
                 integer: bool = False, finite: bool = True, optional: bool = False):  # fmt: skip
        super().__init__(optional=optional)
        self.low, self.high, self.above, self.integer = low, high, above, integer
        self.finite = finite
        self.accepts_nan = not finite
        self.accepts_negative = low is None or low < 0

    def describe(self) -> str:
        what = "an integer" if self.integer else "a finite number" if self.finite else "a number"
        if self.low is not None and self.high is not None and not self.above:
            return f"{what} between {self.low:g} and {self.high:g}"
        bounds = []
        if self.low is not None:
            bounds.append(f"{'>' if self.above else '>='} {self.low:g}")
        if self.high is not None:
            bounds.append(f"<= {self.high:g}")
        return " ".join([what, " and ".join(bounds)]) if bounds else what

    def check_value(self, name, value):
        kind = numbers.Integral if self.integer else numbers.Real
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, kind):
            self.refuse(name, value)  # "must be a finite number > 0, got 'x'"
        if not isinstance(value, numbers.Integral) and not _finite(value):
            if self.finite:
                raise InputError(name, "must be finite (not NaN or infinite)")
            return
        low_ok = self.low is None or (value > self.low if self.above else value >= self.low)
        if not low_ok or (self.high is not None and value > self.high):
            bounds = self.describe().removeprefix("a finite number ")
            raise InputError(name, f"must be {bounds}, got {_shown(value)}")  # as require_*


class Flag(Rule):
    """True or False."""

    def describe(self) -> str:
        return "True or False"

    def check_value(self, name, value):
        if not isinstance(value, (bool, np.bool_)):
            self.refuse(name, value)


class Text(Rule):
    """A string; one of ``choices`` if given; empty only with ``empty``."""

    def __init__(self, choices=None, *, empty: bool = False, optional: bool = False):
        super().__init__(optional=optional)
        self.choices = tuple(choices) if choices is not None else None
        self.empty = self.accepts_empty = empty

    def describe(self) -> str:
        if self.choices is not None:
            return "one of " + ", ".join(repr(c) for c in self.choices)
        return "a string" if self.empty else "a non-empty string"

    def check_value(self, name, value):
        if not isinstance(value, str) or (not value and not self.empty):
            self.refuse(name, value)
        if self.choices is not None and value not in self.choices:
            self.refuse(name, value)


class FilePath(Rule):
    """A file or folder path: a non-empty string or an ``os.PathLike``."""

    def describe(self) -> str:
        return "a path (a non-empty str or os.PathLike)"

    def check_value(self, name, value):
        if isinstance(value, os.PathLike):
            return
        if not isinstance(value, str) or not value:
            self.refuse(name, value)


class Function(Rule):
    """Anything callable."""

    def describe(self) -> str:
        return "callable"

    def check_value(self, name, value):
        if not callable(value):
            self.refuse(name, value)


class Instance(Rule):
    """An instance of one of ``types`` (classes, or ``"module:Name"`` imported on first use; a
    module that is not installed, an optional extra's, contributes no type); ``what`` says it in
    words."""

    def __init__(self, *types, what: str | None = None, optional: bool = False):
        super().__init__(optional=optional)
        self._types = types
        self.what = what

    @functools.cached_property
    def types(self) -> tuple[type, ...]:
        found = []
        for t in self._types:
            if isinstance(t, str):
                module, _, attribute = t.partition(":")
                try:
                    t = getattr(importlib.import_module(module), attribute)
                except ImportError:
                    continue
            found.append(t)
        return tuple(found)

    def describe(self) -> str:
        return self.what or " or ".join(
            f"{'an' if t.__name__[0] in 'AEIOU' else 'a'} {t.__name__}" for t in self.types
        )

    def check_value(self, name, value):
        if not isinstance(value, self.types):
            self.refuse(name, value)


class Attributes(Rule):
    """Any object with the attributes ``names`` (what the function reads of it: a record or a
    stand-in for one); ``what`` says it in words."""

    def __init__(self, *names: str, what: str, optional: bool = False):
        super().__init__(optional=optional)
        self.names, self.what = names, what

    def describe(self) -> str:
        return f"{self.what} (with {', '.join(self.names)})"

    def check_value(self, name, value):
        if not all(hasattr(value, n) for n in self.names):
            self.refuse(name, value)


class Items(Rule):
    """A tuple or list whose every item keeps ``item`` (refused as ``name[i]``); empty only with
    ``empty``."""

    def __init__(self, item: Rule, *, empty: bool = False, optional: bool = False):
        super().__init__(optional=optional)
        self.item = item
        self.empty = self.accepts_empty = empty
        self.accepts_nan = item.accepts_nan
        self.accepts_negative = item.accepts_negative

    def describe(self) -> str:
        size = "a" if self.empty else "a non-empty"
        return f"{size} tuple or list of items each {self.item.describe()}"

    def check_value(self, name, value):
        if not isinstance(value, (tuple, list)) or (not value and not self.empty):
            self.refuse(name, value)
        for i, item in enumerate(value):
            self.item.check(f"{name}[{i}]", item)


class Table(Rule):
    """A mapping with string keys whose every value keeps ``values`` (refused as
    ``name['key']``; any value without a rule); empty only with ``empty``."""

    def __init__(self, values: Rule | None = None, *, empty: bool = False,
                 optional: bool = False):  # fmt: skip
        super().__init__(optional=optional)
        self.values = values
        self.empty = self.accepts_empty = empty
        self.accepts_nan = values is not None and values.accepts_nan
        self.accepts_negative = values is not None and values.accepts_negative

    def describe(self) -> str:
        return f"{'a' if self.empty else 'a non-empty'} mapping with string keys"

    def check_value(self, name, value):
        if not isinstance(value, Mapping) or (not value and not self.empty):
            self.refuse(name, value)
        for key, item in value.items():
            if not isinstance(key, str) or not key:
                self.refuse(name, value, f"the key {_shown(key)}")
            if self.values is not None:
                self.values.check(f"{name}[{key!r}]", item)


class Array(Rule):
    """Numbers as an array (a numpy array or anything with ``__array__``, or a number, list or
    tuple of numbers) of ``ndim``
    dimensions (any if None; an int or a tuple of the allowed ones), complex only with
    ``complex``, every element finite unless ``finite=False`` and >= ``low`` if given (real),
    empty only with ``empty``."""

    def __init__(self, ndim=None, *, low: float | None = None, complex: bool = False,
                 finite: bool = True, empty: bool = False, optional: bool = False):  # fmt: skip
        super().__init__(optional=optional)
        self.ndim = (ndim,) if isinstance(ndim, int) else ndim
        self.low, self.complex, self.finite = low, complex, finite
        self.empty = self.accepts_empty = empty
        self.accepts_nan = not finite
        self.accepts_negative = low is None

    def describe(self) -> str:
        what = "complex numbers" if self.complex else "real numbers"
        parts = [f"an array of {'' if self.finite else 'real or non-finite '}{what}"]
        if self.ndim is not None:
            parts.append(f"with {' or '.join(str(n) for n in self.ndim)} dimension(s)")
        if self.low is not None:
            parts.append(f"each >= {self.low:g}")
        if not self.empty:
            parts.append("not empty")
        return ", ".join(parts)

    def check_value(self, name, value):
        if isinstance(value, (bool, np.bool_)) or not (
            isinstance(value, (numbers.Number, list, tuple)) or hasattr(value, "__array__")
        ):
            self.refuse(name, value)
        try:
            array = np.asarray(value)
        except (TypeError, ValueError):  # ragged nesting
            self.refuse(name, value)
        kinds = "biufc" if self.complex else "biuf"
        if array.dtype.kind not in kinds:
            self.refuse(name, value, f"elements of type {array.dtype}")
        if self.ndim is not None and array.ndim not in self.ndim:
            self.refuse(name, value, f"{array.ndim} dimension(s)")
        if array.size == 0 and not self.empty:
            self.refuse(name, value, "an empty array")
        if self.finite and not np.all(np.isfinite(array)):
            self.refuse(name, value, "a NaN or infinite element")
        if self.low is not None and np.any(array < self.low):
            self.refuse(name, value, f"an element below {self.low:g}")


class Anything(Rule):
    """Any value, ``None`` included: the argument of a question such as "is this a setup?"."""

    accepts_nan = accepts_negative = accepts_empty = True

    def __init__(self):
        super().__init__(optional=True)

    def describe(self) -> str:
        return "anything"

    def check_value(self, name, value):
        pass


class Either(Rule):
    """Whatever one of ``rules`` accepts (``None`` only if ``optional``)."""

    def __init__(self, *rules: Rule, optional: bool = False):
        super().__init__(optional=optional)
        self.rules = rules

    def describe(self) -> str:
        return " or ".join(r.describe() for r in self.rules)

    def check_value(self, name, value):
        for rule in self.rules:
            try:
                rule.check(name, value)
                return
            except InputError:
                continue
        self.refuse(name, value)


def optional(rule: Rule) -> Rule:
    """``rule`` that also accepts ``None``."""
    copy = object.__new__(type(rule))
    copy.__dict__.update(rule.__dict__)
    copy.optional = True
    return copy


REAL = Number()
POSITIVE = Number(0.0, above=True)
NONNEGATIVE = Number(0.0)
FRACTION = Number(0.0, 1.0)
COUNT = Number(1, integer=True)
COUNT0 = Number(0, integer=True)
SEED = Number(0, integer=True)
#: a computed quantity of a result record (NaN where it could not be computed)
RESULT = Number(finite=False)
FLAG = Flag()
TEXT = Text()
PATH = FilePath()


def _check(signature: inspect.Signature, rules: dict, args, kwargs) -> None:
    try:
        bound = signature.bind(*args, **kwargs)
    except TypeError:
        return  # a missing or unexpected argument: Python's own TypeError when called
    for name, value in bound.arguments.items():
        rule = rules.get(name)
        if rule is not None:
            rule.check(name, value)


#: True while a checked call runs: the calls the API makes to itself are not checked again
_INSIDE = contextvars.ContextVar("acdrive_arguments_inside", default=False)


def checked(**rules: Rule):
    """Decorate a function or class so that every call checks its arguments by ``rules``
    (parameter name -> rule; module docstring) before it runs."""
    return _decorator(rules, forwards=False)


def forwarding(**rules: Rule):
    """``checked`` for a function that hands the arguments it has no rule for (``*args``,
    ``**kwargs``) to another checked function: that one checks them."""
    return _decorator(rules, forwards=True)


def _decorator(rules: dict, forwards: bool):
    def decorate(target):
        function = target.__init__ if isinstance(target, type) else target
        signature = inspect.signature(function)
        names = [
            p.name for p in signature.parameters.values()
            if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)
        ]  # fmt: skip
        if isinstance(target, type):
            names = names[1:]  # self
        missing = [n for n in names if n not in rules]
        unknown = [n for n in rules if n not in names]
        if missing or unknown:
            raise TypeError(f"{target.__qualname__}: parameters without a rule {missing}, "
                            f"rules without a parameter {unknown}")  # fmt: skip

        @functools.wraps(function)
        def with_checks(*args, **kwargs):
            if _INSIDE.get():  # called by the API itself, on arguments it made
                return function(*args, **kwargs)
            _check(signature, rules, args, kwargs)
            if forwards:
                return function(*args, **kwargs)
            token = _INSIDE.set(True)
            try:
                return function(*args, **kwargs)
            finally:
                _INSIDE.reset(token)

        setattr(with_checks, RULES, dict(rules))
        if isinstance(target, type):
            target.__init__ = with_checks
            return target
        return with_checks

    return decorate


def rules_of(target) -> dict | None:
    """The rules of a checked function or class (parameter name -> rule), else None."""
    function = target.__init__ if isinstance(target, type) else target
    return getattr(function, RULES, None)


def check_call(target, *args, **kwargs) -> None:
    """Check ``target(*args, **kwargs)``'s arguments by its rules without calling it."""
    function = target.__init__ if isinstance(target, type) else target
    signature = inspect.signature(function)
    if isinstance(target, type):
        args = (None, *args)
    _check(signature, rules_of(target), args, kwargs)
