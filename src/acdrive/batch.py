"""Many variants of one scenario in the compiled batch loop, on all cores, reduced on line.

``simulate_batch(base, variants)`` takes a base scenario (built-in name, TOML path or parsed
dict; or the setup of a registered drive, ``acdrive.drives``, when the variants only change parts
and initial states) and a list of variants, each a dict of overrides in three forms:

* ``"motor[0].controller.speed_bandwidth": 100`` -- a field of the scenario file, dotted as the
  loader names it in its errors (``motor[0].params.R_s`` expands ``machine = "<name>"`` into its
  parameters first, so a built-in machine's parameters can be varied one by one);
* ``"part:shaft0.load": 0.05`` -- a parameter of one part of the built system (checked by the
  part's own declaration);
* ``"initial:shaft0.w": 100.0`` -- an initial state of one part (after the drive's own initial
  state, e.g. a perturbed speed).

Every variant goes through the same validation as a single run (``scenarios._loader``): a bad one
is recorded as invalid with the ``InputError`` text and the batch goes on. An override that names
no field, key or part of the scenario (a misspelt name, ``UnknownField``) is refused instead, as
``variants[i]['<key>']``, before any variant runs. From ``PREPARE_SHARE``
variants per core on, forked workers prepare shares of the variants while this process prepares
the first (``_forked_map``; the same rows in the same order as one process gives). Valid variants are
grouped by compiled topology and table layout (same generated source, parameter offsets, sample
time, duration and substeps) and each group runs in one call of the compiled batch loop
(``CompiledSystem.run_packed``). Where the native loop runs the group's system (every part's C
generated from its kernels, the reducers' among them, and a C compiler), each variant runs in
it as its single run would, the variants spread over the cores, with no numba compile
(``tests/test_native_batch.py``), unless the batch is large enough that numba's lockstep loop
pays for its compile (``sim._compiled.LOCKSTEP_PAYS_STEPS``) or ``lockstep=True`` asks for it.
In numba, a group of at least ``LANES`` (48) variants per core whose modulators make one segment
per sample runs in lockstep, ``LANES`` variants at a time over SIMD lanes
(``sim._lockstep_source``: bit-identical to the single runs, ``tests/test_lockstep.py``);
otherwise numba's ``prange`` runs the single run's loop one variant per row, bit-identical to
running each variant alone (``tests/test_batch.py`` checks ``np.array_equal``).

**On-line reducers.** A ``Reducer`` is a metric computed inside the loop by sampled parts
(``acdrive._reducer_parts``) appended after every other part: one "stats" part (its step
generated for its channels) with one channel per signal, reference, window and exceed limit
(peak |x| and its time, mean, RMS, the count of samples beyond a limit and the first such time,
the final value), one part per oscillation metric
(``oscillation_step``: the band-limited RMS in two late windows) and one per speed error
(``speed_error_step``: the kernel of ``sim._metrics`` that a single run's summary runs on its
logged samples, so a batch row and summary.json give the same figures under the same names).
Each reads one output port (minus a reference port, if given) at the control samples a single
run logs (every ``log_every``-th) and accumulates in its discrete state, read back after the
run. Nothing is logged per sample unless asked for, so the memory of
a batch is a few hundred floats per variant whatever the duration. The reducer parts only read,
so the plant's slots and generated code are those of the single run; the plant states agree
with the reducer-free loop bit for bit (docs/design.md, "Batches and sweeps"). A variant in a
batch equals the same variant alone in the same loop bit for bit.

**The drive** of each variant answers what is particular to it (``acdrive.drives``): its
scenario schema, its system of parts (``Drive.build``), its default metrics
(``Drive.reducers``) and its stability verdict (``Drive.verdict``). An ``oscillation`` reducer
measures the RMS in ``OSCILLATION_BAND_HZ`` (20-200 Hz; on line: two first-order high-pass
sections at 20 Hz, one low-pass at 200 Hz) over the last ``LATE_WINDOW_S`` (0.25 s) of the run;
its ``_growth`` (the ratio to the RMS over the 0.25 s before) tells a growing oscillation from a
settled limit cycle. A variant whose state stopped being finite is ``unstable`` whatever its drive.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import os
from dataclasses import dataclass, field

import numpy as np

from acdrive._forked_map import forked_map
from acdrive._reducer_parts import (
    _NS,
    NO_LIMIT,
    OSC_STATES,
    REDUCER_KINDS,
    Reducer,
    _reducer_class,
    _speed_error_class,
    _stats_class,
    band_coefficients,
    step_response_part,
)
from acdrive.errors import InputError, UnknownField
from acdrive.sim._loop_source import STATUS_OK
from acdrive.sim._metrics import (
    SPEED_ERROR_STATES,
    TrackingRule,
    speed_error_figures,
)
from acdrive.sim._step_response import EVENT_STATES
from acdrive.sim._system import System

__all__ = [
    "BatchResult",
    "Reducer",
    "default_reducers",
    "prepare_variant",
    "simulate_batch",
]

#: prefix of the parts appended to a system for its reducers
REDUCER_PREFIX = "reducer_"


def check_reducer(r: Reducer, where: str) -> Reducer:
    """``r`` if its fields are well formed (an ``InputError`` naming ``where.<field>``)."""
    if not isinstance(r.name, str) or not r.name.replace("_", "a").replace(".", "a").isalnum():
        raise InputError(f"{where}.name", "must be letters, digits, '_' or '.'")
    if r.kind not in REDUCER_KINDS:
        raise InputError(f"{where}.kind", f"must be one of {', '.join(REDUCER_KINDS)}")
    for name in ("signal", "reference"):
        value = getattr(r, name)
        if (value is not None or name == "signal") and (
            not isinstance(value, str) or value.count(".") != 1
        ):
            raise InputError(f"{where}.{name}", 'must name an output as "part.output"')
    numbers = {"start": r.start, "limit": r.limit, "scale": r.scale, "window": r.window}
    if r.stop is not None:
        numbers["stop"] = r.stop
    for name, value in numbers.items():
        if (
            isinstance(value, bool)
            or not isinstance(value, (int, float))
            or not math.isfinite(value)
        ):
            raise InputError(f"{where}.{name}", "must be a finite number")
    if r.window <= 0 or r.limit < 0 or r.start < 0:
        raise InputError(f"{where}.window", "window must be > 0, start and limit >= 0")
    if r.stop is not None and r.stop <= r.start:
        raise InputError(f"{where}.stop", "must be later than start")
    if r.kind == "step_response" and r.reference is None:
        raise InputError(f"{where}.reference", "a step response needs the speed's reference")
    if r.kind == "step_response" and not r.steps:
        raise InputError(f"{where}.steps", "a step response needs at least one event")
    lo, hi = r.band_hz
    if not 0 < lo < hi:
        raise InputError(f"{where}.band_hz", "must be two frequencies 0 < low < high")
    return r


def default_reducers(setup) -> list[Reducer]:
    """The default metrics of ``setup``'s drive (``acdrive.drives``: its ``reducers``)."""
    from acdrive.drives import for_setup

    return list(for_setup(setup).reducers(setup))


