"""Signal declarations: every parameter, state, input and output of a part is declared once here.

A :class:`Var` names one quantity with its unit, its kind and a one-line doc. A :class:`Layout` is
an ordered tuple of them and derives everything else: the slot of each quantity in a flat float64
array, the array size, the column names and units of result tables. Compiled kernels read their
slots from module-level integer constants taken from a layout (``STATES.slot("psi_s")``), which
numba folds into the machine code; nothing is numbered by hand, and every array size comes from
the same declaration that its kernel reads, so a size mismatch cannot exist.

Kinds:

* ``real``: one float.
* ``complex``: a space vector (Bodson (6)) stored as two floats, real then imaginary part.
* ``table``: a piecewise-linear profile (``core._profile``: a number, ``Profile(times, values)``
  or a list of ``[time_s, value]`` points), stored at the *end* of a
  parameter layout as ``[n, t_0 .. t_{n-1}, v_0 .. v_{n-1}]``; its length is chosen per instance,
  so kernels find it with :func:`acdrive.core.table_at` from a fixed start slot.
* ``table2d``: a function of two variables on a rectangular grid (:class:`Table2D`: n_x >= 2
  strictly increasing x breakpoints, n_y >= 2 strictly increasing y breakpoints, n_x x n_y
  values, all finite), stored after every ``table`` as
  ``[n_x, n_y, x_0 .. x_{n_x-1}, y_0 .. y_{n_y-1}, v_00, v_01 .. v_{n_x-1,n_y-1}]`` (the value
  at (x_i, y_j) at ``v_{i n_y + j}``); kernels read it bilinearly with
  :func:`acdrive.core.table2d_at` (clamped to the grid at its edges), from the slot
  :func:`acdrive.core.table2d_offset` gives.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from acdrive.core._profile import ACCEPTED, Profile
from acdrive.errors import InputError, UnknownField

KINDS = ("real", "complex", "table", "table2d")
#: the kinds sized per instance, stored after the fixed part of a layout in this order
TABLE_KINDS = ("table", "table2d")
#: value rules a real quantity or a table's values may declare, checked whenever values are
#: packed (a part checks its parameters at construction)
RULES = {
    "": "",
    "positive": "must be > 0",
    "nonnegative": "must be >= 0",
    "count": "must be a positive integer",
    "whole": "must be an integer >= 0",
    "flag": "must be 0 or 1",
    "fraction": "must be between 0 and 1",
}
#: the rules whose values are integers (an export declares such a quantity an Integer)
INTEGER_RULES = ("count", "whole", "flag")
#: whether a value obeys each rule (the empty rule holds for every value)
_RULE_HOLDS: dict[str, Callable[[float], bool]] = {
    "positive": lambda x: x > 0.0,
    "nonnegative": lambda x: x >= 0.0,
    "count": lambda x: x >= 1.0 and x == int(x),
    "whole": lambda x: x >= 0.0 and x == int(x),
    "flag": lambda x: x in (0.0, 1.0),
    "fraction": lambda x: 0.0 <= x <= 1.0,
}


#: the keywords of C99: a quantity's name is a member of the generated C structs
#: (``sim._ccode``), so none of these can name one
C_KEYWORDS = frozenset("""
    auto break case char const continue default do double else enum extern float for goto if
    inline int long register restrict return short signed sizeof static struct switch typedef
    union unsigned void volatile while _Bool _Complex _Imaginary
