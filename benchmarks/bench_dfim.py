"""Benchmark: control steps per second of the compiled DFIM drive scenarios.

Prints one JSON document: compile and cold-start times, control steps per second and real-time
factor of each scenario, and the ratio against acdrive's own slow path (the same loop driven
from Python) measured in the same run. The matched comparisons with other simulators
(motulator, gym-electric-motor), with both sides' accuracy, are the benchmark suite:
``acdrive bench --json``.

    python benchmarks/bench_dfim.py [--scenarios bodson-ramp bodson-two-motors] [--repeats 3]

Several motors on one supply advance together: one control step counts all of them.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
COLD_SNIPPET = """
import time; t0 = time.perf_counter()
import dataclasses
from acdrive.scenarios import load_scenario
from acdrive.drives import simulate
s = dataclasses.replace(load_scenario({scenario!r}), duration=0.01)
t1 = time.perf_counter(); simulate(s); t2 = time.perf_counter()
print(t1 - t0, t2 - t1)
"""


def first_run_seconds(scenario: str, cache_dir: str) -> tuple[float, float]:
    """(import time, first short simulation time) in a fresh interpreter using ``cache_dir``."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir)
    out = subprocess.run(
        [sys.executable, "-c", COLD_SNIPPET.format(scenario=scenario)],
        capture_output=True,
        text=True,
        env=env,
        check=True,
    )
    imp, first = (float(v) for v in out.stdout.split())
    return imp, first


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenarios", nargs="+", default=["bodson-ramp", "bodson-two-motors"])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()

    from acdrive.drives.dfim._drive import simulate_slow
    from acdrive.drives.dfim._setup import n_steps, simulate
    from acdrive.scenarios import load_scenario

    report: dict = {"benchmark": "dfim-drive", "python": sys.version.split()[0]}
    with tempfile.TemporaryDirectory() as cache:
        imp, cold = first_run_seconds(args.scenarios[0], cache)
        _, cached = first_run_seconds(args.scenarios[0], cache)
    report["compile_s"] = cold
    report["second_process_first_run_s"] = cached
    report["import_s"] = imp

    runs = {}
    for name in args.scenarios:
        setup = load_scenario(name)
        steps = n_steps(setup)
        simulate(setup)  # warm-up
        best = min(simulate(setup).wall_time for _ in range(args.repeats))
        runs[name] = {
            "motors": len(setup.motors),
            "control_steps": steps,
            "substeps_per_control_step": setup.substeps,
            "control_steps_per_s": steps / best,
            "realtime_factor": setup.duration / best,
        }
    report["scenarios"] = runs
    first = runs[args.scenarios[0]]

    # acdrive's own slow path, measured in the same run, against the first scenario (one motor)
    short = dataclasses.replace(load_scenario(args.scenarios[0]), duration=0.2)
    t0 = time.perf_counter()
    simulate_slow(short)
    slow = n_steps(short) / (time.perf_counter() - t0)
    report["slow_path"] = {
        "steps_per_s": slow,
        "compiled_speedup": first["control_steps_per_s"] / slow,
    }
    print(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
