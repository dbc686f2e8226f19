"""C99 source and header of a system's plant: its continuous parts and modulators with
acdrive's integrator, one control period per call (docs/guide/fmu.md).

The plant is everything that is not sampled: machines, shafts, sources (continuous parts) and
converters (modulators). Its **inputs** are the sampled outputs wired into it (the commands of
the controller chain, named ``<part>_<output>`` after the output that feeds them), its
**outputs** every output of its parts. The generated functions repeat the steps of acdrive's
compiled loop (``sim._loop_source``) for one sample t_k:

* ``<name>_step(t, p, s, in)``: the modulators' segments from the commands ``in`` and the plant
  outputs at t_k (``modulate``), then the integration over the merged segments, ``substeps``
  Runge-Kutta steps per segment (``integrate``, ``plant_step``), the same method as the system's
  (``system.method``: rk4 written out as acdrive's, or the Butcher tableau of rk6);
* ``<name>_update_outputs(t, p, s, in)``: the redundant states re-normalised (``project``),
  then the plant outputs from the state at t and the commands ``in`` held (``plant_outputs``);
* ``<name>_reset(t, p, s, in)``: initial states and held modulator outputs, then the outputs at
  t with the commands ``in`` (the values held before the first sample).

A part's *direct* outputs (computed from its inputs of the same evaluation: the DFIM's currents
from its relay input, the supply bus, the stator relay) are computed after the state outputs, in
the system's order of direct parts (``System.direct``), as acdrive's ``plant_outputs`` does. One
of them may read a controller command (the stator relay's, from the synchroniser): acdrive's
loop computes the plant outputs at t_k before the sampled parts run, so they read the command
held from sample k-1, and the command of sample k acts from t_k on, inside the integration. The
plant FMU does the same: the outputs after a step to t_{k+1} are computed with the commands
that step integrated, and setting an input changes no output until the next step. There is no
same-instant feedthrough across the boundary, so nothing is refused for it.

Each kind's C is generated from its kernels (``sim._ccode._kinds``, as the controller kinds'
is). A part with direct outputs or a ``project`` kernel its C lacks is refused, naming the
part.

The plant FMU (``acdrive.export``) is built from this text; the native tier of the loop
(``sim._native``) compiles the same text, with its record hook, into its library.
"""

from __future__ import annotations

from dataclasses import dataclass

from acdrive.core._parts import Port, SampledPart
from acdrive.errors import InputError
from acdrive.sim._ccode._c_source import (
    CFiles,
    KindTypes,
    Member,
    _comment,
    _port_name,
    _struct_lines,
    _value_lines,
    helpers_of,
    kind_declarations,
    kind_types,
    literal,
    part_params_lines,
    require_c_name,
)
from acdrive.sim._ccode._kinds import PLANT_ROLES, plant_c_of
from acdrive.sim._ccode._prelude import PRELUDE
from acdrive.sim._ccode._pieces import TABLE_NEXT_TIME
from acdrive.sim._integrators import METHODS
from acdrive.sim._rk_source import c_dialect, step_lines
from acdrive.sim._loop_source import profile_parts

#: the compiled loop's rule (sim._loop_source.integrate): a segment whose remaining length is
#: at most this fraction of T_s is finished
SEGMENT_END_RTOL = 1e-12


@dataclass
class PlantExport(CFiles):
    """The plant's files and what the FMU needs to know of them: the plant parts, the FMU's
    inputs (ports of sampled parts feeding the plant) and outputs (every plant part output)."""

    continuous: list
    modulators: list
    inputs: list[Port]
    outputs: list[Port]


def _check_exportable(system) -> None:
    for part in system.continuous:
        if part.DIRECT_OUTPUTS and plant_c_of(part).direct_outputs is None:
            raise InputError(
                part.name,
                f"part kind {type(part).__name__} has direct outputs, which its C does not "
                "write (its direct_outputs kernel gave no C)",
            )
        if type(part).project is not None and plant_c_of(part).project is None:
            raise InputError(
                part.name,
                f"part kind {type(part).__name__} re-normalises its states (project), which the "
                "plant export does not write in C yet",
            )


def _plant_inputs(system, parts) -> list[Port]:
    inputs: list[Port] = []
    for part in parts:
        for v in part.INPUTS:
            src = system.source_of[(part.name, v.name)]
            if isinstance(src.part, SampledPart) and all(
                q.part is not src.part or q.var.name != src.var.name for q in inputs
            ):
                inputs.append(src)
    return inputs


