"""The scenario field reference (docs/guide/scenario-fields.md), generated from the drives' schemas.

Each drive's schema (``acdrive/drives/<kind>/_schema.py``) reads its fields through
``acdrive._toml.Section`` (``number``, ``integer``, ``boolean``, ``text``, ``profile``,
``constant_or_profile``, ``get``), each read naming the key, its default and its rule. The
reference is what those reads say: every built-in scenario of a drive kind is loaded with the
reads recorded (``recorded_fields``), so a key is listed as the schema reads it, with

* its **unit**: a machine parameter's from its machine part's declaration (``PARAMS``, the unit
  ``acdrive parts`` shows; the shaft's for J, B, tau_c), any other key's from its name (the
  schemas' convention: units in the key names where not SI, ``UNIT_SUFFIXES``), else SI;
* its **default**: the default the read passes ("required" when it passes none and a missing
  key is refused; "derived" where the loader computes it from other fields, so the defaults of
  two scenarios differ);
* its **rule**: what the read refuses, as its error says it (the rule of a number probed with
  ``PROBES``; an integer's bounds; a text's choices).

A key is listed once some built-in scenario of its drive makes the schema read it: the built-in
scenarios are chosen to use every table (``tests/test_scenario_fields.py`` checks the committed
page against ``reference()``). Run ``python -m acdrive.scenarios._fields`` to print the page.
"""

from __future__ import annotations

import contextlib
import functools
import inspect
import re
from dataclasses import dataclass, field

#: key-name suffix -> unit (longest suffix first; a whole name counts as a suffix)
UNIT_SUFFIXES = (
    ("sample_time", "s"),
    ("duration", "s"),
    ("_time", "s"),
    ("_tau", "s"),
    ("_voltage", "V"),
    ("resistance", "ohm"),
    ("inductance", "H"),
    ("_frequency", "Hz"),
    ("_torque", "N m"),
    ("_rad_s2", "rad/s^2"),
    ("_rad_s", "rad/s"),
    ("_pk_a", "A (phase peak)"),
    ("_n_m", "N m"),
    ("_rpm", "rpm"),
    ("_deg", "deg"),
    ("_rad", "rad"),
    ("_hz", "Hz"),
    ("_pk", "phase peak (A or V)"),
    ("_s", "s"),
    ("_v", "V"),
    ("_a", "A"),
)
#: the values a number's rule is probed with: what it refuses among them is its rule
PROBES = (-1.0, 0.0, 0.5, 1.0, 2.0, 1e6)
#: the reads of ``Section`` recorded (each records its outermost call only)
READS = ("number", "integer", "boolean", "text", "profile", "constant_or_profile", "get")


@dataclass
class Field:
    """One scenario key as the schema reads it."""

    table: str
    key: str
    read: str
    #: the defaults the reads passed where the key was absent (what the loader then used)
    defaults: list = field(default_factory=list)
    rule: str = ""
    #: (scenario, the section's path, e.g. ``motor[0].controller``) of a scenario that gives it
    given_in: tuple | None = None
    required: bool = False


def _table(path: str) -> str:
    """A section's path as a table name: ``motor[1].controller`` -> ``[[motor]].controller``."""
    name = re.sub(r"^(\w+)\[\d+\]", r"[[\1]]", path)
    return name or "(top level)"


def _number_rule(rule) -> str:
    """What ``rule(field, value)`` refuses among ``PROBES``, as its errors say it."""
    from acdrive.errors import InputError

    said = []
    for value in PROBES:
        try:
            rule("x", value)
        except InputError as exc:
            text = re.sub(r",? got .*$", "", str(exc).split(": ", 1)[-1])
            if text not in said:
                said.append(text)
    return "; ".join(said) if said else "a finite number"