# --- variants -------------------------------------------------------------------------------


def _segments(path: str) -> list[tuple[str, int | None]]:
    out = []
    for token in path.split("."):
        index = None
        if token.endswith("]") and "[" in token:
            token, _, rest = token.partition("[")
            if not rest[:-1].isdigit():
                raise InputError(path, "an index must be a non-negative integer, as in motor[0]")
            index = int(rest[:-1])
        if not token.isidentifier():
            raise InputError(path, "is not a dotted scenario field such as motor[0].load_torque")
        out.append((token, index))
    return out


def _expand_machine(table: dict, root: dict, path: str) -> None:
    """Replace ``machine = "<built-in>"`` in ``table`` by its ``params`` (the fields of its
    ``[params]`` form, ``Drive.params_fields``), so one of them can be changed."""
    from acdrive.drives import for_data
    from acdrive.machines import _registry as registry

    if "params" in table:
        return
    drive = for_data(root)
    name = table.get("machine", drive.default_machine)
    if name not in registry.MACHINES:
        raise InputError(path, f"machine {name!r} is not built in: give [params] instead")
    machine = registry.MACHINES[name]
    fields = drive.params_fields(machine)
    if fields is None:
        raise InputError(path, f"machine {name!r} has no [params] form in a scenario")
    table.pop("machine", None)
    table["params"] = {k: getattr(machine, k) for k in fields}


