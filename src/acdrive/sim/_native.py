"""The native tier of the simulation loop: a system's whole sampled-data loop as C, compiled by the
machine's C compiler into a shared library in well under a second, loaded with ctypes.

The C is the engine's (``sim._ccode``: ``_c_source.to_c`` for the controller chains,
``_plant_source.to_plant_c`` for the plant: the same generated text the export writes into the
FMUs and the software-in-the-loop runs), plus one generated driver that repeats the compiled
loop of ``sim._loop_source`` sample by sample:

1. at t_k = t0 + k T_s: the plant's redundant states re-normalised and its outputs computed with
   the commands of sample k-1 held (``<plant>_update_outputs``: ``project``, ``plant_outputs``);
2. each controller chain reads the plant outputs and steps (``<chain>_step``: the sampled parts in
   the system's order); the commands are handed to the plant;
3. the plant's step (``<plant>_step``): the modulators' segments, then, through the hook
   ``ACD_AFTER_MODULATE``, the sample is recorded exactly where the numba loop records it (event
   bits counted, the selected outputs logged every ``log_every`` samples), then the integration
   over the merged segments with the system's Runge-Kutta method;
4. the continuous state is checked finite; a non-finite state ends the run with its status.

The library does not depend on the sample time or the substeps (both are set per run), nor on
the initial state (loaded from acdrive's packed arrays), so ``System.compile()`` builds it once
per topology and parameter set; it is kept in a cache folder keyed by the hash of its source and
compiler flags, written under a temporary name and renamed into place (an interrupted build leaves
nothing), and a library that cannot be loaded is built again with a one-line notice.

Arithmetic: compiled with ``-ffp-contract=off`` (``NATIVE_CFLAGS``), the C repeats the
kernels' operations in their order, so under ``ACDRIVE_STRICT_MATH=1`` (strict IEEE in numba too)
the native tier equals the specialised loop bit for bit, and so it does with numba's default
fast-math flags (``acdrive._jit.FAST_MATH_FLAGS``: no reordering, fusing or reciprocals), since
sine, cosine and magnitudes are acdrive's own on both sides (``sim._lane_math``, ``acd_sincos``
in ``sim._ccode._prelude``): ``tests/test_native_tier.py``.

A system the native tier cannot run is named with the reason (``native_obstacle``): a part kind
without C (a user's own kernel), an integrator without C, no C compiler on the machine.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import re
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from acdrive.core._parts import ContinuousPart, SampledPart
from acdrive.errors import InputError

#: compiler flags of the native library: the SIL build's (no contraction into fused
#: multiply-adds, so the double build rounds as the kernels do), as a shared library, at -O1
#: for the baseline instruction set of the target, chosen by measurement
#: (``benchmarks/native_flags.py``: 2-core Xeon with AVX-512, gcc 12.2, three rounds of three
#: runs interleaved, loop steps per CPU-s, median over -O1's): -O2 0.95 / 1.05 / 1.01 and -O3
#: 0.95 / 1.07 / 1.00 on bodson-ramp / im-foc-speed / pm-bly171d-speed, at 1.5 to 2.2 times
#: -O1's compile (0.37-0.39 CPU-s of cc); the host's instruction set (-march=native) 0.87 /
#: 0.16 / 0.62 at -O2, and it changes results: gcc 12's vectoriser fuses complex products into
#: vfmaddsub instructions under -ffp-contract=off when FMA is enabled (-O2 -mfma alone shows
#: it; at -O1, which does not vectorise, the results stay bit-identical). -pipe: no temporary
#: files between the compiler's passes
NATIVE_CFLAGS = ("-std=c99", "-O1", "-ffp-contract=off", "-fPIC", "-pipe", "-shared")
#: the C names of the generated pieces
_CTL, _PLANT = "acdn_ctl", "acdn_plant"
#: the status codes (as ``sim._loop_source``; and the native loop's own: no memory for its
#: parameters)
STATUS_OK, STATUS_NONFINITE, STATUS_NO_MEMORY = 0, 1, 2


def compiler() -> str | None:
    """The machine's C compiler (``$CC``, else cc, else gcc), or None."""
    named = os.environ.get("CC")
    for name in ([named] if named else []) + ["cc", "gcc"]:
        path = shutil.which(name)
        if path:
            return path
    return None


