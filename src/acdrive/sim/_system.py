"""A system: parts wired output-to-input, compiled into one sampled-data loop.

Per control sample t_k = t_0 + k T_s (the structure of Bodson's bench and of every digital drive):

1. redundant plant states are re-normalised (``project`` kernels);
2. the plant outputs are evaluated at t_k with the inputs held from the previous period: the
   sensors' view of the plant;
3. the sampled parts run in wiring order (sensors, estimators, controllers), then each modulator
   turns its command into piecewise-constant segments over [t_k, t_k + T_s];
4. the selected signals are logged (every ``log_every`` samples) and the event bits counted;
5. the plant is integrated over the segments of all modulators (their boundaries merged), each
   segment by ``substeps`` explicit Runge-Kutta steps with its inputs held (``method``: the
   classical fourth-order method, or Butcher's seven-stage sixth-order one, ``INTEGRATORS``);
6. a state that stops being finite stops the run with the time at which it happened.

Every slot is derived from the parts' declarations (``core._signals``); a wiring mistake (unknown
port, output to output, kind or unit mismatch, an input wired twice or not at all, an algebraic
loop) is an ``InputError`` at construction naming both ends. ``System.compile`` generates the loop
for this topology (``sim._codegen``), cached on disk. The compiled system offers ``run``,
``run_batch`` (a leading batch axis over variants, on all cores), the held-input right-hand side
``derivatives`` and the pieces of one sample (``sample_instant``, ``record``, ``integrate``); the
slow path uses those, as the linearisation will.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from acdrive._jit import STRICT_MATH
from acdrive.core._parts import ContinuousPart, Modulator, Part, Port, SampledPart
from acdrive.errors import InputError, SimulationDiverged, call_interruptible
from acdrive.sim import _codegen as codegen
from acdrive.sim._result import SystemResult

STATUS_OK, STATUS_NONFINITE = 0, 1

#: Butcher's explicit seven-stage Runge-Kutta method of order six (J. C. Butcher, *Numerical
#: Methods for Ordinary Differential Equations*, the rational-coefficient example of section 32):
#: nodes c, coefficient rows a (stage i uses a[i][j] k_j, j < i) and weights b.
RK6_C = (0.0, 1 / 3, 2 / 3, 1 / 3, 1 / 2, 1 / 2, 1.0)
RK6_A = (
    (),
    (1 / 3,),
    (0.0, 2 / 3),
    (1 / 12, 1 / 3, -1 / 12),
    (-1 / 16, 9 / 8, -3 / 16, -3 / 8),
    (0.0, 9 / 8, -3 / 8, -3 / 4, 1 / 2),
    (9 / 44, -9 / 11, 63 / 44, 18 / 11, 0.0, -16 / 11),
)
RK6_B = (11 / 120, 0.0, 27 / 40, 27 / 40, -4 / 15, -4 / 15, 11 / 120)

#: Integration methods per held-input segment: name -> (order, right-hand-side evaluations per
#: step). ``rk4`` is the default (the DFIM results were established with it); ``rk6`` takes
#: 7/4 the work per step for two orders more, so one ``rk6`` step per segment replaces several
#: ``rk4`` substeps where the segments are short against the machine's time constants (the
#: switching inverter's) and rounds off fewer times. Caveat: ``rk6``'s stability region leaves
#: out the imaginary axis (an undamped rotation at h omega = 1 grows by 5e-4 per step, at 0.1 by
#: 6e-12), which RK4's includes up to h omega = 2.8; keep h omega of undamped modes small.
INTEGRATORS = {"rk4": (4, 4), "rk6": (6, 7)}


@dataclass(frozen=True)
class _Slots:
    """Where one part lives in the system's flat arrays: (start, stop) per array (its parameters
    are found at run time, ``System.pack_params``)."""

    x: tuple[int, int]  # continuous states (continuous parts)
    s: tuple[int, int]  # discrete states (sampled parts and modulators)
    u: tuple[int, int]
    y: tuple[int, int]


def _wire_error(src: Port, dst: Port, rule: str) -> InputError:
    return InputError(f"wire {src.path} -> {dst.path}", rule)


class System:
    """Parts and the wires between them, validated at construction.

    ``wires`` is a sequence of ``(output port, input port)`` pairs, e.g.
    ``(supply.out.v_s, machine.inp.v_s)``.
    """

    def __init__(self, parts, wires, method: str = "rk4"):
        if method not in INTEGRATORS:
            raise InputError("method", f"must be one of {', '.join(INTEGRATORS)}")
        self.method = method
        self.parts: tuple[Part, ...] = tuple(parts)
        names = [p.name for p in self.parts]
        for p in self.parts:
            if not isinstance(p, (ContinuousPart, SampledPart, Modulator)):
                raise InputError(f"{getattr(p, 'name', p)}", "is not a part")
            if names.count(p.name) > 1:
                raise InputError(p.name, "two parts have this name; names must be unique")
        self.source_of: dict[tuple[str, str], Port] = {}
        members = {id(p) for p in self.parts}
        for pair in wires:
            if not (isinstance(pair, tuple) and len(pair) == 2):
                raise InputError("wires", "each wire must be a pair (output port, input port)")
            src, dst = pair
            if not (isinstance(src, Port) and isinstance(dst, Port)):
                raise InputError("wires", f"a wire joins two ports, got {src!r} -> {dst!r}")
            if src.direction != "out" or dst.direction != "in":
                raise _wire_error(src, dst, "must go from an output to an input")
            for port in (src, dst):
                if id(port.part) not in members:
                    raise _wire_error(src, dst, f"part {port.part.name} is not in the system")
            if src.var.kind != dst.var.kind:
                raise _wire_error(src, dst, f"kind mismatch ({src.var.kind} -> {dst.var.kind})")
            if src.var.unit != dst.var.unit:
                raise _wire_error(
                    src, dst, f"unit mismatch ({src.var.unit or '-'} -> {dst.var.unit or '-'})"
                )
            key = (dst.part.name, dst.var.name)
            if key in self.source_of:
                raise _wire_error(src, dst, f"input already wired from {self.source_of[key].path}")
            self.source_of[key] = src
        for p in self.parts:
            for v in p.INPUTS:
                if (p.name, v.name) not in self.source_of:
                    raise InputError(f"{p.name}.{v.name}", "input is not wired to any output")
        self.continuous = [p for p in self.parts if isinstance(p, ContinuousPart)]
        self.modulators = [p for p in self.parts if isinstance(p, Modulator)]
        self.sampled = self._sampled_order()
        self.direct = self._direct_order()
        self._allocate()

    # --- ordering ---------------------------------------------------------------------------
    def _toposort(self, nodes, depends_on, what: str):
        order, state = [], {}

        def visit(node, chain):
            mark = state.get(node.name)
            if mark == "done":
                return
            if mark == "active":
                loop = " -> ".join([*chain, node.name])
                raise InputError("wires", f"algebraic loop among {what}: {loop}")
            state[node.name] = "active"
            for dep in depends_on(node):
                visit(dep, [*chain, node.name])
            state[node.name] = "done"
            order.append(node)

        for node in nodes:
            visit(node, [])
        return order

    def _sampled_order(self):
        sampled = [p for p in self.parts if isinstance(p, SampledPart)]

        def deps(part):
            found = []
            for v in part.INPUTS:
                src = self.source_of[(part.name, v.name)].part
                if isinstance(src, SampledPart) and src is not part:
                    found.append(src)
            return found

        return self._toposort(sampled, deps, "sampled parts")

    def _direct_order(self):
        direct = [p for p in self.continuous if p.DIRECT_OUTPUTS]

        def deps(part):
            found = []
            for name in part.DIRECT_FROM:
                src_port = self.source_of[(part.name, name)]
                src = src_port.part
                if isinstance(src, ContinuousPart) and src_port.var.name in src.DIRECT_OUTPUTS:
                    found.append(src)
            return found

        return self._toposort(direct, deps, "continuous parts with direct feedthrough")

    # --- slots ------------------------------------------------------------------------------
    def _allocate(self):
        counters = {"x": 0, "s": 0, "u": 0, "y": 0}
        self.slots: dict[str, _Slots] = {}

        def take(key, n):
            start = counters[key]
            counters[key] += n
            return start, start + n

        for part in self.parts:
            continuous = isinstance(part, ContinuousPart)
            n_state = part.STATES.size()
            self.slots[part.name] = _Slots(
                x=take("x", n_state if continuous else 0),
                s=take("s", 0 if continuous else n_state),
                u=take("u", part.INPUTS.size()),
                y=take("y", part.OUTPUTS.size()),
            )
        self.sizes = dict(counters)

    def output_slot(self, port: Port) -> int:
        return self.slots[port.part.name].y[0] + port.part.OUTPUTS.slot(port.var.name)

    def _copies(self, part: Part, only=None, skip=()) -> list[str]:
        """Generated statements copying ``part``'s inputs (those in ``only``, if given, and not in
        ``skip``) from the outputs wired to them."""
        lines = []
        base = self.slots[part.name].u[0]
        for v in part.INPUTS:
            if (only is not None and v.name not in only) or v.name in skip:
                continue
            src = self.source_of[(part.name, v.name)]
            d = base + part.INPUTS.slot(v.name)
            s = self.output_slot(src)
            for i in range(v.width):
                lines.append(f"U[{d + i}] = Y[{s + i}]")
        return lines

    # --- code generation --------------------------------------------------------------------
    def _step_body(self) -> list[str]:
        """Body of ``plant_step``: one step of ``self.method`` with the inputs held; ``W`` holds
        the stage derivatives and, in its last row, the stage state."""
        if self.method == "rk4":  # written out: the DFIM results' rounding is this sequence
            return [
                "    k1, k2, k3, k4, xt = W[0], W[1], W[2], W[3], W[4]",
                "    derivatives(t, X, P, PO, Y, U, k1)",
                "    for i in range(N_X):",
                "        xt[i] = X[i] + 0.5 * h * k1[i]",
                "    derivatives(t + 0.5 * h, xt, P, PO, Y, U, k2)",
                "    for i in range(N_X):",
                "        xt[i] = X[i] + 0.5 * h * k2[i]",
                "    derivatives(t + 0.5 * h, xt, P, PO, Y, U, k3)",
                "    for i in range(N_X):",
                "        xt[i] = X[i] + h * k3[i]",
                "    derivatives(t + h, xt, P, PO, Y, U, k4)",
                "    for i in range(N_X):",
                "        X[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])",
            ]
        stages = len(RK6_B)
        lines = [f"    xt = W[{stages}]"]

        def combination(weights):
            return " + ".join(f"{w!r} * W[{j}, i]" for j, w in enumerate(weights) if w != 0.0)

        for i in range(stages):
            if i == 0:
                lines.append("    derivatives(t, X, P, PO, Y, U, W[0])")
                continue
            lines.append("    for i in range(N_X):")
            lines.append(f"        xt[i] = X[i] + h * ({combination(RK6_A[i])})")
            lines.append(f"    derivatives(t + {RK6_C[i]!r} * h, xt, P, PO, Y, U, W[{i}])")
        lines.append("    for i in range(N_X):")
        lines.append(f"        X[i] += h * ({combination(RK6_B)})")
        return lines

    def source(self) -> str:
        """The generated module of this topology (every offset a literal from the declarations)."""
        imports, aliases, fingerprints = [], {}, set()
        for k, part in enumerate(self.parts):
            for role, fn in part.kernels().items():
                if fn is None:
                    raise TypeError(f"{type(part).__name__} has no {role} kernel")
                alias = f"k{k}_{role}"
                aliases[(part.name, role)] = alias
                imports.append(codegen.kernel_import(fn, alias))
                fingerprint = codegen.kernel_fingerprint(fn)
                if fingerprint:
                    fingerprints.add(f"# kernels of {fn.py_func.__module__}: {fingerprint}")

        index = {p.name: i for i, p in enumerate(self.parts)}

        def sl(part, key):
            if key == "p":  # runtime offsets: table lengths do not change the generated code
                i = index[part.name]
                return f"PO[{i}]:PO[{i + 1}]"
            a, b = getattr(self.slots[part.name], key)
            return f"{a}:{b}"

        L: list[str] = []
        emit = L.append
        emit('"""Generated by acdrive.sim._system for one topology; do not edit."""')
        L.extend(sorted(fingerprints))  # an edit of a kernel outside acdrive gives a new source
        emit("import numpy as np")
        emit("from numba import njit, prange")
        emit("from acdrive.sim._borrow import borrowed")
        L.extend(sorted(set(imports)))
        # Kernels are inlined (numba IR inlining) into one function per piece of the sample.
        emit("")
        for alias in sorted(set(aliases.values())):
            emit(f'{alias} = njit(inline="always", error_model="numpy")({alias}.py_func)')
        emit("")
        emit('_jit = njit(cache=True, error_model="numpy")')
        # The plant side (outputs, right-hand side, integrator) is fast-math like jit_fast, and
        # runs without numba's reference counting (_nrt=False): the array view it takes per part
        # and per evaluation then costs nothing (it was a third of the loop's time for two motors).
        # Plant kernels and modulators therefore must not allocate arrays; sampled parts may.
        emit("# plant side: fast-math, no reference counting (sim.System.source)")
        emit('_jit_plant = njit(cache=True, error_model="numpy", _nrt=False)')
        emit(
            f'_jit_plant_fast = njit(cache=True, error_model="numpy", fastmath={not STRICT_MATH}, _nrt=False)'
        )
        # LLVM-level inlining (numba's forceinline): the right-hand side goes into each stage of
        # the step and the step into the segment loop without a call and its ~40 array-field
        # arguments per call; unlike numba-level inlining it adds little compile time
        emit(
            f'_jit_plant_fast_inline = njit(cache=True, error_model="numpy", fastmath={not STRICT_MATH}, _nrt=False, forceinline=True)'
        )
        emit('_jit_inline = njit(cache=True, error_model="numpy", inline="always")')
        emit('_jit_into_run = njit(cache=True, error_model="numpy", forceinline=True)')
        emit(
            '_jit_plant_into_run = njit(cache=True, error_model="numpy", _nrt=False, forceinline=True)'
        )
        emit(
            f'_jit_fast_inline = njit(cache=True, error_model="numpy", fastmath={not STRICT_MATH}, inline="always")'
        )
        emit(
            f"N_X, N_S, N_U, N_Y = {self.sizes['x']}, {self.sizes['s']}, {self.sizes['u']}, {self.sizes['y']}"
        )
        n_mod = len(self.modulators)
        max_seg = max([m.MAX_SEGMENTS for m in self.modulators], default=1)
        max_w = max([m.OUTPUTS.size() for m in self.modulators], default=1)
        emit(f"N_EVENTS = {len(self.sampled) + n_mod}")
        emit(f"N_W = {INTEGRATORS[self.method][1] + 1}  # rows of the integrator's scratch W")
        emit(f"N_MOD, MAX_SEG, MAX_W = {max(n_mod, 1)}, {max_seg}, {max(max_w, 1)}")
        emit("")
        # project
        emit("@_jit_plant_into_run")
        emit("def project(X, P, PO):")
        body = [
            f"    {aliases[(p.name, 'project')]}(X[{sl(p, 'x')}], P[{sl(p, 'p')}])"
            for p in self.continuous
            if (p.name, "project") in aliases
        ]
        L.extend(body or ["    pass"])
        emit("")
        # plant outputs
        emit("@_jit_fast_inline")
        emit("def plant_outputs(t, X, P, PO, Y, U):")
        body = []
        for p in self.continuous:
            body.append(
                f"    {aliases[(p.name, 'state_outputs')]}(t, X[{sl(p, 'x')}], P[{sl(p, 'p')}], Y[{sl(p, 'y')}])"
            )
        for p in self.direct:
            body += ["    " + c for c in self._copies(p, only=p.DIRECT_FROM)]
            body.append(
                f"    {aliases[(p.name, 'direct_outputs')]}(t, X[{sl(p, 'x')}], U[{sl(p, 'u')}], P[{sl(p, 'p')}], Y[{sl(p, 'y')}])"
            )
        L.extend(body or ["    pass"])
        emit("")
        # derivatives
        emit("@_jit_plant_fast_inline")
        emit("def derivatives(t, X, P, PO, Y, U, dX):")
        emit("    plant_outputs(t, X, P, PO, Y, U)")
        for p in self.continuous:
            # inputs a direct part reads were copied by plant_outputs, after their sources
            copied = p.DIRECT_FROM if p in self.direct else ()
            L.extend("    " + c for c in self._copies(p, skip=copied))
            emit(
                f"    {aliases[(p.name, 'rhs')]}(t, X[{sl(p, 'x')}], U[{sl(p, 'u')}], P[{sl(p, 'p')}], Y[{sl(p, 'y')}], dX[{sl(p, 'x')}])"
            )
        emit("")
        emit("@_jit_plant_fast_inline")
        emit("def plant_step(t, X, h, P, PO, Y, U, W):")
        L.extend(self._step_body())
        emit("")
        # sampled parts and modulators: one function per sampled part (its input copies and its
        # step), so the slow path can run a Python step in place of any one of them
        for i, p in enumerate(self.sampled):
            emit("@_jit_inline")
            emit(f"def inputs_{i}(Y, U):")
            L.extend(["    " + c for c in self._copies(p)] or ["    pass"])
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
        for m, p in enumerate(self.modulators):
            a, b = self.slots[p.name].y
            body += ["    " + c for c in self._copies(p)]
            body.append(
                f"    NSEG[{m}], E[{len(self.sampled) + m}] = {aliases[(p.name, 'segments')]}(T_s, U[{sl(p, 'u')}], P[{sl(p, 'p')}], S[{sl(p, 's')}], DT[{m}], V[{m}])"
            )
            body += [f"    Y[{a + i}] = V[{m}, 0, {i}]" for i in range(b - a)]
        L.extend(body or ["    pass"])
        emit("")
        emit("@_jit_into_run")
        emit("def sample(t, T_s, P, PO, S, Y, U, E, DT, V, NSEG):")
        body = [
            f"    E[{i}] = sample_{i}(t, T_s, P, PO, S, Y, U)" for i in range(len(self.sampled))
        ]
        body.append("    modulate(T_s, P, PO, S, Y, U, E, DT, V, NSEG)")
        L.extend(body)
        emit("")
        # integration over merged segments
        emit("@_jit_plant_into_run")  # not fast-math: it compares with np.inf
        emit("def integrate(t, T_s, n_sub, X, P, PO, Y, U, W, DT, V, NSEG, IDX, LEFT):")
        if not self.modulators:
            emit("    h = T_s / n_sub")
            emit("    for j in range(n_sub):")
            emit("        plant_step(t + j * h, X, h, P, PO, Y, U, W)")
        else:
            emit("    index, left = IDX, LEFT  # scratch from the caller: no allocation per sample")
            emit("    for m in range(N_MOD):")
            emit("        index[m] = 0")
            emit("        left[m] = DT[m, 0] if NSEG[m] > 0 else np.inf")
            emit("    tk = t")
            emit("    while True:")
            for m, p in enumerate(self.modulators):
                a, b = self.slots[p.name].y
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
            emit("            h = span / n_sub")
            emit("            for j in range(n_sub):")
            emit("                plant_step(tk + j * h, X, h, P, PO, Y, U, W)")
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
        emit(
            "    # borrowed views (sim._borrow): the per-part slices below cost no reference counting"
        )
        emit(
            "    Xb, Pb, Sb, Yb, Ub = borrowed(X), borrowed(P), borrowed(S), borrowed(Y), borrowed(U)"
        )
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

    def compile(self) -> CompiledSystem:
        return CompiledSystem(self, codegen.load_module(self.source()))

    # --- arrays -----------------------------------------------------------------------------
    def part(self, name: str) -> Part:
        for p in self.parts:
            if p.name == name:
                return p
        raise InputError(name, f"no part of this name ({', '.join(q.name for q in self.parts)})")

    def pack_params(self, parts=None) -> tuple[np.ndarray, np.ndarray]:
        """(P, PO): every part's parameters in one array, part i's in ``P[PO[i]:PO[i + 1]]``.

        ``parts`` lists re-parametrised copies (``part.with_params``) that replace the parts of
        the same name; their tables may have other lengths (the offsets are run-time values).
        """
        chosen = {p.name: p for p in self.parts}
        for p in parts or ():
            if p.name not in chosen or type(p) is not type(chosen[p.name]):
                raise InputError(p.name, "replaces no part of the same name and kind")
            chosen[p.name] = p
        arrays = [chosen[p.name].p for p in self.parts]
        PO = np.zeros(len(arrays) + 1, dtype=np.int64)
        PO[1:] = np.cumsum([a.size for a in arrays])
        P = np.concatenate(arrays) if arrays else np.zeros(0)
        return P, PO

    def pack_initial(self, initial: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(X, S) from each part's ``INITIAL`` defaults and ``initial[part name] = {state: value}``."""
        initial = dict(initial or {})
        X, S = np.zeros(self.sizes["x"]), np.zeros(self.sizes["s"])
        for p in self.parts:
            values = initial.pop(p.name, {})
            packed = p.initial_state(**values)
            key = "x" if isinstance(p, ContinuousPart) else "s"
            a, b = getattr(self.slots[p.name], key)
            (X if key == "x" else S)[a:b] = packed
        if initial:
            raise InputError(f"initial.{next(iter(initial))}", "no part of this name")
        return X, S

    def pack_held(self, held: dict | None = None) -> np.ndarray:
        """The output vector Y before the first sample: each sampled part's and modulator's
        ``held_outputs()``, then ``held[part name] = {output: value}``; zero elsewhere."""
        held = dict(held or {})
        Y = np.zeros(self.sizes["y"])
        for p in self.parts:
            values = {**p.held_outputs(), **held.pop(p.name, {})}
            if not values:
                continue
            if isinstance(p, ContinuousPart):
                raise InputError(f"held.{p.name}", "only sampled parts and modulators hold outputs")
            a, b = self.slots[p.name].y
            merged = {v.name: 0.0 for v in p.OUTPUTS}
            merged.update(values)
            Y[a:b] = p.OUTPUTS.pack(f"held.{p.name}", merged)
        if held:
            raise InputError(f"held.{next(iter(held))}", "no part of this name")
        return Y

    def log_columns(self, ports=None) -> list[tuple[str, str, int]]:
        """(column name, unit, slot in Y) of the logged outputs (all outputs if ``ports`` is None)."""
        out = []
        chosen = ports if ports is not None else [port for p in self.parts for port in p.out]
        for port in chosen:
            if not isinstance(port, Port) or port.direction != "out":
                raise InputError("log", f"must list output ports, got {port!r}")
            base = self.output_slot(port)
            if port.var.kind == "complex":
                out += [
                    (f"{port.path}.re", port.var.unit, base),
                    (f"{port.path}.im", port.var.unit, base + 1),
                ]
            else:
                out.append((port.path, port.var.unit, base))
        return out

    def log_descriptions(self, columns) -> dict[str, str]:
        """Column name -> the declaring part's one-line description of that output (``columns``
        from :meth:`log_columns`)."""
        docs = {}
        for p in self.parts:
            for port in p.out:
                docs[port.path] = port.var.doc
                docs[f"{port.path}.re"] = f"{port.var.doc} (real part)"
                docs[f"{port.path}.im"] = f"{port.var.doc} (imaginary part)"
        return {name: docs.get(name, name) for name, _, _ in columns}

    def event_names(self) -> list[tuple[str, tuple[str, ...]]]:
        return [(p.name, p.EVENTS) for p in (*self.sampled, *self.modulators)]


