"""The generated source of a system's lockstep batch loop: ``LANES`` variants advance together,
sample by sample, so the same generated statements run over a lane axis that the compiler can
put in SIMD registers.

Layout (structure of arrays over variants): every slot of every array of the single loop
(``sim._loop_source``: states ``X``, the integrator's scratch ``W``, outputs ``Y``, inputs
``U``, discrete states ``S``, parameters ``P``) is one row of a block workspace ``Z`` of shape
(rows, ``LANES``), row-major, so the values of one slot for the block's variants are contiguous.
Each kernel call of the single loop becomes one loop over the lanes, innermost, with the kernel
inlined (``for v in range(LANES): k(t, X[3:10, v], ...)``): where the kernel's body has no loop
and writes the same slots on every path, LLVM turns the loop into packed arithmetic; where it
has a loop (a profile table's search) the lanes run one after the other, as fast as before.
All offsets are literals, the parameter offsets too (a batch shares them), so every access is a
constant row of one array and the compiler needs no run-time aliasing checks.

What must hold for lockstep (``lockstep_refusal``): the variants share the topology, sample
time, number of samples and substeps (a batch group does), and every modulator makes exactly one
segment spanning the sample (an averaged converter). A switching modulator (the SVPWM inverter)
makes per-variant segment boundaries inside a sample, so such systems run per variant
(``run_batch`` in ``sim._loop_source``). The generated loop checks the one-segment rule at run
time too; a block that breaks it reports so and the caller reruns the batch per variant.

Agreement with the per-variant loop (itself bit-identical to a single run): bit for bit (states,
logs, event counts), in the default mode and under ``ACDRIVE_STRICT_MATH=1`` alike. Every lane
does the single loop's IEEE operations in the written order: the fast-math flags
(``acdrive._jit.FAST_MATH_FLAGS``) leave out reassociation, contraction and reciprocal
approximations, whose use depends on what surrounds an operation after inlining, and every tier
computes sin, cos, |z| and sqrt with acdrive's own arithmetic (``sim._lane_math``), which
vectorises, instead of the C library (tests/test_lockstep.py).
"""

from __future__ import annotations

import warnings

import numba
import numpy as np
from numba import carray, njit

from acdrive._jit import FAST_MATH_SOURCE
from acdrive.errors import InputError, Notice
from acdrive.sim import _codegen as codegen
from acdrive.sim._borrow import _pointer
from acdrive.sim._integrators import INTEGRATORS
from acdrive.sim._loop_source import (
    STATUS_NONFINITE,
    STATUS_OK,
    advance_lines,
    input_copies,
    kernel_header,
    profile_parts,
    step_body,
)

#: variants per block: rows of ``LANES`` doubles (320 bytes, five AVX-512 registers). Measured
#: on this machine (Zen 4, numba 0.68.1), bodson-ramp with the default reducers, one thread,
#: candidates interleaved in one process, control steps per CPU second: 16 lanes 2.19 M, 32 lanes
#: 2.26 M, 40 lanes 2.30 M, 48 lanes 2.30-2.37 M, 56 lanes 2.19 M, 64 lanes 2.00 M, 128 lanes
#: 1.47 M; after the one-point tables (``sim._one_point``) vectorised the supply and the shaft:
#: 32 lanes 2.51 M, 40 lanes 2.65 M, 48 lanes 2.57 M, 56 lanes 2.43 M, 64 lanes 2.19 M; with the
#: lane forms of sin, cos, |z| and sqrt (``sim._lane_math``, session 16's Zen 5 machine, 240
#: variants, relative to 40 lanes = 1): 32 lanes 0.92, 48 lanes 1.06-1.08, 56 lanes 0.88 (its
#: last block padded), 60 lanes 1.00, 80 lanes 1.05. Fewer lanes leave less to vectorise per
#: loop; more make the block outgrow the caches between one kernel's loop and the next. A batch
#: needs LANES variants per thread to run in lockstep.
LANES = 48


#: bytes of an AVX-512 vector: the block workspace starts at a multiple of it. numba aligns its
#: arrays to 32 bytes, so without this about half the blocks had every 512-bit load and store of
#: a lane row split over two cache lines (rows are LANES doubles, a multiple of 64 bytes); the
#: batch's speed then changed from run to run with the allocation (docs/speed.md, "The batch
#: loops").
VECTOR_BYTES = 64


@njit(cache=True, forceinline=True)
def vector_aligned(a, n):
    """The ``n`` float64 of ``a`` from its first ``VECTOR_BYTES`` boundary on (``a`` has
    ``VECTOR_BYTES // 8`` more), as an array that owns nothing (``sim._borrow``)."""
    address = a.ctypes.data
    return carray(_pointer(address + (-address) % VECTOR_BYTES), (n,), np.float64)


