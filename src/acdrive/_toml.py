"""The validated reading of the TOML tables users write (scenario and sweep files).

``parse_toml`` reads a document; ``Section`` wraps one of its tables: every field read through it
is checked (type, finiteness, the rule given) and named by its path in an ``InputError``;
``done()`` reports keys nobody read. ``machine_from``, ``simulation_span`` and ``log_every_of``
read the tables every drive's scenario has. The drives' loaders (``drives.<kind>._schema``) and
the sweep files build on it; it sits below both, so a drive imports nothing of
``acdrive.scenarios`` (which finds the drives through their registry).
"""

from __future__ import annotations

import itertools
import math
import tomllib

from acdrive.core._profile import Profile
from acdrive.errors import (
    InputError,
    UnknownField,
    require_finite,
    require_nonnegative,
    require_positive,
)


def constant(value: float) -> Profile:
    """The profile of a constant ``value``."""
    return Profile.constant(float(value))


#: a UTF-8 byte-order mark, as Windows editors write at the start of a file
BOM = "\ufeff"


def parse_toml(text: str, origin: str, field: str) -> dict:
    """The TOML document ``text`` (read from ``origin``), or an ``InputError`` on ``field``.

    A leading UTF-8 byte-order mark is dropped (TOML requires UTF-8, and a BOM carries nothing
    else). A document nested so deeply that the parser runs out of stack (thousands of ``[``) is
    refused as invalid TOML for acdrive, not left to crash the command."""
    text = text.removeprefix(BOM)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(field, f"{origin} is not valid TOML ({exc})") from None
    except RecursionError:
        raise InputError(
            field, f"{origin} nests arrays or tables too deeply to be read (a scenario or sweep "
            "needs a few levels)"
        ) from None  # fmt: skip


class Section:
    """A TOML table being validated: tracks the keys read so unknown keys can be reported."""

    def __init__(self, data, path: str):
        if not isinstance(data, dict):
            raise InputError(path, "must be a table")
        self.data, self.path, self.used = data, path, set()

    def field(self, key: str) -> str:
        return f"{self.path}.{key}" if self.path else key

    def get(self, key, default=None):
        self.used.add(key)
        return self.data.get(key, default)

    def has(self, key) -> bool:
        return key in self.data

    def number(self, key, default, rule=require_finite):
        value = self.get(key, default)
        return rule(self.field(key), value)

    def integer(self, key, default, minimum=1, maximum=None):
        value = self.get(key, default)
        if isinstance(value, bool) or not isinstance(value, int):
            raise InputError(self.field(key), f"must be an integer, got {type(value).__name__}")
        if value < minimum:
            raise InputError(self.field(key), f"must be an integer >= {minimum}, got {value}")
        if maximum is not None and value > maximum:
            raise InputError(self.field(key), f"must be an integer <= {maximum}, got {value}")
        return value

    def boolean(self, key, default):
        value = self.get(key, default)
        if not isinstance(value, bool):
            raise InputError(self.field(key), "must be true or false")
        return value

    def text(self, key, default=None, choices=None):
        value = self.get(key, default)
        if not isinstance(value, str):
            raise InputError(self.field(key), "must be a string")
        if choices is not None and value not in choices:
            raise InputError(self.field(key), f"must be one of {', '.join(choices)}")
        return value

    def profile(self, key, scale=1.0, rule=require_finite):
        """A list of [t, value] pairs with non-decreasing t >= 0, as a ``core.Profile``."""
        value = self.get(key)
        name = self.field(key)
        if not isinstance(value, list) or not value:
            raise InputError(name, "must be a non-empty list of [time_s, value] pairs")
        times, values = [], []
        for i, pair in enumerate(value):
            if not isinstance(pair, list) or len(pair) != 2:
                raise InputError(f"{name}[{i}]", "must be a [time_s, value] pair")
            times.append(require_nonnegative(f"{name}[{i}][0]", pair[0]))
            values.append(rule(f"{name}[{i}][1]", pair[1]) * scale)
        if any(b < a for a, b in itertools.pairwise(times)):
            raise InputError(name, "times must be non-decreasing")
        return Profile(times, values)

    def constant_or_profile(self, key, default, scale=1.0, rule=require_finite):
        if self.has(key) and self.has(f"{key}_profile"):
            raise InputError(self.field(key), f"give either {key} or {key}_profile, not both")
        if self.has(f"{key}_profile"):
            return self.profile(f"{key}_profile", scale, rule)
        return constant(self.number(key, default, rule) * scale)

    def done(self):
        unknown = sorted(set(self.data) - self.used)
        if unknown:
            raise UnknownField(self.field(unknown[0]), "unknown key")


def machine_from(
    section: Section,
    kind: type,
    fields: tuple[str, ...],
    default: str,
    params_label: str = "[params]",
):
    """The machine of ``section``: a built-in name (``machine``, of parameter class ``kind``) or
    the table ``params`` holding ``fields``, validated by ``kind`` itself; not both."""
    if section.has("machine") and section.has("params"):
        raise InputError(
            section.field("machine"), f"give either machine or {params_label}, not both"
        )
    if section.has("params"):
        params = Section(section.get("params"), section.field("params"))
        values = {k: params.get(k) for k in fields}
        params.done()
        missing = [k for k, v in values.items() if v is None]
        if missing:
            raise InputError(params.field(missing[0]), "is required")
        try:
            return kind(**values)
        except InputError as exc:
            raise InputError(params.field(exc.field), exc.rule) from None
    # the machines (and numba, which their kernels need) are imported only here, when a
    # scenario is built: listing or reading scenarios does not pay for them
    from acdrive.machines import _registry as registry

    name = section.text("machine", default, choices=registry.names(kind))
    return registry.MACHINES[name]


