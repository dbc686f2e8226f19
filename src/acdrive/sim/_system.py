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
   a segment is split further at every point of a continuous part's profile inside it (a load
   step, a ramp's corner), and the stages of a step that ends on such a point read the profile
   just before it: a load step at t_L acts from t_L on, whether or not t_L is a sample instant,
   while a sampled part reading a profile at t_k = t_L sees the value after the step;
6. a state that stops being finite stops the run with the time at which it happened.

Every slot is derived from the parts' declarations (``core._signals``); a wiring mistake (unknown
port, output to output, kind or unit mismatch, an input wired twice or not at all, an algebraic
loop) is an ``InputError`` at construction naming both ends. ``System.compile`` generates the loop
for this topology (``sim._loop_source``), cached on disk (``sim._codegen``). The compiled system offers ``run``,
``run_batch`` (a leading batch axis over variants, on all cores), the held-input right-hand side
``derivatives`` and the pieces of one sample (``sample_instant``, ``record``, ``integrate``); the
slow path uses those, as the linearisation does (``sim._compiled``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acdrive.core._parts import ContinuousPart, Modulator, Part, Port, SampledPart
from acdrive.errors import InputError
from acdrive.sim._compiled import CompiledSystem
from acdrive.sim._integrators import INTEGRATORS
from acdrive.sim._loop_source import loop_source


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

    def source(self) -> str:
        """The generated module of this topology (``sim._loop_source``)."""
        return loop_source(self)

    def topology(self) -> tuple:
        """What ``source()`` is a function of: the integrator, each part's kind and name in
        order (a kind fixes its kernels and its layouts, hence every slot) and each input's
        source. Systems of equal topologies run in the same generated loop; a batch groups its
        variants by it without generating each variant's source."""
        wiring = tuple(sorted((dst, (src.part.name, src.var.name))
                              for dst, src in self.source_of.items()))  # fmt: skip
        return (self.method, tuple((type(p), p.name) for p in self.parts), wiring)

    def compile(self) -> CompiledSystem:
        """The compiled system, its loop compiled or loaded now (``sim._tier`` chooses the
        native or numba's specialised loop; the seconds it took are reported by the first run)."""
        return CompiledSystem(self)

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
