"""Software in the loop: the generated C compiled with the system's C compiler, loaded with
ctypes, and run in acdrive's loop in place of the compiled sampled parts.

Per sample t_k the loop calls the compiled system's pieces, as its own ``run`` does (sim._system,
steps 1-5): ``project`` and ``plant_outputs`` (the plant's outputs at t_k with the held inputs),
then, where ``run`` calls each sampled part's kernel, each chain's ``<chain>_step`` of the C
library (its inputs copied from the output vector Y, every part's held outputs copied back into
Y, its event bits into E), then ``modulate``, ``record`` and ``integrate``. The plant, the
modulators and the log are acdrive's own; only the controller is the C one.
"""

from __future__ import annotations

import ctypes
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from acdrive._arguments import (
    COUNT,
    FLAG,
    PATH,
    POSITIVE,
    REAL,
    Function,
    Instance,
    Items,
    Table,
    Text,
    checked,
    optional,
)
from acdrive.errors import InputError
from acdrive.sim._ccode._c_source import GUARD_MACRO, CExport, ChainModel, Member

#: gcc flags of the library: -ffp-contract=off keeps every product and sum rounded on its own
#: (no fused multiply-add), as numba compiles the kernels (no ``contract`` among
#: ``acdrive._jit.FAST_MATH_FLAGS``)
CFLAGS = ("-std=c99", "-O2", "-ffp-contract=off", "-fPIC", "-shared")


def find_compiler(name: str = "gcc", purpose: str = "running the exported C in the loop") -> str:
    path = shutil.which(name)
    if path is None:
        raise InputError("compiler", f"{name} was not found on PATH: {purpose} needs it")
    return path


def build_library(export: CExport, folder: Path, real: str = "double",
                  guard: bool = False) -> Path:  # fmt: skip
    """Write the export into ``folder`` and compile it into a shared library (``real``:
    "double" or "float", the latter with -DACDRIVE_FLOAT; ``guard``: with the input guard,
    -DACDRIVE_GUARD_INPUTS)."""
    if real not in ("double", "float"):
        raise InputError("real", 'must be "double" or "float"')
    compiler = find_compiler()
    folder = Path(folder)
    (folder / export.header_name).write_text(export.header)
    (folder / export.source_name).write_text(export.source)
    library = folder / f"lib{export.name}_{real}{'_guarded' if guard else ''}.so"
    flags = [*CFLAGS, *(["-DACDRIVE_FLOAT"] if real == "float" else []),
             *([f"-D{GUARD_MACRO}"] if guard else [])]  # fmt: skip
    done = subprocess.run(
        [compiler, *flags, "-o", str(library), str(folder / export.source_name), "-lm"],
        capture_output=True,
        text=True,
        check=False,
    )
    if done.returncode != 0:
        first = (done.stderr.strip().splitlines() or ["(no message)"])[0]
        raise InputError("compiler", f"{compiler} could not compile {export.source_name}: {first}")
    return library


def _ctype(member: Member, real, types: dict):
    spec = member.spec
    if spec == "real":
        return real
    if spec == "complex":
        return types["acd_complex"]
    if spec == "uint32":
        return ctypes.c_uint32
    if spec[0] == "table":
        n = spec[1]
        return _structure(f"table_{n}", [("n", ctypes.c_int), ("t", real * n), ("v", real * n)])
    if spec[0] == "table2d":
        nx, ny = spec[1], spec[2]
        return _structure(f"table2d_{nx}_{ny}", [("nx", ctypes.c_int), ("ny", ctypes.c_int),
                                                 ("x", real * nx), ("y", real * ny),
                                                 ("v", real * (nx * ny))])  # fmt: skip
    return types[spec[1]]


def _structure(name: str, fields):
    return type(name, (ctypes.Structure,), {"_fields_": fields})


def ctypes_mirror(export: CExport, real: str = "double", guard: bool = False) -> dict:
    """ctypes classes of every struct of the export, by C type name, from the same model the
    C text was generated from (``guard``: the state structs of a build with the input guard)."""
    c_real = ctypes.c_double if real == "double" else ctypes.c_float
    types: dict = {"acd_complex": _structure("acd_complex", [("re", c_real), ("im", c_real)])}
    for entry in export.kinds.values():
        for role, members in entry.members.items():
            if members:
                name = f"acd_{entry.cname}_{role}"
                fields = [(m.name, _ctype(m, c_real, types)) for m in members]
                types[name] = _structure(name, fields)
    for model in export.chains:
        c = model.chain.name
        for role, members in (("params", model.params), ("inputs", model.inputs),
                              ("state", model.state), ("outputs", model.outputs)):  # fmt: skip
            if not members:
                continue
            fields = [(m.name, _ctype(m, c_real, types)) for m in members]
            if role == "state" and guard:  # after the inputs' struct (the header's order)
                fields += [("last_finite", types[f"{c}_inputs"]),
                           ("input_faults", ctypes.c_uint32)]  # fmt: skip
            types[f"{c}_{role}"] = _structure(f"{c}_{role}", fields)
    return types