def _rule(read: str, given: dict) -> str:
    """The rule of one read, from its bound arguments ``given`` (name -> value)."""
    from acdrive.errors import require_finite

    if read == "integer":
        high = given.get("maximum")
        return f"an integer >= {given.get('minimum', 1)}" + (
            f" and <= {high}" if high is not None else ""
        )
    if read == "boolean":
        return "true or false"
    if read == "text":
        choices = given.get("choices")
        return f"one of {', '.join(map(str, choices))}" if choices else "a string"
    rule = given.get("rule", require_finite)
    if read == "number":
        return _number_rule(rule)
    if read == "constant_or_profile":
        return f"{_number_rule(rule)}; or the key with _profile: [[t_s, value], ...]"
    if read == "profile":
        return f"[[t_s, value], ...], t >= 0 non-decreasing; value: {_number_rule(rule)}"
    return "read as given, checked where it is used (see the drive's page)"


@contextlib.contextmanager
def _recording(found: dict, scenario: list):
    """Record every ``Section`` read made inside into ``found`` ((table, key) -> ``Field``), the
    scenario being loaded named by ``scenario[0]``."""
    from acdrive._toml import Section

    originals = {name: getattr(Section, name) for name in READS}
    depth = [0]

    def recorder(name, original):
        signature = inspect.signature(original)

        def read(self, key, *args, **kwargs):
            if depth[0] == 0 and isinstance(key, str):
                entry = found.setdefault((_table(self.path), key),
                                         Field(_table(self.path), key, name))  # fmt: skip
                bound = signature.bind(self, key, *args, **kwargs)
                bound.apply_defaults()
                given = dict(bound.arguments)
                if key not in self.data:
                    entry.defaults.append(given.get("default"))
                elif entry.given_in is None:
                    entry.given_in = (scenario[0], self.path)
                if not entry.rule:
                    entry.rule = _rule(name, given)
            depth[0] += 1
            try:
                return original(self, key, *args, **kwargs)
            finally:
                depth[0] -= 1

        return read

    for name, original in originals.items():
        setattr(Section, name, recorder(name, original))
    try:
        yield found
    finally:
        for name, original in originals.items():
            setattr(Section, name, original)


@functools.cache
def recorded_fields(kind: str) -> tuple[Field, ...]:
    """Every key the schema of drive ``kind`` reads when loading its built-in scenarios, in the
    order first read (computed once per kind)."""
    from acdrive.drives import for_data
    from acdrive.drives._registry import DEFAULT_KIND
    from acdrive.scenarios import builtin_names, read_scenario

    found: dict = {}
    loaded = {}
    scenario = [""]
    for name in builtin_names():
        data = read_scenario(name)
        if data.get("drive", DEFAULT_KIND) != kind:
            continue
        loaded[name] = data
        scenario[0] = name
        with _recording(found, scenario):
            for_data(data).load(data)
    tables = {re.sub(r"^\[\[(\w+)\]\]", r"\1", f.table) for f in found.values()}
    fields = []
    for f in found.values():
        path = f.key if f.table == "(top level)" else f"{f.table}.{f.key}"
        if f.read == "get" and re.sub(r"^\[\[(\w+)\]\]", r"\1", path) in tables:
            continue  # a table: its keys are listed
        if not f.defaults and f.given_in is not None:
            f.required, f.defaults = _without(loaded[f.given_in[0]], f.given_in[1], f)
        fields.append(f)
    return tuple(fields)


def _without(data: dict, path: str, f: Field) -> tuple[bool, list]:
    """(refused, defaults): the scenario ``data`` loaded once field ``f`` is removed from its
    section at ``path`` (``motor[0].controller``): True if that is refused naming the key
    (the key is required), else the defaults the reads of the key then passed."""
    import copy

    from acdrive.drives import for_data
    from acdrive.errors import InputError

    data = copy.deepcopy(data)
    section = data
    for part in filter(None, path.split(".")):
        name, _, index = part.partition("[")
        section = section[name] if not index else section[name][int(index.rstrip("]"))]
    del section[f.key]
    found: dict = {}
    try:
        with _recording(found, [""]):
            for_data(data).load(data)
    except InputError as exc:
        if exc.field == f.key or exc.field.endswith(f".{f.key}"):
            return True, []
        return False, []
    entry = found.get((f.table, f.key))
    return False, (entry.defaults if entry is not None else [])


