"""C99 source and header of a system's controller chains, generated from the parts'
declarations (docs/guide/export.md).

Per part kind: up to four structs (``acd_<kind>_params``, ``_state``, ``_in``, ``_out``, each
present if the kind declares any such quantity) with one member per declared quantity, its unit
and description in a comment, and a static step function whose body is the kind's C
(``sim._ccode._kinds``). Per chain: ``<chain>_params`` (the sample time and each part's
parameters), ``<chain>_state`` (each part's discrete state and held outputs),
``<chain>_inputs`` (the plant outputs it reads), ``<chain>_outputs`` (its commands and each
part's event bits), and four functions: ``<chain>_step``, ``<chain>_set_params`` (the values of
the exported system), ``<chain>_reset`` (its initial states and held outputs) and nothing
else: no global variables, no dynamic memory, no recursion, loops with fixed bounds. Above them
the source holds the helpers they call and no other (``_helpers``).

The export writes this text into files (``acdrive.export.to_c``); the native tier of the loop
(``sim._native``) compiles the same text into its library.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from acdrive.core._parts import SampledPart
from acdrive.errors import InputError
from acdrive.sim._ccode._chain import Chain, chains_of
from acdrive.sim._ccode._helpers import helper_text
from acdrive.sim._ccode._kinds import CStep, CSupport, c_step_of
from acdrive.sim._ccode._pieces import kind_name
from acdrive.sim._ccode._prelude import HELPERS, PRELUDE

ROLES = ("params", "state", "in", "out")


def layout_of(part, role: str):
    return {"params": part.PARAMS, "state": part.STATES, "in": part.INPUTS, "out": part.OUTPUTS}[
        role
    ]


@dataclass
class Member:
    """One struct member: ``spec`` is "real", "complex", "uint32", ("table", points),
    ("table2d", x points, y points) or ("struct", type name, [members])."""

    name: str
    spec: object
    comment: str = ""


@dataclass
class KindTypes:
    cls: type
    cname: str
    step: CStep
    body: str = ""
    members: dict = field(default_factory=dict)  # role -> [Member]
    #: the support pieces the body calls (``CStep.support``, or its value for the first part
    #: of a kind whose C is set per instance)
    support: tuple = ()


def literal(value: float, where: str) -> str:
    if not math.isfinite(value):
        raise InputError(where, f"is {value!r}: only finite values can be written as C literals")
    return f"ACD_R({float(value)!r})"


def _tables(part) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Each table parameter of ``part``: (times, values), read from its packed parameters."""
    out, offset = {}, part.PARAMS.table_start
    for v in part.PARAMS.tables:
        n = int(part.p[offset])
        out[v.name] = (
            part.p[offset + 1 : offset + 1 + n],
            part.p[offset + 1 + n : offset + 1 + 2 * n],
        )
        offset += 1 + 2 * n
    return out