@dataclass
class _LoadedChain:
    model: ChainModel
    step: object
    params: object
    state: object
    inputs: object
    outputs: object
    reads: list  # (inputs field, Y slot, width)
    writes: list  # (state field of a part's outputs, output name, Y slot, width)
    events: list  # (index in E, outputs field or None)


def _load(export: CExport, library: Path, real: str, system,
          guard: bool = False) -> list[_LoadedChain]:  # fmt: skip
    lib = ctypes.CDLL(str(library))
    types = ctypes_mirror(export, real, guard)
    c_real = ctypes.c_double if real == "double" else ctypes.c_float
    index = {p.name: i for i, p in enumerate(system.sampled)}
    loaded = []
    for model in export.chains:
        c = model.chain.name
        P, S, IN = (types[f"{c}_{r}"] for r in ("params", "state", "inputs"))
        OUT = types[f"{c}_outputs"] if model.outputs else None
        step = getattr(lib, f"{c}_step")
        step.argtypes = [c_real, *(ctypes.POINTER(t) for t in (P, S, IN, OUT) if t is not None)]
        step.restype = None
        params, state = P(), S()
        getattr(lib, f"{c}_set_params")(ctypes.byref(params))
        getattr(lib, f"{c}_reset")(ctypes.byref(state))
        reads = [(f"{port.part.name}_{port.var.name}", system.output_slot(port), port.var.width)
                 for port in model.chain.inputs]  # fmt: skip
        writes = []
        for part in model.chain.parts:
            for port in part.out:
                writes.append((f"{part.name}_out", port.var.name, system.output_slot(port),
                               port.var.width))  # fmt: skip
        events = [(index[p.name], f"{p.name}_events" if p.EVENTS else None)
                  for p in model.chain.parts]  # fmt: skip
        outputs = OUT() if OUT is not None else None
        loaded.append(
            _LoadedChain(model, step, params, state, IN(), outputs, reads, writes, events)
        )
    return loaded


def _copy_in(chain: _LoadedChain, Y: np.ndarray, float_inputs: bool = False) -> None:
    values = Y.astype(np.float32).astype(np.float64) if float_inputs else Y
    for name, slot, width in chain.reads:
        if width == 2:
            z = getattr(chain.inputs, name)
            z.re, z.im = values[slot], values[slot + 1]
        else:
            setattr(chain.inputs, name, values[slot])


def _copy_out(chain: _LoadedChain, Y: np.ndarray, E: np.ndarray) -> None:
    for held, name, slot, width in chain.writes:
        value = getattr(getattr(chain.state, held), name)
        if width == 2:
            Y[slot], Y[slot + 1] = value.re, value.im
        else:
            Y[slot] = value
    for i, field in chain.events:
        E[i] = getattr(chain.outputs, field) if field is not None else 0