def compiler_command() -> list[str] | None:
    """The command the native tier compiles with: the machine's C compiler (``compiler``), else
    the clang that the ``ziglang`` package from PyPI carries (``python -m ziglang cc``: a
    compiler without a system install, for Windows and macOS machines without one), else None.
    Measured against gcc 12 on the developers' machine (docs/speed.md, "A compiler from PyPI"):
    the same results bit for bit, 2-4 times gcc's compile time per topology, and one build of
    its own runtime (about 23 CPU-s) the first time it is used."""
    found = compiler()
    if found is not None:
        return [found]
    from importlib.util import find_spec

    if find_spec("ziglang") is not None:
        import sys

        return [sys.executable, "-m", "ziglang", "cc"]
    return None


def native_obstacle(system) -> str | None:
    """Why the native tier cannot run ``system`` (None: it can)."""
    from acdrive.sim._ccode._kinds import c_step_of, plant_c_of

    if compiler_command() is None:
        return "no C compiler found (cc, gcc, $CC or the ziglang package)"
    if system.method not in ("rk4", "rk6"):
        return f"the integrator {system.method} has no C"
    if not system.continuous:
        return "the system has no continuous part"
    from acdrive.sim._ccode._kinds import untranslatable
    from acdrive.sim._ccode._translate import UnsupportedKernel

    missing = {}
    for part in system.parts:
        lookup = c_step_of if isinstance(part, SampledPart) else plant_c_of
        try:
            entry = lookup(part)
            if callable(getattr(entry, "body", None)):  # written per instance: translated now
                entry.body(part)
        except InputError:
            missing[type(part).__name__] = untranslatable(type(part))
        except UnsupportedKernel as exc:
            missing[type(part).__name__] = str(exc)
    if missing:
        names = ", ".join(f"{n} ({why})" if why else n for n, why in sorted(missing.items()))
        return f"no C for the part kind(s) {names}"
    return None


def _folder() -> Path:
    """The native libraries' folder: beside the numba cache acdrive keys by its own sources
    (``acdrive/__init__.py`` sets NUMBA_CACHE_DIR before numba is imported), else a temporary
    folder."""
    from acdrive._cache import cache_folder

    return cache_folder("native", "acdrive")


def _value(target: str, var) -> list[str]:
    """The C lvalues of a quantity (a complex one is two reals)."""
    return [f"{target}.re", f"{target}.im"] if var.kind == "complex" else [target]


@dataclass
class NativeSource:
    """The three C files of one system's native loop and the key they are cached by."""

    controller_header: str
    controller_source: str
    plant_header: str
    plant_source: str
    driver: str

    @property
    def key(self) -> str:
        digest = hashlib.sha256()
        for text in (self.controller_header, self.controller_source, self.plant_header,
                     self.plant_source, self.driver, " ".join(NATIVE_CFLAGS)):  # fmt: skip
            digest.update(text.encode())
            digest.update(b"\0")
        return digest.hexdigest()[:24]