#: Size bounds of one run (also applied by the scenario loader): substeps per segment, memory
#: for the logs, and RK4 steps (samples x substeps x variants; about 2 us each: half an hour).
MAX_SUBSTEPS = 1000
LOG_BUDGET_BYTES = 2 * 1024**3
MAX_WORK = 1e9


class CompiledSystem:
    """A system with its compiled loop: run once or over a batch of variants."""

    def __init__(self, system: System, module):
        self.system = system
        self.module = module

    def _log_setup(self, log, n_steps, log_every):
        if isinstance(log_every, bool) or not isinstance(log_every, int) or log_every < 1:
            raise InputError("log_every", "must be an integer >= 1")
        if log_every > n_steps:
            raise InputError(
                "log_every", f"must not exceed the number of samples in the run ({n_steps})"
            )
        columns = self.system.log_columns(log)
        rows = n_steps // log_every + (n_steps % log_every > 0)
        return columns, rows

    def _steps(self, duration, sample_time, substeps):
        for field_name, value in (("duration", duration), ("sample_time", sample_time)):
            if (
                isinstance(value, bool)
                or not isinstance(value, (int, float))
                or not np.isfinite(value)
                or value <= 0
            ):
                raise InputError(field_name, "must be a finite number > 0")
        if (
            isinstance(substeps, bool)
            or not isinstance(substeps, int)
            or not 1 <= substeps <= MAX_SUBSTEPS
        ):
            raise InputError("substeps", f"must be an integer from 1 to {MAX_SUBSTEPS}")
        n = round(duration / sample_time)
        if n < 1:
            raise InputError("duration", "must be at least one sample time")
        for part in self.system.parts:
            part.check_run(sample_time)
        return n

    def _check_size(self, n_steps, substeps, rows, n_columns, variants=1) -> None:
        """Refuse, before anything is allocated, a run beyond the bounds of this module."""
        n_values = variants * rows * (n_columns + len(self.system.event_names()))
        if n_values * 8 > LOG_BUDGET_BYTES:
            raise InputError(
                "log_every",
                f"the log would take {n_values * 8 / 1024**3:.3g} GB (limit "
                f"{LOG_BUDGET_BYTES / 1024**3:g} GB): log fewer signals, raise log_every or split "
                "the batch",
            )
        work = float(n_steps) * substeps * variants
        if work > MAX_WORK:
            raise InputError(
                "duration",
                f"needs {work:.3g} RK4 steps per segment (limit {MAX_WORK:.0e}): shorten the run, "
                "lengthen sample_time or use fewer substeps",
            )

    def run(self, duration: float, sample_time: float, substeps: int = 4, initial=None,
            log=None, log_every: int = 1, t0: float = 0.0, parts=None,
            held=None) -> SystemResult:  # fmt: skip
        """Simulate ``duration`` seconds; ``initial[part] = {state: value}``; ``held[part] =
        {output: value}`` for the outputs of sampled parts and modulators held before the first
        sample; ``log`` lists the output ports to record (default: all); ``parts`` replaces parts
        by re-parametrised copies of the same shape (``part.with_params``)."""
        sys_ = self.system
        n_steps = self._steps(duration, sample_time, substeps)
        columns, rows = self._log_setup(log, n_steps, log_every)
        self._check_size(n_steps, substeps, rows, len(columns))
        P, PO = sys_.pack_params(parts)
        X, S = sys_.pack_initial(initial)
        Y, U = sys_.pack_held(held), np.zeros(sys_.sizes["u"])
        LOG = np.zeros((rows, len(columns)))
        n_ev = len(sys_.event_names())
        ELOG = np.zeros((rows, n_ev), dtype=np.int64)
        ECOUNT = np.zeros((n_ev, 64), dtype=np.int64)
        idx = np.array([c[2] for c in columns], dtype=np.int64)
        start = time.perf_counter()
        done, status = self.module.run(X, P, PO, S, Y, U, float(t0), float(sample_time), substeps,
                                       n_steps, log_every, idx, LOG, ELOG, ECOUNT)  # fmt: skip
        wall = time.perf_counter() - start
        if status != STATUS_OK:
            bad = [
                name
                for name, _, _ in self._state_columns()
                if not np.isfinite(X[self._state_index(name)])
            ]
            raise SimulationDiverged(
                t0 + done * sample_time,
                f"state {', '.join(bad[:3]) or '?'} not finite; use a shorter sample_time or more "
                "substeps",
            )
        return self._result(
            t0, sample_time, log_every, rows, columns, LOG, ELOG, ECOUNT, X, wall, n_steps
        )

    def _state_columns(self):
        out = []
        for p in self.system.continuous:
            a, _ = self.system.slots[p.name].x
            for name, unit, _, s in p.STATES.columns(f"{p.name}."):
                out.append((name, unit, a + s))
        return out

    def _state_index(self, name):
        for n, _, i in self._state_columns():
            if n == name:
                return i
        raise KeyError(name)

    def _result(self, t0, T_s, log_every, rows, columns, LOG, ELOG, ECOUNT, X, wall, n_steps):
        events = {}
        for i, (part, names) in enumerate(self.system.event_names()):
            events[part] = {name: int(ECOUNT[i, b]) for b, name in enumerate(names)}
        return SystemResult(
            t=t0 + np.arange(rows) * T_s * log_every,
            data=LOG,
            columns=[c[0] for c in columns],
            units={c[0]: c[1] for c in columns},
            descriptions=self.system.log_descriptions(columns),
            events=events,
            event_log=ELOG,
            final_state=X.copy(),
            wall_time=wall,
            steps=n_steps,
        )

    def run_batch(self, variants, duration, sample_time, substeps=4, initial=None, log=None,
                  log_every=1, t0=0.0, held=None) -> list[SystemResult]:  # fmt: skip
        """Run many variants at once on all cores. ``variants`` is a list of dicts
        ``{part name: {parameter: value}}``; each variant's result equals running it alone."""
        sys_ = self.system
        if not isinstance(variants, (list, tuple)):
            raise InputError(
                "variants", "must be a list of dicts {part name: {parameter: value}}, one per "
                f"variant, got {type(variants).__name__}"
            )  # fmt: skip
        for b, changes in enumerate(variants):
            if not isinstance(changes, dict) or not all(
                isinstance(params, dict) for params in changes.values()
            ):
                raise InputError(f"variants[{b}]", "must be a dict {part name: {parameter: value}}")
        n_steps = self._steps(duration, sample_time, substeps)
        columns, rows = self._log_setup(log, n_steps, log_every)
        B = len(variants)
        if B < 1:
            raise InputError("variants", "must hold at least one variant")
        self._check_size(n_steps, substeps, rows, len(columns), variants=B)
        packed = []
        for b, changes in enumerate(variants):
            parts = [sys_.part(name).with_params(**params) for name, params in changes.items()]
            packed.append(sys_.pack_params(parts))
        PO = packed[0][1]
        for b, (_, offsets) in enumerate(packed):
            if not np.array_equal(offsets, PO):
                raise InputError(
                    f"variants[{b}]", "tables of one batch must have the same number of points"
                )
        P = np.stack([params for params, _ in packed])
        X0, S0 = sys_.pack_initial(initial)
        X, S = np.tile(X0, (B, 1)), np.tile(S0, (B, 1))
        Y = np.tile(sys_.pack_held(held), (B, 1))
        LOG, ELOG, ECOUNT, DONE, STATUS, wall = self._batch_loop(
            P, PO, X, S, Y, t0, sample_time, substeps, n_steps, log_every, columns, rows
        )
        results = []
        for b in range(B):
            r = self._result(
                t0,
                sample_time,
                log_every,
                rows,
                columns,
                LOG[b],
                ELOG[b],
                ECOUNT[b],
                X[b],
                wall / B,
                n_steps,
            )
            r.extra["status"] = (
                "ok"
                if STATUS[b] == STATUS_OK
                else f"diverged at t = {t0 + DONE[b] * sample_time:.6g} s"
            )
            results.append(r)
        return results

    def run_packed(self, P, PO, X, S, Y, duration, sample_time, substeps=4, log=None,
                   log_every=None, t0=0.0):  # fmt: skip
        """The batch loop on arrays packed per variant, row b being variant b: ``P[b]`` (with the
        common offsets ``PO``), ``X[b]``, ``S[b]``, ``Y[b]`` as each variant's own system gives
        them (``pack_params``, ``pack_initial``, ``pack_held``). This is ``run_batch`` for
        variants that differ in more than parameters (initial states, held outputs, whole parts
        of the same shape); each row's result equals running that variant alone.

        ``X`` and ``S`` hold the final states on return (a sampled part that accumulates a
        metric in its state, ``acdrive.batch``, leaves it there). ``log`` lists output ports
        (default: none) logged every ``log_every`` samples (default: only the first sample, so
        nothing is kept per sample). Returns ``(LOG, ELOG, ECOUNT, DONE, STATUS, wall time)``.
        """
        n_steps = self._steps(duration, sample_time, substeps)
        log = [] if log is None else log
        log_every = n_steps if log_every is None else log_every
        columns, rows = self._log_setup(log, n_steps, log_every)
        B = X.shape[0]
        sizes = self.system.sizes
        if B < 1:
            raise InputError("variants", "must hold at least one variant")
        for name, array, width in (("X", X, sizes["x"]), ("S", S, sizes["s"]),
                                   ("Y", Y, sizes["y"]), ("P", P, int(PO[-1]))):  # fmt: skip
            if array.ndim != 2 or array.shape != (B, width) or array.dtype != np.float64:
                raise InputError(name, f"must be a float64 array of shape ({B}, {width})")
        self._check_size(n_steps, substeps, rows, len(columns), variants=B)
        PO = np.asarray(PO, dtype=np.int64)
        return self._batch_loop(
            P, PO, X, S, Y, t0, sample_time, substeps, n_steps, log_every, columns, rows
        )

    def _batch_loop(self, P, PO, X, S, Y, t0, sample_time, substeps, n_steps, log_every,
                    columns, rows):  # fmt: skip
        """The compiled batch loop over rows of packed arrays (states updated in place): the
        logs, event counts, samples done and status of every variant, and the wall time."""
        B = X.shape[0]
        U = np.zeros((B, self.system.sizes["u"]))
        n_ev = len(self.system.event_names())
        LOG = np.zeros((B, rows, len(columns)))
        ELOG = np.zeros((B, rows, n_ev), dtype=np.int64)
        ECOUNT = np.zeros((B, n_ev, 64), dtype=np.int64)
        DONE = np.zeros(B, dtype=np.int64)
        STATUS = np.zeros(B, dtype=np.int64)
        idx = np.array([c[2] for c in columns], dtype=np.int64)
        start = time.perf_counter()
        call_interruptible(self.module.run_batch, X, P, PO, S, Y, U, float(t0),
                           float(sample_time), substeps, n_steps, log_every, idx, LOG, ELOG,
                           ECOUNT, DONE, STATUS)  # fmt: skip
        return LOG, ELOG, ECOUNT, DONE, STATUS, time.perf_counter() - start

    # --- pieces for the slow path and the linearisation -------------------------------------
    def derivatives(self, t: float, X: np.ndarray, held: np.ndarray, parts=None) -> np.ndarray:
        """dX/dt with every non-plant output held at ``held`` (a Y vector): the right-hand side a
        Radau reference or a linearisation uses between two samples."""
        return self.evaluate(t, X, held, parts)[1]

    def evaluate(self, t: float, X: np.ndarray, held: np.ndarray, parts=None):
        """(Y, dX/dt): every output (plant outputs computed at ``X``, the rest as ``held``) and
        the right-hand side, at time ``t``."""
        P, PO = self.system.pack_params(parts)
        Y = np.array(held, dtype=float)
        U = np.zeros(self.system.sizes["u"])
        dX = np.empty_like(X)
        self.module.derivatives(t, X, P, PO, Y, U, dX)
        return Y, dX

    def output(self, Y: np.ndarray, port) -> complex | float:
        """The value of output ``port`` in an output vector ``Y``."""
        i = self.system.output_slot(port)
        return complex(Y[i], Y[i + 1]) if port.var.kind == "complex" else float(Y[i])