def _tables2d(part) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Each 2-D table parameter of ``part``: (x, y, values row by row), read from its packed
    parameters (after its tables)."""
    out, offset = {}, part.PARAMS.table_start
    for v in part.PARAMS.tables:
        offset += 1 + 2 * int(part.p[offset])
    for v in part.PARAMS.tables2d:
        n_x, n_y = int(part.p[offset]), int(part.p[offset + 1])
        x0 = offset + 2
        out[v.name] = (
            part.p[x0 : x0 + n_x],
            part.p[x0 + n_x : x0 + n_x + n_y],
            part.p[x0 + n_x + n_y : x0 + n_x + n_y + n_x * n_y],
        )
        offset += 2 + n_x + n_y + n_x * n_y
    return out


def _comment(var) -> str:
    return f"[{var.unit or '-'}] {var.doc}"


def kind_types(parts, lookup=c_step_of) -> dict[type, KindTypes]:
    """The structs of every kind among ``parts`` (a table holds as many points as the longest
    table of that name among the kind's instances); ``lookup`` gives a part's C (the sampled
    kinds' registry, or the plant kinds' one)."""
    kinds: dict[type, KindTypes] = {}
    for part in parts:
        cls = type(part)
        step = lookup(part)
        body = step.body(part) if callable(step.body) else step.body
        if cls not in kinds:
            support = step.support(part) if callable(step.support) else step.support
            kinds[cls] = KindTypes(cls, kind_name(cls), step, body, support=support)
        entry = kinds[cls]
        if body != entry.body:
            raise InputError(
                part.name,
                f"its C differs from another {cls.__name__} of the system (a kind whose C is "
                "set per instance can be exported once per system)",
            )
        for role in ROLES:
            members = []
            for v in layout_of(part, role):
                if v.kind == "table":
                    points = len(_tables(part)[v.name][0])
                    members.append(Member(v.name, ("table", points), _comment(v)))
                elif v.kind == "table2d":
                    x, y, _ = _tables2d(part)[v.name]
                    members.append(Member(v.name, ("table2d", len(x), len(y)), _comment(v)))
                else:
                    members.append(Member(v.name, v.kind, _comment(v)))
            old = entry.members.get(role)
            if old is None:
                entry.members[role] = members
                continue
            if [(m.name, m.spec if not isinstance(m.spec, tuple) else m.spec[0]) for m in old] != [
                (m.name, m.spec if not isinstance(m.spec, tuple) else m.spec[0]) for m in members
            ]:
                raise InputError(
                    part.name,
                    f"its {role} declarations differ from another {cls.__name__} of the system; "
                    "one C kind needs one layout",
                )
            for a, b in zip(old, members, strict=True):
                if isinstance(a.spec, tuple) and a.spec[0] == "table":
                    a.spec = ("table", max(a.spec[1], b.spec[1]))
                elif isinstance(a.spec, tuple) and a.spec[0] == "table2d":
                    a.spec = ("table2d", max(a.spec[1], b.spec[1]), max(a.spec[2], b.spec[2]))
    return kinds


def _first_sentence(cls: type) -> str:
    """The first sentence of a class's own docstring (for a struct's comment)."""
    text = " ".join((getattr(cls, "_own_doc", None) or cls.__doc__ or cls.__name__).split())
    end = text.find(". ")
    return (text[: end + 1] if end >= 0 else text).replace("*/", "* /")


def _struct_lines(type_name: str, members: list[Member], doc: str, kind: str = "") -> list[str]:
    lines = [f"/* {doc} */", "typedef struct {"]
    for m in members:
        lines.append(f"    {_declaration(m, kind)} /* {m.comment} */")
    lines.append(f"}} {type_name};")
    return lines


def _declaration(m: Member, kind: str = "") -> str:
    if m.spec == "real":
        return f"ACDRIVE_REAL {m.name};"
    if m.spec == "complex":
        return f"acd_complex {m.name};"
    if m.spec == "uint32":
        return f"uint32_t {m.name};"
    if m.spec[0] == "table":
        n = f"ACD_{kind.upper()}_{m.name.upper()}_POINTS" if kind else m.spec[1]
        return f"struct {{ int n; ACDRIVE_REAL t[{n}]; ACDRIVE_REAL v[{n}]; }} {m.name};"
    if m.spec[0] == "table2d":
        name = f"ACD_{kind.upper()}_{m.name.upper()}"
        nx, ny = (f"{name}_X_POINTS", f"{name}_Y_POINTS") if kind else m.spec[1:]
        return (f"struct {{ int nx; int ny; ACDRIVE_REAL x[{nx}]; ACDRIVE_REAL y[{ny}]; "
                f"ACDRIVE_REAL v[({nx}) * ({ny})]; }} {m.name};")  # fmt: skip
    return f"{m.spec[1]} {m.name};"


def _support_order(kinds, extra: tuple[CSupport, ...] = ()) -> list[CSupport]:
    """The support pieces of ``kinds`` and ``extra``, each after the pieces it needs."""
    seen, order = set(), []

    def visit(support):
        if support.name in seen:
            return
        seen.add(support.name)
        for dep in support.needs:
            visit(dep)
        order.append(support)

    for entry in kinds.values():
        for support in entry.support:
            visit(support)
    for support in extra:
        visit(support)
    return order


def helpers_of(kinds, code: list[str], extra: tuple[CSupport, ...] = ()) -> str:
    """The helpers the lines ``code`` call (``_helpers``), drawn from the prelude's and from
    the support of ``kinds`` and ``extra`` (with what each piece needs)."""
    pieces = [HELPERS] + [support.code for support in _support_order(kinds, extra)]
    return helper_text(pieces, "\n".join(code), PRELUDE)


def _step_signature(entry: KindTypes) -> str:
    args = ["ACDRIVE_REAL t", "ACDRIVE_REAL T_s"]
    for role, const, arg in (("in", True, "u"), ("params", True, "p"), ("state", False, "s"),
                             ("out", False, "y")):  # fmt: skip
        if entry.members.get(role):
            args.append(f"{'const ' if const else ''}acd_{entry.cname}_{role} *{arg}")
    return f"static uint32_t acd_{entry.cname}_step({', '.join(args)})"


@dataclass
class ChainModel:
    """The structs of one chain (members by struct) for the C text and its ctypes mirror."""

    chain: Chain
    params: list[Member]
    state: list[Member]
    inputs: list[Member]
    outputs: list[Member]


def _port_name(port) -> str:
    return f"{port.part.name}_{port.var.name}"


def chain_model(chain: Chain, kinds, open_loop: bool = False) -> ChainModel:
    """The structs of ``chain``; ``open_loop``: a chain that reads no plant output (an open-loop
    program) gets an inputs struct with one unused member instead of being refused (the native
    loop runs such chains; an export of a controller refuses them)."""
    params = [Member("sample_time", "real", "[s] T_s, the period at which the step is called")]
    state, outputs = [], []
    for part in chain.parts:
        entry = kinds[type(part)]
        what = f"{type(part).__name__} {part.name}"
        if entry.members["params"]:
            params.append(Member(part.name, ("struct", f"acd_{entry.cname}_params", None), what))
        if entry.members["state"]:
            state.append(Member(part.name, ("struct", f"acd_{entry.cname}_state", None), what))
        if entry.members["out"]:
            held = f"{what}: outputs, held between samples"
            state.append(
                Member(f"{part.name}_out", ("struct", f"acd_{entry.cname}_out", None), held)
            )
    inputs = [
        Member(_port_name(port), port.var.kind, f"{_comment(port.var)} (from {port.path})")
        for port in chain.inputs
    ]
    for port in chain.outputs:
        outputs.append(
            Member(_port_name(port), port.var.kind, f"{_comment(port.var)} ({port.path})")
        )
    for part in chain.parts:
        if part.EVENTS:
            masks = ", ".join(
                f"ACD_{kinds[type(part)].cname.upper()}_{e.upper()}" for e in part.EVENTS
            )
            outputs.append(
                Member(f"{part.name}_events", "uint32", f"{part.name}'s event bits: {masks}")
            )
    if not inputs and open_loop:
        inputs = [Member("unused", "real", "no plant output is read: an open-loop chain")]
    if not inputs:
        raise InputError(chain.name, "the chain reads no plant output: nothing to export")
    return ChainModel(chain, params, state, inputs, outputs)


def _value_lines(target: str, var, values, where: str) -> list[str]:
    """Assignments of a part's quantity ``var`` (value(s) from the packed arrays)."""
    if var.kind == "complex":
        return [f"{target}.re = {literal(values[0], where)};",
                f"{target}.im = {literal(values[1], where)};"]  # fmt: skip
    return [f"{target} = {literal(values[0], where)};"]