def _walk(data: dict, path: str, create: bool):
    """(parent table, last key) of a dotted field; ``create`` makes missing tables."""
    parts = _segments(path)
    node = data
    for i, (key, index) in enumerate(parts):
        last = i == len(parts) - 1
        if key == "params" and isinstance(node, dict) and not last:
            _expand_machine(node, data, path)
        if last and index is None:
            if not isinstance(node, dict):
                raise InputError(path, "is not inside a table")
            return node, key
        if not isinstance(node, dict):
            raise InputError(path, "is not inside a table")
        if key not in node:
            if not create or index is not None:
                raise UnknownField(path, f"the base scenario has no {key}")
            node[key] = {}
        node = node[key]
        if index is not None:
            if not isinstance(node, list) or index >= len(node):
                raise UnknownField(path, f"the base scenario has no {key}[{index}]")
            if last:
                raise InputError(path, "names a whole table, not a field")
            node = node[index]
    raise InputError(path, "is empty")  # pragma: no cover


def get_field(data: dict, path: str):
    """The value of dotted field ``path`` in a parsed scenario (None if absent); a built-in
    machine's parameter is read from the machine (``motor[0].params.R_s``)."""
    data = copy.deepcopy(data)
    parent, key = _walk(data, path, create=True)
    return parent.get(key)


def apply_overrides(data: dict, overrides: dict) -> dict:
    """A copy of the parsed scenario ``data`` with dotted fields set (``motor[0].load_torque``).

    An unknown field is set as given: the loader then names it as an unknown key
    (``UnknownField``)."""
    out = copy.deepcopy(data)
    for path, value in overrides.items():
        parent, key = _walk(out, path, create=True)
        parent[key] = value
    return out


def _split(overrides: dict) -> tuple[dict, dict, dict]:
    fields, parts, initial = {}, {}, {}
    for key, value in overrides.items():
        if not isinstance(key, str):
            raise InputError(f"{key!r}", "a variant's keys must be strings")
        if key.startswith(("part:", "initial:")):
            prefix, _, rest = key.partition(":")
            name, dot, param = rest.partition(".")
            if not dot or not name.isidentifier() or not param.isidentifier():
                raise InputError(key, f'must read "{prefix}:<part>.<name>"')
            target = parts if prefix == "part" else initial
            target.setdefault(name, {})[param] = value
        else:
            fields[key] = value
    return fields, parts, initial


def _base_data(base):
    """(parsed scenario dict or None, setup or None) of ``base``."""
    from acdrive.drives import is_setup
    from acdrive.scenarios._files import read_scenario

    if isinstance(base, dict):
        return copy.deepcopy(base), None
    if isinstance(base, str) or hasattr(base, "__fspath__"):
        return read_scenario(base), None
    if is_setup(base):
        return None, base
    raise InputError("base", "must be a scenario name, a TOML path, a parsed dict or a setup")


def build_variant_setup(data: dict):
    """The setup of a parsed scenario, validated by its drive's loader (``Drive.load``)."""
    from acdrive.scenarios._loader import build_setup

    return build_setup(data)


def _drive_of(setup):
    """The built system of one variant (``Drive.build``)."""
    from acdrive.drives import for_setup

    return for_setup(setup).build(setup)


def _port(system: System, path: str, where: str):
    part, _, output = path.partition(".")
    try:
        return getattr(system.part(part).out, output)
    except InputError as exc:
        raise InputError(where, exc.rule) from None


