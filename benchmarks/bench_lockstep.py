"""Lockstep batch loop against the per-variant batch loop, and both against the machine's
measured floating-point yardsticks; prints one JSON object.

    python benchmarks/bench_lockstep.py [--variants 1000] [--duration 0.2] [--rounds 3]

The batch is ``--variants`` variants of ``bodson-ramp`` (with the default reducers of
``acdrive.batch``, as a user's batch runs, or none with ``--no-reducers``) that differ in shaft
inertia and rotor resistance. The two loops run interleaved (A B A B, ``--rounds`` windows each)
on all of numba's threads; each window's rate is control steps (variants x samples) per wall
second and per process CPU second. The load average is recorded before and after.

Yardsticks (``_yardstick``): a numba kernel of eight dependent fused multiply-adds per element
over a contiguous array that stays in the L1 cache, compiled once with LLVM's loop vectoriser
(as numba does by default) and once in a child process with it switched off
(``NUMBA_LOOP_VECTORIZE=0``): the machine's vectorised and scalar GFLOP/s on one core.

``fraction_of_vectorised_yardstick_at_most``: the lockstep loop's flop rate as a fraction of
the vectorised yardstick, bounded from above. The flops of one control step are not counted
here; the per-variant loop does them scalar, at most at the scalar yardstick's rate (the issue
measured it near that rate), so flops per step <= scalar GFLOP/s x per-variant CPU-s per step,
and the fraction is at most (lockstep / per-variant steps per CPU-s) x (scalar / vectorised
GFLOP/s).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

import numpy as np

N_FMA = 8  # dependent multiply-adds per element in the yardstick kernel
YARD_N = 2048  # elements: 16 kB, inside L1


def _yardstick_kernel():
    from numba import njit

    @njit(fastmath=True, error_model="numpy")
    def fma_kernel(x, a, b, reps):
        for _ in range(reps):
            for i in range(x.shape[0]):
                v = x[i]
                v = v * a + b
                v = v * a + b
                v = v * a + b
                v = v * a + b
                v = v * a + b
                v = v * a + b
                v = v * a + b
                v = v * a + b
                x[i] = v

    return fma_kernel


def _yardstick(seconds: float = 0.5) -> float:
    """GFLOP/s of the yardstick kernel on one core (CPU time), best of three windows."""
    kernel = _yardstick_kernel()
    x = np.full(YARD_N, 0.5)
    a, b = 0.999999, 1e-6  # a fixed point near 1: no overflow, no denormals
    kernel(x, a, b, 1)
    reps = 1000
    while True:
        t0 = time.process_time()
        kernel(x, a, b, reps)
        dt = time.process_time() - t0
        if dt > seconds / 4:
            break
        reps *= 4
    rates = []
    for _ in range(3):
        t0 = time.process_time()
        kernel(x, a, b, reps)
        rates.append(2 * N_FMA * YARD_N * reps / (time.process_time() - t0) / 1e9)
    return max(rates)


def _scalar_yardstick() -> float:
    """The same kernel in a child process with numba's loop vectoriser off (SLP is off in numba
    by default)."""
    env = {**os.environ, "NUMBA_LOOP_VECTORIZE": "0", "NUMBA_SLP_VECTORIZE": "0"}
    out = subprocess.run([sys.executable, __file__, "--yardstick-only"], env=env, check=True,
                         capture_output=True, text=True).stdout  # fmt: skip
    return float(out.strip().splitlines()[-1])


def _group(n: int, duration: float, reducers=None):
    """The packed batch: compiled system, P, PO, X, S, Y, setup (``reducers`` None: the drive's
    default metrics, as ``simulate_batch`` appends them)."""
    from acdrive.batch import prepare_variant

    setup, _drive, system, initial, held, _used = prepare_variant(
        "bodson-ramp", {"simulation.duration": duration}, reducers=reducers
    )
    rng = np.random.default_rng(2026)
    parts = []
    for _ in range(n):
        parts.append([
            system.part("shaft0").with_params(J=float(3.5e-4 * (0.8 + 0.4 * rng.random()))),
            system.part("dfim0").with_params(R_r=float(0.8 + 0.8 * rng.random())),
        ])  # fmt: skip
    P = np.stack([system.pack_params(p)[0] for p in parts])
    PO = system.pack_params()[1]
    X0, S0 = system.pack_initial(initial)
    Y0 = system.pack_held(held)
    X, S, Y = np.tile(X0, (n, 1)), np.tile(S0, (n, 1)), np.tile(Y0, (n, 1))
    return system.compile(), P, PO, X, S, Y, setup


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variants", type=int, default=1000)
    parser.add_argument("--duration", type=float, default=0.2, help="model time per variant [s]")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--no-reducers", action="store_true",
                        help="the plant and controllers only (no on-line metric parts)")  # fmt: skip
    parser.add_argument("--yardstick-only", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.yardstick_only:
        print(_yardstick())
        return
    import numba

    os.environ.setdefault("ACDRIVE_COMPILE_NOTICE", "0")
    compiled, P, PO, X, S, Y, setup = _group(
        args.variants, args.duration, [] if args.no_reducers else None
    )
    n_steps = round(setup.duration / setup.sample_time)

    def window(lockstep: bool):
        x, s, y = X.copy(), S.copy(), Y.copy()
        c0, w0 = time.process_time(), time.perf_counter()
        *_, status, _ = compiled.run_packed(P, PO, x, s, y, setup.duration, setup.sample_time,
                                            setup.substeps, lockstep=lockstep)  # fmt: skip
        cpu, wall = time.process_time() - c0, time.perf_counter() - w0
        assert compiled.last_batch_loop == ("lockstep" if lockstep else "per-variant")
        steps = args.variants * n_steps
        return {"steps_per_s": steps / wall, "steps_per_cpu_s": steps / cpu,
                "ok": int((status == 0).sum())}  # fmt: skip

    load_before = os.getloadavg()
    c0 = time.perf_counter()
    window(True)  # compiles or loads the lockstep loop
    window(False)  # and the per-variant one
    warm_up = time.perf_counter() - c0
    runs = {"lockstep": [], "per_variant": []}
    for _ in range(args.rounds):
        runs["lockstep"].append(window(True))
        runs["per_variant"].append(window(False))
    load_after = os.getloadavg()
    vector = _yardstick()
    scalar = _scalar_yardstick()

    def spread(name, key):
        values = [r[key] for r in runs[name]]
        return {"min": min(values), "median": statistics.median(values), "max": max(values)}

    out = {
        "scenario": "bodson-ramp",
        "reducers": "none" if args.no_reducers else "the drive's defaults",
        "variants": args.variants,
        "samples_per_variant": n_steps,
        "threads": numba.get_num_threads(),
        "lanes": __import__("acdrive.sim._lockstep_source", fromlist=["LANES"]).LANES,
        "rounds": args.rounds,
        "warm_up_s": warm_up,
        "load_average_before_after": [load_before[0], load_after[0]],
        "all_variants_ok": all(r["ok"] == args.variants for v in runs.values() for r in v),
    }
    for name in runs:
        out[name] = {key: spread(name, key) for key in ("steps_per_s", "steps_per_cpu_s")}
    ratio = [a["steps_per_cpu_s"] / b["steps_per_cpu_s"]
             for a, b in zip(runs["lockstep"], runs["per_variant"], strict=True)]  # fmt: skip
    out["lockstep_over_per_variant_per_cpu_s"] = {
        "min": min(ratio), "median": statistics.median(ratio), "max": max(ratio)
    }  # fmt: skip
    out["yardstick_gflops_per_core"] = {"vectorised": vector, "scalar": scalar}
    median_ratio = out["lockstep_over_per_variant_per_cpu_s"]["median"]
    out["fraction_of_vectorised_yardstick_at_most"] = median_ratio * scalar / vector
    median_rate = out["lockstep"]["steps_per_s"]["median"]
    out["targets"] = {
        "steps_per_s_at_least_6e6": {"value": median_rate, "met": median_rate >= 6e6},
        "lockstep_at_least_3x_per_cpu_s": {"value": median_ratio, "met": median_ratio >= 3.0},
    }
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