def part_params_lines(part) -> list[str]:
    """Assignments of every parameter of ``part`` to ``p-><part name>`` (its packed values)."""
    lines = []
    for v in part.PARAMS:
        where = f"{part.name}.{v.name}"
        if v.kind == "table":
            times, values = _tables(part)[v.name]
            lines.append(f"p->{part.name}.{v.name}.n = {len(times)};")
            for i, (a, b) in enumerate(zip(times, values, strict=True)):
                lines.append(f"p->{part.name}.{v.name}.t[{i}] = {literal(a, where)};")
                lines.append(f"p->{part.name}.{v.name}.v[{i}] = {literal(b, where)};")
            continue
        if v.kind == "table2d":
            target = f"p->{part.name}.{v.name}"
            x, y, values = _tables2d(part)[v.name]
            lines += [f"{target}.nx = {len(x)};", f"{target}.ny = {len(y)};"]
            for axis, points in (("x", x), ("y", y), ("v", values)):
                lines += [f"{target}.{axis}[{i}] = {literal(a, where)};"
                          for i, a in enumerate(points)]  # fmt: skip
            continue
        k = part.PARAMS.slot(v.name)
        lines += _value_lines(f"p->{part.name}.{v.name}", v, part.p[k : k + v.width], where)
    return lines


