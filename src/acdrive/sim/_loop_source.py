"""The generated source of a system's compiled loop: every slot offset a literal taken from the
parts' declarations, the kernels imported by name and inlined (the steps are listed in
``sim._system``'s docstring). ``sim._codegen`` caches and loads the module this text becomes.
"""

from __future__ import annotations

from acdrive._jit import FAST_MATH_SOURCE
from acdrive.core._parts import Part
from acdrive.sim._codegen import (
    INLINED_KERNEL_IMPORTS,
    inlined_kernel,
    kernel_fingerprint,
    kernel_import,
)
from acdrive.sim._integrators import INTEGRATORS
from acdrive.sim._rk_source import NUMBA, step_lines

#: the status codes ``run`` returns (mirrored by the generated source)
STATUS_OK, STATUS_NONFINITE = 0, 1


def copy_pairs(system, part: Part, only=None, skip=()) -> list[tuple[int, int]]:
    """(slot in U, slot in Y) of every value copied into ``part``'s inputs (those in ``only``, if
    given, and not in ``skip``) from the outputs wired to them, in declaration order."""
    pairs = []
    base = system.slots[part.name].u[0]
    for v in part.INPUTS:
        if (only is not None and v.name not in only) or v.name in skip:
            continue
        src = system.source_of[(part.name, v.name)]
        d = base + part.INPUTS.slot(v.name)
        s = system.output_slot(src)
        pairs += [(d + i, s + i) for i in range(v.width)]
    return pairs


def input_copies(system, part: Part, only=None, skip=(), lane="") -> list[str]:
    """Generated statements copying ``part``'s inputs (``copy_pairs``); ``lane`` (e.g. ``", v"``)
    is appended to every index (the lockstep loop's arrays have a trailing axis over variants,
    ``sim._lockstep_source``)."""
    return [f"U[{d}{lane}] = Y[{s}{lane}]" for d, s in copy_pairs(system, part, only, skip)]


def profile_parts(system) -> list[tuple[int, Part]]:
    """(index, part) of every continuous part with profile tables: the profiles the integrator's
    stages read between two samples, whose points split the integration (``advance_lines``)."""
    return [(i, p) for i, p in enumerate(system.parts)
            if p in system.continuous and p.PARAMS.tables]  # fmt: skip


def advance_lines(system, params, po: str = "PO") -> list[str]:
    """``next_break`` and ``advance``, the integration of the plant over one span with the
    inputs held. A profile of a continuous part (a load step, a supply's ramp) changes where it
    has a point; ``advance`` splits the span at every such point inside it, so no step of the
    integrator straddles one, and caps every stage time of a piece just below the point that
    ends it (``cap``): the last stage of a step ending on a load step reads the load before it,
    whatever the rounding of its time, and the first stage of the next piece, at the point
    itself, the load after it (``core._tables.table_at``). Without a point inside or at the end
    of the span the cap is never reached and the steps are those of an unsplit span.
    ``params(i)``: the generated slice of part i's parameters; ``po``: the argument
    ``plant_step`` takes for the parameter offsets."""
    L = ["@_jit_plant_into_run", "def next_break(t, P, PO):",
         '    """The first point of a continuous part\'s profile later than t (NO_BREAK if none)."""',
         "    earliest = NO_BREAK"]  # fmt: skip
    for i, part in profile_parts(system):
        L += [f"    later = tables_next_time({params(i)}, {part.PARAMS.table_start}, "
              f"{len(part.PARAMS.tables)}, t)",
              "    if later < earliest:", "        earliest = later"]  # fmt: skip
    L += ["    return earliest", ""]
    L += ["@_jit_plant_into_run  # not fast-math: NO_BREAK is compared and nextafter called",
          "def advance(a, span, n_sub, X, P, PO, Y, U, W):",
          '    """n_sub steps over [a, a + span], split at the profiles\' points inside it."""',
          "    nb = next_break(a, P, PO)",
          "    while nb < a + span:",
          "        end = a + span",
          "        h = (nb - a) / n_sub",
          "        cap = np.nextafter(nb, -NO_BREAK)",
          "        for j in range(n_sub):",
          f"            plant_step(a + j * h, X, h, cap, P, {po}, Y, U, W)",
          "        a, span = nb, end - nb",
          "        nb = next_break(a, P, PO)",
          "    h = span / n_sub",
          "    cap = np.nextafter(nb, -NO_BREAK) if nb < NO_BREAK else NO_BREAK",
          "    for j in range(n_sub):",
          f"        plant_step(a + j * h, X, h, cap, P, {po}, Y, U, W)",
          ""]  # fmt: skip
    return L