@dataclass
class _Prepared:
    """One valid variant, packed. Only the first of a group holds its system and log ports
    (every member of a group has the same topology, hence the same slots and ports)."""

    index: int
    setup: object
    system: System | None
    reducers: list[tuple[Reducer, tuple[str, int]]]
    log_ports: list
    packed: tuple  # (P, X, S, Y) of this variant, packed once


#: variants per process below which a batch prepares them in one process (``_forked_map``):
#: a fork and the pickled results cost about as much as preparing 100 variants
PREPARE_SHARE = 128


def _portable(topology: tuple) -> tuple:
    """``System.topology()`` with each part class made at run time (a reducer part) named by
    its ``FACTORY_KEY``, so that it pickles; the same grouping, since each key has one class."""
    method, parts, wiring = topology
    named = tuple((kind.__dict__.get("FACTORY_KEY", kind), name) for kind, name in parts)
    return (method, named, wiring)


def _prepared_outcome(overrides, base, reducers, integrator, substeps, base_data, log,
                      log_every):  # fmt: skip
    """One variant prepared (``prepare_variant``), validated and packed: the picklable outcome
    ``("ok", group key, setup, [(reducer, (part, slot))], (P, X, S, Y))`` or
    ``("invalid", the InputError text)`` or ``("unknown", field, rule)`` for an override of a
    field, key or part that does not exist (``UnknownField``), and the variant's system (None
    if invalid)."""
    if not isinstance(overrides, dict):
        return ("invalid", "variants: each variant must be a dict"), None
    try:
        setup, _drive, system, initial, held, used = prepare_variant(
            base, overrides, reducers, integrator, substeps, base_data
        )
        ports = []
        if log is not None:
            ports = [_port(system, name, f"log[{j}]") for j, name in enumerate(log)]
        every = log_every if log_every is not None else setup.log_every
        P, PO = system.pack_params()
        X, S = system.pack_initial(initial)  # validates the initial-state overrides now
        Y = system.pack_held(held)
    except UnknownField as exc:
        return ("unknown", exc.field, exc.rule), None
    except InputError as exc:
        return ("invalid", str(exc)), None
    key = (_portable(system.topology()), tuple(PO), setup.duration, setup.sample_time,
           setup.substeps, every if ports else None)  # fmt: skip
    return ("ok", key, setup, used, (P, X, S, Y)), system