def _set_params_lines(model: ChainModel, sample_time: float) -> list[str]:
    lines = [f"p->sample_time = {literal(sample_time, 'sample_time')};"]
    for part in model.chain.parts:
        lines += part_params_lines(part)
    return lines


def _reset_lines(system, model: ChainModel, S: np.ndarray, Y: np.ndarray) -> list[str]:
    lines = []
    for part in model.chain.parts:
        a, _ = system.slots[part.name].s
        for v in part.STATES:
            k = a + part.STATES.slot(v.name)
            lines += _value_lines(f"s->{part.name}.{v.name}", v, S[k : k + v.width],
                                  f"initial.{part.name}.{v.name}")  # fmt: skip
        a, _ = system.slots[part.name].y
        for v in part.OUTPUTS:
            k = a + part.OUTPUTS.slot(v.name)
            lines += _value_lines(f"s->{part.name}_out.{v.name}", v, Y[k : k + v.width],
                                  f"held.{part.name}.{v.name}")  # fmt: skip
    return lines


def _chain_step_lines(model: ChainModel, kinds, source_of) -> list[str]:
    """Body of ``<chain>_step``: each part's inputs gathered (from the chain's inputs or from
    the held outputs of the parts before it), its step called, the commands copied out."""
    chain = model.chain
    members = {id(p) for p in chain.parts}
    lines = ["const ACDRIVE_REAL T_s = p->sample_time;"]
    for part in chain.parts:
        entry = kinds[type(part)]
        args = ["t", "T_s"]
        lines.append(f"{{ /* {part.name}: {type(part).__name__} */")
        if entry.members["in"]:
            lines.append(f"    acd_{entry.cname}_in u;")
            for v in part.INPUTS:
                src = source_of[(part.name, v.name)]
                if id(src.part) in members:
                    value = f"s->{src.part.name}_out.{src.var.name}"
                else:
                    value = f"in->{_port_name(src)}"
                lines.append(f"    u.{v.name} = {value};")
            args.append("&u")
        if entry.members["params"]:
            args.append(f"&p->{part.name}")
        if entry.members["state"]:
            args.append(f"&s->{part.name}")
        if entry.members["out"]:
            args.append(f"&s->{part.name}_out")
        call = f"acd_{entry.cname}_step({', '.join(args)})"
        if part.EVENTS:
            lines.append(f"    out->{part.name}_events = {call};")
        else:
            lines.append(f"    (void){call};")
        lines.append("}")
    for port in chain.outputs:
        lines.append(f"out->{_port_name(port)} = s->{port.part.name}_out.{port.var.name};")
    return lines


#: the compile-time switch of the input guard (docs/guide/export.md, "Non-finite inputs")
GUARD_MACRO = "ACDRIVE_GUARD_INPUTS"


def _guard_members(chain_name: str) -> list[str]:
    """The state members of the input guard, compiled only with ``-DACDRIVE_GUARD_INPUTS``."""
    return [f"#ifdef {GUARD_MACRO}",
            f"    {chain_name}_inputs last_finite; /* the input guard: each input's last finite "
            "value (0 before the first) */",
            "    uint32_t input_faults; /* the input guard: bit k set when input k (in the order "
            f"of {chain_name}_inputs; bit 31 for 31 and later) was not finite at the last step "
            "and its last finite value was used */",
            "#endif"]  # fmt: skip


def _guard_lines(model: ChainModel) -> list[str]:
    """Start of ``<chain>_step`` with ``-DACDRIVE_GUARD_INPUTS``: every input that is not finite
    (NaN or infinite; a complex one if either part is) is replaced by its last finite value and
    flagged in ``s->input_faults``; a finite one becomes the last finite value. The step then
    reads the guarded copy. Without the macro the step reads ``in`` as given."""
    c = model.chain.name
    lines = [f"#ifdef {GUARD_MACRO}", f"{c}_inputs guarded = *in;", "s->input_faults = 0u;"]
    for k, m in enumerate(model.inputs):
        bit = f"(1u << {min(k, 31)})"
        finite = (f"isfinite(guarded.{m.name}.re) && isfinite(guarded.{m.name}.im)"
                  if m.spec == "complex" else f"isfinite(guarded.{m.name})")  # fmt: skip
        lines += [f"if ({finite}) {{", f"    s->last_finite.{m.name} = guarded.{m.name};",
                  "} else {", f"    guarded.{m.name} = s->last_finite.{m.name};",
                  f"    s->input_faults |= {bit};", "}"]  # fmt: skip
    return [*lines, "in = &guarded;", "#endif"]


