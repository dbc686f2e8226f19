"""C generated from the part kernels (``sim._ccode._translate``): for every sampled part kind
whose C is generated from its kernel, the C step and the compiled kernel (as every numba tier
compiles it: strict arithmetic, acdrive's sin, cos, |z| and sqrt) give the same bits.

Each kind's structs, its generated step and the helpers it calls are compiled as the native tier
compiles them (``sim._native.NATIVE_CFLAGS``) with a wrapper that reads and writes the kernel's
flat arrays; both sides then run on the same random draws: parameters, inputs, states and held
outputs among ordinary values, signed zeros, the "no limit" stand-in 1e300 and values of either
sign spanning 1e-3 to 1e3, and sample instants that include every table breakpoint exactly.
On a draw where the C overflows, divides by zero or meets an invalid operation (its
floating-point exception flags say so), the values either side computes as non-finite and the
events are left out of the comparison (``_same_where_finite``); every other value is compared.

The translator's refusals are checked too: a construct outside the kernel language is one line
naming the kernel, its line and the construct.
"""

from __future__ import annotations

import ctypes
import shutil
import subprocess

import numpy as np
import pytest

from acdrive.core._parts import SampledPart
from acdrive.sim._ccode import _kinds
from acdrive.sim._ccode._c_source import KindTypes, Member, _step_signature, helpers_of, kind_name
from acdrive.sim._ccode._c_source import kind_declarations
from acdrive.sim._ccode._prelude import PRELUDE
from acdrive.sim._ccode._translate import UnsupportedKernel, translate_step
from acdrive.sim._kernels import kind_source
from acdrive.sim._native import NATIVE_CFLAGS

pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc is not installed")

#: points of every table of the test's structs and flat arrays
POINTS = 4
DRAWS = 400


def built_in_kinds() -> list[type]:
    """Every built-in part kind: the catalog's (``acdrive.machines``, ``plant``, ``control``)
    and the PM drive's own controller kinds."""
    from acdrive._part_catalog import part_kinds
    from acdrive.drives.pm import PMSpeedPI, PMTorqueReference, RotorFrameCurrentController

    return [*part_kinds().values(), PMSpeedPI, PMTorqueReference, RotorFrameCurrentController]


def generated_kinds() -> list[type]:
    """The built-in sampled kinds whose C is written per class, each generated from its kernel
    on its look-up (a kind whose C is written per instance is checked per instance:
    ``_instances``)."""
    out = []
    for cls in built_in_kinds():
        if issubclass(cls, SampledPart) and _kinds._entry(_kinds._REGISTRY, cls) is not None:
            if not callable(_kinds._REGISTRY[cls].body):
                out.append(cls)
    return sorted(set(out), key=lambda c: c.__name__)


def kind_module(cls):
    """The kind's kernels compiled alone, as the loops inline them (``sim._kernels.kind_source``),
    compiled in this process rather than loaded from the on-disk cache, which other processes
    of the suite (children under ACDRIVE_STRICT_MATH=1 among them) also write."""
    from acdrive.sim import _codegen as codegen

    return codegen.load_module(kind_source(cls).replace("cache=True", "cache=False"))


def _instances() -> list:
    """Parts of the kinds whose layouts are set per instance (``PER_INSTANCE``): each form
    their structure takes."""
    from acdrive.control._current import StationaryCurrentController
    from acdrive.control._delay import ComputationDelay
    from acdrive.control._lti import LTI

    pi, lag = LTI.pi(2.0, 300.0), LTI.pi_lag(3.0, 100.0, [500.0], [2000.0])
    parts = [ComputationDelay("delay"), ComputationDelay("delay", unit="A", kind="real"),
             StationaryCurrentController("pi", pi, T_s=1e-4),
             StationaryCurrentController("pi_dc", pi, T_s=1e-4, v_dc_input=True),
             StationaryCurrentController("lag", lag, T_s=1e-4, aw_gain=0.0, v_max=50.0),
             *_reducers()]  # fmt: skip
    for part in parts:
        _kinds.c_step_of(part)  # a kind made at run time is registered on its first look-up
    return parts