def _with_reducers(drive, reducers: list[Reducer], duration: float, sample_time: float,
                   replaced=None, every: int = 1) -> tuple[System, list[tuple[str, int]]]:  # fmt: skip
    """The drive's system with the reducer parts appended after every other part (the same
    wires; the plant's slots and generated code unchanged), and (part name, first state slot
    within the part) of each reducer. Peak, mean, RMS, exceed and final metrics of the same
    signal, reference and window share one channel of the one "stats" part (at most one exceed
    limit per channel); each oscillation and speed error has its own part. Every metric reads
    the ``every``-th control samples (those a single run logs).
    ``replaced[name]`` is a re-parametrised copy of part ``name`` used in its place."""
    from acdrive.core._parts import Port

    base = drive.system
    replaced = replaced or {}

    def remap(port):
        part = replaced.get(port.part.name)
        return port if part is None else Port(part, port.var, port.direction)

    parts = [replaced.get(p.name, p) for p in base.parts]
    wires = []
    for (dst_part, dst_var), src in base.source_of.items():
        wires.append((remap(src), remap(getattr(base.part(dst_part).inp, dst_var))))
    groups: dict[tuple, dict] = {}
    served = []
    for r in reducers:
        where = f"metrics.{r.name}"
        x = remap(_port(base, r.signal, f"{where}.signal"))
        ref = None
        if r.reference is not None:
            ref = remap(_port(base, r.reference, f"{where}.reference"))
        if ref is not None and (ref.var.kind, ref.var.unit) != (x.var.kind, x.var.unit):
            raise InputError(f"{where}.reference", "must have the kind and unit of the signal")
        if x.var.kind not in ("real", "complex"):
            raise InputError(f"{where}.signal", "must be a real or complex output")
        if r.kind == "oscillation" and x.var.kind == "complex":
            raise InputError(f"{where}.signal", "an oscillation is measured on a real signal")
        if r.kind == "speed_error":
            gate = None if r.gate is None else remap(_port(base, r.gate, f"{where}.gate"))
            rule = r.rule or TrackingRule()
            cls = _speed_error_class(x.var.unit, gate is not None, len(rule.windows))
            values = {"every": float(every), "slew": rule.slew_s_per_rad_s,
                      "settle": rule.settle_s, "has_gate": float(gate is not None)}  # fmt: skip
            for j, (a, b) in enumerate(rule.windows):
                values.update({f"start{j}": a, f"end{j}": b})
            part = cls(f"{REDUCER_PREFIX}speed_error{len(served)}", **values)
            parts.append(part)
            wires += [(x, part.inp.x), (ref, part.inp.ref)]
            if gate is not None:
                wires.append((gate, part.inp.gate))
            served.append((part.name, 0))
            continue
        if r.kind == "step_response":
            name = f"{REDUCER_PREFIX}step_response{len(served)}"
            part = step_response_part(r, x.var.unit, name, every)
            parts.append(part)
            wires += [(x, part.inp.x), (ref, part.inp.ref)]
            served.append((part.name, 0))
            continue
        stop = duration if r.stop is None else min(r.stop, duration)
        start, split, a_hp, b_lp = r.start, 0.0, 0.0, 0.0
        kind = "oscillation" if r.kind == "oscillation" else "stats"
        limit = r.limit if r.kind == "exceed" else None
        if kind == "oscillation":  # two windows at the end of the run
            split = max(stop - r.window, 0.0)
            start = max(split - r.window, r.start)
            a_hp, b_lp = band_coefficients(r.band_hz, sample_time * every)
        key = (kind, r.signal, r.reference, start, stop, split, a_hp, b_lp)
        group = groups.get(key)
        if group is None or (limit is not None and group["limit"] not in (None, limit)):
            key = (*key, len(groups))  # a new channel (stats) or part (oscillation)
            group = groups[key] = {"limit": None, "x": x, "ref": ref, "kind": kind,
                                   "start": start, "stop": stop, "split": split, "a": a_hp,
                                   "b": b_lp, "served": []}  # fmt: skip
        if limit is not None:
            group["limit"] = limit
        group["served"].append(len(served))
        served.append(None)
    stats = [g for g in groups.values() if g["kind"] == "stats"]
    if stats:
        channels = tuple(
            (g["x"].var.unit, g["x"].var.kind == "complex", g["ref"] is not None) for g in stats
        )
        cls = _stats_class(channels)
        values = {"every": float(every)}
        for c, g in enumerate(stats):
            values.update({
                f"start{c}": g["start"], f"stop{c}": g["stop"],
                f"limit{c}": NO_LIMIT if g["limit"] is None else g["limit"],
            })  # fmt: skip
        part = cls(f"{REDUCER_PREFIX}stats", **values)
        parts.append(part)
        for c, g in enumerate(stats):
            wires.append((g["x"], getattr(part.inp, f"x{c}")))
            if g["ref"] is not None:
                wires.append((g["ref"], getattr(part.inp, f"ref{c}")))
            for i in g["served"]:
                served[i] = (part.name, _NS * c)
    oscillations = [g for g in groups.values() if g["kind"] == "oscillation"]
    for j, g in enumerate(oscillations):
        x, ref = g["x"], g["ref"]
        cls = _reducer_class("oscillation", x.var.unit, False, ref is not None)
        part = cls(
            f"{REDUCER_PREFIX}oscillation{j}", start=g["start"], stop=g["stop"],
            split=g["split"], a_hp=g["a"], b_lp=g["b"], is_complex=0.0,
            has_ref=float(ref is not None), every=float(every),
        )  # fmt: skip
        parts.append(part)
        wires.append((x, part.inp.x))
        if ref is not None:
            wires.append((ref, part.inp.ref))
        for i in g["served"]:
            served[i] = (part.name, 0)
    return System(parts, wires, method=base.method), served