""".split())


@dataclass(frozen=True)
class Var:
    """One declared quantity: ``name`` (an identifier), SI ``unit`` ("" if dimensionless),
    ``kind`` (real, complex, table or table2d), a one-line ``doc`` and, for a real quantity or a
    table (each of its values), a value ``rule`` (one of ``RULES``) that packing enforces.

    ``derived`` marks a parameter that is not a free number of the built part: computed when
    the part is constructed (a discretised matrix, an order) or read only then (a gain that
    enters those matrices). Its kernels hold it fixed; an export shows it as calculated, not
    settable (changing it alone would change nothing, or break what it was computed with)."""

    name: str
    unit: str
    doc: str
    kind: str = "real"
    rule: str = ""
    derived: bool = False

    def __post_init__(self):
        if not self.name.isidentifier():
            raise ValueError(f"Var name {self.name!r} must be an identifier")
        if self.name in C_KEYWORDS:
            raise ValueError(f"Var name {self.name!r} is a C keyword: the generated C names a "
                             "quantity by its name (a struct member)")  # fmt: skip
        if self.kind not in KINDS:
            raise ValueError(f"Var {self.name}: kind must be one of {', '.join(KINDS)}")
        if not self.doc:
            raise ValueError(f"Var {self.name}: a one-line doc is required")
        if self.rule not in RULES or (self.rule and self.kind == "complex"):
            raise ValueError(
                f"Var {self.name}: rule must be one of {list(RULES)} on a real or a table"
            )

    def checked(self, field: str, value) -> float:
        """A real ``value`` as float if it is a finite number obeying the declared rule, else an
        InputError naming ``field`` (what packing does with one real quantity)."""
        return self.check(field, _number(field, value, allow_complex=False))

    def check(self, field: str, value: float) -> float:
        """``value`` if it obeys the declared rule, else an InputError naming ``field``."""
        if self.rule and not _RULE_HOLDS[self.rule](value):
            raise InputError(field, f"{RULES[self.rule]}, got {value:g}")
        return value

    def check_table(self, field: str, packed: np.ndarray) -> np.ndarray:
        """A packed table (:func:`pack_table`) if each of its values obeys the declared rule,
        else an InputError naming ``field`` and the first value that breaks it."""
        if self.rule:
            n = int(packed[0])
            for value in packed[1 + n :]:
                self.check(field, float(value))
        return packed

    def check_table2d(self, field: str, packed: np.ndarray) -> np.ndarray:
        """A packed 2-D table (:func:`pack_table2d`) if each of its values obeys the declared
        rule, else an InputError naming ``field.values`` and the first value that breaks it."""
        if self.rule:
            n_x, n_y = int(packed[0]), int(packed[1])
            for value in packed[2 + n_x + n_y :]:
                self.check(f"{field}.values", float(value))
        return packed

    @property
    def width(self) -> int:
        """Floats taken by a real or complex quantity (tables are sized per instance)."""
        return 2 if self.kind == "complex" else 1


@dataclass(frozen=True)
class Relation:
    """A rule over several real parameters (a cross-field check), declared with them.

    ``rule`` is the rule as one phrase ("leakage factor sigma = 1 - M^2/(L_s L_r) must be > 0"),
    ``holds`` tells, from the values of ``fields`` in that order, whether it is met; ``blame``
    (same arguments) names the field out of proportion, ``fields[-1]`` if not given. A broken
    relation is an InputError naming that field, the rule and the values of every field in it.
    ``c`` is the same condition in C, each field written ``{name}`` (an export checks it there);
    empty if the relation has none.
    """

    fields: tuple[str, ...]
    rule: str
    holds: Callable[..., bool]
    blame: Callable[..., str] | None = None
    c: str = ""

    def check(self, owner: str, values: dict, units: dict) -> None:
        """Raise InputError (field ``owner.<field>``, or ``<field>`` if ``owner`` is empty)
        unless the relation holds for ``values`` (name -> float)."""
        args = [values[f] for f in self.fields]
        if self.holds(*args):
            return
        named = self.blame(*args) if self.blame is not None else self.fields[-1]
        given = ", ".join(
            f"{f} = {v:g}" + (f" {units[f]}" if units.get(f) else "")
            for f, v in zip(self.fields, args, strict=True)
        )
        raise InputError(f"{owner}.{named}" if owner else named, f"{self.rule} ({given})")


def real(name: str, unit: str, doc: str, rule: str = "", derived: bool = False) -> Var:
    return Var(name, unit, doc, "real", rule, derived)


def cplx(name: str, unit: str, doc: str) -> Var:
    return Var(name, unit, doc, "complex")


def table(name: str, unit: str, doc: str, rule: str = "") -> Var:
    return Var(name, unit, doc, "table", rule)


def table2d(name: str, unit: str, doc: str, rule: str = "") -> Var:
    """A 2-D table parameter (:class:`Table2D`); ``unit`` is the unit of its values."""
    return Var(name, unit, doc, "table2d", rule)


class Layout:
    """Ordered declarations and the flat float64 slots they occupy.

    Tables, if any, must come after every real and complex quantity: the fixed part of the layout
    then has the same slots for every instance, whatever the table lengths. ``relations`` are the
    cross-field rules (:class:`Relation`) over its real quantities, checked by ``pack`` after
    each value's own rule.
    """

    def __init__(self, *variables: Var, relations: tuple[Relation, ...] = ()):
        self.vars = tuple(variables)
        self._by_name = {v.name: v for v in self.vars}
        names = [v.name for v in self.vars]
        if len(self._by_name) != len(names):
            duplicates = {n for n in names if names.count(n) > 1}
            raise ValueError(f"duplicate declarations: {', '.join(sorted(duplicates))}")
        self.relations = tuple(relations)
        for relation in self.relations:
            for f in relation.fields:
                if f not in names or self.var(f).kind != "real":
                    raise ValueError(f"relation {relation.rule!r}: {f} is not a declared real")
        seen_table = seen_table2d = False
        self._slots: dict[str, int] = {}
        offset = 0
        for v in self.vars:
            if v.kind == "table2d":
                seen_table2d = True
                continue
            if v.kind == "table":
                if seen_table2d:
                    raise ValueError(f"{v.name}: 2-D tables must come after every table")
                seen_table = True
                continue
            if seen_table or seen_table2d:
                raise ValueError(
                    f"{v.name}: tables must come after every real and complex quantity"
                )
            self._slots[v.name] = offset
            offset += v.width
        self.fixed_size = offset
        self.tables = tuple(v for v in self.vars if v.kind == "table")
        #: the 2-D tables, stored after the tables (``core._tables.table2d_offset``)
        self.tables2d = tuple(v for v in self.vars if v.kind == "table2d")
        # size() of one-point tables and 2 x 2 2-D tables
        self._one_point_size = self.fixed_size + 3 * len(self.tables) + 10 * len(self.tables2d)

    def extended(self, *variables: Var) -> Layout:
        """This layout with ``variables`` appended and the same relations: every quantity
        declared here keeps its slot (slots follow the order of declaration)."""
        return Layout(*self.vars, *variables, relations=self.relations)

    def check_relations(self, owner: str, values: dict) -> None:
        """Each relation on ``values`` (name -> float; InputError naming the field)."""
        units = {v.name: v.unit for v in self.vars}
        for relation in self.relations:
            relation.check(owner, values, units)

    def __iter__(self):
        return iter(self.vars)

    def __len__(self) -> int:
        return len(self.vars)

    def __contains__(self, name: str) -> bool:
        return name in self._by_name

    def var(self, name: str) -> Var:
        return self._by_name[name]

    def slot(self, name: str) -> int:
        """First slot of a real or complex quantity."""
        if name in self._slots:
            return self._slots[name]
        if name in self:
            raise KeyError(f"{name} is a table: use the table start slot")
        raise KeyError(name)

    @property
    def table_start(self) -> int:
        """Slot at which the first table begins (tables are stored one after another)."""
        return self.fixed_size

    def size(self, table_lengths: dict[str, int] | None = None) -> int:
        """Floats needed for this layout with the given number of points per table."""
        if not table_lengths:
            return self._one_point_size
        return (
            self.fixed_size
            + sum(1 + 2 * table_lengths.get(v.name, 1) for v in self.tables)
            + 10 * len(self.tables2d)
        )

    def columns(self, prefix: str = "") -> list[tuple[str, str, str, int]]:
        """(column name, unit, kind, first slot) per float of the fixed part: a complex
        quantity gives ``name.re`` and ``name.im``."""
        out = []
        for v in self.vars:
            if v.kind in TABLE_KINDS:
                continue
            full = f"{prefix}{v.name}"
            s = self._slots[v.name]
            if v.kind == "complex":
                out += [(f"{full}.re", v.unit, "real", s), (f"{full}.im", v.unit, "real", s + 1)]
            else:
                out.append((full, v.unit, "real", s))
        return out

    def pack(self, owner: str, values: dict, defaults: dict | None = None) -> np.ndarray:
        """Flat array of ``values`` (name -> number, complex number or a table's profile).

        Every declared quantity must be given (or have a default); an unknown name, a non-finite
        number, a malformed table, a value against its rule or a broken relation is an
        ``InputError`` naming ``owner.name``.
        """
        merged = dict(defaults or {})
        merged.update(values)
        unknown = sorted(set(merged) - self._by_name.keys())
        if unknown:
            raise UnknownField(
                f"{owner}.{unknown[0]}",
                f"is not declared by {owner} ({', '.join(v.name for v in self.vars)})",
            )
        fixed = np.zeros(self.fixed_size)
        tables, tables2d = [], []
        for v in self.vars:
            field = f"{owner}.{v.name}"
            if v.name not in merged:
                raise InputError(field, "must be given")
            value = merged[v.name]
            if v.kind == "table2d":
                tables2d.append(v.check_table2d(field, pack_table2d(field, value)))
                continue
            if v.kind == "table":
                tables.append(v.check_table(field, pack_table(field, value)))
                continue
            s = self._slots[v.name]
            if v.kind == "complex":
                z = _number(field, value, allow_complex=True)
                fixed[s], fixed[s + 1] = z.real, z.imag
            else:
                fixed[s] = v.checked(field, value)
        if self.relations:
            self.check_relations(owner, {n: float(fixed[s]) for n, s in self._slots.items()})
        return np.concatenate([fixed, *tables, *tables2d]) if tables or tables2d else fixed

    def unpack(self, array: np.ndarray) -> dict:
        """name -> value (float or complex) for the fixed part of ``array``."""
        out = {}
        for v in self.vars:
            if v.kind in TABLE_KINDS:
                continue
            s = self._slots[v.name]
            out[v.name] = (
                complex(array[s], array[s + 1]) if v.kind == "complex" else float(array[s])
            )
        return out


def _number(field: str, value, allow_complex: bool):
    if type(value) is float:  # the common case, checked as below without numpy's scalar overhead
        if not math.isfinite(value):
            raise InputError(field, "must be finite (not NaN or infinite)")
        return complex(value) if allow_complex else value
    if value is None:
        raise InputError(field, "must be given (got None)")
    if isinstance(value, bool) or not isinstance(value, (int, float, complex, np.number)):
        raise InputError(field, f"must be a number, got {type(value).__name__}")
    if isinstance(value, (complex, np.complexfloating)):
        if not allow_complex:
            raise InputError(field, "must be a real number")
        z = complex(value)
        if not (math.isfinite(z.real) and math.isfinite(z.imag)):
            raise InputError(field, "must be finite (not NaN or infinite)")
        return z
    x = float(value)
    if not math.isfinite(x):
        raise InputError(field, "must be finite (not NaN or infinite)")
    return complex(x) if allow_complex else x


def pack_table(field: str, value) -> np.ndarray:
    """``[n, t_0 .. t_{n-1}, v_0 .. v_{n-1}]`` from one of the three forms of
    ``core._profile``: a number (constant), a ``Profile(times, values)`` or a list of
    ``[time_s, value]`` points; times finite, >= 0 and non-decreasing. Anything else, a bare
    ``(times, values)`` tuple included (it reads like a list of two points), is an InputError
    naming ``field`` and the accepted forms."""
    if isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool):
        times, values = np.array([0.0]), np.array([_number(field, value, False)])
    elif isinstance(value, Profile):
        times, values = value
    elif isinstance(value, tuple):
        raise InputError(field, f"a bare (times, values) tuple is ambiguous: give {ACCEPTED}")
    else:
        try:
            points = (
                np.asarray(value, dtype=float) if isinstance(value, (list, np.ndarray)) else None
            )
        except (TypeError, ValueError):
            points = None
        if points is None or points.ndim != 2 or points.shape[1] != 2:
            raise InputError(field, f"must be {ACCEPTED}")
        times, values = points[:, 0], points[:, 1]
    if times.size == 0 or times.shape != values.shape:
        raise InputError(field, f"must have as many times as values, at least one ({ACCEPTED})")
    if not (np.all(np.isfinite(times)) and np.all(np.isfinite(values))):
        raise InputError(field, "must be finite (not NaN or infinite)")
    if times[0] < 0 or np.any(np.diff(times) < 0):
        raise InputError(field, "times must be >= 0 and non-decreasing")
    return np.concatenate([[float(times.size)], times, values])


class Table2D(NamedTuple):
    """The value of a ``table2d`` parameter: ``values[i][j]`` at (``x[i]``, ``y[j]``); ``x``
    and ``y`` strictly increasing, at least two breakpoints each, everything finite. Read
    bilinearly inside the grid, clamped at its edges (``core._tables.table2d_at``)."""

    x: object
    y: object
    values: object


#: the forms a 2-D table parameter is given in
ACCEPTED_2D = "Table2D(x, y, values) or a table {x = [...], y = [...], values = [[...], ...]}"


def pack_table2d(field: str, value) -> np.ndarray:
    """``[n_x, n_y, x.., y.., values row by row]`` from a :class:`Table2D` or a mapping with keys
    ``x``, ``y``, ``values`` (a scenario's table); an InputError naming ``field`` (or
    ``field.x``, ``field.y``, ``field.values``) and the rule otherwise."""
    if isinstance(value, dict):
        unknown = sorted(set(value) - {"x", "y", "values"})
        if unknown:
            raise InputError(
                f"{field}.{unknown[0]}", f"is not a key of a 2-D table ({ACCEPTED_2D})"
            )
        missing = [k for k in ("x", "y", "values") if k not in value]
        if missing:
            raise InputError(f"{field}.{missing[0]}", f"must be given ({ACCEPTED_2D})")
        value = Table2D(value["x"], value["y"], value["values"])
    if not isinstance(value, Table2D):
        raise InputError(field, f"must be {ACCEPTED_2D}")
    axes = []
    for name in ("x", "y"):
        where = f"{field}.{name}"
        try:
            axis = np.asarray(getattr(value, name), dtype=float)
        except (TypeError, ValueError):
            raise InputError(where, "must be a list of numbers") from None
        if axis.ndim != 1 or axis.size < 2:
            raise InputError(where, f"must be a list of at least 2 numbers, got shape {axis.shape}")
        if not np.all(np.isfinite(axis)):
            raise InputError(where, "must be finite (not NaN or infinite)")
        steps = np.diff(axis)
        if np.any(steps <= 0.0):
            k = int(np.argmax(steps <= 0.0))
            raise InputError(
                where,
                f"must be strictly increasing, got {axis[k]:g} then {axis[k + 1]:g} "
                f"(entries {k} and {k + 1})",
            )
        axes.append(axis)
    x, y = axes
    try:
        values = np.asarray(value.values, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{field}.values", "must be a list of rows of numbers") from None
    if values.shape != (x.size, y.size):
        raise InputError(
            f"{field}.values",
            f"must have len(x) = {x.size} rows of len(y) = {y.size} values, got shape "
            f"{values.shape}",
        )
    if not np.all(np.isfinite(values)):
        i, j = np.argwhere(~np.isfinite(values))[0]
        raise InputError(
            f"{field}.values", f"must be finite, got {values[i, j]} at row {i}, column {j}"
        )
    return np.concatenate([[float(x.size), float(y.size)], x, y, values.ravel()])


def unpack_table2d(packed: np.ndarray) -> Table2D:
    """The :class:`Table2D` of a packed 2-D table (arrays)."""
    n_x, n_y = int(packed[0]), int(packed[1])
    x = np.array(packed[2 : 2 + n_x])
    y = np.array(packed[2 + n_x : 2 + n_x + n_y])
    values = np.array(packed[2 + n_x + n_y : 2 + n_x + n_y + n_x * n_y]).reshape(n_x, n_y)
    return Table2D(x, y, values)
