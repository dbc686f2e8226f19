"""Batch simulation speed: N variants of ``bodson-ramp`` (load torque and speed bandwidth drawn
with a fixed seed) in the compiled batch loop with the default on-line reducers and no
per-sample log; prints JSON.

    python benchmarks/bench_batch.py [--variants 1000] [--integrator rk4|rk6] [--substeps N]

Reports: aggregate control steps per second of the compiled loop (``loop_steps_per_s``) and
end to end including validation and packing (``end_to_end_steps_per_s``), cores used, wall
times, the single-run speed of the same system in the same process, a bit-identity check of a
sample of variants against running each alone, and, with ``--integrator`` or ``--substeps``,
the speed and torque error of that choice and of the scenario's RK4 x 4 against RK6 x 16 over
the first 3 s of one variant (relative to each signal's peak).

On a shared machine the wall-clock figures fall with the other processes' load; the process's
CPU time (all threads) does much less, so ``steps_per_cpu_s`` x cores
(``projected_free_cores_steps_per_s``) is what the same run gives on free cores if the batch
scales linearly; it is a projection, stated as such, not a measurement of the target.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numba
import numpy as np

from acdrive._bench.windows import children_cpu
from acdrive.batch import prepare_variant, simulate_batch

BASE = "bodson-ramp"


def variants(n: int, seed: int = 1) -> list[dict]:
    rng = np.random.default_rng(seed)
    return [
        {"motor[0].load_torque": float(rng.uniform(0.0, 0.1)),
         "motor[0].controller.speed_bandwidth": float(rng.uniform(150.0, 400.0))}
        for _ in range(n)
    ]  # fmt: skip


def single_run(overrides, integrator=None, substeps=None, duration=None, log=()):
    """(final state, logged data, control steps per second) of one variant run alone in the
    same compiled loop (reducers included)."""
    if duration is not None:
        overrides = {**overrides, "simulation.duration": duration}
    setup, _, system, initial, held, _ = prepare_variant(
        BASE, overrides, None, integrator, substeps
    )
    compiled = system.compile()
    ports = [getattr(system.part(p.split(".")[0]).out, p.split(".")[1]) for p in log]
    n = round(setup.duration / setup.sample_time)
    start = time.perf_counter()
    r = compiled.run(setup.duration, setup.sample_time, setup.substeps, initial=initial,
                     held=held, log=ports, log_every=1 if ports else n)  # fmt: skip
    return r, n / (time.perf_counter() - start)


def accuracy(integrator, substeps) -> dict:
    v = variants(1)[0]
    log = ("shaft0.w", "dfim0.tau_e")
    ref, _ = single_run(v, "rk6", 16, 3.0, log)
    out = {}
    for label, (method, sub) in {"chosen": (integrator, substeps), "rk4x4": ("rk4", 4)}.items():
        r, _ = single_run(v, method, sub, 3.0, log)
        out[label] = {
            name: float(np.max(np.abs(r.signal(name) - ref.signal(name)))
                        / np.max(np.abs(ref.signal(name))))
            for name in log
        }  # fmt: skip
    return {"reference": "rk6 x 16, first 3 s, max |error| / peak", **out}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--variants", type=int, default=1000)
    ap.add_argument("--integrator", choices=("rk4", "rk6"), default=None)
    ap.add_argument("--substeps", type=int, default=None)
    ap.add_argument("--check", type=int, default=4, help="variants checked against single runs")
    args = ap.parse_args()
    vs = variants(args.variants)
    simulate_batch(BASE, vs[:2], integrator=args.integrator, substeps=args.substeps)  # compile
    # CPU: this process's and that of the workers it forks to prepare the variants
    start, cpu_start = time.perf_counter(), time.process_time() + children_cpu()
    batch = simulate_batch(BASE, vs, integrator=args.integrator, substeps=args.substeps)
    wall, cpu = time.perf_counter() - start, time.process_time() + children_cpu() - cpu_start
    _, single_speed = single_run(vs[0], args.integrator, args.substeps)
    _, single_speed = single_run(vs[0], args.integrator, args.substeps)  # warm
    sample = np.linspace(0, args.variants - 1, args.check).astype(int)
    check = simulate_batch(BASE, [vs[i] for i in sample], integrator=args.integrator,
                           substeps=args.substeps, log=["shaft0.w"], log_every=10_000)  # fmt: skip
    identical = True
    for j, i in enumerate(sample):
        alone, _ = single_run(vs[i], args.integrator, args.substeps)
        identical &= bool(np.array_equal(check.traces[j].final_state, alone.final_state))
        identical &= all(
            batch.rows[i][k] == check.rows[j][k] or batch.rows[i][k] != batch.rows[i][k]
            for k in batch.rows[i] if k != "variant"
        )  # fmt: skip
    report = {
        "scenario": BASE,
        "variants": args.variants,
        "control_steps": batch.steps,
        "integrator": args.integrator or "rk4 (scenario)",
        "substeps": args.substeps or "scenario (4)",
        "cores": numba.get_num_threads(),
        "cpu_count": os.cpu_count(),
        "loop_wall_s": round(batch.wall_time, 3),
        "end_to_end_wall_s": round(wall, 3),
        "loop_steps_per_s": round(batch.steps / batch.wall_time),
        "end_to_end_steps_per_s": round(batch.steps / wall),
        "process_cpu_s": round(cpu, 3),
        "steps_per_cpu_s": round(batch.steps / cpu),
        "projected_free_cores_steps_per_s": round(batch.steps / cpu * numba.get_num_threads()),
        "single_run_steps_per_s": round(single_speed),
        "target_steps_per_s": 2_000_000,
        "all_ok": all(r["status"] == "ok" for r in batch.rows),
        "bit_identical_to_single_runs": {"checked": len(sample), "identical": identical},
    }
    if args.integrator or args.substeps:
        report["accuracy"] = accuracy(args.integrator or "rk4", args.substeps or 4)
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