def _reducers() -> list:
    """The batch reducers' parts (``acdrive._reducer_parts``), one of each form: the stats part
    over a space vector with a reference and a real signal; the oscillation part with and
    without a reference; the speed error with a relay gate and two excluded windows, and
    without either."""
    from acdrive._reducer_parts import _reducer_class, _speed_error_class, _stats_class

    stats = _stats_class((("A", True, True), ("rad/s", False, False)))
    window = {"start0": 0.1, "stop0": 0.9, "limit0": 1.0, "start1": 0.0, "stop1": 1.0,
              "limit1": 0.5}  # fmt: skip
    gated, free = _speed_error_class("rad/s", True, 2), _speed_error_class("rad/s", False, 0)
    return [stats("stats", every=2.0, **window),
            _reducer_class("oscillation", "rad/s", False, True)(
                "osc_ref", start=0.1, stop=0.9, split=0.5, a_hp=0.9, b_lp=0.1, is_complex=0.0,
                has_ref=1.0),
            _reducer_class("oscillation", "rad/s", False, False)(
                "osc", start=0.1, stop=0.9, split=0.5, a_hp=0.9, b_lp=0.1, is_complex=0.0,
                has_ref=0.0),
            gated("gated", every=1.0, slew=0.01, settle=0.02, has_gate=1.0, start0=0.2, end0=0.3,
                  start1=0.6, end1=0.7),
            free("free", every=1.0, slew=0.01, settle=0.02, has_gate=0.0)]  # fmt: skip


def cases() -> list:
    """(kind, part or None): a class-level kind once, a per-instance kind per instance."""
    return [(cls, None) for cls in generated_kinds()] + [(type(p), p) for p in _instances()]


def test_the_translated_kinds_are_registered():
    sampled = [c for c in built_in_kinds() if issubclass(c, SampledPart)]
    names = {c.__name__ for c in sampled if _kinds._entry(_kinds._REGISTRY, c) is not None}
    assert {"Encoder", "CurrentSensors", "VoltageSensor", "SpeedReference", "ForcedRelay",
            "RelayCommand", "SpeedEstimator", "IndirectFOC", "SpeedPI", "SaturatedSpeedP",
            "PositionP", "CarrierLatch", "SupplyFrequencyEstimator", "Synchroniser",
            "SpeedController", "CurrentProgram", "VoltageProgram", "ComplexProgram",
            "ComputationDelay", "StationaryCurrentController", "PMTorqueReference",
            "PMSpeedPI", "RotorFrameCurrentController"} <= names  # fmt: skip
    per_instance = {c for c in sampled if callable(_kinds._REGISTRY[c].body)}
    assert per_instance <= {type(part) for part in _instances()}  # each one is exercised


_ROLES = (("in", "INPUTS", "u"), ("params", "PARAMS", "p"), ("state", "STATES", "s"),
          ("out", "OUTPUTS", "y"))  # fmt: skip


def _members(layout) -> list[Member]:
    specs = {"table": ("table", POINTS), "table2d": ("table2d", POINTS, POINTS)}
    return [Member(v.name, specs.get(v.kind, v.kind)) for v in layout]


def _copy_lines(layout, struct: str, array: str, into_struct: bool) -> list[str]:
    """C lines copying between a flat array (the kernel's) and a struct (the C step's)."""
    lines = []
    for v in layout:
        if v.kind in ("table", "table2d"):
            continue
        k = layout.slot(v.name)
        parts = [(f"{struct}.{v.name}.re", k), (f"{struct}.{v.name}.im", k + 1)] if (
            v.kind == "complex") else [(f"{struct}.{v.name}", k)]  # fmt: skip
        for member, slot in parts:
            lines.append(f"    {member} = {array}[{slot}];" if into_struct
                         else f"    {array}[{slot}] = {member};")  # fmt: skip
    offset = layout.table_start
    for v in layout.tables:
        if into_struct:
            lines += [f"    {struct}.{v.name}.n = (int){array}[{offset}];",
                      f"    for (i = 0; i < {POINTS}; ++i) {{",
                      f"        {struct}.{v.name}.t[i] = {array}[{offset} + 1 + i];",
                      f"        {struct}.{v.name}.v[i] = {array}[{offset} + 1 + {POINTS} + i];",
                      "    }"]  # fmt: skip
        offset += 1 + 2 * POINTS
    for v in layout.tables2d:  # POINTS x POINTS grids
        if into_struct:
            lines += [f"    {struct}.{v.name}.nx = {POINTS};",
                      f"    {struct}.{v.name}.ny = {POINTS};",
                      f"    for (i = 0; i < {POINTS}; ++i) {{",
                      f"        {struct}.{v.name}.x[i] = {array}[{offset} + 2 + i];",
                      f"        {struct}.{v.name}.y[i] = {array}[{offset} + 2 + {POINTS} + i];",
                      "    }", f"    for (i = 0; i < {POINTS * POINTS}; ++i) {{",
                      f"        {struct}.{v.name}.v[i] = {array}[{offset} + 2 + {2 * POINTS} + i];",
                      "    }"]  # fmt: skip
        offset += 2 + 2 * POINTS + POINTS * POINTS
    return lines