def _guard_reset_lines(model: ChainModel) -> list[str]:
    """``<chain>_reset``'s part of the input guard: no fault, every last finite value 0."""
    lines = [f"#ifdef {GUARD_MACRO}", "s->input_faults = 0u;"]
    for m in model.inputs:
        if m.spec == "complex":
            lines += [f"s->last_finite.{m.name}.re = 0;", f"s->last_finite.{m.name}.im = 0;"]
        else:
            lines.append(f"s->last_finite.{m.name} = 0;")
    return [*lines, "#endif"]


def _step_prototype(model: ChainModel) -> str:
    c = model.chain.name
    out = f", {c}_outputs *out" if model.outputs else ""
    return (f"void {c}_step(ACDRIVE_REAL t, const {c}_params *p, {c}_state *s, "
            f"const {c}_inputs *in{out})")  # fmt: skip


def kind_declarations(kinds) -> list[str]:
    """Header lines of every kind: its event masks, table sizes and structs."""
    H = []
    for entry in kinds.values():
        cls = entry.cls
        first = _first_sentence(cls)
        H.append(f"/* ---- {cls.__name__} ({cls.__module__}): {entry.step.source} ---- */")
        for b, event in enumerate(cls.EVENTS):
            H.append(f"#define ACD_{entry.cname.upper()}_{event.upper()} (1u << {b})")
        for role in ROLES:
            members = entry.members[role]
            if not members:
                continue
            for m in members:
                if isinstance(m.spec, tuple) and m.spec[0] == "table":
                    H.append(
                        f"#define ACD_{entry.cname.upper()}_{m.name.upper()}_POINTS {m.spec[1]}"
                    )
                if isinstance(m.spec, tuple) and m.spec[0] == "table2d":
                    name = f"ACD_{entry.cname.upper()}_{m.name.upper()}"
                    H += [f"#define {name}_X_POINTS {m.spec[1]}",
                          f"#define {name}_Y_POINTS {m.spec[2]}"]  # fmt: skip
            H += _struct_lines(
                f"acd_{entry.cname}_{role}", members, f"{cls.__name__} {role}: {first}", entry.cname
            )
        H.append("")
    return H


@dataclass
class CFiles:
    """A generated C header and source (text) named ``name``, and the kinds' struct types."""

    name: str
    header: str
    source: str
    kinds: dict

    @property
    def header_name(self) -> str:
        return f"{self.name}.h"

    @property
    def source_name(self) -> str:
        return f"{self.name}.c"


@dataclass
class CExport(CFiles):
    """The controller chains' files and the model of their structs."""

    chains: list[ChainModel]


def require_c_name(field_name: str, name: str) -> str:
    if not isinstance(name, str) or not re.fullmatch(r"[a-z_][a-z0-9_]*", name):
        raise InputError(field_name, "must be a C identifier of lower-case letters, digits and _")
    return name


#: what ``to_c`` reads of a ``System`` (acdrive.sim.System)
_SYSTEM_READS = ("parts", "sampled", "slots", "source_of", "part", "pack_initial", "pack_held")