def native_source(system) -> NativeSource:
    """The C of ``system``'s native loop (module docstring)."""
    from acdrive.sim._ccode._c_source import to_c
    from acdrive.sim._ccode._plant_source import to_plant_c

    # the sample time and substeps are overwritten per run (acdn_run); 1.0 and 1 are stand-ins
    plant = to_plant_c(system, 1.0, 1, name=_PLANT, description="acdrive native loop",
                       values=False)  # fmt: skip
    has_chains = bool(system.sampled)
    if has_chains:
        ctl = to_c(system, 1.0, name=_CTL, description="acdrive native loop", open_loop=True,
                   values=False)  # fmt: skip
        models = ctl.chains
    else:
        ctl, models = None, []

    plant_kinds = plant.kinds
    chain_of = {p.name: m for m in models for p in m.chain.parts}
    ctl_kinds = ctl.kinds if ctl else {}

    def plant_has(part, role: str) -> bool:
        return bool(plant_kinds[type(part)].members.get(role))

    def chain_has(part, role: str) -> bool:
        return bool(ctl_kinds[type(part)].members.get(role))

    def chain_var(part) -> str:
        return f"c_{chain_of[part.name].chain.name}"

    def output_lvalue(port) -> str:
        """Where an output lives in the driver: a plant part's in the plant's outputs, a sampled
        part's in its chain's held outputs."""
        part = port.part
        if isinstance(part, SampledPart):
            return f"{chain_var(part)}.s.{part.name}_out.{port.var.name}"
        return f"ps.y.{part.name}.{port.var.name}"

    def held_rvalue(part, var) -> str:
        """An output inside the record hook (the chains through the context)."""
        if isinstance(part, SampledPart):
            return f"ctx->{chain_var(part)}->s.{part.name}_out.{var.name}"
        return f"s->y.{part.name}.{var.name}"

    D: list[str] = []
    emit = D.append
    emit("/* Generated by acdrive.sim._native: the native tier's loop; do not edit. */")
    emit("#include <stdint.h>")
    emit("#include <math.h>")
    emit("#include <stdlib.h>")
    emit(f'#include "{_PLANT}.h"')
    if has_chains:
        emit(f'#include "{_CTL}.h"')
    emit("")
    for m in models:
        c = m.chain.name
        outs = f"    {c}_outputs o;" if m.outputs else ""
        emit(f"typedef struct {{ {c}_params p; {c}_state s; {c}_inputs i;{outs} }} acdn_{c};")
    emit("typedef struct {")
    for m in models:
        emit(f"    acdn_{m.chain.name} *c_{m.chain.name};")
    emit("    int64_t k, log_every, n_log, n_events;")
    emit("    const int64_t *log_idx;")
    emit("    double *log, *y;")
    emit("    int64_t *elog, *ecount, *e;")
    emit("} acdn_context;")
    emit("static __thread acdn_context *ctx;")
    emit("")
    # every output into the flat Y of acdrive's layout (for the log), from the plant state s
    emit(f"static void acdn_fill_y(const {_PLANT}_state *s)")
    emit("{")
    emit("    double *Y = ctx->y;")
    emit("    (void)s;")
    for part in system.parts:
        a, _ = system.slots[part.name].y
        for v in part.OUTPUTS:
            k = a + part.OUTPUTS.slot(v.name)
            for j, value in enumerate(_value(held_rvalue(part, v), v)):
                emit(f"    Y[{k + j}] = {value};")
    emit("}")
    emit("")
    # the event bits of this sample (sampled parts in the system's order, then the modulators)
    emit(f"static void acdn_events(const {_PLANT}_state *s)")
    emit("{")
    emit("    int64_t *E = ctx->e;")
    emit("    (void)s;")
    n_sampled = len(system.sampled)
    for i, part in enumerate(system.sampled):
        if part.EVENTS:
            emit(f"    E[{i}] = (int64_t)ctx->{chain_var(part)}->o.{part.name}_events;")
        else:
            emit(f"    E[{i}] = 0;")
    for m, part in enumerate(system.modulators):
        value = f"(int64_t)s->{part.name}_events" if part.EVENTS else "0"
        emit(f"    E[{n_sampled + m}] = {value};")
    emit("}")
    emit("")
    # the hook the plant's step calls after its modulators: record sample k (sim._loop_source.record)
    emit("void acdn_after_modulate(const void *state)")
    emit("{")
    emit(f"    const {_PLANT}_state *s = (const {_PLANT}_state *)state;")
    emit("    int64_t i, j, row;")
    emit("    acdn_events(s);")
    emit("    for (i = 0; i < ctx->n_events; ++i) {")
    emit("        int64_t bits = ctx->e[i], b = 0;")
    emit("        while (bits) {")
    emit("            if (bits & 1) {")
    emit("                ctx->ecount[i * 64 + b] += 1;")
    emit("            }")
    emit("            bits >>= 1;")
    emit("            b += 1;")
    emit("        }")
    emit("    }")
    emit("    if (ctx->k % ctx->log_every == 0) {")
    emit("        row = ctx->k / ctx->log_every;")
    emit("        acdn_fill_y(s);")
    emit("        for (j = 0; j < ctx->n_log; ++j) {")
    emit("            ctx->log[row * ctx->n_log + j] = ctx->y[ctx->log_idx[j]];")
    emit("        }")
    emit("        for (i = 0; i < ctx->n_events; ++i) {")
    emit("            ctx->elog[row * ctx->n_events + i] = ctx->e[i];")
    emit("        }")
    emit("    }")
    emit("}")
    emit("")

    # load / store the packed arrays (X continuous states, S discrete states, Y held outputs)
    def transfer(direction: str) -> list[str]:
        L = []

        def pair(lvalue, array, k):
            L.append(f"    {lvalue} = {array}[{k}];" if direction == "in" else
                     f"    {array}[{k}] = {lvalue};")  # fmt: skip

        for part in system.parts:
            sl = system.slots[part.name]
            if isinstance(part, ContinuousPart):
                if plant_has(part, "state"):
                    for v in part.STATES:
                        k = sl.x[0] + part.STATES.slot(v.name)
                        for j, lv in enumerate(_value(f"ps.x.{part.name}.{v.name}", v)):
                            pair(lv, "X", k + j)
                continue
            if isinstance(part, SampledPart):
                prefix = f"{chain_var(part)}.s.{part.name}"
                has_state, has_out = chain_has(part, "state"), chain_has(part, "out")
            else:  # a modulator
                prefix, has_state, has_out = f"ps.s.{part.name}", plant_has(part, "state"), True
            if has_state:
                for v in part.STATES:
                    k = sl.s[0] + part.STATES.slot(v.name)
                    for j, lv in enumerate(_value(f"{prefix}.{v.name}", v)):
                        pair(lv, "S", k + j)
            if has_out:
                out = (f"{chain_var(part)}.s.{part.name}_out" if isinstance(part, SampledPart)
                       else f"ps.y.{part.name}")  # fmt: skip
                for v in part.OUTPUTS:
                    k = sl.y[0] + part.OUTPUTS.slot(v.name)
                    for j, lv in enumerate(_value(f"{out}.{v.name}", v)):
                        pair(lv, "Y", k + j)
        return L

    # the parameters from the packed array P (part i's from PO[i], ``System.pack_params``): the
    # fixed ones at their slots, then the tables one after another (core._tables), each
    # [n, t_0 .. t_n-1, v_0 .. v_n-1] into a struct sized for this system's tables
    P_lines = []
    for i, part in enumerate(system.parts):
        if isinstance(part, SampledPart):
            if not chain_has(part, "params"):
                continue
            target = f"c_{chain_of[part.name].chain.name}->p.{part.name}"
        else:
            if not plant_has(part, "params"):
                continue
            target = f"pp->{part.name}"
        for v in part.PARAMS:
            if v.kind in ("table", "table2d"):
                continue
            k = part.PARAMS.slot(v.name)
            for j, lv in enumerate(_value(f"{target}.{v.name}", v)):
                P_lines.append(f"    {lv} = P[PO[{i}] + {k + j}];")
        if part.PARAMS.tables or part.PARAMS.tables2d:
            P_lines.append(f"    o = PO[{i}] + {part.PARAMS.table_start};")
        for v in part.PARAMS.tables:
            tab = f"{target}.{v.name}"
            P_lines += ["    n = (int)P[o];", f"    {tab}.n = n;",
                        "    for (j = 0; j < n; ++j) {",
                        f"        {tab}.t[j] = P[o + 1 + j];",
                        f"        {tab}.v[j] = P[o + 1 + n + j];", "    }",
                        "    o += 1 + 2 * (int64_t)n;"]  # fmt: skip
        for v in part.PARAMS.tables2d:  # [n_x, n_y, x.., y.., values] after the tables
            tab = f"{target}.{v.name}"
            P_lines += [f"    {tab}.nx = (int)P[o];", f"    {tab}.ny = (int)P[o + 1];",
                        f"    for (j = 0; j < {tab}.nx; ++j) {{",
                        f"        {tab}.x[j] = P[o + 2 + j];", "    }",
                        f"    for (j = 0; j < {tab}.ny; ++j) {{",
                        f"        {tab}.y[j] = P[o + 2 + {tab}.nx + j];", "    }",
                        f"    for (j = 0; j < {tab}.nx * {tab}.ny; ++j) {{",
                        f"        {tab}.v[j] = P[o + 2 + {tab}.nx + {tab}.ny + j];", "    }",
                        f"    o += 2 + {tab}.nx + {tab}.ny + (int64_t){tab}.nx * {tab}.ny;"]  # fmt: skip
    chain_args = "".join(f", acdn_{m.chain.name} *c_{m.chain.name}" for m in models)
    emit(
        f"static void acdn_params(const double *P, const int64_t *PO, {_PLANT}_params *pp{chain_args})"
    )
    emit("{")
    emit("    int64_t o = 0;")
    emit("    int n = 0, j = 0;")
    emit("    (void)P;")
    emit("    (void)PO;")
    emit("    (void)o;")
    emit("    (void)n;")
    emit("    (void)j;")
    D.extend(P_lines)
    emit("}")
    emit("")
    emit(
        "/* one run of n_steps samples from the packed arrays (X, S, Y: updated in place); returns"
    )
    emit("   the samples done, *status 0 (finished) or 1 (a state stopped being finite) */")
    emit("int64_t acdn_run(const double *P, const int64_t *PO, double *X, double *S, double *Y,")
    emit("                 double t0, double T_s, int64_t n_sub,")
    emit(
        "                 int64_t n_steps, int64_t log_every, const int64_t *log_idx, int64_t n_log,"
    )
    emit("                 double *LOG, int64_t *ELOG, int64_t *ECOUNT, double *Yscratch,")
    emit("                 int64_t *E, int64_t *status)")
    emit("{")
    run_start = len(D)
    # the parameters (tables of any length) and the chains live on the heap, not the stack
    emit(
        f"    struct {{ {_PLANT}_params pp;"
        + "".join(f" acdn_{m.chain.name} c_{m.chain.name};" for m in models)
        + " } *w = calloc(1, sizeof *w);"
    )
    emit(f"    {_PLANT}_state ps;")
    plant_inputs = bool(plant.inputs)
    if plant_inputs:
        emit(f"    {_PLANT}_inputs pin;")
    pin = "&pin" if plant_inputs else "(const void *)0"
    emit("    acdn_context context;")
    emit("    int64_t k, i, done = n_steps;")
    emit("    acdn_context *saved = ctx;")
    emit("    if (w == 0) {")
    emit(f"        *status = {STATUS_NO_MEMORY};")
    emit("        return 0;")
    emit("    }")
    chain_refs = "".join(f", &c_{m.chain.name}" for m in models)
    emit(f"    acdn_params(P, PO, &pp{chain_refs});")
    emit("    pp.sample_time = T_s;")
    emit("    pp.substeps = (int)n_sub;")
    for m in models:
        emit(f"    c_{m.chain.name}.p.sample_time = T_s;")
    for part in system.modulators:
        if part.EVENTS:
            emit(f"    ps.{part.name}_events = 0u;")
    D.extend(transfer("in"))
    # the commands held before the first sample: the plant's inputs from the held outputs
    if plant_inputs:
        for q in plant.inputs:
            k = system.output_slot(q)
            for j, lv in enumerate(_value(f"pin.{q.part.name}_{q.var.name}", q.var)):
                emit(f"    {lv} = Y[{k + j}];")
    for m in models:
        emit(f"    context.c_{m.chain.name} = &c_{m.chain.name};")
    emit("    context.log_every = log_every;")
    emit("    context.log_idx = log_idx;")
    emit("    context.n_log = n_log;")
    emit(f"    context.n_events = {len(system.sampled) + len(system.modulators)};")
    emit("    context.log = LOG;")
    emit("    context.elog = ELOG;")
    emit("    context.ecount = ECOUNT;")
    emit("    context.y = Yscratch;")
    emit("    context.e = E;")
    emit("    ctx = &context;")
    emit("    *status = 0;")
    emit("    for (k = 0; k < n_steps; ++k) {")
    emit("        const double t = t0 + (double)k * T_s;")
    emit("        int finite = 1;")
    emit("        context.k = k;")
    emit(f"        {_PLANT}_update_outputs(t, &pp, &ps, {pin});")
    for m in models:
        c = m.chain.name
        for port in m.chain.inputs:
            for lv, rv in zip(_value(f"c_{c}.i.{port.part.name}_{port.var.name}", port.var),
                              _value(output_lvalue(port), port.var), strict=True):  # fmt: skip
                emit(f"        {lv} = {rv};")
        out = f", &c_{c}.o" if m.outputs else ""
        emit(f"        {c}_step(t, &c_{c}.p, &c_{c}.s, &c_{c}.i{out});")
    if plant_inputs:
        for q in plant.inputs:
            for lv, rv in zip(_value(f"pin.{q.part.name}_{q.var.name}", q.var),
                              _value(output_lvalue(q), q.var), strict=True):  # fmt: skip
                emit(f"        {lv} = {rv};")
    emit(f"        {_PLANT}_step(t, &pp, &ps, {pin});")
    emit(f"        for (i = 0; i < {system.sizes['x']}; ++i) {{")
    emit("            if (!isfinite(((const double *)(const void *)&ps.x)[i])) {")
    emit("                finite = 0;")
    emit("            }")
    emit("        }")
    emit("        if (!finite) {")
    emit("            done = k + 1;")
    emit(f"            *status = {STATUS_NONFINITE};")
    emit("            break;")
    emit("        }")
    emit("    }")
    D.extend(transfer("out"))
    emit("    ctx = saved;")
    emit("    free(w);")
    emit("    return done;")
    emit("}")
    # inside acdn_run the parameters and chains are the heap block's members
    names = ["pp"] + [f"c_{m.chain.name}" for m in models]
    pattern = re.compile(r"(?<![\w.>])(" + "|".join(map(re.escape, names)) + r")\b(?=[.)]|,|;|$)")
    D[run_start:] = [line if "*w = calloc" in line else pattern.sub(r"w->\1", line)
                     for line in D[run_start:]]  # fmt: skip
    hook = ["/* the native loop records each sample after the modulators (acdrive.sim._native) */",
            "void acdn_after_modulate(const void *state);",
            "#define ACD_AFTER_MODULATE(t, s) acdn_after_modulate((const void *)(s))", ""]  # fmt: skip
    return NativeSource(
        controller_header=ctl.header if ctl else "",
        controller_source=ctl.source if ctl else "",
        plant_header=plant.header,
        plant_source="\n".join(hook) + plant.source,
        driver="\n".join(D) + "\n",
    )


