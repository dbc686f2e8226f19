"""The generic loop: one compiled loop, compiled once per installation, that runs any topology
from tables (part order, slots, wire copies) and calls the part-kind kernels (``sim._kernels``)
through their addresses.

It is the same sampled-data loop as the specialised one (``sim._loop_source``; steps in
``sim._system``), statement for statement and with the same compile flags per piece, so it gives
the same numbers; it only does not inline the kernels nor know the offsets in advance, which costs
time per step and saves the compile of each new topology.

Tables (int64): ``SLOT[i] = (x0, x1, s0, s1, u0, u1, y0, y1)`` of part i; ``PROJECT``,
``STATE_OUT`` rows ``(part, address)``; ``DIRECT``, ``RHS``, ``SAMPLED``, ``MODS`` rows ``(part,
address, c0, c1, address of the fast variant)`` whose inputs are the copies ``COPY[c0:c1]`` of
``(U index, Y index)`` pairs made just before the call; ``BREAKS`` rows ``(part, first table
slot, tables)`` of the continuous parts with profiles (``sim._loop_source.advance_lines``);
``SIZES = (N_W, MAX_SEG, MAX_W, method)``.
"""

from __future__ import annotations

import numpy as np
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic

from acdrive._jit import FAST_MATH_FLAGS
from acdrive.core._tables import NO_BREAK, tables_next_time
from acdrive.sim._borrow import borrowed
from acdrive.sim._integrators import RK6_A, RK6_B, RK6_C
from acdrive.sim._kernels import ROLES
from acdrive.sim._loop_source import STATUS_NONFINITE, STATUS_OK

FAST = set(FAST_MATH_FLAGS)


def _function_from_address(signature):
    """An intrinsic turning a kernel's native address (int64) into a callable of ``signature``
    (numba's first-class function value, called with numba's own calling convention)."""
    function_type = types.FunctionType(signature)

    @intrinsic
    def make(typingctx, address):
        def codegen(context, builder, sig, args):
            value = cgutils.create_struct_proxy(function_type)(context, builder)
            pointer = builder.inttoptr(args[0], cgutils.voidptr_t)
            value.c_addr = pointer
            value.jit_addr = pointer
            value.py_addr = cgutils.get_null_value(cgutils.voidptr_t)
            return value._getvalue()

        return function_type(address), codegen

    return make


_state_outputs = _function_from_address(ROLES["state_outputs"][1])
_direct_outputs = _function_from_address(ROLES["direct_outputs"][1])
_rhs = _function_from_address(ROLES["rhs"][1])
_project = _function_from_address(ROLES["project"][1])
_step = _function_from_address(ROLES["step"][1])
_segments = _function_from_address(ROLES["segments"][1])

_RK6_A = np.zeros((len(RK6_B), len(RK6_B)))
for _i, _row in enumerate(RK6_A):
    _RK6_A[_i, : len(_row)] = _row
_RK6_B = np.array(RK6_B)
_RK6_C = np.array(RK6_C)

_plant = njit(cache=True, error_model="numpy", _nrt=False)
_plant_fast = njit(cache=True, error_model="numpy", fastmath=FAST, _nrt=False)
_strict = njit(cache=True, error_model="numpy")


@_plant
def _copies(COPY, c0, c1, Y, U):
    for c in range(c0, c1):
        U[COPY[c, 0]] = Y[COPY[c, 1]]


@_plant
def project(X, P, PO, SLOT, PROJECT):
    for r in range(PROJECT.shape[0]):
        i = PROJECT[r, 0]
        _project(PROJECT[r, 1])(X[SLOT[i, 0] : SLOT[i, 1]], P[PO[i] : PO[i + 1]])