#: the floating-point exceptions the last guarded call raised (``_guarded``), read by ``raised()``
_RAISED = ("static int acd_test_raised;", "int raised(void) { return acd_test_raised; }")


def _guarded(call: str) -> list[str]:
    """The wrapper's line ``call`` between clearing the floating-point exception flags and
    recording whether it overflowed, divided by zero or met an invalid operation."""
    return ["    feclearexcept(FE_ALL_EXCEPT);", call,
            "    acd_test_raised = fetestexcept(FE_OVERFLOW | FE_DIVBYZERO | FE_INVALID) != 0;"]


def _compiled_run(kinds, code: list[str], wrapper: list[str], folder, name: str, argtypes,
                  restype):
    """The kinds' declarations, the helpers ``code`` calls, ``code`` and the test's ``wrapper``
    compiled as the native tier compiles (plus -Wall -Wextra -Werror: a mistyped pointer is an
    error, not a warning); the wrapper's ``run`` loaded."""
    source = "\n".join(["#include <stdint.h>", "#include <math.h>", "#include <fenv.h>", PRELUDE,
                        *kind_declarations(kinds), helpers_of(kinds, code), *code, *_RAISED,
                        *wrapper])  # fmt: skip
    path, library = folder / f"{name}.c", folder / f"lib{name}.so"
    path.write_text(source)
    strict = ("-Wall", "-Wextra", "-Werror")
    done = subprocess.run(["gcc", *NATIVE_CFLAGS, *strict, "-o", str(library), str(path), "-lm"],
                          capture_output=True, text=True, check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr
    lib = ctypes.CDLL(str(library))
    lib.run.argtypes = argtypes
    lib.run.restype = restype
    lib.raised.restype = ctypes.c_int
    return lib.run, lib.raised


def c_library(cls, part, folder):
    """The kind's generated C step (for ``part``, a per-instance kind) with a flat-array
    wrapper ``run``, compiled."""
    step = _kinds._REGISTRY[cls]
    of = part if part is not None else cls
    body = step.body(part) if callable(step.body) else step.body
    support = step.support(part) if callable(step.support) else step.support
    entry = KindTypes(cls, kind_name(cls), step, body, support=support)
    for role, attr, _ in _ROLES:
        entry.members[role] = _members(getattr(of, attr))
    kinds = {cls: entry}
    code = [_step_signature(entry), "{", "    (void)t;", "    (void)T_s;", body, "}"]
    wrapper = ["uint32_t run(double t, double T_s, const double *u, const double *p, double *s, "
               "double *y)", "{", "    int i = 0;", "    uint32_t events;",
               "    (void)u;", "    (void)p;", "    (void)s;", "    (void)y;"]  # fmt: skip
    args = ["t", "T_s"]
    for role, attr, arg in _ROLES:
        if not entry.members[role]:
            continue
        wrapper.append(f"    acd_{entry.cname}_{role} {arg.upper()};")
        args.append(f"&{arg.upper()}")
    for role, attr, arg in _ROLES:
        if entry.members[role]:
            wrapper += _copy_lines(getattr(of, attr), arg.upper(), arg, True)
    wrapper += _guarded(f"    events = acd_{entry.cname}_step({', '.join(args)});")
    for role, attr, arg in _ROLES[2:]:
        if entry.members[role]:
            wrapper += _copy_lines(getattr(of, attr), arg.upper(), arg, False)
    wrapper += ["    (void)i;", "    return events;", "}"]
    pointer = ctypes.POINTER(ctypes.c_double)
    return _compiled_run(kinds, code, wrapper, folder, entry.cname,
                         [ctypes.c_double, ctypes.c_double, *([pointer] * 4)], ctypes.c_uint32)


SPECIAL = np.array([0.0, -0.0, 1e300, -1e300, 1.0, -1.0, 0.5, 2.0])


def _values(rng, n: int) -> np.ndarray:
    out = np.exp(rng.uniform(np.log(1e-3), np.log(1e3), n)) * rng.choice([-1.0, 1.0], n)
    special = rng.random(n) < 0.15
    out[special] = rng.choice(SPECIAL, int(special.sum()))
    return out


def _flat(rng, layout) -> tuple[np.ndarray, list[float]]:
    """A flat array of ``layout`` (tables of POINTS sorted times) and the table times."""
    fixed = _values(rng, layout.fixed_size)
    times, tables = [], []
    for _ in layout.tables:
        t = np.sort(rng.uniform(0.0, 1.0, POINTS))
        t[2] = t[1]  # a vertical step
        tables += [np.array([float(POINTS)]), t, _values(rng, POINTS)]
        times += list(t)
    for _ in layout.tables2d:  # strictly increasing axes in [-2, 2], where draws land often
        axes = [np.sort(rng.uniform(-2.0, 2.0, POINTS)) for _ in range(2)]
        tables += [np.array([float(POINTS), float(POINTS)]), *axes, _values(rng, POINTS**2)]
    return np.concatenate([fixed, *tables]) if tables else fixed, times


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    both_nan = np.isnan(a) & np.isnan(b)
    return bool(np.all(both_nan | (a.view(np.int64) == b.view(np.int64))))


def _same_where_finite(a: np.ndarray, b: np.ndarray) -> bool:
    """``_same`` except where either side is not finite: the comparison of a draw on which the
    C step overflowed, divided by zero or met an invalid operation. There the IEEE result (NaN
    from inf * 0, say) was seen to come out of numba's strict build as a finite number on one CI
    machine (as if x * 0.0 had been folded to 0), while this machine's numba and the C agree;
    every value both sides compute as finite must still be the same bits."""
    either = ~np.isfinite(a) | ~np.isfinite(b)
    return bool(np.all(either | (a.view(np.int64) == b.view(np.int64))))


def _in_a_fresh_interpreter(check: str, index: int, folder) -> None:
    """Run ``check(index, folder)`` of this module in a child interpreter: the numba reference is
    compiled there from scratch, away from what the suite's earlier tests left in this process
    (a kernel module compiled after every built-in scenario was built was seen to give other
    values at the edges, -inf where a fresh interpreter gives NaN, from the same source)."""
    import os
    import sys
    from pathlib import Path

    code = (f"import sys; sys.path.insert(0, {str(Path(__file__).parent)!r}); "
            f"import test_kernel_translation as t; t.{check}({index}, {str(folder)!r})")  # fmt: skip
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=dict(os.environ), timeout=900, check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]