@dataclass
class NativeLoop:
    """A loaded native library: ``run`` as ``CompiledSystem.run`` calls its loops."""

    path: Path
    library: object

    def run(self, P, PO, X, S, Y, t0, T_s, n_sub, n_steps, log_every, idx, LOG, ELOG, ECOUNT):
        """Run in place; returns (samples done, status). ``P``, ``PO``: the packed parameters
        (``System.pack_params``), with the table lengths the library was generated for."""
        f = self.library.acdn_run
        status = np.zeros(1, dtype=np.int64)
        scratch = np.zeros(max(Y.size, 1))
        E = np.zeros(max(ECOUNT.shape[0], 1), dtype=np.int64)
        if not all(a.flags.c_contiguous and a.dtype == np.float64 for a in (X, S, Y)):
            raise ValueError(
                "the packed arrays X, S, Y must be contiguous float64 (updated in place)"
            )
        ptr = ctypes.c_void_p
        P, PO = np.ascontiguousarray(P, dtype=float), np.ascontiguousarray(PO, dtype=np.int64)
        done = f(ptr(P.ctypes.data), ptr(PO.ctypes.data),
                 ptr(X.ctypes.data), ptr(S.ctypes.data), ptr(Y.ctypes.data), ctypes.c_double(t0),
                 ctypes.c_double(T_s), ctypes.c_int64(n_sub), ctypes.c_int64(n_steps),
                 ctypes.c_int64(log_every), ptr(idx.ctypes.data), ctypes.c_int64(idx.size),
                 ptr(LOG.ctypes.data), ptr(ELOG.ctypes.data), ptr(ECOUNT.ctypes.data),
                 ptr(scratch.ctypes.data), ptr(E.ctypes.data), ptr(status.ctypes.data))  # fmt: skip
        if int(status[0]) == STATUS_NO_MEMORY:
            raise MemoryError("the native loop could not allocate its parameters and chains")
        return int(done), int(status[0])


