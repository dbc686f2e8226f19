"""The slow path: a compiled system stepped from Python.

The sampled parts, the modulators, the log and the plant's right-hand side are the compiled
system's own pieces (``project``, ``plant_outputs``, ``sample_<i>``, ``modulate``, ``record``,
``derivatives`` and ``integrate`` of the generated module). Two things can differ from the fast
loop:

* the integrator between segment boundaries: ``method="RK4"`` is the fast loop's own
  (``integrate``, the same numbers), any ``scipy.integrate.solve_ivp`` method (Radau by default)
  at a tight tolerance is the accuracy reference: both solve the same held-input equations, so
  their difference is the fixed-step integrator's error alone;
* any sampled part may be replaced by a Python function with the signature of its compiled step,
  ``step(t, T_s, u, p, s, y) -> event bits`` (numpy arrays of the part's inputs, parameters,
  discrete states and outputs, by the part's declarations): a prototype controller runs in the
  real loop before it is compiled.

Meant for verification and prototyping, not speed.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from acdrive.errors import InputError, SimulationDiverged
from acdrive.sim._compiled import CompiledSystem
from acdrive.sim._result import SystemResult


def simulate_reference(compiled: CompiledSystem, duration: float, sample_time: float,
                       initial=None, log=None, method: str = "Radau", rtol: float = 1e-10,
                       atol: float = 1e-12, t0: float = 0.0, held=None, substeps: int = 4,
                       python_steps: dict | None = None) -> SystemResult:  # fmt: skip
    """Run ``compiled`` for ``duration`` from Python; logs every sample.

    ``method``: "RK4" (the fast loop's integrator with ``substeps``) or a ``solve_ivp`` method
    with ``rtol``/``atol``. ``python_steps[part name]`` replaces that sampled part's step.
    """
    system, m = compiled.system, compiled.module
    n_steps = compiled._steps(duration, sample_time, substeps)
    columns, rows = compiled._log_setup(log, n_steps, 1)
    P, PO = system.pack_params()
    X, S = system.pack_initial(initial)
    Y, U = system.pack_held(held), np.zeros(system.sizes["u"])
    # scratch sized by the generated module's own constants
    DT, V = np.zeros((m.N_MOD, m.MAX_SEG)), np.zeros((m.N_MOD, m.MAX_SEG, m.MAX_W))
    NSEG = np.zeros(m.N_MOD, dtype=np.int64)
    E = np.zeros(m.N_EVENTS, dtype=np.int64)
    LOG = np.zeros((rows, len(columns)))
    ELOG = np.zeros((rows, m.N_EVENTS), dtype=np.int64)
    ECOUNT = np.zeros((m.N_EVENTS, 64), dtype=np.int64)
    idx = np.array([c[2] for c in columns], dtype=np.int64)
    out_slots = [system.slots[p.name].y for p in system.modulators]
    W = np.empty((m.N_W, system.sizes["x"]))
    IDX, LEFT = np.zeros(m.N_MOD, dtype=np.int64), np.zeros(m.N_MOD)
    steps = _sampled_steps(system, m, P, PO, S, Y, U, python_steps or {})

    def rhs(t, x, cap):
        dx = np.empty_like(x)
        m.derivatives(min(t, cap), x, P, PO, Y, U, dx)
        return dx

    def breaks(t):  # the profiles' points in (t, t + sample_time)
        points, nb = [], m.next_break(t, P, PO)
        while nb < t + sample_time:
            points.append(nb)
            nb = m.next_break(nb, P, PO)
        return points, nb

    for k in range(n_steps):
        t = t0 + k * sample_time
        m.project(X, P, PO)
        m.plant_outputs(t, X, P, PO, Y, U)
        for i, step in enumerate(steps):
            E[i] = step(t, sample_time)
        m.modulate(sample_time, P, PO, S, Y, U, E, DT, V, NSEG)
        m.record(k, 1, Y, E, idx, LOG, ELOG, ECOUNT)
        if method == "RK4":
            m.integrate(t, sample_time, substeps, X, P, PO, Y, U, W, DT, V, NSEG, IDX, LEFT)
        else:
            _integrate_adaptive(t, sample_time, X, Y, DT, V, NSEG, out_slots, rhs, method, rtol,
                                atol, len(system.modulators), *breaks(t))  # fmt: skip
        if not np.all(np.isfinite(X)):
            raise SimulationDiverged(t + sample_time, "the slow-path integration diverged")
    return compiled._result(t0, sample_time, 1, rows, columns, LOG, ELOG, ECOUNT, X, 0.0, n_steps)


def _sampled_steps(system, m, P, PO, S, Y, U, python_steps: dict) -> list:
    """One callable per sampled part, in the loop's order: compiled or the user's Python step."""
    unknown = set(python_steps) - {p.name for p in system.sampled}
    if unknown:
        raise InputError(f"python_steps.{min(unknown)}", "names no sampled part of this system")
    steps = []
    for i, part in enumerate(system.sampled):
        compiled_step = getattr(m, f"sample_{i}")
        if part.name not in python_steps:
            steps.append(lambda t, T_s, f=compiled_step: f(t, T_s, P, PO, S, Y, U))
            continue
        j = system.parts.index(part)
        sl = system.slots[part.name]
        views = (
            U[sl.u[0] : sl.u[1]],
            P[PO[j] : PO[j + 1]],
            S[sl.s[0] : sl.s[1]],
            Y[sl.y[0] : sl.y[1]],
        )
        copy_inputs, user = getattr(m, f"inputs_{i}"), python_steps[part.name]

        def python_step(t, T_s, copy_inputs=copy_inputs, user=user, views=views):
            copy_inputs(Y, U)
            return int(user(t, T_s, *views) or 0)

        steps.append(python_step)
    return steps


def _integrate_adaptive(t, T_s, X, Y, DT, V, NSEG, out_slots, rhs, method, rtol, atol, n_mod,
                        points, after):  # fmt: skip
    """Integrate over [t, t + T_s] segment by segment with ``solve_ivp``, split at the profiles'
    ``points`` inside it (``after``: the first point after them); a piece's right-hand side reads
    the profiles just below the point that ends it (``sim._loop_source.advance_lines``)."""
    ends = {T_s} | {float(np.sum(DT[j, : n + 1])) for j, n_j in enumerate(NSEG[:n_mod])
                    for n in range(n_j)}  # fmt: skip
    boundaries = sorted({t + end for end in ends} | set(points))  # absolute times
    start = t
    for end in boundaries:
        if end - start <= 1e-12 * T_s and end not in points:
            continue
        middle = 0.5 * (start + end) - t
        for j, (a, b) in enumerate(out_slots):  # each modulator's segment covering `middle`
            edges = np.cumsum(DT[j, : NSEG[j]])
            seg = min(int(np.searchsorted(edges, middle)), NSEG[j] - 1)
            Y[a:b] = V[j, seg, : b - a]
        cap = np.nextafter(min([b for b in (*points, after) if b > start]), -np.inf)
        sol = solve_ivp(rhs, (start, end), X, method=method, rtol=rtol, atol=atol, args=(cap,))
        if not sol.success:
            raise FloatingPointError(
                f"reference integration failed at t = {start:.6g} s: {sol.message}"
            )
        X[:] = sol.y[:, -1]
        start = end