def _case_id(case) -> str:
    return "-".join(c.__name__ if isinstance(c, type) else c if isinstance(c, str)
                    else getattr(c, "name", "") for c in case if c is not None)  # fmt: skip


@pytest.mark.parametrize("index", range(len(cases())),
                         ids=[_case_id(c) for c in cases()])  # fmt: skip
def test_generated_c_equals_the_compiled_kernel_bit_for_bit(index, tmp_path):
    _in_a_fresh_interpreter("check_step", index, tmp_path)


def check_step(index: int, folder) -> None:
    """Case ``index`` of ``cases()``: the kind's generated step against its compiled kernel."""
    from pathlib import Path

    cls, part = cases()[index]
    tmp_path = Path(folder)
    run_c, raised = c_library(cls, part, tmp_path)
    kernel = kind_module(cls).step
    of = part if part is not None else cls
    rng = np.random.default_rng(sum(map(ord, cls.__name__ + getattr(part, "name", ""))))
    structural = {of.PARAMS.slot(n) for n in getattr(cls, "STRUCTURAL", ())}
    T_s = 1e-4
    for draw in range(DRAWS):
        p, times = _flat(rng, of.PARAMS)
        for k in structural:  # the instance's structure, which its C is written for
            p[k] = part.p[k]
        if part is not None and not of.PARAMS.tables and draw % 2:
            p = np.array(part.p, dtype=float)  # the part as configured (a reducer's every)
        u, _ = _flat(rng, of.INPUTS)
        s, _ = _flat(rng, of.STATES)
        y, _ = _flat(rng, of.OUTPUTS)
        t = times[draw % len(times)] if times and draw % 2 else float(rng.uniform(0.0, 1.2))
        s_c, y_c = s.copy(), y.copy()
        events = kernel(t, T_s, u, p, s, y)
        as_pointer = (lambda a: a.ctypes.data_as(ctypes.POINTER(ctypes.c_double)))
        events_c = run_c(t, T_s, as_pointer(u), as_pointer(p), as_pointer(s_c), as_pointer(y_c))
        same = _same_where_finite if raised() else _same
        assert raised() or events_c == events, (draw, events, events_c)
        assert same(s, s_c), (draw, s, s_c)
        assert same(y, y_c), (draw, y, y_c)