def _configure(library) -> None:
    f = library.acdn_run
    f.restype = ctypes.c_int64
    p = ctypes.c_void_p
    f.argtypes = [p, p, p, p, p, ctypes.c_double, ctypes.c_double, ctypes.c_int64, ctypes.c_int64,
                  ctypes.c_int64, p, ctypes.c_int64, p, p, p, p, p, p]  # fmt: skip


def library_path(source: NativeSource, folder: Path | None = None) -> Path:
    """Where the library of ``source`` is kept (``folder``: default the cache's)."""
    return (folder or _folder()) / f"acdn_{source.key}.so"


def build(
    source: NativeSource, notice=None, folder: Path | None = None
) -> tuple[NativeLoop, float, bool]:
    """(loaded library, seconds spent, compiled now) of ``source``: loaded from the cache folder
    (``folder``: default the cache's), or compiled into it first. ``notice(message)`` receives
    the one-line notices (a damaged library rebuilt)."""
    start = time.perf_counter()
    path = library_path(source, folder)
    compiled = False
    if path.exists():
        try:
            library = ctypes.CDLL(str(path))
            _configure(library)
            return NativeLoop(path, library), time.perf_counter() - start, False
        except (OSError, AttributeError) as error:
            if notice is not None:
                notice(f"the native library {path.name} could not be loaded ({error}); built again")
            path.unlink(missing_ok=True)
    try:
        _compile(source, path)
    except RuntimeError:  # a damaged kept object is removed by the failed link: once more
        _compile(source, path)
    compiled = True
    library = ctypes.CDLL(str(path))
    _configure(library)
    return NativeLoop(path, library), time.perf_counter() - start, compiled