@_plant
def plant_outputs(t, X, P, PO, Y, U, SLOT, STATE_OUT, DIRECT, COPY, column):
    """The plant's outputs at ``t``; ``column`` 1 calls the kernels' strict variants (the sample
    instant), 4 the fast-math ones (inside the integrator's stages)."""
    for r in range(STATE_OUT.shape[0]):
        i = STATE_OUT[r, 0]
        _state_outputs(STATE_OUT[r, column])(
            t, X[SLOT[i, 0] : SLOT[i, 1]], P[PO[i] : PO[i + 1]], Y[SLOT[i, 6] : SLOT[i, 7]]
        )
    for r in range(DIRECT.shape[0]):
        i = DIRECT[r, 0]
        _copies(COPY, DIRECT[r, 2], DIRECT[r, 3], Y, U)
        _direct_outputs(DIRECT[r, column])(
            t, X[SLOT[i, 0] : SLOT[i, 1]], U[SLOT[i, 4] : SLOT[i, 5]], P[PO[i] : PO[i + 1]],
            Y[SLOT[i, 6] : SLOT[i, 7]],
        )  # fmt: skip


@_plant_fast
def derivatives(t, X, P, PO, Y, U, dX, SLOT, STATE_OUT, DIRECT, RHS, COPY):
    plant_outputs(t, X, P, PO, Y, U, SLOT, STATE_OUT, DIRECT, COPY, 4)
    for r in range(RHS.shape[0]):
        i = RHS[r, 0]
        _copies(COPY, RHS[r, 2], RHS[r, 3], Y, U)
        _rhs(RHS[r, 1])(
            t, X[SLOT[i, 0] : SLOT[i, 1]], U[SLOT[i, 4] : SLOT[i, 5]], P[PO[i] : PO[i + 1]],
            Y[SLOT[i, 6] : SLOT[i, 7]], dX[SLOT[i, 0] : SLOT[i, 1]],
        )  # fmt: skip