def _signature(entry: KindTypes, role: str) -> str:
    """The static function of one kernel role of a plant kind (arguments present only for the
    structs the kind declares)."""
    c, has = entry.cname, {r: bool(entry.members.get(r)) for r in ("params", "state", "in", "out")}
    if role == "state_outputs":
        args = ["ACDRIVE_REAL t"]
        args += [f"const acd_{c}_params *p"] if has["params"] else []
        args += [f"const acd_{c}_state *x"] if has["state"] else []
        args += [f"acd_{c}_out *y"]
        return f"static void acd_{c}_state_outputs({', '.join(args)})"
    if role == "rhs":
        args = ["ACDRIVE_REAL t"]
        args += [f"const acd_{c}_params *p"] if has["params"] else []
        args += [f"const acd_{c}_state *x"]
        args += [f"const acd_{c}_in *u"] if has["in"] else []
        args += [f"const acd_{c}_out *y", f"acd_{c}_state *dx"]
        return f"static void acd_{c}_rhs({', '.join(args)})"
    if role == "direct_outputs":
        args = ["ACDRIVE_REAL t"]
        args += [f"const acd_{c}_params *p"] if has["params"] else []
        args += [f"const acd_{c}_state *x"] if has["state"] else []
        args += [f"const acd_{c}_in *u"] if has["in"] else []
        args += [f"acd_{c}_out *y"]
        return f"static void acd_{c}_direct_outputs({', '.join(args)})"
    if role == "project":
        args = [f"const acd_{c}_params *p"] if has["params"] else []
        return f"static void acd_{c}_project({', '.join([*args, f'acd_{c}_state *x'])})"
    args = ["ACDRIVE_REAL T_s"]
    args += [f"const acd_{c}_in *u"] if has["in"] else []
    args += [f"const acd_{c}_params *p"] if has["params"] else []
    args += [f"acd_{c}_state *s"] if has["state"] else []
    args += ["int *n", "ACDRIVE_REAL *dt", f"acd_{c}_out *v"]
    return f"static uint32_t acd_{c}_segments({', '.join(args)})"


def _unused(signature: str) -> list[str]:
    """``(void)arg;`` for every argument, so a body need not use them all (-Wextra clean)."""
    inner = signature[signature.index("(") + 1 : signature.rindex(")")]
    names = [a.split()[-1].lstrip("*") for a in inner.split(", ")]
    return [f"    (void){n};" for n in names]


def _kind_functions(kinds, parts) -> list[str]:
    C = []
    for entry in kinds.values():
        c = entry.step
        part = next(q for q in parts if type(q) is entry.cls)  # its instances' C is one
        for role in PLANT_ROLES:
            body = c.role(role, part)
            if body is None:
                continue
            signature = _signature(entry, role)
            C += [f"/* {entry.cls.__name__}.{role}: {c.source} */", signature, "{"]
            C += _unused(signature)
            C += [body.strip("\n"), "}", ""]
    return C


def _input_source(system, part, var_name: str, outputs: str) -> str:
    """The C expression of one input of ``part``: a command of the chain (``in->``) or an output
    of a plant part (``outputs`` is the prefix of the outputs struct, ``y->`` or ``s->y.``)."""
    src = system.source_of[(part.name, var_name)]
    if isinstance(src.part, SampledPart):
        return f"in->{_port_name(src)}"
    return f"{outputs}{src.part.name}.{src.var.name}"


def _call_args(entry: KindTypes, role: str, part, x: str, y: str, dx: str = "") -> str:
    has = {r: bool(entry.members.get(r)) for r in ("params", "state", "in")}
    args = ["t"]
    args += [f"&p->{part.name}"] if has["params"] else []
    if role == "state_outputs":
        args += [f"&{x}->{part.name}"] if has["state"] else []
        args += [f"&{y}->{part.name}"]
    else:
        args += [f"&{x}->{part.name}"]
        args += ["&u"] if has["in"] else []
        args += [f"&{y}->{part.name}", f"&{dx}->{part.name}"]
    return ", ".join(args)