def _reduce(r: Reducer, s: np.ndarray, n_ok: bool) -> dict:
    """The metric columns of reducer ``r`` from its part's final discrete state ``s``."""
    nan = math.nan
    if not n_ok:
        return dict.fromkeys(r.columns(), nan)
    if r.kind == "speed_error":
        figures = speed_error_figures(s, abs(r.scale), r.unit)
        return {k + r.suffix: nan if v is None else v for k, v in figures.items()}
    if r.kind == "step_response":
        return r.reduce(s[: len(r.steps) * len(EVENT_STATES)])
    if r.kind == "oscillation":
        late = math.sqrt(s[7] / s[8]) * abs(r.scale) if s[8] else nan
        early = math.sqrt(s[5] / s[6]) * abs(r.scale) if s[6] else nan
        growth = late / early if early and early > 0 else nan
        return {r.name: late, f"{r.name}_growth": growth}
    n = s[0]
    if r.kind == "peak":
        return {r.name: s[1] * abs(r.scale) if n else nan, f"{r.name}_time": s[2] if n else nan}
    if r.kind == "mean":
        return {r.name: s[3] / n * r.scale if n else nan}
    if r.kind == "rms":
        return {r.name: math.sqrt(s[4] / n) * abs(r.scale) if n else nan}
    if r.kind == "exceed":
        return {r.name: float(s[5]), f"{r.name}_first_time": s[6] if s[5] else nan}
    return {r.name: s[7] * r.scale if n else nan}  # final


@dataclass
class BatchResult:
    """Per variant (in the order given) one row of scalars: ``variant`` (its index), ``valid``
    and ``reason`` (the ``InputError`` text of an invalid variant), ``status`` (``ok``,
    ``invalid`` or ``diverged at t = ... s``), ``stable`` (DFIM: the verdict of the module
    docstring; None for other drives or invalid variants), the reducers' metrics and
    ``events.<part>.<event>`` (samples on which the event was raised). ``traces[i]`` holds the
    ``SystemResult`` of variant i when ``log`` was asked for. ``wall_time`` is the compiled
    loops' time; ``steps`` the control steps simulated (valid variants). ``units``: column ->
    unit ("" for flags, counts, ratios and text; ``Reducer.column_units``). ``loops``: the
    batch loop each group ran in ("native", "lockstep" or "per-variant"), in group order."""

    rows: list[dict]
    traces: dict = field(default_factory=dict)
    wall_time: float = 0.0
    steps: int = 0
    groups: int = 0
    units: dict = field(default_factory=dict)
    loops: tuple = ()

    def to_dataframe(self):
        """The rows as a pandas DataFrame; each column's unit in ``frame.attrs["units"]``."""
        import pandas as pd

        frame = pd.DataFrame(self.rows)
        frame.attrs["units"] = {c: self.units.get(c, "") for c in frame.columns}
        return frame


def prepare_variant(base, overrides: dict, reducers=None, integrator: str | None = None,
                    substeps: int | None = None, base_data=None):  # fmt: skip
    """(setup, drive, system with reducers, initial, held, [(reducer, (part, slot))]) of one
    variant; raises ``InputError`` if it is invalid. ``reducers`` None: the drive's default
    metrics. ``base_data``: ``_base_data(base)`` read once for a whole batch (a scenario file
    is then parsed once, not once per variant); this variant works on a copy of it."""
    if base_data is None:
        data, setup = _base_data(base)
    else:
        data, setup = base_data
        data = copy.deepcopy(data)
    fields, part_changes, initial_changes = _split(dict(overrides))
    if fields:
        if data is None:
            raise InputError(next(iter(fields)), "scenario fields need a scenario as the base")
        data = apply_overrides(data, fields)
    if setup is None:
        setup = build_variant_setup(data)
    changes = {}
    if integrator is not None:
        changes["integrator"] = integrator
    if substeps is not None:
        changes["substeps"] = substeps
    if changes:
        setup = dataclasses.replace(setup, **changes)
    drive = _drive_of(setup)
    names = [p.name for p in drive.system.parts]
    for prefix, changes in (("part", part_changes), ("initial", initial_changes)):
        for name in changes:
            if name not in names:
                raise UnknownField(f"{prefix}:{name}", f"no part of this name ({', '.join(names)})")
    replaced = {}
    for name, params in part_changes.items():
        try:
            replaced[name] = drive.system.part(name).with_params(**params)
        except TypeError as exc:  # a parameter the part does not declare
            raise UnknownField(f"part:{name}", str(exc)) from None
    initial, held = drive.initial()
    for name, values in initial_changes.items():
        initial[name] = {**initial.get(name, {}), **values}
    if reducers is None:
        reducers = default_reducers(setup)
    elif callable(reducers):
        reducers = [check_reducer(r, f"metrics[{i}]") for i, r in enumerate(reducers(setup))]
    system, served = _with_reducers(
        drive, list(reducers), setup.duration, setup.sample_time, replaced, setup.log_every
    )
    return setup, drive, system, initial, held, list(zip(reducers, served, strict=True))