def _kernel(source: str):
    namespace: dict = {"np": np}
    exec(compile(source, "<kernel>", "exec"), namespace)  # noqa: S102 (a test's own kernel)
    return namespace["step"]


@pytest.mark.parametrize(("body", "construct"), [
    ("    while t > 0.0:\n        t -= 1.0\n    return 0\n", "statement While"),
    ("    y[0] = u[0] ** 3\n    return 0\n", "operator Pow"),
    ("    y[0] = np.arcsinh(u[0])\n    return 0\n", "library function arcsinh"),
    ("    k = int(u[0])\n    y[0] = u[k]\n    return 0\n", "not a constant of the module"),
])  # fmt: skip
def test_a_construct_outside_the_language_names_kernel_line_and_construct(body, construct):
    from acdrive.core._signals import Layout, real

    import linecache

    source = "def step(t, T_s, u, p, s, y):\n" + body
    linecache.cache["<kernel>"] = (len(source), None, source.splitlines(True), "<kernel>")
    roles = {"u": _Role(Layout(real("a", "", "input a"), real("b", "", "input b"))),
             "y": _Role(Layout(real("c", "", "output c")))}  # fmt: skip
    with pytest.raises(UnsupportedKernel) as exc:
        translate_step(_kernel(source), roles)
    message = str(exc.value)
    assert message.startswith("__main__.step (line ") or ".step (line " in message
    assert construct in message and "\n" not in message


def _Role(layout):  # noqa: N802 (a stand-in constructor)
    from acdrive.sim._ccode._translate import Role

    return Role(layout, "x")


def test_only_sampled_parts_are_translated():
    assert all(issubclass(c, SampledPart) for c in generated_kinds())


def test_the_current_controller_is_written_for_its_order():
    """Per instance: a controller of order n names its states x_0 to x_{n-1} (the PI on both
    axes is of order 2, the PI x lag of order 4); the v_dc input appears only in the instance
    that has it."""
    from acdrive.sim._ccode._kind_c import translate_part

    pi, pi_dc, lag = _instances()[2:5]
    assert (pi.discrete.order, lag.discrete.order) == (2, 4)
    for part in (pi, lag):
        n, body = part.discrete.order, translate_part(part).body
        assert f"s->x_{n - 1}" in body and f"s->x_{n}" not in body
    assert "u->v_dc" in translate_part(pi_dc).body and "u->v_dc" not in translate_part(pi).body


# --- plant kinds: the continuous parts' kernels -------------------------------------------------

#: C argument order of each plant role (``sim._ccode._plant_source._signature``): (array, struct
#: role) present when the kind declares that struct; "y" and "x"/"dx" always where listed
_PLANT_ARGS = {
    "state_outputs": ("t", "p", "x?", "y"),
    "direct_outputs": ("t", "p", "x?", "u", "y"),
    "rhs": ("t", "p", "x", "u", "y", "dx"),
    "project": ("p", "x"),
}
_PLANT_STRUCT = {"p": ("PARAMS", "params"), "x": ("STATES", "state"), "u": ("INPUTS", "in"),
                 "y": ("OUTPUTS", "out"), "dx": ("STATES", "state")}  # fmt: skip