def to_c(system, sample_time: float, initial=None, held=None, name: str = "acdrive_chain",
         description: str = "", open_loop: bool = False, values: bool = True) -> CExport:  # fmt: skip
    """C99 header and source of the controller chains of ``system`` (docs/guide/export.md):
    ``initial`` and ``held`` as for ``CompiledSystem.run`` give the values ``<chain>_reset``
    writes, ``sample_time`` the period ``<chain>_set_params`` writes. Raises ``InputError``
    naming a part whose kind has no C (``sim._ccode._kinds``), and one for anything but a
    ``System``: a list of parts has no wiring, and the wiring is what says which plant outputs a
    chain reads and which commands it gives (build the System from the parts first).
    ``open_loop``: a chain that reads no plant output is kept (``chain_model``; the native loop's
    use), where an export refuses it. ``values=False`` leaves out the definitions of
    ``<chain>_set_params`` and ``<chain>_reset`` (the native loop loads both from acdrive's packed
    arrays, so its C names no parameter value and one library serves every parameter set)."""
    # a System by what the export reads of it (its parts, chains, slots and wiring), not by
    # importing acdrive.sim._system: System imports the loop's tiers (sim._compiled), whose
    # native tier (sim._native) calls to_c, so the class check here would close an import cycle
    if not all(hasattr(system, attr) for attr in _SYSTEM_READS):
        what = "a list of parts" if isinstance(system, (list, tuple)) else type(system).__name__
        raise InputError(
            "system",
            f"must be a System (acdrive.sim.System), got {what}: the export reads the chain's "
            "inputs and commands from the System's wiring; build one from the parts first",
        )
    name = require_c_name("name", name)
    if (
        isinstance(sample_time, bool)
        or not isinstance(sample_time, (int, float))
        or not (math.isfinite(sample_time) and sample_time > 0)
    ):
        raise InputError("sample_time", "must be a finite number > 0")
    chains = chains_of(system, name)
    kinds = kind_types([p for c in chains for p in c.parts])
    _, S = system.pack_initial(initial)
    Y = system.pack_held(held)
    models = [chain_model(c, kinds, open_loop) for c in chains]
    guard = f"{name.upper()}_H"
    stamp = [f"/* Generated by acdrive.export.to_c{': ' + description if description else ''}.",
             " * Compile with -DACDRIVE_FLOAT for the float build (docs/guide/export.md).",
             " * Do not edit: regenerate from the system. */"]  # fmt: skip
    H = [*stamp, f"#ifndef {guard}", f"#define {guard}", "", "#include <stdint.h>", PRELUDE]
    H += kind_declarations(kinds)
    for model in models:
        c = model.chain.name
        parts = ", ".join(p.name for p in model.chain.parts)
        H.append(f"/* ==== chain {c}: {parts} ==== */")
        for role, members, what in (("params", model.params, "parameters"),
                                    ("inputs", model.inputs, "plant outputs read at each sample"),
                                    ("state", model.state, "discrete states and held outputs"),
                                    ("outputs", model.outputs, "commands and event bits")):  # fmt: skip
            if members:  # a chain that commands nothing (estimators only) has no outputs
                lines = _struct_lines(f"{c}_{role}", members, f"{c}: {what}")
                if role == "state":
                    lines[-1:-1] = _guard_members(c)
                H += lines
        H += [
            "/* one sample at time t [s]: reads in, updates s, writes out; call every",
            f"   p->sample_time seconds, first with the state from {c}_reset */",
            f"{_step_prototype(model)};",
            "/* the parameter values of the exported system */",
            f"void {c}_set_params({c}_params *p);",
            "/* the initial states and held outputs of the exported system */",
            f"void {c}_reset({c}_state *s);",
            "",
        ]
    H.append(f"#endif /* {guard} */")

    C = []  # the kinds' steps and the chains' functions; the helpers they call go above
    for entry in kinds.values():
        C.append(f"/* {entry.cls.__name__}.step: {entry.step.source} */")
        C.append(_step_signature(entry))
        C.append("{")
        C += ["    (void)t;", "    (void)T_s;"]
        C.append(entry.body.strip("\n"))
        C.append("}")
        C.append("")
    for model in models:
        c = model.chain.name
        C.append(_step_prototype(model))
        C.append("{")
        C += ["    " + line for line in _guard_lines(model)]
        C += ["    " + line for line in _chain_step_lines(model, kinds, system.source_of)]
        C += ["}", ""]
        if not values:
            continue
        C += [f"void {c}_set_params({c}_params *p)", "{"]
        C += ["    " + line for line in _set_params_lines(model, sample_time)]
        C += ["}", "", f"void {c}_reset({c}_state *s)", "{"]
        C += ["    " + line for line in _reset_lines(system, model, S, Y)]
        C += ["    " + line for line in _guard_reset_lines(model)]
        C += ["}", ""]
    C = [*stamp, f'#include "{name}.h"', "", "#include <math.h>", "", helpers_of(kinds, C), "", *C]
    return CExport(name, "\n".join(H) + "\n", "\n".join(C) + "\n", kinds, models)


def sampled_parts_without_c(system) -> list[str]:
    """Names of the sampled parts whose kind has no C (for a message listing them all)."""
    missing = []
    for part in system.parts:
        if isinstance(part, SampledPart):
            try:
                c_step_of(part)
            except InputError:
                missing.append(part.name)
    return missing