def _invalid_row(i: int, reason: str, reducers) -> dict:
    row = {"variant": i, "valid": False, "reason": reason, "status": "invalid", "stable": None}
    for r in () if reducers is None or callable(reducers) else reducers:
        row.update(dict.fromkeys(r.columns(), math.nan))
    return row


def _unknown_field(i: int, overrides: dict, field: str, rule: str) -> InputError:
    """The refusal of variant ``i`` whose override names a field that does not exist: naming
    the override (``variants[i]['key']``) whose key is, or lies under or above, ``field``; the
    field itself if no override names it (the base scenario's own unknown key)."""
    for key in overrides:
        if key.startswith(("part:", "initial:")):  # the part's own name: "<part>[ ...].<name>"
            part, _, name = key.partition(":")[2].partition(".")
            if field.startswith(part) and field.endswith(f".{name}"):
                return InputError(f"variants[{i}][{key!r}]", f"{field}: {rule}")
        inside = (field + ".", field + "[", key + ".", key + "[")
        if key == field or key.startswith(inside[:2]) or field.startswith(inside[2:]):
            said = rule if key == field else f"{field}: {rule}"
            return InputError(f"variants[{i}][{key!r}]", said)
    return InputError(field, rule)


def simulate_batch(base, variants, *, reducers=None, log=None, log_every: int | None = None,
                   integrator: str | None = None, substeps: int | None = None,
                   lockstep: bool | None = None) -> BatchResult:  # fmt: skip
    """Simulate every variant of ``base`` (module docstring) in the compiled batch loop.

    ``reducers``: the metrics (a list of ``Reducer``, or a function of a variant's setup giving
    them; default: ``default_reducers`` of each variant). ``log``: None (no per-sample data) or a list of "part.output" signals to keep,
    every ``log_every`` samples (default: the scenario's), in ``BatchResult.traces``.
    ``integrator`` / ``substeps``: override the scenario's (e.g. ``"rk6"``, 1), applied to every
    variant; running a variant alone with the same setup gives the same bits.
    ``lockstep``: None lets the compiled system choose the native loop or numba's SIMD lockstep
    loop (module docstring), True requires lockstep (``InputError`` naming the modulator where
    it cannot apply), False runs one variant at a time (in the native loop where it runs the
    system).
    """
    if not isinstance(variants, (list, tuple)):
        raise InputError("variants", "must be a list of dicts of overrides")
    if reducers is not None and not callable(reducers):
        reducers = [check_reducer(r, f"metrics[{i}]") for i, r in enumerate(reducers)]
    rows: list[dict | None] = [None] * len(variants)
    base_data = _base_data(base)  # the scenario parsed once for every variant

    here = os.getpid()
    built: dict[tuple, tuple[int, System]] = {}  # group key -> (first index, system), this process

    def prepare(item):
        i, overrides = item
        outcome, system = _prepared_outcome(overrides, base, reducers, integrator, substeps,
                                            base_data, log, log_every)  # fmt: skip
        if system is not None and os.getpid() == here:  # a worker's system stays in the worker
            built.setdefault(outcome[1], (i, system))
        return outcome

    groups: dict[tuple, list[_Prepared]] = {}
    for i, outcome in enumerate(forked_map(prepare, list(enumerate(variants)), PREPARE_SHARE)):
        if outcome[0] == "unknown":
            raise _unknown_field(i, variants[i], *outcome[1:])
        if outcome[0] == "invalid":
            rows[i] = _invalid_row(i, outcome[1], reducers)
            continue
        _, key, setup, used, packed = outcome
        members = groups.setdefault(key, [])
        system, ports = None, []
        if not members:  # the group's system: the one built here, else built again
            first, system = built.get(key, (None, None))
            if first != i:
                _, _, system, _, _, _ = prepare_variant(
                    base, variants[i], reducers, integrator, substeps, base_data
                )
            if log is not None:
                ports = [_port(system, name, f"log[{j}]") for j, name in enumerate(log)]
        members.append(_Prepared(i, setup, system, used, ports, packed))
    wall, steps = 0.0, 0
    loops = []
    traces, units = {}, {}
    for key, members in groups.items():
        _, PO, duration, sample_time, n_sub, every = key
        first = members[0]
        compiled = first.system.compile()
        P, X, S, Y = (np.stack(arrays) for arrays in zip(*(m.packed for m in members)))
        LOG, ELOG, ECOUNT, DONE, STATUS, seconds = compiled.run_packed(
            P, np.array(PO, dtype=np.int64), X, S, Y, duration, sample_time, n_sub,
            log=first.log_ports, log_every=every, lockstep=lockstep,
        )  # fmt: skip
        wall += seconds
        loops.append(compiled.last_batch_loop)
        n_steps = round(duration / sample_time)
        steps += n_steps * len(members)
        names = first.system.event_names()
        for b, m in enumerate(members):
            ok = STATUS[b] == STATUS_OK
            row = {
                "variant": m.index,
                "valid": True,
                "reason": "",
                "status": "ok" if ok else f"diverged at t = {DONE[b] * sample_time:.6g} s",
            }
            for r, (part, offset) in m.reducers:
                units.update(r.column_units(_port(first.system, r.signal, "signal").var.unit))
                a = first.system.slots[part].s[0] + offset
                width = max(_NS, len(OSC_STATES), len(SPEED_ERROR_STATES),
                            len(r.steps) * len(EVENT_STATES))  # fmt: skip
                values = _reduce(r, S[b, a : a + width], ok)
                row.update({k: float(x) for k, x in values.items()})
            for e, (part, events) in enumerate(names):
                if part.startswith(REDUCER_PREFIX):
                    continue
                for bit, name in enumerate(events):
                    row[f"events.{part}.{name}"] = int(ECOUNT[b, e, bit])
            row["stable"] = _verdict(m.setup, row, ok)
            rows[m.index] = row
            if first.log_ports:
                traces[m.index] = compiled._result(
                    0.0, sample_time, every, LOG.shape[1],
                    first.system.log_columns(first.log_ports), LOG[b], ELOG[b], ECOUNT[b], X[b],
                    seconds / len(members), n_steps,
                )  # fmt: skip
                traces[m.index].extra["status"] = row["status"]
    metric_names = {}
    for row in rows:
        if row["valid"]:
            metric_names.update(dict.fromkeys(k for k in row if not k.startswith("events.")))
    for row in rows:  # an invalid variant has every metric column, NaN
        if not row["valid"]:
            for name in metric_names:
                row.setdefault(name, math.nan)
    return BatchResult(rows=rows, traces=traces, wall_time=wall, steps=steps, groups=len(groups),
                       units=units, loops=tuple(loops))  # fmt: skip


def _verdict(setup, row: dict, finite: bool):
    """False if the state stopped being finite; else the drive's own verdict on the row
    (``Drive.verdict``: the DFIM's late speed oscillation; None for a drive without one)."""
    if not finite:
        return False
    from acdrive.drives import for_setup

    return for_setup(setup).verdict(setup, row)