def generated_plant_kinds() -> list[type]:
    """The built-in plant kinds (continuous parts and modulators), their C generated on their
    look-up."""
    found = [cls for cls in built_in_kinds() if not issubclass(cls, SampledPart)
             and _kinds._entry(_kinds._PLANT_REGISTRY, cls) is not None]  # fmt: skip
    return sorted(set(found), key=lambda c: c.__name__)


def test_the_translated_plant_kinds_are_registered():
    names = {c.__name__ for c in generated_plant_kinds()}
    assert {"DCSource", "CageInductionMachine", "ThreePhaseSource", "StatorRelay",
            "DoublyFedMachine", "PermanentMagnetMachine", "Shaft", "PrescribedSpeed",
            "AveragedConverter", "DCFedConverter", "Inverter"} <= names  # fmt: skip


def segments_library(cls, folder):
    """A modulator's generated ``segments`` with a flat-array wrapper
    ``run(T_s, u, p, s, dt, v)`` returning n + 256 * events (v: MAX_SEGMENTS rows)."""
    from acdrive.sim._ccode._plant_source import _signature, _unused

    c = _kinds._PLANT_REGISTRY[cls]
    entry = KindTypes(cls, kind_name(cls), c, "", support=c.support)
    for r, attr, _ in _ROLES:
        entry.members[r] = _members(getattr(cls, attr))
    signature = _signature(entry, "segments")
    code = [signature, "{", *_unused(signature), c.role("segments", None).strip("\n"), "}"]
    kinds = {cls: entry}
    width, rows = cls.OUTPUTS.fixed_size, cls.MAX_SEGMENTS
    wrapper = ["uint32_t run(double T_s, const double *u, const double *p, double *s, "
               "double *dt, double *v)", "{", "    int i = 0, n = 0, r;", "    uint32_t events;",
               f"    acd_{entry.cname}_out V[{rows}];",
               "    (void)u; (void)p; (void)s;"]  # fmt: skip
    args = ["T_s"]
    for r, attr, arg in (("in", "INPUTS", "u"), ("params", "PARAMS", "p"),
                         ("state", "STATES", "s")):  # fmt: skip
        if entry.members[r]:
            wrapper.append(f"    acd_{entry.cname}_{r} {arg.upper()}_;")
            wrapper += _copy_lines(getattr(cls, attr), arg.upper() + "_", arg, True)
            args.append(f"&{arg.upper()}_")
    wrapper.append(f"    for (r = 0; r < {rows}; ++r) {{")
    wrapper += ["    " + line.replace("= v[", f"= v[r * {width} + ")
                for line in _copy_lines(cls.OUTPUTS, "V[r]", "v", True)]  # fmt: skip
    wrapper.append("    }")
    wrapper += _guarded(f"    events = acd_{entry.cname}_segments({', '.join([*args, '&n', 'dt', 'V'])});")
    if entry.members["state"]:
        wrapper += _copy_lines(cls.STATES, "S_", "s", False)
    wrapper.append(f"    for (r = 0; r < {rows}; ++r) {{")
    wrapper += ["    " + line.replace("    v[", f"    v[r * {width} + ")
                for line in _copy_lines(cls.OUTPUTS, "V[r]", "v", False)]  # fmt: skip
    wrapper += ["    }", "    (void)i;", "    return (uint32_t)n + 256u * events;", "}"]
    pointer = ctypes.POINTER(ctypes.c_double)
    return _compiled_run(kinds, code, wrapper, folder, f"{entry.cname}_segments",
                         [ctypes.c_double, *([pointer] * 5)], ctypes.c_uint32)


def _modulators() -> list:
    return [c for c in generated_plant_kinds() if _kinds._PLANT_REGISTRY[c].segments is not None]


@pytest.mark.parametrize("index", range(len(_modulators())),
                         ids=[c.__name__ for c in _modulators()])  # fmt: skip
def test_generated_segments_equal_the_compiled_kernel_bit_for_bit(index, tmp_path):
    _in_a_fresh_interpreter("check_segments", index, tmp_path)