def simulation_span(sim: Section, duration: float, sample_time: float) -> tuple[float, float]:
    """(duration, sample time) [s] of a ``[simulation]`` table (defaults ``duration`` and
    ``sample_time``), both > 0 and the run at least one sample long (a run shorter than the
    default sample time blames the duration, one shorter than a given sample time the latter)."""
    default_sample_time = sample_time
    duration = sim.number("duration", duration, require_positive)
    sample_time = sim.number("sample_time", default_sample_time, require_positive)
    if sample_time > duration:
        if not sim.has("sample_time"):  # the default sample time: the duration is at fault
            raise InputError(
                sim.field("duration"),
                f"must be at least one sample, {sim.field('sample_time')} = {sample_time:g} s "
                f"(the default), got {duration:g} s",
            )
        raise InputError(sim.field("sample_time"), f"must not exceed {sim.field('duration')}")
    return duration, sample_time


def log_every_of(sim: Section, duration: float, sample_time: float) -> int:
    """``log_every`` of a ``[simulation]`` table: a positive integer at most the number of
    control steps of the run (default: ``acdrive.sim._log_plan.default_log_every``, every sample
    of a run of at most 100,000)."""
    from acdrive.sim._log_plan import default_log_every

    steps = duration / sample_time  # a float: may be astronomically large
    log_every = sim.integer("log_every", default_log_every(round(steps)) if math.isfinite(steps) else 1)
    if math.isfinite(steps) and log_every > round(steps):
        raise InputError(
            sim.field("log_every"),
            f"must not exceed the number of control steps of the run ({round(steps)} = "
            f"{sim.field('duration')} / {sim.field('sample_time')})",
        )
    return log_every


def perturbed_plant(
    section: Section, nominal, fields: tuple[str, ...], apart: tuple[str, ...] = ()
):
    """(simulated plant, factors) of the table ``perturbation`` of ``section``: each of
    ``fields`` (parameters of ``nominal``) multiplied by its factor (> 0, default 1) on the
    simulated plant only; the controllers keep ``nominal`` (Amezquita-Brooks et al. sec. VIII:
    the controller of the nominal design on a perturbed machine); the factors named in ``apart``
    are read and returned but not applied (a parameter the drive keeps elsewhere, as the cage
    IM's shaft inertia). No table: (nominal, {})."""
    if not section.has("perturbation"):
        return nominal, {}
    import dataclasses

    pert = Section(section.get("perturbation"), section.field("perturbation"))
    factors = {k: pert.number(k, 1.0, require_positive) for k in (*fields, *apart)}
    pert.done()
    scaled = {k: getattr(nominal, k) * factors[k] for k in fields}
    try:
        plant = dataclasses.replace(nominal, **scaled)
    except InputError as exc:
        raise InputError(pert.field(exc.field), f"the perturbed plant: {exc.rule}") from None
    return plant, factors


#: the largest machine parameter file ``[design] machine_file`` reads (an ``acdrive identify``
#: file is a few kB)
_MAX_DESIGN_FILE_BYTES = 1_000_000


def design_machine(section: Section, truth, fields: tuple[str, ...], aliases: dict | None = None):
    """(design machine, fields taken from the estimates) of a ``[design]`` table: the machine the
    controllers are designed on, the simulated plant staying ``truth``.

    ``machine_file``: a machine parameter file (``acdrive identify`` writes one; its
    ``[machine.params]``), or ``[design.params]`` inline; each of ``fields`` given there (or under
    its alias, e.g. the DFIM's M as L_m) replaces ``truth``'s, the others keep ``truth``'s value
    (the pole pairs, the inertia a standstill test does not give). Relative paths are read from
    the working folder. The design machine is validated by its class, errors naming the field."""
    import dataclasses
    from pathlib import Path

    aliases = aliases or {}
    if section.has("machine_file") and section.has("params"):
        raise InputError(section.field("machine_file"), "give either it or [params], not both")
    if section.has("machine_file"):
        name = section.field("machine_file")
        path = Path(section.text("machine_file"))
        if not path.is_file():
            raise InputError(name, f"'{path}' is not a file")
        if path.stat().st_size > _MAX_DESIGN_FILE_BYTES:
            raise InputError(name, f"'{path}' is larger than a machine parameter file can be")
        doc = parse_toml(path.read_text(encoding="utf-8", errors="replace"), f"'{path}'", name)
        table = (
            doc.get("machine", {}).get("params") if isinstance(doc.get("machine"), dict) else None
        )
        if not isinstance(table, dict):
            raise InputError(name, f"'{path}' has no [machine.params] table")
        where = f"{name} [machine.params]"
    elif section.has("params"):
        table = section.get("params")
        if not isinstance(table, dict):
            raise InputError(section.field("params"), "must be a table of machine parameters")
        where = section.field("params")
    else:
        raise InputError(
            section.field("machine_file"), "is required in a [design] table (or [params])"
        )
    section.used.add("params")
    values, taken = {}, []
    for key in fields:
        for name in (key, aliases.get(key)):
            if name is not None and name in table:
                value = (
                    require_positive(f"{where}.{name}", table[name])
                    if key != "n_p"
                    else table[name]
                )
                values[key] = value
                taken.append(key)
                break
    known = set(fields) | {aliases[k] for k in fields if k in aliases}
    unknown = sorted(set(table) - known)
    if unknown:
        raise InputError(
            f"{where}.{unknown[0]}", f"unknown machine parameter (known: {', '.join(fields)})"
        )
    try:
        design = dataclasses.replace(truth, **values)
    except InputError as exc:
        raise InputError(f"{where}.{exc.field}", exc.rule) from None
    return design, tuple(taken)
