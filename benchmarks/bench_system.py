"""Benchmark: the DFIM drive built from parts against the previous hand-wired engine, same run.

Prints one JSON document with, for ``bodson-ramp`` and ``bodson-two-motors`` (the matched case:
the same scenario, the same sample time and substeps, the same results to rounding, see
``benchmarks/compare_engines.py``; the previous engine is frozen in ``benchmarks/previous_engine``):

* control steps per second of each engine, best of ``REPEATS`` alternating runs after a
  warm-up, and their ratio (parts / previous);
* the start cost in a second process (import + a 0.01 s run) with the compiled code cached by a
  first process, for each engine: the second process must load, not compile.

    python benchmarks/bench_system.py
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPEATS = 10
SCENARIOS = ("bodson-ramp", "bodson-two-motors")

HERE = Path(__file__).resolve().parent
IMPORTS = {
    "simulate_previous_engine": f"import sys; sys.path.insert(0, {str(HERE)!r}); "
    "from previous_engine import simulate_previous_engine as run",
    "simulate": "from acdrive.drives.dfim._setup import simulate as run",
}
START_SNIPPET = """
import time; t0 = time.perf_counter()
import dataclasses
from acdrive.scenarios import load_scenario
{import_line}
s = dataclasses.replace(load_scenario("bodson-step"), duration=0.01)
t1 = time.perf_counter(); run(s); t2 = time.perf_counter()
print(t1 - t0, t2 - t1)
"""


def start_cost(function: str, cache_dir: str) -> dict:
    """Seconds to import and run 0.01 s, in a first and a second fresh interpreter."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir)
    out = {}
    for which in ("first_process", "second_process"):
        result = subprocess.run(
            [sys.executable, "-c", START_SNIPPET.format(import_line=IMPORTS[function])],
            capture_output=True, text=True, env=env, check=True,
        )  # fmt: skip
        imp, run = (float(v) for v in result.stdout.split())
        out[which] = {"import_s": imp, "first_run_s": run, "total_s": imp + run}
    return out


def steps_per_second(engines: dict, setup) -> dict:
    """Control steps per second of each engine (name -> simulate function), best of ``REPEATS``
    runs after a warm-up, the engines' runs alternating so that both see the same machine load."""
    for simulate in engines.values():
        simulate(setup)  # warm-up (compiles once)
    best = dict.fromkeys(engines, float("inf"))
    for _ in range(REPEATS):
        for name, simulate in engines.items():
            best[name] = min(best[name], simulate(setup).wall_time)
    steps = round(setup.duration / setup.sample_time)
    return {name: steps / wall for name, wall in best.items()}


def main() -> None:
    from acdrive.drives import simulate
    from acdrive.scenarios import load_scenario

    sys.path.insert(0, str(HERE))
    from previous_engine import simulate_previous_engine

    report = {"repeats": REPEATS, "steps_per_second": {}, "start": {}}
    for name in SCENARIOS:
        s = load_scenario(name)
        s = s.with_mode(s.compare_modes[0]) if s.compare_modes else s
        rates = steps_per_second({"previous": simulate_previous_engine, "parts": simulate}, s)
        previous, parts = rates["previous"], rates["parts"]
        report["steps_per_second"][name] = {
            "previous_engine": round(previous),
            "parts": round(parts),
            "ratio_parts_vs_previous": round(parts / previous, 3),
        }
    with tempfile.TemporaryDirectory() as cache:
        for function in ("simulate_previous_engine", "simulate"):
            report["start"][function] = start_cost(function, cache)
    report["measured_at"] = time.strftime("%Y-%m-%d %H:%M:%S")
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