def _direct_lines(system, kinds) -> list[str]:
    """The direct outputs of every direct part, in the system's order (``System.direct``, each
    after the parts it reads), from the inputs it declares in ``DIRECT_FROM``: the statements
    of ``sim._loop_source.plant_outputs`` after the state outputs."""
    L = []
    for part in system.direct:
        entry = kinds[type(part)]
        L.append(f"    {{ /* {part.name}: {type(part).__name__}, direct outputs */")
        args = ["t"]
        args += [f"&p->{part.name}"] if entry.members["params"] else []
        args += [f"&x->{part.name}"] if entry.members["state"] else []
        if entry.members["in"]:
            L.append(f"        acd_{entry.cname}_in u;")
            for v in part.INPUTS:
                if v.name in part.DIRECT_FROM:
                    L.append(f"        u.{v.name} = {_input_source(system, part, v.name, 'y->')};")
            args.append("&u")
        args.append(f"&y->{part.name}")
        L += [f"        acd_{entry.cname}_direct_outputs({', '.join(args)});", "    }"]
    return L


def _rk_lines(method: str, n_x: int, name: str) -> list[str]:
    """Body of ``<name>_plant_step``: one Runge-Kutta step with the inputs held and the stage
    times capped at ``cap``, the method's tableau expanded as every loop expands it
    (``sim._rk_source``)."""
    if method not in METHODS:
        raise InputError("integrator", f"{method} has no C in the plant export ({', '.join(METHODS)} have)")
    return step_lines(method, c_dialect(name, n_x))


def _advance_lines(system, name: str, in_arg: str) -> list[str]:
    """``<name>_next_break`` and ``<name>_advance``: the integration over one span split at the
    points of the continuous parts' profiles, with the stage times capped below the point that
    ends a piece (``sim._loop_source.advance_lines``, same rule and order)."""
    L = [f"static ACDRIVE_REAL {name}_next_break(ACDRIVE_REAL t, const {name}_params *p)", "{",
         "    ACDRIVE_REAL earliest = ACD_HUGE, later;", "    (void)p;", "    (void)later;"]  # fmt: skip
    for _, part in profile_parts(system):
        for v in part.PARAMS.tables:
            tab = f"p->{part.name}.{v.name}"
            L += [f"    later = acd_table_next_time({tab}.n, {tab}.t, t);",
                  "    if (later < earliest) {", "        earliest = later;", "    }"]  # fmt: skip
    L += ["    return earliest;", "}", ""]
    step = f"{name}_plant_step(a + (ACDRIVE_REAL)j * h, h, cap, p, X, in, y);"
    L += [(f"static void {name}_advance(ACDRIVE_REAL a, ACDRIVE_REAL span, const {name}_params *p, "
           f"{name}_vector *X, {in_arg}, {name}_outputs *y)"), "{",
          "    ACDRIVE_REAL nb = " + f"{name}_next_break(a, p), end, h, cap;", "    int j;",
          "    while (nb < a + span) {", "        end = a + span;",
          "        h = (nb - a) / (ACDRIVE_REAL)p->substeps;",
          "        cap = ACD_NEXTAFTER(nb, -ACD_HUGE);",
          "        for (j = 0; j < p->substeps; ++j) {", f"            {step}", "        }",
          "        a = nb;", "        span = end - nb;", f"        nb = {name}_next_break(a, p);",
          "    }", "    h = span / (ACDRIVE_REAL)p->substeps;",
          "    cap = nb < ACD_HUGE ? ACD_NEXTAFTER(nb, -ACD_HUGE) : ACD_HUGE;",
          "    for (j = 0; j < p->substeps; ++j) {", f"        {step}", "    }", "}", ""]  # fmt: skip
    return L


