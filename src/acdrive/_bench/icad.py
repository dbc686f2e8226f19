"""The ICAD benchmark: full ICAD of the DeLorenzo IM with controller (20), 100 speeds x 2,000
frequencies, and the same quantities one point at a time.

"Full ICAD" is gamma, both channels c_i, both h_i, k_i g_ii, gamma h_j, S_i, T_i and the
coupling (10), batched over the (speed, frequency) grid from state-space data
(``analysis._icad_frequency.icad_response_arrays``). The optional peer is python-control's
``frequency_response`` computing only the plant G(jw) of the same grid (one call per speed), timed
in the same run when python-control is importable.

The point path (``point_evaluations``) is what the analysis's root finding and margins call
thousands of times: ``PointEvaluator.all`` of one plant at one s = j w. It is timed in process
CPU time, which counts every thread of the process, so work that a call starts on other cores
(a parallel region per point) shows in it.
"""

from __future__ import annotations

import time

import numpy as np

N_SPEEDS, N_FREQ = 100, 2000
TARGET_MS = 20.0
#: the point path: one-point evaluations per round, at this rotor speed [rad/s]
N_POINTS, POINT_SPEED = 500, 200.0


def best_of(fn, repeat: int) -> float:
    """Smallest wall time of ``repeat`` calls after one warm-up call [s]."""
    fn()
    times = []
    for _ in range(max(repeat, 1)):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def point_evaluations(repeat: int = 3) -> dict:
    """CPU time of one ICAD point evaluation [us] (module docstring): ``N_POINTS`` frequencies
    over the grid's decade range, one call each, after one warm-up call; min, median and max
    over ``repeat`` rounds."""
    from acdrive._bench.windows import spread
    from acdrive.analysis._freqresp import LTI
    from acdrive.analysis._icad_frequency import PointEvaluator
    from acdrive.analysis._plants import plant_for

    k = LTI.paper_20()
    point = PointEvaluator(plant_for("delorenzo-im", POINT_SPEED), k, k)
    s = 1j * np.logspace(0.0, 5.0, N_POINTS)
    point.all(s[:1])
    cpu, wall = [], []
    for _ in range(max(repeat, 1)):
        c0, w0 = time.process_time(), time.perf_counter()
        for x in s:
            point.all(np.array([x]))
        cpu.append(1e6 * (time.process_time() - c0) / N_POINTS)
        wall.append(1e6 * (time.perf_counter() - w0) / N_POINTS)
    return {
        "case": f"DeLorenzo IM at {POINT_SPEED:g} rad/s, controller (20), one point per call",
        "points_per_round": N_POINTS,
        "cpu_us_per_point": spread(cpu),
        "wall_us_per_point": spread(wall),
    }


def run_icad(repeat: int = 7, peer: bool = True) -> dict:
    """Best-of-``repeat`` wall time of the full ICAD [ms], the plant build, the point path's
    CPU time per point (``point_evaluations``) and the peer's."""
    from acdrive.analysis._freqresp import LTI
    from acdrive.analysis._icad_frequency import icad_response_arrays, stack_plants
    from acdrive.analysis._plants import plants_for

    speeds = np.linspace(0.0, 375.0, N_SPEEDS)
    w = np.logspace(0.0, 5.0, N_FREQ)
    k = LTI.paper_20()
    plants = plants_for("delorenzo-im", speeds)
    A, B, C, D, sp = stack_plants(plants)

    def ours():
        return icad_response_arrays(A, B, C, D, k, k, w, sp)

    t_build = best_of(lambda: stack_plants(plants_for("delorenzo-im", speeds)), 3)
    t_ours = best_of(ours, repeat)
    result = {
        "case": "DeLorenzo IM, controller (20), full ICAD",
        "grid": {"speeds": N_SPEEDS, "frequencies": N_FREQ},
        "icad_ms": 1e3 * t_ours,
        "plant_build_ms": 1e3 * t_build,
        "repeats": repeat,
        "points": point_evaluations(max(1, repeat // 2)),
    }
    if not peer:
        return result
    try:
        import control
    except ImportError:
        result["peer"] = {"available": False, "reason": "python-control is not installed"}
        return result
    systems = [control.ss(p.A, p.B, p.C, p.D) for p in plants]

    def theirs():
        return [s.frequency_response(w).complex for s in systems]

    t_peer = best_of(theirs, max(1, repeat // 3))
    G_peer = np.stack([np.moveaxis(g, -1, 0) for g in theirs()])
    err = float(np.max(np.abs(ours().G - G_peer) / np.maximum(np.abs(G_peer), 1e-300)))
    result["peer"] = {
        "available": True,
        "what": f"python-control {control.__version__} frequency_response (plant only)",
        "plant_only_ms": 1e3 * t_peer,
        "speedup": t_peer / t_ours,
        "max_rel_diff_plant": err,
    }
    return result