def step_body(method: str, lanes: bool = False) -> list[str]:
    """Body of ``plant_step(t, X, h, cap, ...)``: one step of ``system.method`` with the inputs
    held, every stage time capped at ``cap`` (``advance_lines``); ``W`` holds the stage
    derivatives and, in its last row, the stage state. ``lanes``: every array has a
    trailing axis over variants, run by an innermost loop over ``LANES`` (``sim._lockstep_source``)."""
    lines = step_lines(method, NUMBA)
    if not lanes:
        return lines
    out = []
    for line in lines:
        if line.strip() == "for i in range(N_X):":
            out += [line, "        for v in range(LANES):"]
        elif line.startswith("        "):  # the statement of a loop over the states
            out.append("    " + line.replace("[i]", "[i, v]").replace(", i]", ", i, v]"))
        else:
            out.append(line)
    return out


def kernel_header(
    system, generator: str, one_point: frozenset[str] = frozenset()
) -> tuple[list[str], dict]:
    """The generated module's first lines (docstring naming ``generator``, the fingerprints of
    kernels from outside acdrive, the imports, each kernel re-jitted for numba-IR inlining with
    acdrive's elementary functions, and without the table search for the parts named in
    ``one_point``, ``sim._one_point``) and the alias of every (part name, kernel role)."""
    imports, aliases, fingerprints = [], {}, set()
    for k, part in enumerate(system.parts):
        for role, fn in part.kernels().items():
            if fn is None:
                raise TypeError(f"{type(part).__name__} has no {role} kernel")
            alias = f"k{k}_{role}"
            aliases[(part.name, role)] = alias
            imports.append(kernel_import(fn, alias))
            fingerprint = kernel_fingerprint(fn)
            if fingerprint:
                fingerprints.add(f"# kernels of {fn.py_func.__module__}: {fingerprint}")

    L: list[str] = []
    emit = L.append
    emit(f'"""Generated by {generator} for one topology; do not edit."""')
    L.extend(sorted(fingerprints))  # an edit of a kernel outside acdrive gives a new source
    emit("import numpy as np")
    emit("from numba import njit, prange")
    emit("from acdrive.sim._borrow import borrowed")
    emit("from acdrive.core._tables import NO_BREAK, tables_next_time")
    L.extend(sorted(set(imports)))
    L.extend(INLINED_KERNEL_IMPORTS)
    if one_point:
        emit("from acdrive.sim._one_point import ONE_POINT")
    # Kernels are inlined (numba IR inlining) into one function per piece of the sample.
    emit("")
    for (name, _role), alias in sorted(aliases.items(), key=lambda item: item[1]):
        emit(inlined_kernel(alias, alias, *(("ONE_POINT",) if name in one_point else ())))
    emit("")
    return L, aliases