def check_segments(index: int, folder) -> None:
    """A modulator's segments (their count, lengths, outputs, events and its state) from the
    generated C and from the compiled kernel, on random draws (strict: its kernel is ``jit``)."""
    from pathlib import Path

    cls, tmp_path = _modulators()[index], Path(folder)
    run_c, raised = segments_library(cls, tmp_path)
    kernel = kind_module(cls).segments
    rng = np.random.default_rng(sum(map(ord, cls.__name__)))
    width, rows = cls.OUTPUTS.fixed_size, cls.MAX_SEGMENTS
    as_pointer = (lambda a: a.ctypes.data_as(ctypes.POINTER(ctypes.c_double)))
    for draw in range(DRAWS):
        p, _ = _flat(rng, cls.PARAMS)
        u, _ = _flat(rng, cls.INPUTS)
        s = _values(rng, max(cls.STATES.fixed_size, 1))
        dt, v = np.zeros(rows), np.zeros((rows, width))
        s_c, dt_c, v_c = s.copy(), dt.copy(), v.copy()
        n, events = kernel(1e-4, u, p, s, dt, v)
        packed = run_c(1e-4, as_pointer(u), as_pointer(p), as_pointer(s_c), as_pointer(dt_c),
                       as_pointer(v_c))  # fmt: skip
        same = _same_where_finite if raised() else _same
        assert raised() or (packed % 256, packed // 256) == (n, events), draw
        assert same(s, s_c) and same(dt, dt_c) and same(v.ravel(), v_c.ravel()), draw


def plant_library(cls, role: str, folder, part=None):
    """The kind's generated C of ``role`` (for ``part``, a per-instance kind) with a flat-array
    wrapper ``run(t, x, u, p, y, dx)``."""
    from acdrive.sim._ccode._plant_source import _signature, _unused

    c = _kinds._PLANT_REGISTRY[cls]
    of = part if part is not None else cls
    support = c.support(part) if callable(c.support) else c.support
    entry = KindTypes(cls, kind_name(cls), c, "", support=support)
    for r, attr, _ in _ROLES:
        entry.members[r] = _members(getattr(of, attr))
    signature = _signature(entry, role)
    code = [signature, "{", *_unused(signature), c.role(role, part).strip("\n"), "}"]
    kinds = {cls: entry}
    wrapper = ["void run(double t, double *x, const double *u, const double *p, double *y, "
               "double *dx)", "{", "    int i = 0;",
               "    (void)t; (void)x; (void)u; (void)p; (void)y; (void)dx;"]  # fmt: skip
    args = []
    for name in _PLANT_ARGS[role]:
        if name == "t":
            args.append("t")
            continue
        optional = name.endswith("?")
        name = name.rstrip("?")
        attr, struct = _PLANT_STRUCT[name]
        layout = getattr(of, attr)
        if not entry.members[struct] and (name == "p" or optional or name == "u"):
            continue
        var = name.upper() + "_"
        wrapper.append(f"    acd_{entry.cname}_{struct} {var};")
        wrapper += _copy_lines(layout, var, name, True)
        args.append(f"&{var}")
    wrapper.append(f"    acd_{entry.cname}_{role}({', '.join(args)});")
    written = {"state_outputs": "y", "direct_outputs": "y", "rhs": "dx", "project": "x"}[role]
    attr = _PLANT_STRUCT[written][0]
    wrapper += _copy_lines(getattr(of, attr), written.upper() + "_", written, False)
    wrapper += ["    (void)i;", "}"]
    pointer = ctypes.POINTER(ctypes.c_double)
    return _compiled_run(kinds, code, wrapper, folder, f"{entry.cname}_{role}",
                         [ctypes.c_double, *([pointer] * 5)], None)


def _same_up_to_zero_sign(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal bits, or both zeros of either sign, or both NaN: what a kernel compiled with
    numba's no-signed-zeros flag promises."""
    both_nan = np.isnan(a) & np.isnan(b)
    zeros = (a == 0.0) & (b == 0.0)
    return bool(np.all(both_nan | zeros | (a.view(np.int64) == b.view(np.int64))))


def _finite_values(rng, n: int) -> np.ndarray:
    """Values of either sign from 1e-3 to 1e3 and signed zeros (no 1e300: a fast-math kernel
    assumes no overflow to infinity)."""
    out = np.exp(rng.uniform(np.log(1e-3), np.log(1e3), n)) * rng.choice([-1.0, 1.0], n)
    zero = rng.random(n) < 0.1
    out[zero] = rng.choice([0.0, -0.0], int(zero.sum()))
    return out


def _plant_cases() -> list:
    """(kind, role, part or None): a per-instance kind (the supply bus, of one and of three
    machines) per instance."""
    from acdrive.plant._network import SupplyBus

    out = []
    for cls in generated_plant_kinds():
        if getattr(cls, "PER_INSTANCE", None):
            continue
        out += [(cls, role, None) for role in PLANT_ROLES_TRANSLATED
                if _kinds._PLANT_REGISTRY[cls].role(role, None)]  # fmt: skip
    for bus in (SupplyBus("bus1", R=0.1, L=1e-3), SupplyBus("bus3", n_machines=3, R=0.1, L=1e-3)):
        out.append((SupplyBus, "direct_outputs", bus))
    return out


PLANT_ROLES_TRANSLATED = ("state_outputs", "direct_outputs", "rhs", "project")  # and segments


@pytest.mark.parametrize("index", range(len(_plant_cases())),
                         ids=[_case_id(c) for c in _plant_cases()])  # fmt: skip
def test_generated_plant_c_equals_the_compiled_kernel(index, tmp_path):
    _in_a_fresh_interpreter("check_plant", index, tmp_path)


def check_plant(index: int, folder) -> None:
    """Against the kernel as every tier compiles it, at the sample instant and inside the
    integrator's stages: bit for bit for a kernel without fast-math, up to the sign of a zero
    for one with acdrive's fast-math flags (``jit_fast``), which leave that sign unspecified."""
    from pathlib import Path

    from acdrive.sim._ccode._translate import _fast_math

    cls, role, part = _plant_cases()[index]
    tmp_path = Path(folder)
    run_c, _ = plant_library(cls, role, tmp_path, part)
    of = part if part is not None else cls
    module = kind_module(cls)
    exact = _same_up_to_zero_sign if _fast_math(getattr(cls, role), False) else _same
    strict = getattr(module, role, None) if role != "rhs" else None
    fast = getattr(module, f"{role}_fast", None) if role != "rhs" else module.rhs
    rng = np.random.default_rng(sum(map(ord, cls.__name__ + role)))
    as_pointer = (lambda a: a.ctypes.data_as(ctypes.POINTER(ctypes.c_double)))
    for draw in range(DRAWS):
        p, times = _flat(rng, of.PARAMS)
        p[: of.PARAMS.fixed_size] = np.abs(_finite_values(rng, of.PARAMS.fixed_size)) + 1e-3
        x = _finite_values(rng, max(of.STATES.fixed_size, 1))
        u = _finite_values(rng, of.INPUTS.fixed_size) if of.INPUTS.fixed_size else np.zeros(1)
        y = _finite_values(rng, max(of.OUTPUTS.fixed_size, 1))
        dx = np.zeros(max(of.STATES.fixed_size, 1))
        t = times[draw % len(times)] if times and draw % 2 else float(rng.uniform(0.0, 1.2))
        c_arrays = [a.copy() for a in (x, u, p, y, dx)]
        run_c(t, *(as_pointer(a) for a in c_arrays))
        for kernel, same in ((strict, exact), (fast, _same_up_to_zero_sign)):
            if kernel is None:
                continue
            k_arrays = [a.copy() for a in (x, u, p, y, dx)]
            kx, ku, kp, ky, kdx = k_arrays
            if role == "state_outputs":
                kernel(t, kx, kp, ky)
            elif role == "direct_outputs":
                kernel(t, kx, ku, kp, ky)
            elif role == "rhs":
                kernel(t, kx, ku, kp, ky, kdx)
            else:
                kernel(kx, kp)
            for name, ka, ca in zip("x u p y dx".split(), k_arrays, c_arrays, strict=True):
                assert same(ka, ca), (draw, name, ka, ca)