def _integrate_lines(system, kinds, modulators, name: str) -> list[str]:
    """Body of ``<name>_step``: modulate, then integrate over the merged segments
    (``sim._loop_source``: ``modulate`` and ``integrate``, same rule and order)."""
    L = ["    const ACDRIVE_REAL T_s = p->sample_time;", "    ACDRIVE_REAL tk = t;",
         "    (void)tk;"]  # fmt: skip
    # a hook between the modulators and the integration, where acdrive's loop records a sample
    # (undefined in an export; the native tier defines it, acdrive.sim._native)
    hook = ["#ifdef ACD_AFTER_MODULATE", "    ACD_AFTER_MODULATE(t, s);", "#endif"]
    if not modulators:
        L += hook
        L += [f"    {name}_advance(t, T_s, p, ({name}_vector *)(void *)&s->x, in, &s->y);"]
        return L
    total = sum(m.MAX_SEGMENTS for m in modulators)
    L += ["    int pass;"]
    for k, part in enumerate(modulators):
        entry = kinds[type(part)]
        seg = part.MAX_SEGMENTS
        L += [f"    int n{k} = 0, index{k} = 0;", f"    ACDRIVE_REAL dt{k}[{seg}], left{k};",
              f"    acd_{entry.cname}_out v{k}[{seg}];"]  # fmt: skip
    for k, part in enumerate(modulators):  # modulate: inputs from the outputs at t, segments
        entry = kinds[type(part)]
        has = {r: bool(entry.members.get(r)) for r in ("params", "state", "in")}
        L.append(f"    {{ /* {part.name}: {type(part).__name__} */")
        args = ["T_s"]
        if has["in"]:
            L.append(f"        acd_{entry.cname}_in u;")
            for v in part.INPUTS:
                L.append(f"        u.{v.name} = {_input_source(system, part, v.name, 's->y.')};")
            args.append("&u")
        args += [f"&p->{part.name}"] if has["params"] else []
        args += [f"&s->s.{part.name}"] if has["state"] else []
        args += [f"&n{k}", f"dt{k}", f"v{k}"]
        call = f"acd_{entry.cname}_segments({', '.join(args)})"
        L.append(
            f"        s->{part.name}_events = {call};" if part.EVENTS else f"        (void){call};"
        )
        L.append(f"        s->y.{part.name} = v{k}[0];")
        L.append("    }")
    L += hook
    for k in range(len(modulators)):
        L.append(f"    left{k} = n{k} > 0 ? dt{k}[0] : ACD_INF;")
    L.append(f"    for (pass = 0; pass <= {total}; ++pass) {{ /* each pass ends >= 1 segment */")
    L.append("        ACDRIVE_REAL span = ACD_INF;")
    for k, part in enumerate(modulators):
        L.append(f"        if (index{k} < n{k}) {{ s->y.{part.name} = v{k}[index{k}]; }}")
    for k in range(len(modulators)):
        L.append(f"        if (left{k} < span) {{ span = left{k}; }}")
    L += ["        if (span == ACD_INF) {", "            break;", "        }",
          "        if (span > ACD_R(0.0)) {",
          f"            {name}_advance(tk, span, p, ({name}_vector *)(void *)&s->x, in, &s->y);",
          "            tk += span;", "        }"]  # fmt: skip
    rtol = literal(SEGMENT_END_RTOL, "SEGMENT_END_RTOL")
    for k in range(len(modulators)):
        L += [f"        left{k} -= span;", f"        if (left{k} <= {rtol} * T_s) {{",
              f"            index{k} += 1;",
              f"            left{k} = index{k} < n{k} ? dt{k}[index{k}] : ACD_INF;", "        }"]  # fmt: skip
    L.append("    }")
    return L


def _source(stamp: list[str], name: str, kinds, code: list[str]) -> str:
    """The plant's source: ``code`` below the helpers it calls (``_helpers``; the profile
    break look-up of ``_advance_lines`` among the pieces it may call)."""
    helpers = helpers_of(kinds, code, (TABLE_NEXT_TIME,))
    return "\n".join([*stamp, f'#include "{name}.h"', "", "#include <math.h>", "", helpers, "",
                      *code]) + "\n"  # fmt: skip


