"""The slow path: a compiled system stepped from Python, the plant integrated by scipy.

The sampled parts, the modulators, the log and the plant's right-hand side are the compiled
system's own pieces (``sample_instant``, ``record``, ``derivatives`` of the generated module); only
the integration between segment boundaries differs: ``scipy.integrate.solve_ivp`` (Radau by
default) at a tight tolerance. This is the accuracy reference for the fixed-step loop: both solve
the same held-input equations, so their difference is the integrator's error alone.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from acdrive.errors import SimulationDiverged
from acdrive.sim.system import CompiledSystem, SystemResult


def simulate_reference(compiled: CompiledSystem, duration: float, sample_time: float,
                       initial=None, log=None, method: str = "Radau", rtol: float = 1e-10,
                       atol: float = 1e-12, t0: float = 0.0) -> SystemResult:  # fmt: skip
    """Run ``compiled`` for ``duration`` with an adaptive integrator between segment boundaries;
    logs every sample. Meant for verification, not speed."""
    system, m = compiled.system, compiled.module
    n_steps = compiled._steps(duration, sample_time, 1)
    columns, rows = compiled._log_setup(log, n_steps, 1)
    P = system.pack_params()
    X, S = system.pack_initial(initial)
    Y, U = np.zeros(system.sizes["y"]), np.zeros(system.sizes["u"])
    # scratch sized by the generated module's own constants
    DT, V = np.zeros((m.N_MOD, m.MAX_SEG)), np.zeros((m.N_MOD, m.MAX_SEG, m.MAX_W))
    NSEG = np.zeros(m.N_MOD, dtype=np.int64)
    E = np.zeros(m.N_EVENTS, dtype=np.int64)
    LOG = np.zeros((rows, len(columns)))
    ELOG = np.zeros((rows, m.N_EVENTS), dtype=np.int64)
    ECOUNT = np.zeros((m.N_EVENTS, 64), dtype=np.int64)
    idx = np.array([c[2] for c in columns], dtype=np.int64)
    out_slots = [system.slots[p.name].y for p in system.modulators]

    def rhs(t, x):
        dx = np.empty_like(x)
        m.derivatives(t, x, P, Y, U, dx)
        return dx

    for k in range(n_steps):
        t = t0 + k * sample_time
        m.sample_instant(t, sample_time, X, P, S, Y, U, E, DT, V, NSEG)
        m.record(k, 1, Y, E, idx, LOG, ELOG, ECOUNT)
        boundaries = sorted(
            {sample_time}
            | {
                float(np.sum(DT[j, : n + 1]))
                for j, n_j in enumerate(NSEG[: len(system.modulators)])
                for n in range(n_j)
            }
        )
        start = 0.0
        for end in boundaries:
            if end - start <= 1e-12 * sample_time:
                continue
            middle = 0.5 * (start + end)
            for j, (a, b) in enumerate(out_slots):  # each modulator's segment covering `middle`
                edges = np.cumsum(DT[j, : NSEG[j]])
                seg = min(int(np.searchsorted(edges, middle)), NSEG[j] - 1)
                Y[a:b] = V[j, seg, : b - a]
            sol = solve_ivp(rhs, (t + start, t + end), X, method=method, rtol=rtol, atol=atol)
            if not sol.success:
                raise FloatingPointError(
                    f"reference integration failed at t = {t + start:.6g} s: {sol.message}"
                )
            X[:] = sol.y[:, -1]
            start = end
        if not np.all(np.isfinite(X)):
            raise SimulationDiverged(t + sample_time, "the reference integration diverged")
    return compiled._result(t0, sample_time, 1, rows, columns, LOG, ELOG, ECOUNT, X, 0.0, n_steps)