def _units() -> dict[str, str]:
    """Machine-parameter name -> unit, from the machine parts' and the shaft's declarations."""
    from acdrive.machines import CageInductionMachine, DoublyFedMachine, PermanentMagnetMachine
    from acdrive.plant import Shaft

    units = {}
    for part in (DoublyFedMachine, CageInductionMachine, PermanentMagnetMachine, Shaft):
        for var in part.PARAMS.vars:
            units.setdefault(var.name, var.unit or "-")
    return units


def unit_of(f: Field, units: dict[str, str]) -> str:
    """A key's unit: none for a text, a flag or a count; a machine parameter's declared unit;
    else its name's suffix; else SI."""
    table, key = f.table, f.key
    if f.read in ("text", "boolean", "integer"):
        return "-"
    if (table.endswith("params") or table.endswith("perturbation")) and key in units:
        return "factor" if table.endswith("perturbation") else units[key]
    for suffix, unit in UNIT_SUFFIXES:
        if key.endswith(suffix):
            return unit
    return "SI"


def _default_text(f: Field) -> str:
    """The default a field's reads used where it was absent: "required" if removing it is
    refused, "derived" where the defaults differ between scenarios (computed from other
    fields), "see the drive's page" where no built-in scenario leaves it out."""
    if f.required:
        return "required"
    if not f.defaults:
        return "see the drive's page"
    shown = {repr(d) for d in f.defaults}
    if len(shown) > 1:
        return "derived"
    d = f.defaults[0]
    if d is None:
        return "none (optional)"
    if isinstance(d, bool):
        return "true" if d else "false"
    if isinstance(d, str):
        return f'"{d}"'
    if isinstance(d, float):
        return f"{d:g}"
    if isinstance(d, (int, list, tuple)):
        return str(d)
    return "derived"


def reference() -> str:
    """The field reference page (Markdown), one section per built-in drive kind."""
    from acdrive.drives._registry import BUILTIN

    units = _units()
    lines = [
        "# Scenario fields",
        "",
        "Every key a scenario file may set, per drive kind, as the drive's schema reads it: the",
        "table, the key, its unit, its default and its rule (what a value must be; a value that",
        "breaks it is refused in one line naming the key, before any work). This page is generated",
        "from the schemas by `python -m acdrive.scenarios._fields`, from the keys each schema reads",
        "when loading the drive's built-in scenarios; a test keeps it equal to what they say now.",
        "Forms no built-in scenario uses (a machine given by its own `[machine.params]` or",
        "`[[motor]].params`, a `[design]` machine, a constant where the built-ins give a profile)",
        "are described on the drive's page and in {doc}`scenarios`.",
        "",
        "Units: a machine parameter's unit is its machine part's declaration (`acdrive parts`);",
        "any other key carries its unit in its name where it is not SI. Defaults: *required* keys",
        "must be given; *derived* ones are computed from other fields when omitted (the drive's",
        "page says how); *none (optional)* means the feature is off when the key is absent;",
        "*see the drive's page* where a default depends on other keys in a way no built-in shows.",
        "A `key_profile` form (a list of `[t_s, value]` points) is listed where a key has one.",
    ]
    for kind in BUILTIN:
        lines += ["", f'## `drive = "{kind}"`', "", "| table | key | unit | default | rule |",
                  "|---|---|---|---|---|"]  # fmt: skip
        for f in recorded_fields(kind):
            rule = f.rule.replace("|", "\\|")
            unit = unit_of(f, units)
            lines.append(
                f"| `{f.table}` | `{f.key}` | {unit} | {_default_text(f)} | {rule} |"
            )
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    print(reference(), end="")