@njit(cache=True, forceinline=True)
def lane_view(a, shape):
    """A float64 array of ``shape`` over the memory of ``a`` that owns nothing (``sim._borrow``):
    the workspace's 2-D and 3-D views come from one address, so LLVM sees every access as a
    constant offset from one pointer."""
    return carray(_pointer(a.ctypes.data), shape, np.float64)


def lockstep_refusal(system) -> str | None:
    """Why ``system`` cannot run its variants in lockstep (None if it can)."""
    for m in system.modulators:
        if m.MAX_SEGMENTS != 1:
            return (
                f"modulator {m.name} ({type(m).__name__}) switches within a sample: its segment "
                "boundaries differ per variant"
            )
    return None


def profile_points_differ(system, P, PO) -> str | None:
    """The first continuous part whose profiles have points at other times in some row of the
    packed parameters ``P`` than in the first (None if every row has the same points): the
    integration splits at those points (``sim._loop_source.advance_lines``), so lanes stepping
    together must share them."""
    for i, part in profile_parts(system):
        offset = int(PO[i]) + part.PARAMS.table_start
        for _ in part.PARAMS.tables:
            n = P[0, offset]
            if np.any(P[:, offset] != n):
                return part.name
            times = P[:, offset + 1 : offset + 1 + int(n)]
            if np.any(times != times[0]):
                return part.name
            offset += 1 + 2 * int(n)
    return None


def one_point_parts(system, P, PO) -> frozenset[str]:
    """The parts with profile tables whose tables have one point in every row of the packed
    parameters ``P`` (offsets ``PO``): their kernels run without the table search in lockstep
    (``sim._one_point``)."""
    chosen = set()
    for i, part in enumerate(system.parts):
        tables = part.PARAMS.tables
        if not tables or P.shape[0] == 0:
            continue
        start = int(PO[i]) + part.PARAMS.fixed_size
        one_point = True
        for _ in tables:  # each one-point table is [1, t_0, v_0]: the next starts 3 slots on
            one_point = bool(np.all(P[:, start] == 1.0))
            if not one_point:
                break
            start += 3
        if one_point and start == int(PO[i + 1]):
            chosen.add(part.name)
    return frozenset(chosen)


def lockstep_plan(system, PO, variants: int, lockstep=None, P=None):
    """The compiled lockstep module to run ``variants`` rows of ``system`` in, or None for the
    per-variant loop. ``lockstep``: True requires lockstep (an ``InputError`` if the system
    cannot), False refuses it, None (the default) takes it when it pays: at least ``LANES``
    variants for every thread numba runs (fewer would leave a core idle or lanes empty).
    ``P``: the packed parameters, if known: parts whose tables have one point in every variant
    then run without the table search (``one_point_parts``)."""
    if lockstep is False:
        return None
    if lockstep not in (None, True):
        raise InputError("lockstep", f"must be None, True or False, got {lockstep!r}")
    reason = lockstep_refusal(system)
    differing = None if P is None else profile_points_differ(system, P, PO)
    if reason is None and differing is not None:
        reason = (f"the profiles of {differing} have their points at other times in some "
                  "variants (the integration splits a sample at them)")
    wide = variants >= LANES * numba.get_num_threads()
    if reason is not None:
        if lockstep:
            raise InputError("lockstep", f"this system cannot run in lockstep: {reason}")
        if wide:
            warnings.warn(Notice(f"the batch runs one variant at a time per core: {reason}"),
                          stacklevel=4)  # fmt: skip
        return None
    if lockstep is None and not wide:
        return None
    one_point = frozenset() if P is None else one_point_parts(system, P, PO)
    return codegen.load_module(lockstep_source(system, PO, one_point))


def lockstep_broken(before, states, outputs) -> None:
    """After a lockstep run that reported a modulator breaking the one-segment rule: put the
    packed ``states`` (X, S, Y) back to ``before`` and clear the ``outputs`` (logs, event
    counts), so the per-variant loop reruns the batch from the start, and say so."""
    for array, saved in zip(states, before, strict=True):
        array[...] = saved
    for array in outputs:
        array[...] = 0
    warnings.warn(
        Notice("a modulator made more than one segment in a sample: the batch reruns one "
               "variant at a time"), stacklevel=3)  # fmt: skip