def loop_source(system) -> str:
    """The generated module of this topology (every offset a literal from the declarations)."""
    L, aliases = kernel_header(system, "acdrive.sim._loop_source")
    emit = L.append
    index = {p.name: i for i, p in enumerate(system.parts)}

    def sl(part, key):
        if key == "p":  # runtime offsets: table lengths do not change the generated code
            i = index[part.name]
            return f"PO[{i}]:PO[{i + 1}]"
        a, b = getattr(system.slots[part.name], key)
        return f"{a}:{b}"

    emit('_jit = njit(cache=True, error_model="numpy")')
    # The plant side (outputs, right-hand side, integrator) is fast-math like jit_fast, and
    # runs without numba's reference counting (_nrt=False): the array view it takes per part
    # and per evaluation then costs nothing (it was a third of the loop's time for two motors).
    # Plant kernels and modulators therefore must not allocate arrays; sampled parts may.
    emit("# plant side: fast-math, no reference counting (sim._loop_source)")
    emit('_jit_plant = njit(cache=True, error_model="numpy", _nrt=False)')
    emit(
        f'_jit_plant_fast = njit(cache=True, error_model="numpy", fastmath={FAST_MATH_SOURCE}, _nrt=False)'
    )
    # LLVM-level inlining (numba's forceinline): the right-hand side goes into each stage of
    # the step and the step into the segment loop without a call and its ~40 array-field
    # arguments per call; unlike numba-level inlining it adds little compile time
    emit(
        f'_jit_plant_fast_inline = njit(cache=True, error_model="numpy", fastmath={FAST_MATH_SOURCE}, _nrt=False, forceinline=True)'
    )
    emit('_jit_inline = njit(cache=True, error_model="numpy", inline="always")')
    emit('_jit_into_run = njit(cache=True, error_model="numpy", forceinline=True)')
    emit(
        '_jit_plant_into_run = njit(cache=True, error_model="numpy", _nrt=False, forceinline=True)'
    )
    emit(
        f'_jit_fast_inline = njit(cache=True, error_model="numpy", fastmath={FAST_MATH_SOURCE}, inline="always")'
    )
    emit(
        f"N_X, N_S, N_U, N_Y = {system.sizes['x']}, {system.sizes['s']}, {system.sizes['u']}, {system.sizes['y']}"
    )
    n_mod = len(system.modulators)
    max_seg = max([m.MAX_SEGMENTS for m in system.modulators], default=1)
    max_w = max([m.OUTPUTS.size() for m in system.modulators], default=1)
    emit(f"N_EVENTS = {len(system.sampled) + n_mod}")
    emit(f"N_W = {INTEGRATORS[system.method][1] + 1}  # rows of the integrator's scratch W")
    emit(f"N_MOD, MAX_SEG, MAX_W = {max(n_mod, 1)}, {max_seg}, {max(max_w, 1)}")
    emit("")
    # project
    emit("@_jit_plant_into_run")
    emit("def project(X, P, PO):")
    body = [
        f"    {aliases[(p.name, 'project')]}(X[{sl(p, 'x')}], P[{sl(p, 'p')}])"
        for p in system.continuous
        if (p.name, "project") in aliases
    ]
    L.extend(body or ["    pass"])
    emit("")
    # plant outputs
    emit("@_jit_fast_inline")
    emit("def plant_outputs(t, X, P, PO, Y, U):")
    body = []
    for p in system.continuous:
        body.append(
            f"    {aliases[(p.name, 'state_outputs')]}(t, X[{sl(p, 'x')}], P[{sl(p, 'p')}], Y[{sl(p, 'y')}])"
        )
    for p in system.direct:
        body += ["    " + c for c in input_copies(system, p, only=p.DIRECT_FROM)]
        body.append(
            f"    {aliases[(p.name, 'direct_outputs')]}(t, X[{sl(p, 'x')}], U[{sl(p, 'u')}], P[{sl(p, 'p')}], Y[{sl(p, 'y')}])"
        )
    L.extend(body or ["    pass"])
    emit("")
    # derivatives
    emit("@_jit_plant_fast_inline")
    emit("def derivatives(t, X, P, PO, Y, U, dX):")
    emit("    plant_outputs(t, X, P, PO, Y, U)")
    for p in system.continuous:
        # inputs a direct part reads were copied by plant_outputs, after their sources
        copied = p.DIRECT_FROM if p in system.direct else ()
        L.extend("    " + c for c in input_copies(system, p, skip=copied))
        emit(
            f"    {aliases[(p.name, 'rhs')]}(t, X[{sl(p, 'x')}], U[{sl(p, 'u')}], P[{sl(p, 'p')}], Y[{sl(p, 'y')}], dX[{sl(p, 'x')}])"
        )
    emit("")
    emit("@_jit_plant_fast_inline")
    emit("def plant_step(t, X, h, cap, P, PO, Y, U, W):")
    L.extend(step_body(system.method))
    emit("")
    L.extend(advance_lines(system, lambda i: f"P[PO[{i}]:PO[{i + 1}]]"))
    # sampled parts and modulators: one function per sampled part (its input copies and its
    # step), so the slow path can run a Python step in place of any one of them
    for i, p in enumerate(system.sampled):
        emit("@_jit_inline")
        emit(f"def inputs_{i}(Y, U):")
        L.extend(["    " + c for c in input_copies(system, p)] or ["    pass"])
        emit("")
        emit("@_jit_inline")
        emit(f"def sample_{i}(t, T_s, P, PO, S, Y, U):")
        emit(f"    inputs_{i}(Y, U)")
        emit(
            f"    return {aliases[(p.name, 'step')]}(t, T_s, U[{sl(p, 'u')}], P[{sl(p, 'p')}], S[{sl(p, 's')}], Y[{sl(p, 'y')}])"
        )
        emit("")
    emit("@_jit_inline")
    emit("def modulate(T_s, P, PO, S, Y, U, E, DT, V, NSEG):")
    body = []
    for m, p in enumerate(system.modulators):
        a, b = system.slots[p.name].y
        body += ["    " + c for c in input_copies(system, p)]
        body.append(
            f"    NSEG[{m}], E[{len(system.sampled) + m}] = {aliases[(p.name, 'segments')]}(T_s, U[{sl(p, 'u')}], P[{sl(p, 'p')}], S[{sl(p, 's')}], DT[{m}], V[{m}])"
        )
        body += [f"    Y[{a + i}] = V[{m}, 0, {i}]" for i in range(b - a)]
    L.extend(body or ["    pass"])
    emit("")
    emit("@_jit_into_run")
    emit("def sample(t, T_s, P, PO, S, Y, U, E, DT, V, NSEG):")
    body = [f"    E[{i}] = sample_{i}(t, T_s, P, PO, S, Y, U)" for i in range(len(system.sampled))]
    body.append("    modulate(T_s, P, PO, S, Y, U, E, DT, V, NSEG)")
    L.extend(body)
    emit("")
    # integration over merged segments
    emit("@_jit_plant_into_run")  # not fast-math: it compares with np.inf
    emit("def integrate(t, T_s, n_sub, X, P, PO, Y, U, W, DT, V, NSEG, IDX, LEFT):")
    if not system.modulators:
        emit("    advance(t, T_s, n_sub, X, P, PO, Y, U, W)")
    else:
        emit("    index, left = IDX, LEFT  # scratch from the caller: no allocation per sample")
        emit("    for m in range(N_MOD):")
        emit("        index[m] = 0")
        emit("        left[m] = DT[m, 0] if NSEG[m] > 0 else np.inf")
        emit("    tk = t")
        emit("    while True:")
        for m, p in enumerate(system.modulators):
            a, b = system.slots[p.name].y
            emit(f"        if index[{m}] < NSEG[{m}]:")
            for i in range(b - a):
                emit(f"            Y[{a + i}] = V[{m}, index[{m}], {i}]")
        emit("        span = np.inf")
        emit("        for m in range(N_MOD):")
        emit("            if left[m] < span:")
        emit("                span = left[m]")
        emit("        if span == np.inf:")
        emit("            break")
        emit("        if span > 0.0:")
        emit("            advance(tk, span, n_sub, X, P, PO, Y, U, W)")
        emit("            tk += span")
        emit("        for m in range(N_MOD):")
        emit("            left[m] -= span")
        emit("            if left[m] <= 1e-12 * T_s:")
        emit("                index[m] += 1")
        emit("                left[m] = DT[m, index[m]] if index[m] < NSEG[m] else np.inf")
    emit("")
    emit("@_jit_into_run")
    emit("def sample_instant(t, T_s, X, P, PO, S, Y, U, E, DT, V, NSEG):")
    emit(
        '    """At t_k: project, read the plant with held inputs, run sampled parts and modulators."""'
    )
    emit("    project(X, P, PO)")
    emit("    plant_outputs(t, X, P, PO, Y, U)")
    emit("    sample(t, T_s, P, PO, S, Y, U, E, DT, V, NSEG)")
    emit("")
    emit("@_jit_plant_into_run")
    emit("def record(k, log_every, Y, E, LOG_IDX, LOG, ELOG, ECOUNT):")
    emit(
        '    """Count the event bits of sample k; log the selected outputs every log_every samples."""'
    )
    emit("    for i in range(N_EVENTS):")
    emit("        bits = E[i]")
    emit("        b = 0")
    emit("        while bits:")
    emit("            if bits & 1:")
    emit("                ECOUNT[i, b] += 1")
    emit("            bits >>= 1")
    emit("            b += 1")
    emit("    if k % log_every == 0:")
    emit("        row = k // log_every")
    emit("        for j in range(LOG_IDX.shape[0]):")
    emit("            LOG[row, j] = Y[LOG_IDX[j]]")
    emit("        for i in range(N_EVENTS):")
    emit("            ELOG[row, i] = E[i]")
    emit("")
    emit("@_jit")
    emit(
        "def run(X, P, PO, S, Y, U, t0, T_s, n_sub, n_steps, log_every, LOG_IDX, LOG, ELOG, ECOUNT):"
    )
    emit('    """Run n_steps samples in place; returns (samples done, status)."""')
    emit("    W_owner = np.empty((N_W, N_X))")
    emit("    DT_owner = np.zeros((N_MOD, MAX_SEG))")
    emit("    V_owner = np.zeros((N_MOD, MAX_SEG, MAX_W))")
    emit("    NSEG = np.zeros(N_MOD, dtype=np.int64)")
    emit("    E = np.zeros(N_EVENTS, dtype=np.int64)")
    emit("    IDX = np.zeros(N_MOD, dtype=np.int64)")
    emit("    LEFT = np.zeros(N_MOD)")
    emit("    # borrowed views (sim._borrow): the per-part slices below cost no reference counting")
    emit("    Xb, Pb, Sb, Yb, Ub = borrowed(X), borrowed(P), borrowed(S), borrowed(Y), borrowed(U)")
    emit("    W, DT, V = borrowed(W_owner), borrowed(DT_owner), borrowed(V_owner)")
    emit("    done, status = n_steps, " + str(STATUS_OK))
    emit("    for k in range(n_steps):")
    emit("        t = t0 + k * T_s")
    emit("        sample_instant(t, T_s, Xb, Pb, PO, Sb, Yb, Ub, E, DT, V, NSEG)")
    emit("        record(k, log_every, Yb, E, LOG_IDX, LOG, ELOG, ECOUNT)")
    emit("        integrate(t, T_s, n_sub, Xb, Pb, PO, Yb, Ub, W, DT, V, NSEG, IDX, LEFT)")
    emit("        finite = True")
    emit("        for i in range(N_X):")
    emit("            if not np.isfinite(Xb[i]):")
    emit("                finite = False")
    emit("        if not finite:")
    emit(f"            done, status = k + 1, {STATUS_NONFINITE}")
    emit("            break")
    emit("    # the owners of the borrowed scratch arrays stay alive until here")
    emit("    W_owner[:] = 0.0")
    emit("    DT_owner[:] = 0.0")
    emit("    V_owner[:] = 0.0")
    emit("    return done, status")
    emit("")
    emit('@njit(cache=True, parallel=True, error_model="numpy")')
    emit(
        "def run_batch(X, P, PO, S, Y, U, t0, T_s, n_sub, n_steps, log_every, LOG_IDX, LOG, ELOG, ECOUNT, DONE, STATUS):"
    )
    emit("    for b in prange(X.shape[0]):")
    emit(
        "        DONE[b], STATUS[b] = run(X[b], P[b], PO, S[b], Y[b], U[b], t0, T_s, n_sub, n_steps, log_every, LOG_IDX, LOG[b], ELOG[b], ECOUNT[b])"
    )
    return "\n".join(L) + "\n"