def _run_compiler(command: list[str], what: str) -> None:
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        first = (done.stderr.strip().splitlines() or ["(no message)"])[0]
        raise RuntimeError(f"{command[0]} could not compile {what}: {first}")


def _compile(source: NativeSource, path: Path) -> None:
    """Compile each of the three files to an object kept beside the libraries under the hash of
    its text, its header and the flags (a new controller on a plant compiled before compiles
    only the controller and the driver), then link the library; every file is written under a
    temporary name and renamed into place, so an interrupted build leaves none half-written."""
    cc = compiler_command()
    if cc is None:
        raise InputError("compiler", "no C compiler found (cc, gcc, $CC or the ziglang package): "
                         "the native tier needs one")  # fmt: skip
    object_flags = [f for f in NATIVE_CFLAGS if f != "-shared"]
    units = [(f"{_PLANT}.c", source.plant_source, source.plant_header)]
    if source.controller_source:
        units.append((f"{_CTL}.c", source.controller_source, source.controller_header))
    units.append(("acdn_driver.c", source.driver, source.plant_header + source.controller_header))
    with tempfile.TemporaryDirectory(prefix="acdrive-native-", dir=path.parent) as scratch:
        folder = Path(scratch)
        (folder / f"{_PLANT}.h").write_text(source.plant_header)
        if source.controller_source:
            (folder / f"{_CTL}.h").write_text(source.controller_header)
        objects = []
        for name, text, headers in units:
            digest = hashlib.sha256("\0".join([*object_flags, text, headers]).encode())
            obj = path.parent / f"{Path(name).stem}_{digest.hexdigest()[:24]}.o"
            if not obj.exists():
                (folder / name).write_text(text)
                built = folder / f"{name}.o"
                _run_compiler([*cc, *object_flags, "-c", "-o", str(built), str(folder / name)],
                              name)  # fmt: skip
                os.replace(built, obj)
            objects.append(obj)
        out = folder / "library.so"
        try:
            _run_compiler([*cc, "-shared", "-o", str(out), *map(str, objects), "-lm"], "the link")
        except RuntimeError:
            # a kept object that does not link (damaged): none of them is trusted again
            for obj in objects:
                obj.unlink(missing_ok=True)
            raise
        os.replace(out, path)