@_plant_fast
def plant_step(t, X, h, cap, P, PO, Y, U, W, SLOT, STATE_OUT, DIRECT, RHS, COPY, method, RA, RB,
               RC):  # fmt: skip
    """One step of the integrator with the inputs held and the stage times capped at ``cap``,
    written as ``sim._loop_source``'s ``step_body`` writes it (RK4 literally; RK6 with its zero
    coefficients skipped)."""
    n_x = X.shape[0]
    if method == 0:
        k1, k2, k3, k4, xt = W[0], W[1], W[2], W[3], W[4]
        derivatives(min(t, cap), X, P, PO, Y, U, k1, SLOT, STATE_OUT, DIRECT, RHS, COPY)
        for i in range(n_x):
            xt[i] = X[i] + 0.5 * h * k1[i]
        derivatives(min(t + 0.5 * h, cap), xt, P, PO, Y, U, k2, SLOT, STATE_OUT, DIRECT, RHS,
                    COPY)  # fmt: skip
        for i in range(n_x):
            xt[i] = X[i] + 0.5 * h * k2[i]
        derivatives(min(t + 0.5 * h, cap), xt, P, PO, Y, U, k3, SLOT, STATE_OUT, DIRECT, RHS,
                    COPY)  # fmt: skip
        for i in range(n_x):
            xt[i] = X[i] + h * k3[i]
        derivatives(min(t + h, cap), xt, P, PO, Y, U, k4, SLOT, STATE_OUT, DIRECT, RHS, COPY)
        for i in range(n_x):
            X[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        return
    stages = RB.shape[0]
    xt = W[stages]
    derivatives(min(t, cap), X, P, PO, Y, U, W[0], SLOT, STATE_OUT, DIRECT, RHS, COPY)
    for s in range(1, stages):
        for i in range(n_x):
            acc = 0.0
            first = True
            for j in range(s):
                if RA[s, j] != 0.0:
                    if first:
                        acc = RA[s, j] * W[j, i]
                        first = False
                    else:
                        acc = acc + RA[s, j] * W[j, i]
            xt[i] = X[i] + h * acc
        derivatives(min(t + RC[s] * h, cap), xt, P, PO, Y, U, W[s], SLOT, STATE_OUT, DIRECT,
                    RHS, COPY)  # fmt: skip
    for i in range(n_x):
        acc = 0.0
        first = True
        for j in range(stages):
            if RB[j] != 0.0:
                if first:
                    acc = RB[j] * W[j, i]
                    first = False
                else:
                    acc = acc + RB[j] * W[j, i]
        X[i] += h * acc


@_plant
def next_break(t, P, PO, BREAKS):
    """The first point of a continuous part's profile later than t (``NO_BREAK`` if none)."""
    earliest = NO_BREAK
    for r in range(BREAKS.shape[0]):
        i = BREAKS[r, 0]
        later = tables_next_time(P[PO[i] : PO[i + 1]], BREAKS[r, 1], BREAKS[r, 2], t)
        if later < earliest:
            earliest = later
    return earliest


@_plant
def advance(a, span, n_sub, X, P, PO, Y, U, W, SLOT, STATE_OUT, DIRECT, RHS, COPY, BREAKS,
            method, RA, RB, RC):  # fmt: skip
    """n_sub steps over [a, a + span], split at the profiles' points inside it (as
    ``sim._loop_source.advance_lines`` writes ``advance``)."""
    nb = next_break(a, P, PO, BREAKS)
    while nb < a + span:
        end = a + span
        h = (nb - a) / n_sub
        cap = np.nextafter(nb, -NO_BREAK)
        for j in range(n_sub):
            plant_step(a + j * h, X, h, cap, P, PO, Y, U, W, SLOT, STATE_OUT, DIRECT, RHS, COPY,
                       method, RA, RB, RC)  # fmt: skip
        a, span = nb, end - nb
        nb = next_break(a, P, PO, BREAKS)
    h = span / n_sub
    cap = np.nextafter(nb, -NO_BREAK) if nb < NO_BREAK else NO_BREAK
    for j in range(n_sub):
        plant_step(a + j * h, X, h, cap, P, PO, Y, U, W, SLOT, STATE_OUT, DIRECT, RHS, COPY,
                   method, RA, RB, RC)  # fmt: skip


@_strict
def sample(t, T_s, P, PO, S, Y, U, E, DT, V, NSEG, SLOT, SAMPLED, MODS, COPY):
    """The sampled parts in wiring order, then each modulator's segments (its first segment's
    values become its held outputs)."""
    n_sampled = SAMPLED.shape[0]
    for r in range(n_sampled):
        i = SAMPLED[r, 0]
        _copies(COPY, SAMPLED[r, 2], SAMPLED[r, 3], Y, U)
        E[r] = _step(SAMPLED[r, 1])(
            t, T_s, U[SLOT[i, 4] : SLOT[i, 5]], P[PO[i] : PO[i + 1]], S[SLOT[i, 2] : SLOT[i, 3]],
            Y[SLOT[i, 6] : SLOT[i, 7]],
        )  # fmt: skip
    for m in range(MODS.shape[0]):
        i = MODS[m, 0]
        _copies(COPY, MODS[m, 2], MODS[m, 3], Y, U)
        NSEG[m], E[n_sampled + m] = _segments(MODS[m, 1])(
            T_s, U[SLOT[i, 4] : SLOT[i, 5]], P[PO[i] : PO[i + 1]], S[SLOT[i, 2] : SLOT[i, 3]],
            DT[m], V[m],
        )  # fmt: skip
        for k in range(SLOT[i, 7] - SLOT[i, 6]):
            Y[SLOT[i, 6] + k] = V[m, 0, k]


@_plant
def integrate(t, T_s, n_sub, X, P, PO, Y, U, W, DT, V, NSEG, IDX, LEFT, SLOT, STATE_OUT, DIRECT,
              RHS, MODS, COPY, BREAKS, method, RA, RB, RC):  # fmt: skip
    """The plant over the sample: ``n_sub`` steps per segment of the merged modulator segments
    (as ``sim._loop_source`` writes ``integrate``)."""
    n_mod = MODS.shape[0]
    if n_mod == 0:
        advance(t, T_s, n_sub, X, P, PO, Y, U, W, SLOT, STATE_OUT, DIRECT, RHS, COPY, BREAKS,
                method, RA, RB, RC)  # fmt: skip
        return
    index, left = IDX, LEFT
    for m in range(n_mod):
        index[m] = 0
        left[m] = DT[m, 0] if NSEG[m] > 0 else np.inf
    tk = t
    while True:
        for m in range(n_mod):
            if index[m] < NSEG[m]:
                i = MODS[m, 0]
                for k in range(SLOT[i, 7] - SLOT[i, 6]):
                    Y[SLOT[i, 6] + k] = V[m, index[m], k]
        span = np.inf
        for m in range(n_mod):
            if left[m] < span:  # noqa: PLR1730 - as sim._loop_source writes it
                span = left[m]
        if span == np.inf:
            break
        if span > 0.0:
            advance(tk, span, n_sub, X, P, PO, Y, U, W, SLOT, STATE_OUT, DIRECT, RHS, COPY,
                    BREAKS, method, RA, RB, RC)  # fmt: skip
            tk += span
        for m in range(n_mod):
            left[m] -= span
            if left[m] <= 1e-12 * T_s:
                index[m] += 1
                left[m] = DT[m, index[m]] if index[m] < NSEG[m] else np.inf


@_plant
def record(k, log_every, Y, E, LOG_IDX, LOG, ELOG, ECOUNT):
    """Count the event bits of sample k; log the selected outputs every log_every samples."""
    n_events = E.shape[0]
    for i in range(n_events):
        bits = E[i]
        b = 0
        while bits:
            if bits & 1:
                ECOUNT[i, b] += 1
            bits >>= 1
            b += 1
    if k % log_every == 0:
        row = k // log_every
        for j in range(LOG_IDX.shape[0]):
            LOG[row, j] = Y[LOG_IDX[j]]
        for i in range(n_events):
            ELOG[row, i] = E[i]


@_strict
def run(X, P, PO, S, Y, U, t0, T_s, n_sub, n_steps, log_every, LOG_IDX, LOG, ELOG, ECOUNT,
        SLOT, PROJECT, STATE_OUT, DIRECT, RHS, SAMPLED, MODS, COPY, BREAKS, SIZES):  # fmt: skip
    """Run n_steps samples in place; returns (samples done, status). ``SIZES = (N_W, MAX_SEG,
    MAX_W, method)``."""
    n_x = X.shape[0]
    n_w, max_seg, max_w, method = SIZES[0], SIZES[1], SIZES[2], SIZES[3]
    n_mod = max(MODS.shape[0], 1)
    RA, RB, RC = _RK6_A, _RK6_B, _RK6_C
    W_owner = np.empty((n_w, n_x))
    DT_owner = np.zeros((n_mod, max_seg))
    V_owner = np.zeros((n_mod, max_seg, max_w))
    NSEG = np.zeros(n_mod, dtype=np.int64)
    E = np.zeros(SAMPLED.shape[0] + MODS.shape[0], dtype=np.int64)
    IDX = np.zeros(n_mod, dtype=np.int64)
    LEFT = np.zeros(n_mod)
    Xb, Pb, Sb, Yb, Ub = borrowed(X), borrowed(P), borrowed(S), borrowed(Y), borrowed(U)
    W, DT, V = borrowed(W_owner), borrowed(DT_owner), borrowed(V_owner)
    done, status = n_steps, STATUS_OK
    for k in range(n_steps):
        t = t0 + k * T_s
        project(Xb, Pb, PO, SLOT, PROJECT)
        plant_outputs(t, Xb, Pb, PO, Yb, Ub, SLOT, STATE_OUT, DIRECT, COPY, 1)
        sample(t, T_s, Pb, PO, Sb, Yb, Ub, E, DT, V, NSEG, SLOT, SAMPLED, MODS, COPY)
        record(k, log_every, Yb, E, LOG_IDX, LOG, ELOG, ECOUNT)
        integrate(t, T_s, n_sub, Xb, Pb, PO, Yb, Ub, W, DT, V, NSEG, IDX, LEFT, SLOT, STATE_OUT,
                  DIRECT, RHS, MODS, COPY, BREAKS, method, RA, RB, RC)  # fmt: skip
        finite = True
        for i in range(n_x):
            if not np.isfinite(Xb[i]):
                finite = False
        if not finite:
            done, status = k + 1, STATUS_NONFINITE
            break
    W_owner[:] = 0.0
    DT_owner[:] = 0.0
    V_owner[:] = 0.0
    return done, status