@checked(
    compiled=Instance("acdrive.sim._compiled:CompiledSystem"), export=Instance(CExport),
    duration=POSITIVE, sample_time=POSITIVE, substeps=COUNT,
    initial=Table(Table(empty=True), empty=True, optional=True),
    held=Table(Table(empty=True), empty=True, optional=True),
    log=Items(Instance("acdrive.core._parts:Port"), optional=True), log_every=COUNT, t0=REAL,
    real=Text(("double", "float")), folder=optional(PATH), on_inputs=Function(optional=True),
    float_inputs=FLAG, guard=FLAG,
)
def run_in_loop(compiled, export: CExport, duration: float, sample_time: float,
                substeps: int = 4, initial=None, held=None, log=None, log_every: int = 1,
                t0: float = 0.0, real: str = "double", folder=None,
                on_inputs=None, float_inputs: bool = False, guard: bool = False):  # fmt: skip
    """Run ``compiled`` (a CompiledSystem) with the C chains of ``export`` in place of its
    sampled parts; returns the same result type as ``compiled.run`` with the same arguments.
    ``export`` must have been generated from ``compiled.system`` with the same ``initial``,
    ``held`` and ``sample_time`` (its ``_reset`` and ``_set_params`` give the controller's
    start). ``folder``: where the library is built (default: a temporary folder).
    ``on_inputs(chain_index, inputs)``, if given, sees each chain's inputs struct (ctypes) just
    before its step (the replay of ``acdrive export m4``); ``float_inputs`` rounds every input to
    float32 before the step (the perturbation the float bound is derived from,
    ``export._scenario.float_bound``); ``guard``: the library is built with the input guard
    (``-DACDRIVE_GUARD_INPUTS``, docs/guide/export.md)."""
    system = compiled.system
    covered = {p.name for m in export.chains for p in m.chain.parts}
    if covered != {p.name for p in system.sampled}:
        raise InputError("export", "was not generated from this system's sampled parts")
    n_steps = compiled._steps(duration, sample_time, substeps)
    columns, rows = compiled._log_setup(log, n_steps, log_every)
    module = compiled.module
    with tempfile.TemporaryDirectory(prefix="acdrive-sil-") as scratch:
        library = build_library(export, Path(folder or scratch), real, guard)
        chains = _load(export, library, real, system, guard)
        P, PO = system.pack_params()
        X, S = system.pack_initial(initial)
        Y, U = system.pack_held(held), np.zeros(system.sizes["u"])
        n_ev = len(system.event_names())
        LOG = np.zeros((rows, len(columns)))
        ELOG = np.zeros((rows, n_ev), dtype=np.int64)
        ECOUNT = np.zeros((n_ev, 64), dtype=np.int64)
        idx = np.array([c[2] for c in columns], dtype=np.int64)
        W = np.empty((int(module.N_W), system.sizes["x"]))
        DT = np.zeros((int(module.N_MOD), int(module.MAX_SEG)))
        V = np.zeros((int(module.N_MOD), int(module.MAX_SEG), int(module.MAX_W)))
        NSEG = np.zeros(int(module.N_MOD), dtype=np.int64)
        E = np.zeros(n_ev, dtype=np.int64)
        IDX = np.zeros(int(module.N_MOD), dtype=np.int64)
        LEFT = np.zeros(int(module.N_MOD))
        byref = [tuple(ctypes.byref(x) for x in (c.params, c.state, c.inputs, c.outputs)
                       if x is not None) for c in chains]  # fmt: skip
        T_s = float(sample_time)
        for k in range(n_steps):
            t = t0 + k * T_s
            module.project(X, P, PO)
            module.plant_outputs(t, X, P, PO, Y, U)
            for c, (chain, refs) in enumerate(zip(chains, byref, strict=True)):
                _copy_in(chain, Y, float_inputs)
                if on_inputs is not None:
                    on_inputs(c, chain.inputs)
                chain.step(t, *refs)
                _copy_out(chain, Y, E)
            module.modulate(T_s, P, PO, S, Y, U, E, DT, V, NSEG)
            module.record(k, log_every, Y, E, idx, LOG, ELOG, ECOUNT)
            module.integrate(t, T_s, substeps, X, P, PO, Y, U, W, DT, V, NSEG, IDX, LEFT)
            if not np.all(np.isfinite(X)):
                raise InputError("run", f"the plant state stopped being finite at t = {t:.6g} s")
    return compiled._result(t0, sample_time, log_every, rows, columns, LOG, ELOG, ECOUNT, X,
                            0.0, n_steps)  # fmt: skip


def deviation(reference, other, no_limit: float | None = None) -> dict[str, tuple[float, float]]:
    """Per logged signal: (largest |difference| over the run, peak |value| of the reference).
    ``no_limit``: samples where both runs are at or beyond it in magnitude (each holding its
    build's "no limit" stand-in, ``sim._ccode._prelude.FLOAT_NO_LIMIT`` in float, 1e300 in
    double) are left out of both; a sample where only one of them is counts as the difference it
    is."""
    out = {}
    for j, name in enumerate(reference.columns):
        a, b = reference.data[:, j], other.data[:, j]
        if no_limit is not None:
            kept = ~((np.abs(a) >= no_limit) & (np.abs(b) >= no_limit))
            a, b = a[kept], b[kept]
        if a.size == 0:
            out[name] = (0.0, 0.0)
            continue
        out[name] = (float(np.max(np.abs(a - b))), float(np.max(np.abs(a))))
    return out