def to_plant_c(system, sample_time: float, substeps: int, initial=None, held=None,
               name: str = "acdrive_plant", description: str = "",
               values: bool = True) -> PlantExport:  # fmt: skip
    """C99 header and source of the plant of ``system`` (module docstring); ``initial`` and
    ``held`` as for ``CompiledSystem.run`` give what ``<name>_reset`` writes; ``values=False``
    leaves out the definitions of ``<name>_set_params`` and ``<name>_reset`` (the native loop
    loads both from acdrive's packed arrays). Raises ``InputError`` naming a part without C or
    with direct feedthrough from the controller."""
    name = require_c_name("name", name)
    _check_exportable(system)
    continuous, modulators = list(system.continuous), list(system.modulators)
    if not continuous:
        raise InputError("system", "has no continuous part: there is no plant to export")
    kinds = kind_types([*continuous, *modulators], lookup=plant_c_of)
    X0, S0 = system.pack_initial(initial)
    Y0 = system.pack_held(held)
    inputs = _plant_inputs(system, [*continuous, *modulators])
    outputs = [port for part in (*continuous, *modulators) for port in part.out]
    n_x = system.sizes["x"]

    stamp = [f"/* Generated by acdrive.export (plant){': ' + description if description else ''}.",
             " * One control period per <name>_step; docs/guide/fmu.md.",
             " * Do not edit: regenerate from the system. */"]  # fmt: skip
    guard = f"{name.upper()}_H"
    H = [*stamp, f"#ifndef {guard}", f"#define {guard}", "", "#include <stdint.h>", PRELUDE]
    H += kind_declarations(kinds)
    params = [Member("sample_time", "real", "[s] T_s, the control period of one step"),
              Member("substeps", ("struct", "int", None), "Runge-Kutta steps per segment")]  # fmt: skip
    params += [Member(p.name, ("struct", f"acd_{kinds[type(p)].cname}_params", None),
                      type(p).__name__) for p in (*continuous, *modulators)
               if kinds[type(p)].members["params"]]  # fmt: skip
    states = [Member(p.name, ("struct", f"acd_{kinds[type(p)].cname}_state", None),
                     type(p).__name__) for p in continuous if kinds[type(p)].members["state"]]  # fmt: skip
    discrete = [Member(p.name, ("struct", f"acd_{kinds[type(p)].cname}_state", None),
                       type(p).__name__) for p in modulators if kinds[type(p)].members["state"]]  # fmt: skip
    outs = [Member(p.name, ("struct", f"acd_{kinds[type(p)].cname}_out", None), type(p).__name__)
            for p in (*continuous, *modulators)]  # fmt: skip
    ins = [Member(_port_name(q), q.var.kind, f"{_comment(q.var)} (from {q.path})") for q in inputs]
    if not states:
        raise InputError("system", "its plant has no continuous state: nothing to integrate")
    H += _struct_lines(f"{name}_params", params, f"{name}: parameters")
    H += _struct_lines(f"{name}_continuous", states, f"{name}: continuous states (integrated)")
    if discrete:
        H += _struct_lines(f"{name}_discrete", discrete, f"{name}: modulators' discrete states")
    H += _struct_lines(f"{name}_outputs", outs, f"{name}: every part's outputs")
    if ins:
        H += _struct_lines(f"{name}_inputs", ins, f"{name}: the controller's commands, held")
    whole = [Member("x", ("struct", f"{name}_continuous", None), "continuous states")]
    whole += (
        [Member("s", ("struct", f"{name}_discrete", None), "discrete states")] if discrete else []
    )
    whole += [Member("y", ("struct", f"{name}_outputs", None), "outputs")]
    whole += [Member(f"{p.name}_events", "uint32", f"{p.name}'s event bits of the last step")
              for p in modulators if p.EVENTS]  # fmt: skip
    H += _struct_lines(f"{name}_state", whole, f"{name}: everything that evolves")
    in_arg = f"const {name}_inputs *in" if ins else "const void *in"
    H += [
        "/* one control period from t [s]: the commands in held, p->substeps steps per segment */",
        f"void {name}_step(ACDRIVE_REAL t, const {name}_params *p, {name}_state *s, {in_arg});",
        "/* the outputs s->y of the state s->x at t, the commands in held (a direct output, such",
        "   as the stator relay's voltage, reads them: docs/guide/fmu.md) */",
        f"void {name}_update_outputs(ACDRIVE_REAL t, const {name}_params *p, {name}_state *s, {in_arg});",
        "/* the parameter values of the exported system */",
        f"void {name}_set_params({name}_params *p);",
        "/* the initial states and held outputs of the exported system, and the outputs at t */",
        f"void {name}_reset(ACDRIVE_REAL t, const {name}_params *p, {name}_state *s, {in_arg});",
        "", f"#endif /* {guard} */",
    ]  # fmt: skip

    C = _kind_functions(kinds, [*continuous, *modulators])  # the helpers they call go above
    C += [f"/* the continuous states as one array, for the integrator ({n_x} reals) */",
          f"typedef union {{ {name}_continuous x; ACDRIVE_REAL v[{n_x}]; }} {name}_vector;",
          (f"typedef char {name}_states_are_reals[(sizeof({name}_continuous) == {n_x} * "
          "sizeof(ACDRIVE_REAL)) ? 1 : -1];"), ""]  # fmt: skip
    # outputs of every continuous part from the state
    C += [(f"static void {name}_state_outputs(ACDRIVE_REAL t, const {name}_params *p, "
          f"const {name}_continuous *x, {in_arg}, {name}_outputs *y)"), "{", "    (void)x;",
          "    (void)in;"]  # fmt: skip
    for part in continuous:
        if kinds[type(part)].step.role("state_outputs", part) is None:
            continue  # every output of the part is direct
        C.append(
            f"    acd_{kinds[type(part)].cname}_state_outputs({_call_args(kinds[type(part)], 'state_outputs', part, 'x', 'y')});"
        )
    C += _direct_lines(system, kinds)
    C += ["}", ""]
    C += [(f"static void {name}_derivatives(ACDRIVE_REAL t, const {name}_params *p, "
          f"const {name}_continuous *x, {in_arg}, {name}_outputs *y, {name}_continuous *dx)"),
          "{", "    (void)in;", f"    {name}_state_outputs(t, p, x, in, y);"]  # fmt: skip
    for part in continuous:
        entry = kinds[type(part)]
        if not entry.members["state"]:
            continue  # no states, no derivative (the kernel's rhs is empty)
        if entry.step.rhs is None:
            raise InputError(part.name, f"part kind {type(part).__name__} has states but no C rhs")
        C.append(f"    {{ /* {part.name}: {type(part).__name__} */")
        if entry.members["in"]:
            C.append(f"        acd_{entry.cname}_in u;")
            for v in part.INPUTS:
                C.append(f"        u.{v.name} = {_input_source(system, part, v.name, 'y->')};")
        C.append(
            f"        acd_{entry.cname}_rhs({_call_args(entry, 'rhs', part, 'x', 'y', 'dx')});"
        )
        C.append("    }")
    C += ["}", ""]
    C += [(f"static void {name}_plant_step(ACDRIVE_REAL t, ACDRIVE_REAL h, ACDRIVE_REAL cap, "
          f"const {name}_params *p, {name}_vector *X, {in_arg}, {name}_outputs *y)"), "{"]  # fmt: skip
    C += _rk_lines(system.method, n_x, name)
    C += ["}", ""]
    C += _advance_lines(system, name, in_arg)
    C += [
        f"void {name}_step(ACDRIVE_REAL t, const {name}_params *p, {name}_state *s, {in_arg})",
        "{",
    ]
    C += _integrate_lines(system, kinds, modulators, name)
    C += ["}", ""]
    # acdrive's sample instant: project (re-normalise redundant states), then the outputs
    projections = []
    for part in continuous:
        entry = kinds[type(part)]
        if entry.step.project is not None:
            params = f"&p->{part.name}, " if entry.members["params"] else ""
            projections.append(f"    acd_{entry.cname}_project({params}&s->x.{part.name});")
    C += [(f"void {name}_update_outputs(ACDRIVE_REAL t, const {name}_params *p, "
           f"{name}_state *s, {in_arg})"),
          "{", *projections, f"    {name}_state_outputs(t, p, &s->x, in, &s->y);", "}", ""]  # fmt: skip
    if not values:
        return PlantExport(name, "\n".join(H) + "\n", _source(stamp, name, kinds, C), kinds,
                           continuous, modulators, inputs, outputs)  # fmt: skip
    C += [f"void {name}_set_params({name}_params *p)", "{",
          f"    p->sample_time = {literal(sample_time, 'sample_time')};",
          f"    p->substeps = {int(substeps)};"]  # fmt: skip
    for part in (*continuous, *modulators):
        C += ["    " + line for line in part_params_lines(part)]
    C += [
        "}",
        "",
        f"void {name}_reset(ACDRIVE_REAL t, const {name}_params *p, {name}_state *s, {in_arg})",
        "{",
    ]
    for part in continuous:
        a, _ = system.slots[part.name].x
        for v in part.STATES:
            k = a + part.STATES.slot(v.name)
            C += ["    " + line for line in _value_lines(f"s->x.{part.name}.{v.name}", v,
                  X0[k : k + v.width], f"initial.{part.name}.{v.name}")]  # fmt: skip
    for part in modulators:
        a, _ = system.slots[part.name].s
        for v in part.STATES:
            k = a + part.STATES.slot(v.name)
            C += ["    " + line for line in _value_lines(f"s->s.{part.name}.{v.name}", v,
                  S0[k : k + v.width], f"initial.{part.name}.{v.name}")]  # fmt: skip
        a, _ = system.slots[part.name].y
        for v in part.OUTPUTS:
            k = a + part.OUTPUTS.slot(v.name)
            C += ["    " + line for line in _value_lines(f"s->y.{part.name}.{v.name}", v,
                  Y0[k : k + v.width], f"held.{part.name}.{v.name}")]  # fmt: skip
        if part.EVENTS:
            C.append(f"    s->{part.name}_events = 0u;")
    C += [f"    {name}_update_outputs(t, p, s, in);", "}", ""]
    return PlantExport(name, "\n".join(H) + "\n", _source(stamp, name, kinds, C), kinds,
                       continuous, modulators, inputs, outputs)  # fmt: skip
