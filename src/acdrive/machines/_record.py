"""Machine parameter records, generated from the declarations of the parts that use them.

A record (``DFIMParams``, ``IMParams``, ``PMSGParams``) is the frozen dataclass that analysis,
design, scenarios and the catalog pass around: one machine's electrical parameters and the
mechanics of its shaft. Nothing of it is typed twice. Its fields, their units, docs and value
rules, and the cross-field relations (e.g. sigma > 0), are

* the machine part's ``PARAMS``, in their order, less the parameters that are not the machine's
  (``leave_out``, e.g. the DFIM rotor converter's voltage loss ``V_loss``), then
* the shaft's ``J``, ``B``, ``tau_c`` as ``plant.Shaft`` declares them (``MECHANICS``).

Defaults are the part's ``DEFAULTS`` and the shaft's (B = tau_c = 0); the inertia J is required
unless the record is built with ``inertia_required=False`` (a current-subsystem analysis does not
need it), when it may be None. Validation on construction applies the same declarations: a value
against its rule or a broken relation is an ``InputError`` naming the field.
"""

from __future__ import annotations

from dataclasses import dataclass

from acdrive.core._parts import ContinuousPart
from acdrive.core._signals import RULES, Var
from acdrive.errors import InputError
from acdrive.plant._mechanics import SHAFT_PARAMS, Shaft

#: the most pole pairs a machine record accepts: above any machine built (low-speed hydro and
#: direct-drive wind generators have up to a few hundred poles), so that more is a mistake in the
#: input, refused before the electrical speed n_p w outruns every sample time
MAX_POLE_PAIRS = 1000

#: the shaft's mechanics every machine record carries, as ``plant.Shaft`` declares them
MECHANICS: tuple[Var, ...] = tuple(SHAFT_PARAMS.var(n) for n in ("J", "B", "tau_c"))


class MachinePart(ContinuousPart):
    """A machine's continuous part whose parameters a record (``machine_record``) carries."""

    @classmethod
    def from_params(cls, name: str, params, **extra):
        """The part named ``name`` with the parameters of the record ``params`` (e.g.
        ``acdrive.machines.DFIMParams``; its J, B, tau_c go to a ``plant.Shaft``); ``extra``
        gives the part's own other parameters (e.g. a DFIM's ``V_loss``)."""
        fields = getattr(params, "__dataclass_fields__", {})
        values = {v.name: getattr(params, v.name) for v in cls.PARAMS if v.name in fields}
        return cls(name, **values, **extra)


def electrical_fields(record) -> tuple[str, ...]:
    """The names of a record's (class or instance) machine parameters, its part's declaration
    in order, without the shaft's mechanics: what a scenario's machine parameter table holds."""
    mechanics = {v.name for v in MECHANICS}
    return tuple(v.name for v in record.DECLARED if v.name not in mechanics)


def _rule_text(var: Var) -> str:
    return f", {RULES[var.rule]}" if var.rule else ""


def machine_record(part: type[MachinePart], leave_out: tuple[str, ...] = (),
                   inertia_required: bool = True):  # fmt: skip
    """Class decorator: the decorated class (docstring, derived properties) becomes a frozen
    dataclass whose fields are ``part``'s declaration (module docstring)."""
    declared = tuple(v for v in part.PARAMS if v.name not in leave_out) + MECHANICS
    names = {v.name for v in declared}
    unknown = set(leave_out) - {v.name for v in part.PARAMS}
    if unknown:
        raise ValueError(f"{part.__name__} declares no {', '.join(sorted(unknown))}")
    defaults = {n: value for n, value in part.DEFAULTS.items() if n in names}
    defaults.update({n: value for n, value in Shaft.DEFAULTS.items() if n in names})
    if not inertia_required:
        defaults["J"] = None

    def build(cls):
        cls.__annotations__ = {
            v.name: ("int" if v.rule == "count" else "float")
            + (" | None" if v.name in defaults and defaults[v.name] is None else "")
            for v in declared
        }
        for name, value in defaults.items():
            setattr(cls, name, value)
        cls.PART = part
        cls.DECLARED = declared
        cls.RELATIONS = part.PARAMS.relations
        cls.OPTIONAL = frozenset(n for n, value in defaults.items() if value is None)
        cls.__post_init__ = _validate
        listing = "\n".join(
            f"    * {v.name} [{v.unit or '-'}]: {v.doc}{_rule_text(v)}"
            + (" (None if unknown)" if v.name in cls.OPTIONAL else "")
            for v in declared
        )
        rules = "\n".join(f"    * {r.rule}" for r in cls.RELATIONS)
        cls.__doc__ = (
            f"{(cls.__doc__ or '').rstrip()}\n\n    Fields (``{part.__name__}.PARAMS``"
            f"{' less ' + ', '.join(leave_out) if leave_out else ''}, then the shaft's J, B,"
            f" tau_c):\n\n{listing}\n" + (f"\n    Relations:\n\n{rules}\n" if rules else "")
        )
        return dataclass(frozen=True)(cls)

    return build


def _validate(self) -> None:
    """Each field against its declared rule (n_p stored as int, at most ``MAX_POLE_PAIRS``), then
    the relations."""
    values = {}
    for v in self.DECLARED:
        value = getattr(self, v.name)
        if value is None and v.name in self.OPTIONAL:
            continue
        value = v.checked(v.name, value)
        if v.rule == "count":
            value = int(value)
        if v.name == "n_p" and value > MAX_POLE_PAIRS:
            raise InputError(v.name, f"must be at most {MAX_POLE_PAIRS} pole pairs, got {value:g}")
        object.__setattr__(self, v.name, value)
        values[v.name] = value
    units = {v.name: v.unit for v in self.DECLARED}
    for relation in self.RELATIONS:
        relation.check("", values, units)
