"""FMI 2.0 (and 3.0) co-simulation FMUs of a system's controller chains and of its plant, built
from the generated C (docs/guide/fmu.md).

An FMU is a zip: ``modelDescription.xml`` (written here from the parts' declarations: every
variable with its causality, variability, unit, start value and description; the units in
``UnitDefinitions`` with their SI exponents), ``sources/`` (the generated C: the chain's or the
plant's header and source, and ``<id>_fmi2.c``, the model glue plus the FMI 2.0 functions of
``_fmi2``) and ``binaries/linux64/<id>.so`` compiled from those sources with gcc against the
FMI 2.0 headers fmpy ships (``fmpy/c-code``; the headers are not copied into the FMU, an
importing tool has its own). An FMI 3.0 FMU (``version=3``) has the same variables as
``Float64``/``Int32`` and the independent ``time`` (``model_description3``), ``<id>_fmi3.c``
with the FMI 3.0 functions of ``_fmi3`` and ``binaries/x86_64-linux/<id>.so``.

Variables. A real quantity is one ``Real``; a space vector two, ``<name>.re`` and ``<name>.im``.
The controller FMU's inputs are the plant outputs its chains read, named ``<part>.<output>``
after the plant part's output; its outputs the commands, named after the sampled part's output
(``latch.v_ref.re``), and each part's event bits (``<part>.events``, Integer). The plant FMU's
inputs are those commands, under the same names; its outputs every output of its parts and the
modulators' event bits. So the two FMUs connect by equal names. Parameters are every real and
space-vector parameter of the parts (a table parameter is not exposed, it stays the exported
profile): a free one causality parameter, variability fixed, start the exported value, its
declared rule (``core._signals.RULES``) as ``min``/``max`` where the rule has such bounds and
checked in C when it is set (``RULE_C``); a derived one (``Var.derived``: the discretised
controller's matrices, its order, T_s) causality calculatedParameter, read only. A parameter
whose rule makes it an integer (``INTEGER_RULES``: pole pairs, an order, a 0/1 flag) is an
``Integer``. The relations over several parameters that declare their C (``Relation.c``) are
checked when initialisation ends. Changing a parameter changes that number only: nothing derived
from it is recomputed (which is why the derived numbers are not settable).
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import re
import subprocess
import tempfile
import uuid
import zipfile
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

from acdrive.core._parts import Part
from acdrive.core._signals import INTEGER_RULES, RULES
from acdrive.errors import InputError
from acdrive.export._fmi2 import FMI2_WRAPPER
from acdrive.export._fmi3 import FMI3_WRAPPER
from acdrive.export._sil import CFLAGS, find_compiler
from acdrive.sim._ccode._c_source import CExport, _port_name, _value_lines
from acdrive.sim._ccode._plant_source import PlantExport


#: SI base-unit exponents (kg, m, s, A, K, mol, cd, rad) of the unit words acdrive declares
_SI = {
    "kg": {"kg": 1}, "m": {"m": 1}, "s": {"s": 1}, "A": {"A": 1}, "K": {"K": 1},
    "rad": {"rad": 1}, "Hz": {"s": -1}, "N": {"kg": 1, "m": 1, "s": -2},
    "J": {"kg": 1, "m": 2, "s": -2}, "W": {"kg": 1, "m": 2, "s": -3},
    "V": {"kg": 1, "m": 2, "s": -3, "A": -1}, "Wb": {"kg": 1, "m": 2, "s": -2, "A": -1},
    "H": {"kg": 1, "m": 2, "s": -2, "A": -2}, "Ohm": {"kg": 1, "m": 2, "s": -3, "A": -2},
    "ohm": {"kg": 1, "m": 2, "s": -3, "A": -2}, "var": {"kg": 1, "m": 2, "s": -3},
    "F": {"kg": -1, "m": -2, "s": 4, "A": 2},
}  # fmt: skip


def si_exponents(unit: str) -> dict[str, int] | None:
    """The SI base exponents of a unit written as acdrive declares them ("N m s/rad",
    "kg m^2", "1/(V s)"), or None for a word outside ``_SI``."""
    total: dict[str, int] = {}
    for side, text in enumerate(unit.split("/", 1)):
        for word in text.strip().removeprefix("(").removesuffix(")").split():
            if word == "1":
                continue
            base, _, power = word.partition("^")
            if base not in _SI or (power and not re.fullmatch(r"-?\d+", power)):
                return None
            for k, e in _SI[base].items():
                total[k] = total.get(k, 0) + e * int(power or 1) * (-1 if side else 1)
    return {k: e for k, e in total.items() if e != 0}


#: each value rule of ``core._signals.RULES`` as a C condition on ``value`` (a double)
RULE_C = {
    "positive": "value > 0.0",
    "nonnegative": "value >= 0.0",
    "count": "value >= 1.0 && value == floor(value)",
    "whole": "value >= 0.0 && value == floor(value)",
    "flag": "value == 0.0 || value == 1.0",
    "fraction": "value >= 0.0 && value <= 1.0",
}
#: each rule's bounds as FMI ``min``/``max`` attributes (only bounds a value may equal)
RULE_BOUNDS = {"nonnegative": (0, None), "count": (1, None), "whole": (0, None),
               "flag": (0, 1), "fraction": (0, 1)}  # fmt: skip
NOT_FINITE = "must be finite (not NaN or infinite)"


@dataclass
class Variable:
    """One FMU variable: ``c`` is its C lvalue in the model struct ``m``; ``rule`` the declared
    value rule of a parameter (``core._signals.RULES``)."""

    name: str
    type: str  # "Real" or "Integer"
    causality: str  # "input", "output", "parameter", "calculatedParameter"
    variability: str  # "continuous", "discrete", "fixed"
    c: str
    unit: str = ""
    description: str = ""
    start: float | None = None
    vr: int = 0
    rule: str = ""


@dataclass
class RelationCheck:
    """A rule over several parameters of one part (``core._signals.Relation``) as the FMU
    checks it when initialisation ends: ``condition`` in C, ``names`` the FMU variables."""

    rule: str
    condition: str
    names: tuple[str, ...]


def _scalars(name: str, var, c: str, values, **kw) -> list[Variable]:
    """The Real variables of one declared quantity (``.re``/``.im`` for a space vector)."""
    doc = var.doc
    if var.kind == "complex":
        return [
            Variable(f"{name}.re", "Real", c=f"{c}.re", unit=var.unit, description=f"{doc} (real part)",
                     start=None if values is None else float(values[0]), **kw),
            Variable(f"{name}.im", "Real", c=f"{c}.im", unit=var.unit,
                     description=f"{doc} (imaginary part)",
                     start=None if values is None else float(values[1]), **kw),
        ]  # fmt: skip
    return [Variable(name, "Real", c=c, unit=var.unit, description=doc,
                     start=None if values is None else float(values[0]), **kw)]  # fmt: skip


def _parameters(parts, prefix) -> list[Variable]:
    """Every real and space-vector parameter of ``parts``: a free one a ``parameter`` (settable
    until initialisation ends, checked against its declared rule), a derived one
    (``Var.derived``) a ``calculatedParameter`` (read only, no start); one whose rule makes it
    an integer (``INTEGER_RULES``) an ``Integer``."""
    out = []
    for part in parts:
        for v in part.PARAMS:
            if v.kind in ("table", "table2d"):  # fixed in the exported C, not FMU variables
                continue
            k = part.PARAMS.slot(v.name)
            causality = "calculatedParameter" if v.derived else "parameter"
            values = None if v.derived else part.p[k : k + v.width]
            scalars = _scalars(f"{part.name}.{v.name}", v, f"{prefix}{part.name}.{v.name}",
                               values, causality=causality, variability="fixed")  # fmt: skip
            for scalar in scalars:
                scalar.rule = v.rule
                if v.rule in INTEGER_RULES:
                    scalar.type = "Integer"
            out += scalars
    return out


def _relations(parts, prefix) -> list[RelationCheck]:
    """The relations over the parameters of ``parts`` that declare their C (``Relation.c``)."""
    out = []
    for part in parts:
        for relation in part.PARAMS.relations:
            if relation.c:
                lvalues = {f: f"({prefix}{part.name}.{f})" for f in relation.fields}
                names = tuple(f"{part.name}.{f}" for f in relation.fields)
                # named after its last field (a relation's own blame is Python, not C)
                out.append(RelationCheck(f"{part.name}.{relation.fields[-1]}: {relation.rule}",
                                         relation.c.format(**lvalues), names))  # fmt: skip
    return out


def _events(part: Part, c: str, causality: str = "output") -> Variable:
    return Variable(f"{part.name}.events", "Integer", causality, "discrete", c,
                    description=f"{part.name}'s event bits of the last period: "
                    + ", ".join(f"bit {b} {e}" for b, e in enumerate(part.EVENTS)))  # fmt: skip


@dataclass
class FMUModel:
    """What one FMU is made of: its identifier, description, variables, C files and glue."""

    identifier: str
    description: str
    variables: list[Variable]
    files: dict[str, str]  # sources/ file name -> text
    glue: str  # C of the model struct and the acd_fmu_* functions
    sample_time: float
    stop_time: float
    relations: list[RelationCheck]


def controller_model(export: CExport, sample_time: float, stop_time: float,
                     description: str) -> FMUModel:  # fmt: skip
    """The controller FMU of ``export`` (every chain of it in one FMU; ``sample_time`` the
    period ``to_c`` was given)."""
    variables: list[Variable] = []
    relations: list[RelationCheck] = []
    fields, defaults, start, advance = [], [], [], []
    read_by: dict[str, str] = {}  # plant output path -> the inputs member that holds it
    for model in export.chains:
        c = model.chain.name
        fields += [f"    {c}_params p_{c};", f"    {c}_state s_{c};", f"    {c}_inputs in_{c};"]
        if model.outputs:
            fields.append(f"    {c}_outputs out_{c};")
        defaults.append(f"    {c}_set_params(&m->p_{c});")
        start.append(f"    {c}_reset(&m->s_{c});")
        out = f", &m->out_{c}" if model.outputs else ""
        for port in model.chain.inputs:
            if port.path in read_by:  # one variable for a plant output several chains read
                advance.append(f"    m->in_{c}.{_port_name(port)} = {read_by[port.path]};")
                continue
            read_by[port.path] = f"m->in_{c}.{_port_name(port)}"
            variables += _scalars(port.path, port.var, f"m->in_{c}.{_port_name(port)}", None,
                                  causality="input", variability="continuous")  # fmt: skip
            for var in variables[-port.var.width :]:
                var.start = 0.0
            defaults += [f"    {v.c} = 0.0;" for v in variables[-port.var.width :]]
        advance.append(f"    {c}_step(t, &m->p_{c}, &m->s_{c}, &m->in_{c}{out});")
        for port in model.chain.outputs:
            variables += _scalars(port.path, port.var, f"m->out_{c}.{_port_name(port)}", None,
                                  causality="output", variability="discrete")  # fmt: skip
            start.append(f"    m->out_{c}.{_port_name(port)} = m->s_{c}.{port.part.name}_out."
                         f"{port.var.name};")  # fmt: skip
        for part in model.chain.parts:
            if part.EVENTS:
                variables.append(_events(part, f"m->out_{c}.{part.name}_events"))
                start.append(f"    m->out_{c}.{part.name}_events = 0u;")
        variables += _parameters(model.chain.parts, f"m->p_{c}.")
        relations += _relations(model.chain.parts, f"m->p_{c}.")
    first = export.chains[0].chain.name
    glue = "\n".join([
        f'#include "{export.header_name}"', "",
        "typedef struct {", *fields, "} acd_fmu_model;", "",
        "static void acd_fmu_defaults(acd_fmu_model *m)", "{", *defaults, "}", "",
        "static void acd_fmu_start(acd_fmu_model *m, double t0)", "{", "    (void)t0;", *start,
        "}", "",
        f"static double acd_fmu_period(const acd_fmu_model *m) {{ return m->p_{first}.sample_time; }}",
        "",
        "static void acd_fmu_advance(acd_fmu_model *m, double t, double t_next)", "{",
        "    (void)t_next;", *advance, "}", "",
    ])  # fmt: skip
    files = {export.header_name: export.header, export.source_name: export.source}
    return FMUModel(export.name, description, variables, files, glue, sample_time, stop_time,
                    relations)


def plant_model(export: PlantExport, system, held, sample_time: float, stop_time: float,
                description: str) -> FMUModel:  # fmt: skip
    """The plant FMU of ``export``: inputs the commands (start: the held values), outputs every
    part output and the modulators' event bits, parameters the parts' real parameters."""
    n = export.name
    Y0 = system.pack_held(held)
    variables: list[Variable] = []
    defaults = [f"    {n}_set_params(&m->p);"]
    for port in export.inputs:
        k = system.output_slot(port)
        variables += _scalars(port.path, port.var, f"m->in.{_port_name(port)}",
                              Y0[k : k + port.var.width], causality="input",
                              variability="discrete")  # fmt: skip
        defaults += [
            "    " + line
            for line in _value_lines(
                f"m->in.{_port_name(port)}", port.var, Y0[k : k + port.var.width], port.path
            )
        ]
    for port in export.outputs:
        variables += _scalars(port.path, port.var, f"m->s.y.{port.part.name}.{port.var.name}",
                              None, causality="output", variability="continuous")  # fmt: skip
    for part in export.modulators:
        if part.EVENTS:
            variables.append(_events(part, f"m->s.{part.name}_events"))
    variables += _parameters([*export.continuous, *export.modulators], "m->p.")
    relations = _relations([*export.continuous, *export.modulators], "m->p.")
    inputs = "&m->in" if export.inputs else "NULL"
    glue = "\n".join([
        f'#include "{export.header_name}"', "",
        "typedef struct {", f"    {n}_params p;", f"    {n}_state s;",
        *([f"    {n}_inputs in;"] if export.inputs else []), "} acd_fmu_model;", "",
        "static void acd_fmu_defaults(acd_fmu_model *m)", "{", *defaults, "}", "",
        "static void acd_fmu_start(acd_fmu_model *m, double t0)", "{",
        f"    {n}_reset(t0, &m->p, &m->s, {inputs});", "}", "",
        "static double acd_fmu_period(const acd_fmu_model *m) { return m->p.sample_time; }", "",
        "static void acd_fmu_advance(acd_fmu_model *m, double t, double t_next)", "{",
        f"    {n}_step(t, &m->p, &m->s, {inputs});",
        f"    {n}_update_outputs(t_next, &m->p, &m->s, {inputs});", "}", "",
    ])  # fmt: skip
    files = {export.header_name: export.header, export.source_name: export.source}
    return FMUModel(n, description, variables, files, glue, sample_time, stop_time, relations)


def _number(x: float) -> str:
    return repr(float(x))


def _unit_definitions(units) -> list[str]:
    """The ``UnitDefinitions`` element of ``units``, each with its SI exponents (the same in
    FMI 2.0 and 3.0)."""
    if not units:
        return []
    L = ["  <UnitDefinitions>"]
    for unit in units:
        exponents = si_exponents(unit)
        if exponents:
            attrs = " ".join(f'{k}="{e}"' for k, e in exponents.items())
            L += [f"    <Unit name={quoteattr(unit)}>", f"      <BaseUnit {attrs}/>",
                  "    </Unit>"]  # fmt: skip
        else:
            L.append(f"    <Unit name={quoteattr(unit)}/>")
    return [*L, "  </UnitDefinitions>"]


def model_description(model: FMUModel, guid: str) -> str:
    """modelDescription.xml of ``model`` (FMI 2.0, co-simulation)."""
    from acdrive import __version__

    units = sorted({v.unit for v in model.variables if v.unit})
    sources = [*model.files, f"{model.identifier}_fmi2.c"]
    L = ['<?xml version="1.0" encoding="UTF-8"?>',
         (f'<fmiModelDescription fmiVersion="2.0" modelName={quoteattr(model.identifier)} '
         f'guid="{guid}" description={quoteattr(model.description)} '
         f'generationTool="acdrive {__version__}" variableNamingConvention="flat" '
         'numberOfEventIndicators="0">'),
         (f'  <CoSimulation modelIdentifier="{model.identifier}" '
         'canHandleVariableCommunicationStepSize="true" canGetAndSetFMUstate="false" '
         'canSerializeFMUstate="false" providesDirectionalDerivative="false">'),
         "    <SourceFiles>", *(f'      <File name="{f}"/>' for f in sources if f.endswith(".c")),
         "    </SourceFiles>", "  </CoSimulation>"]  # fmt: skip
    L += _unit_definitions(units)
    L += ["  <LogCategories>",
          '    <Category name="logStatusError" description="errors: a refused call, why"/>',
          '    <Category name="logAll" description="every message"/>', "  </LogCategories>",
          (f'  <DefaultExperiment startTime="0.0" stopTime="{_number(model.stop_time)}" '
          f'stepSize="{_number(model.sample_time)}"/>'), "  <ModelVariables>"]  # fmt: skip
    for v in model.variables:
        L.append(f"    <ScalarVariable name={quoteattr(v.name)} valueReference=\"{v.vr}\" "
                 f"description={quoteattr(v.description)} causality=\"{v.causality}\" "
                 f"variability=\"{v.variability}\">")  # fmt: skip
        attrs = ""
        if v.start is not None:
            attrs += f' start="{_number(v.start) if v.type == "Real" else int(v.start)}"'
        if v.unit:
            attrs += f" unit={quoteattr(v.unit)}"
        for key, bound in zip(("min", "max"), RULE_BOUNDS.get(v.rule, (None, None)), strict=True):
            if bound is not None:
                attrs += f' {key}="{_number(bound) if v.type == "Real" else bound}"'
        L += [f"      <{v.type}{attrs}/>", "    </ScalarVariable>"]
    L += ["  </ModelVariables>", "  <ModelStructure>"]
    outputs = [i for i, v in enumerate(model.variables, 1) if v.causality == "output"]
    # what the FMU computes in initialisation: its outputs and its calculated parameters (fixed
    # when it was built: they depend on no variable a master sets)
    initial = [i for i, v in enumerate(model.variables, 1)
               if v.causality in ("output", "calculatedParameter")]  # fmt: skip
    if outputs:
        L.append("    <Outputs>")
        L += [f'      <Unknown index="{i}" dependencies=""/>' for i in outputs]
        L.append("    </Outputs>")
    if initial:
        L.append("    <InitialUnknowns>")
        L += [f'      <Unknown index="{i}" dependencies=""/>'
              if model.variables[i - 1].causality == "calculatedParameter"
              else f'      <Unknown index="{i}"/>' for i in initial]  # fmt: skip
        L.append("    </InitialUnknowns>")
    L += ["  </ModelStructure>", "</fmiModelDescription>"]
    return "\n".join(L) + "\n"


def model_description3(model: FMUModel, token: str) -> str:
    """modelDescription.xml of ``model`` (FMI 3.0, co-simulation): the variables of the FMI 2.0
    description as ``Float64``/``Int32``, and ``time`` (value reference 0), the independent
    variable FMI 3.0 requires."""
    from acdrive import __version__

    units = sorted({v.unit for v in model.variables if v.unit} | {"s"})
    L = ['<?xml version="1.0" encoding="UTF-8"?>',
         (f'<fmiModelDescription fmiVersion="3.0" modelName={quoteattr(model.identifier)} '
          f'instantiationToken="{token}" description={quoteattr(model.description)} '
          f'generationTool="acdrive {__version__}" variableNamingConvention="flat">'),
         (f'  <CoSimulation modelIdentifier="{model.identifier}" '
          'canHandleVariableCommunicationStepSize="true" canGetAndSetFMUState="false" '
          'canSerializeFMUState="false" providesDirectionalDerivatives="false" '
          'providesAdjointDerivatives="false" hasEventMode="false" '
          f'fixedInternalStepSize="{_number(model.sample_time)}"/>')]  # fmt: skip
    L += _unit_definitions(units)
    L += ["  <LogCategories>",
          '    <Category name="logStatusError" description="errors: a refused call, why"/>',
          '    <Category name="logAll" description="every message"/>', "  </LogCategories>",
          (f'  <DefaultExperiment startTime="0.0" stopTime="{_number(model.stop_time)}" '
           f'stepSize="{_number(model.sample_time)}"/>'), "  <ModelVariables>",
          ('    <Float64 name="time" valueReference="0" causality="independent" '
           'variability="continuous" description="simulation time" unit="s"/>')]  # fmt: skip
    for v in model.variables:
        element = "Float64" if v.type == "Real" else "Int32"
        attrs = (f"name={quoteattr(v.name)} valueReference=\"{v.vr}\" "
                 f"description={quoteattr(v.description)} causality=\"{v.causality}\" "
                 f"variability=\"{v.variability}\"")  # fmt: skip
        if v.start is not None:
            attrs += f' start="{_number(v.start) if v.type == "Real" else int(v.start)}"'
        if v.unit and element == "Float64":
            attrs += f" unit={quoteattr(v.unit)}"
        for key, bound in zip(("min", "max"), RULE_BOUNDS.get(v.rule, (None, None)), strict=True):
            if bound is not None:
                attrs += f' {key}="{_number(bound) if v.type == "Real" else bound}"'
        L.append(f"    <{element} {attrs}/>")
    L += ["  </ModelVariables>", "  <ModelStructure>"]
    L += [f'    <Output valueReference="{v.vr}" dependencies=""/>'
          for v in model.variables if v.causality == "output"]  # fmt: skip
    L += [f'    <InitialUnknown valueReference="{v.vr}"'
          + (' dependencies=""/>' if v.causality == "calculatedParameter" else "/>")
          for v in model.variables if v.causality in ("output", "calculatedParameter")]  # fmt: skip
    L += ["  </ModelStructure>", "</fmiModelDescription>"]
    return "\n".join(L) + "\n"


#: the access code of each causality in the generated ``acd_fmu_access`` table
ACCESS = {"output": 1, "input": 2, "parameter": 3, "calculatedParameter": 4}


def _c_string(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


#: per FMI version: the C types of a Real, an Integer and a value reference, the header, the
#: functions, the folder of the linux binary
VERSIONS = {
    2: {"real": "fmi2Real", "integer": "fmi2Integer", "vr": "fmi2ValueReference",
        "header": "fmi2Functions.h", "wrapper": FMI2_WRAPPER, "platform": "linux64"},
    3: {"real": "fmi3Float64", "integer": "fmi3Int32", "vr": "fmi3ValueReference",
        "header": "fmi3Functions.h", "wrapper": FMI3_WRAPPER, "platform": "x86_64-linux"},
}  # fmt: skip


def fmi_source(model: FMUModel, guid: str, version: int = 2) -> str:
    """``<id>_fmi<version>.c``: the model glue, the value-reference tables (access, names, the
    outputs checked finite, the parameters' rules and relations) and the FMI functions of FMI
    ``version`` (2 or 3)."""
    kind = VERSIONS[version]
    reals = [v for v in model.variables if v.type == "Real"]
    integers = [v for v in model.variables if v.type == "Integer"]
    settable_integers = [v for v in integers if v.causality == "parameter"]
    table = ["0"] * (len(model.variables) + 1)
    names = ['""'] * (len(model.variables) + 1)
    for v in model.variables:
        table[v.vr] = str(ACCESS[v.causality])
        names[v.vr] = _c_string(v.name)
    outputs = [str(v.vr) for v in reals if v.causality == "output"]
    checked = [v for v in model.variables if v.causality == "parameter"]
    widest = max([len(r.names) for r in model.relations] + [1])
    L = [f"/* Generated by acdrive.export (FMI {version}.0 co-simulation): {model.description}.",
         (f" * Build: cc -std=c99 -O2 -ffp-contract=off -fPIC -shared -I<FMI {version}.0 headers>"
         " *.c -lm */"), "", "#include <float.h>", "#include <math.h>",
         f'#include "{kind["header"]}"', "", "#ifdef ACDRIVE_FLOAT",
         "#error \"the FMU reals are doubles: build it in double\"",
         "#endif", "", f'#define ACD_FMU_GUID "{guid}"', "", model.glue,
         f"#define ACD_FMU_VARIABLES {len(model.variables)}",
         ("/* by value reference: 1 output (read only), 2 input, 3 parameter (settable until "
          "initialisation ends),"), " * 4 calculated parameter (read only) */",
         f"static const unsigned char acd_fmu_access[{len(table)}] = {{{', '.join(table)}}};", "",
         f"static const char *const acd_fmu_names[{len(names)}] = {{",
         *(f"    {n}," for n in names),
         "};", "", "/* the Real outputs, each checked finite after every period */",
         f"static const size_t acd_fmu_real_output_count = {len(outputs)};",
         (f"static const {kind['vr']} acd_fmu_real_outputs[{len(outputs) + 1}] = "
          f"{{{', '.join([*outputs, '0'])}}};"), "",
         f"static {kind['real']} *acd_fmu_real(acd_fmu_model *m, {kind['vr']} vr)", "{",
         "    switch (vr) {"]  # fmt: skip
    L += [f"    case {v.vr}: return &{v.c}; /* {v.name} */" for v in reals]
    L += ["    default: return NULL;", "    }", "}", "",
          (f"static int acd_fmu_get_integer(const acd_fmu_model *m, {kind['vr']} vr, "
          f"{kind['integer']} *value)"), "{", "    switch (vr) {"]  # fmt: skip
    L += [f"    case {v.vr}: *value = ({kind['integer']}){v.c}; return 1; /* {v.name} */"
          for v in integers]  # fmt: skip
    L += ["    default: (void)m; (void)value; return 0;", "    }", "}", "",
          "/* an Integer parameter, stored as a real of the generated C */",
          (f"static int acd_fmu_set_integer(acd_fmu_model *m, {kind['vr']} vr, "
          f"{kind['integer']} value)"), "{", "    switch (vr) {"]  # fmt: skip
    L += [f"    case {v.vr}: {v.c} = (double)value; return 1; /* {v.name} */"
          for v in settable_integers]  # fmt: skip
    L += ["    default: (void)m; (void)value; return 0;", "    }", "}", "",
          "/* the declared rule a parameter's value breaks (core._signals.RULES), NULL if none */",
          f"static const char *acd_fmu_broken_rule({kind['vr']} vr, double value)", "{",
          "    if (!isfinite(value)) {", f"        return {_c_string(NOT_FINITE)};", "    }",
          "    switch (vr) {"]  # fmt: skip
    for v in checked:
        if v.rule:
            L.append(f"    case {v.vr}: /* {v.name} */")
            L.append(f"        return {RULE_C[v.rule]} ? NULL : {_c_string(RULES[v.rule])};")
    L += ["    default: return NULL;", "    }", "}", "",
          "/* the rules over several parameters of one part (core._signals.Relation), checked "
          "when",
          " * initialisation ends: the rule, its parameters' value references, whether it holds */",
          "typedef struct {", "    const char *rule;", "    unsigned n;",
          f"    {kind['vr']} vr[{widest}];", "} acd_fmu_relation;", "",
          f"#define ACD_FMU_RELATIONS {len(model.relations)}",
          (f"static const acd_fmu_relation acd_fmu_relations[{len(model.relations) + 1}]"
           " = {")]  # fmt: skip
    vr_of = {v.name: v.vr for v in model.variables}
    for r in model.relations:
        refs = ", ".join(str(vr_of[n]) for n in r.names)
        L.append(f"    {{{_c_string(r.rule)}, {len(r.names)}u, {{{refs}}}}},")
    L += ["    {NULL, 0u, {0}},", "};", "",
          "static int acd_fmu_relation_holds(const acd_fmu_model *m, int i)", "{",
          "    switch (i) {"]  # fmt: skip
    L += [f"    case {i}: return {r.condition};" for i, r in enumerate(model.relations)]
    L += ["    default: (void)m; return 1;", "    }", "}", kind["wrapper"]]
    return "\n".join(L) + "\n"


def fmi_headers() -> Path:
    """The folder of the FMI 2.0 and 3.0 headers fmpy ships, or an InputError saying fmpy is
    needed."""
    spec = importlib.util.find_spec("fmpy")
    folder = Path(spec.origin).parent / "c-code" if spec and spec.origin else None
    if folder is None or not all((folder / f"{v['header']}").is_file() for v in VERSIONS.values()):
        raise InputError("fmpy", "is not installed: building an FMU needs the FMI 2.0 and 3.0 "
                         "headers it ships (pip install 'acdrive[fmu]')")  # fmt: skip
    return folder


def build_fmu(model: FMUModel, path: Path, version: int = 2) -> Path:
    """Write the FMI ``version`` (2 or 3) FMU of ``model`` to ``path`` (a .fmu zip): sources,
    the linux binary compiled from them, modelDescription.xml. Built in a temporary folder; the
    zip is written beside ``path`` under a hidden name and renamed into place, so ``path`` is
    whole or untouched."""
    compiler, headers = find_compiler("gcc", "building an FMU's binary"), fmi_headers()
    path = Path(path)
    for i, v in enumerate(model.variables, 1):
        v.vr = i
    body = "".join(f"{v.name}|{v.type}|{v.causality}|{v.c}\n" for v in model.variables)
    digest = hashlib.sha256((model.glue + body + "".join(model.files.values())).encode())
    guid = "{" + str(uuid.UUID(digest.hexdigest()[:32])) + "}"
    files = {**model.files,
             f"{model.identifier}_fmi{version}.c": fmi_source(model, guid, version)}  # fmt: skip
    with tempfile.TemporaryDirectory(prefix="acdrive-fmu-build-") as scratch:
        work = Path(scratch)
        (work / "sources").mkdir()
        for name, text in files.items():
            (work / "sources" / name).write_text(text)
        binary = work / "binaries" / VERSIONS[version]["platform"] / f"{model.identifier}.so"
        binary.parent.mkdir(parents=True)
        sources = [str(work / "sources" / f) for f in files if f.endswith(".c")]
        flags = [*CFLAGS, "-fvisibility=default", f"-I{headers}", f"-I{work / 'sources'}"]
        done = subprocess.run([compiler, *flags, "-o", str(binary), *sources, "-lm"],
                              capture_output=True, text=True, check=False)  # fmt: skip
        if done.returncode != 0:
            first = (done.stderr.strip().splitlines() or ["(no message)"])[0]
            raise InputError("compiler", f"{compiler} could not compile the FMU's sources: {first}")
        describe = model_description if version == 2 else model_description3
        (work / "modelDescription.xml").write_text(describe(model, guid))
        partial = path.with_name(f".{path.name}.partial")
        try:
            with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as fmu:
                for file in sorted(work.rglob("*")):
                    if file.is_file():
                        fmu.write(file, file.relative_to(work).as_posix())
            os.replace(partial, path)
        finally:
            partial.unlink(missing_ok=True)
    return path