def _rows(system, PO) -> dict[str, int]:
    """First row of each array in the block workspace ``Z``."""
    n_w = INTEGRATORS[system.method][1] + 1
    sizes = system.sizes
    rows, at = {}, 0
    for key, n in (("W", n_w * sizes["x"]), ("X", sizes["x"]), ("Y", sizes["y"]),
                   ("U", sizes["u"]), ("S", sizes["s"]), ("P", int(PO[-1])),
                   ("DT", max(len(system.modulators), 1)), ("FIN", 1)):  # fmt: skip
        rows[key] = at
        at += n
    rows["N"] = at
    return rows


def lockstep_source(system, PO, one_point: frozenset[str] = frozenset()) -> str:
    """The generated lockstep module of this topology and parameter layout ``PO``; the kernels
    of the parts named in ``one_point`` (every variant's tables of one point) without the table
    search (``sim._one_point``)."""
    reason = lockstep_refusal(system)
    if reason is not None:
        raise ValueError(reason)
    L, aliases = kernel_header(system, "acdrive.sim._lockstep_source", one_point)
    emit = L.append
    index = {p.name: i for i, p in enumerate(system.parts)}
    PO = [int(o) for o in PO]
    lane = ", v"

    def sl(part, key):
        if key == "p":
            i = index[part.name]
            return f"{PO[i]}:{PO[i + 1]}{lane}"
        a, b = getattr(system.slots[part.name], key)
        return f"{a}:{b}{lane}"

    def lanes(statements):
        return ["    for v in range(LANES):", *("        " + s for s in statements)]

    fast = FAST_MATH_SOURCE
    emit("from acdrive.sim._lockstep_source import LANES, VECTOR_BYTES, lane_view, vector_aligned")
    emit('_jit = njit(cache=True, error_model="numpy")')
    emit('_jit_inline = njit(cache=True, error_model="numpy", inline="always")')
    emit('_jit_into_run = njit(cache=True, error_model="numpy", forceinline=True)')
    emit(
        '_jit_plant_into_run = njit(cache=True, error_model="numpy", _nrt=False, forceinline=True)'
    )
    emit(f'_jit_plant_fast_inline = njit(cache=True, error_model="numpy", fastmath={fast}, _nrt=False, forceinline=True)')  # fmt: skip
    sizes = system.sizes
    n_mod = len(system.modulators)
    max_w = max([m.OUTPUTS.size() for m in system.modulators], default=1)
    rows = _rows(system, PO)
    emit(
        f"N_X, N_S, N_U, N_Y, N_P = {sizes['x']}, {sizes['s']}, {sizes['u']}, {sizes['y']}, {PO[-1]}"
    )
    emit(f"N_EVENTS = {len(system.sampled) + n_mod}")
    emit(f"N_W = {INTEGRATORS[system.method][1] + 1}")
    emit(f"N_MOD, MAX_W = {max(n_mod, 1)}, {max(max_w, 1)}")
    emit("# first rows of the block workspace Z (rows x LANES)")
    emit(", ".join(f"R_{k}" for k in rows) + " = " + ", ".join(str(v) for v in rows.values()))
    emit("")
    # project
    emit("@_jit_plant_into_run")
    emit("def project(X, P):")
    body = []
    for p in system.continuous:
        if (p.name, "project") in aliases:
            body += lanes([f"{aliases[(p.name, 'project')]}(X[{sl(p, 'x')}], P[{sl(p, 'p')}])"])
    L.extend(body or ["    pass"])
    emit("")
    # plant outputs: one lane loop per kernel call (with the input copies it reads)
    emit("@_jit_plant_fast_inline")
    emit("def plant_outputs(t, X, P, PO, Y, U):")
    for p in system.continuous:
        L.extend(lanes([f"{aliases[(p.name, 'state_outputs')]}(t, X[{sl(p, 'x')}], P[{sl(p, 'p')}], Y[{sl(p, 'y')}])"]))  # fmt: skip
    for p in system.direct:
        L.extend(lanes([*input_copies(system, p, only=p.DIRECT_FROM, lane=lane),
                        f"{aliases[(p.name, 'direct_outputs')]}(t, X[{sl(p, 'x')}], U[{sl(p, 'u')}], P[{sl(p, 'p')}], Y[{sl(p, 'y')}])"]))  # fmt: skip
    if not system.continuous:
        emit("    pass")
    emit("")
    emit("@_jit_plant_fast_inline")
    emit("def derivatives(t, X, P, PO, Y, U, dX):")
    emit("    plant_outputs(t, X, P, PO, Y, U)")
    for p in system.continuous:
        copied = p.DIRECT_FROM if p in system.direct else ()
        L.extend(lanes([*input_copies(system, p, skip=copied, lane=lane),
                        f"{aliases[(p.name, 'rhs')]}(t, X[{sl(p, 'x')}], U[{sl(p, 'u')}], P[{sl(p, 'p')}], Y[{sl(p, 'y')}], dX[{sl(p, 'x')}])"]))  # fmt: skip
    emit("")
    emit("@_jit_plant_fast_inline")
    emit("def plant_step(t, X, h, cap, P, PO, Y, U, W):")
    L.extend(step_body(system.method, lanes=True))
    emit("")
    # the lanes share their profiles' points (lockstep_plan): the first lane's are every lane's
    L.extend(advance_lines(system, lambda i: f"P[{PO[i]}:{PO[i + 1]}, 0]", po="0"))
    # sampled parts, then modulators (one segment each, checked)
    emit("@_jit_into_run")
    emit("def sample(t, T_s, P, S, Y, U, E, DT, V, BAD):")
    for i, p in enumerate(system.sampled):
        L.extend(lanes([*input_copies(system, p, lane=lane),
                        f"E[{i}, v] = {aliases[(p.name, 'step')]}(t, T_s, U[{sl(p, 'u')}], P[{sl(p, 'p')}], S[{sl(p, 's')}], Y[{sl(p, 'y')}])"]))  # fmt: skip
    for m, p in enumerate(system.modulators):
        a, b = system.slots[p.name].y
        L.extend(lanes([
            *input_copies(system, p, lane=lane),
            f"n, E[{len(system.sampled) + m}, v] = {aliases[(p.name, 'segments')]}(T_s, U[{sl(p, 'u')}], P[{sl(p, 'p')}], S[{sl(p, 's')}], DT[{m}:{m + 1}, v], V[{m}, :, :, v])",
            f"if n != 1 or DT[{m}, v] != T_s:",
            "    BAD[v] = 1",
            *(f"Y[{a + i}, v] = V[{m}, 0, {i}, v]" for i in range(b - a)),
        ]))  # fmt: skip
    if not system.sampled and not system.modulators:
        emit("    pass")
    emit("")
    emit("@_jit_plant_into_run")
    emit("def integrate(t, T_s, n_sub, X, P, Y, U, W):")
    emit("    advance(t, T_s, n_sub, X, P, 0, Y, U, W)  # the single loop's, one span of T_s")
    emit("")
    emit("@_jit_plant_into_run")
    emit("def not_finite(X, FIN):")
    emit('    """Per lane, whether a state is not finite (x - x is 0 only for a finite x)."""')
    emit("    for v in range(LANES):")
    emit("        FIN[v] = 0.0")
    emit("    for i in range(N_X):")
    emit("        for v in range(LANES):")
    emit("            FIN[v] += X[i, v] - X[i, v]")
    emit("")
    emit("@_jit_plant_into_run")
    emit("def record(k, log_every, b0, nb, ACTIVE, Y, E, LOG_IDX, LOG, ELOG, ECOUNT):")
    emit("    for v in range(nb):")
    emit("        if not ACTIVE[v]:")
    emit("            continue")
    emit("        b = b0 + v")
    emit("        for i in range(N_EVENTS):")
    emit("            bits = E[i, v]")
    emit("            c = 0")
    emit("            while bits:")
    emit("                if bits & 1:")
    emit("                    ECOUNT[b, i, c] += 1")
    emit("                bits >>= 1")
    emit("                c += 1")
    emit("        if k % log_every == 0:")
    emit("            row = k // log_every")
    emit("            for j in range(LOG_IDX.shape[0]):")
    emit("                LOG[b, row, j] = Y[LOG_IDX[j], v]")
    emit("            for i in range(N_EVENTS):")
    emit("                ELOG[b, row, i] = E[i, v]")
    emit("")
    emit("@_jit_plant_into_run")
    emit("def copy_out(v, b, Z, X, S, Y):")
    emit("    for i in range(N_X):")
    emit("        X[b, i] = Z[R_X + i, v]")
    emit("    for i in range(N_S):")
    emit("        S[b, i] = Z[R_S + i, v]")
    emit("    for i in range(N_Y):")
    emit("        Y[b, i] = Z[R_Y + i, v]")
    emit("")
    emit("@_jit")
    emit("def run_block(b0, nb, X, P, S, Y, t0, T_s, n_sub, n_steps, log_every, LOG_IDX, LOG, ELOG, ECOUNT, DONE, STATUS):")  # fmt: skip
    emit('    """Variants b0 .. b0 + nb - 1 in lockstep (lanes past nb repeat the last variant and')
    emit('    are dropped); returns 1 if a modulator broke the one-segment rule, else 0."""')
    emit("    Z_owner = np.zeros(R_N * LANES + VECTOR_BYTES // 8)")
    emit("    Z_flat = vector_aligned(Z_owner, R_N * LANES)  # rows start on vector boundaries")
    emit("    V_owner = np.zeros((N_MOD, 1, MAX_W, LANES))")
    emit("    E = np.zeros((N_EVENTS, LANES), dtype=np.int64)")
    emit("    BAD = np.zeros(LANES, dtype=np.int64)")
    emit("    ACTIVE = np.zeros(LANES, dtype=np.bool_)")
    emit("    for v in range(LANES):")
    emit("        b = b0 + min(v, nb - 1)")
    emit("        ACTIVE[v] = v < nb")
    emit("        for i in range(N_X):")
    emit("            Z_flat[(R_X + i) * LANES + v] = X[b, i]")
    emit("        for i in range(N_S):")
    emit("            Z_flat[(R_S + i) * LANES + v] = S[b, i]")
    emit("        for i in range(N_Y):")
    emit("            Z_flat[(R_Y + i) * LANES + v] = Y[b, i]")
    emit("        for i in range(N_P):")
    emit("            Z_flat[(R_P + i) * LANES + v] = P[b, i]")
    emit(
        "    # one address for every view of the workspace (lane_view), W first: rows 0 .. N_W N_X"
    )
    emit(
        "    Z, Wz, V = lane_view(Z_flat, (R_N, LANES)), lane_view(Z_flat, (N_W, N_X, LANES)), borrowed(V_owner)"
    )
    emit("    Xz, Yz, Uz, Sz, Pz = Z[R_X:R_X + N_X], Z[R_Y:R_Y + N_Y], Z[R_U:R_U + N_U], Z[R_S:R_S + N_S], Z[R_P:R_P + N_P]")  # fmt: skip
    emit("    DTz, FIN = Z[R_DT:R_DT + N_MOD], Z[R_FIN]")
    emit("    live = nb")
    emit("    for k in range(n_steps):")
    emit("        t = t0 + k * T_s")
    emit("        project(Xz, Pz)")
    emit("        plant_outputs(t, Xz, Pz, 0, Yz, Uz)")
    emit("        sample(t, T_s, Pz, Sz, Yz, Uz, E, DTz, V, BAD)")
    emit("        record(k, log_every, b0, nb, ACTIVE, Yz, E, LOG_IDX, LOG, ELOG, ECOUNT)")
    emit("        integrate(t, T_s, n_sub, Xz, Pz, Yz, Uz, Wz)")
    emit("        not_finite(Xz, FIN)")
    emit("        for v in range(nb):")
    emit("            if ACTIVE[v] and FIN[v] != 0.0:")
    emit("                ACTIVE[v] = False")
    emit("                live -= 1")
    emit(f"                DONE[b0 + v], STATUS[b0 + v] = k + 1, {STATUS_NONFINITE}")
    emit("                copy_out(v, b0 + v, Z, X, S, Y)")
    emit("        if live == 0:")
    emit("            break")
    emit("    for v in range(nb):")
    emit("        if ACTIVE[v]:")
    emit(f"            DONE[b0 + v], STATUS[b0 + v] = n_steps, {STATUS_OK}")
    emit("            copy_out(v, b0 + v, Z, X, S, Y)")
    emit("    bad = 0")
    emit("    for v in range(nb):")
    emit("        bad |= BAD[v]")
    emit("    # the owners of the borrowed workspace stay alive until here")
    emit("    Z_owner[0] = 0.0")
    emit("    V_owner[0, 0, 0, 0] = 0.0")
    emit("    return bad")
    emit("")
    emit('@njit(cache=True, parallel=True, error_model="numpy")')
    emit("def run(X, P, S, Y, t0, T_s, n_sub, n_steps, log_every, LOG_IDX, LOG, ELOG, ECOUNT, DONE, STATUS):")  # fmt: skip
    emit(
        '    """All rows of the packed arrays, LANES at a time on all cores; returns the number of'
    )
    emit('    blocks whose modulators broke the one-segment rule (0: every result is valid)."""')
    emit("    n_blocks = (X.shape[0] + LANES - 1) // LANES")
    emit("    bad = np.zeros(n_blocks, dtype=np.int64)")
    emit("    for blk in prange(n_blocks):")
    emit("        b0 = blk * LANES")
    emit("        nb = min(LANES, X.shape[0] - b0)")
    emit("        bad[blk] = run_block(b0, nb, X, P, S, Y, t0, T_s, n_sub, n_steps, log_every, LOG_IDX, LOG, ELOG, ECOUNT, DONE, STATUS)")  # fmt: skip
    emit("    return bad.sum()")
    return "\n".join(L) + "\n"
