"""Benchmark: start cost of a system built from parts against today's DFIM engine, same run.

Prints one JSON document. For each engine, in fresh interpreters sharing one empty numba cache
folder: the first short run (compiles) and the same in a second process (must load the cached
machine code, not compile). The matched case is the start cost itself, "process up, loop loaded,
0.01 s simulated": the parts-built system is the README's DFIM (stator onto the grid, rotor
shorted), today's engine runs ``bodson-step``. Control steps per second of the parts engine are
not compared here: its matched case (the Bodson drive built from parts) does not exist yet.
Compare the totals (import + first run): numba's one-time registry set-up of a process (about
0.3-0.5 s, it imports scipy.linalg) falls into the first dispatch of the parts system but into the
import phase of today's engine, whose scenario set-up already calls compiled functions.

    python benchmarks/bench_system.py
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

SYSTEM_SNIPPET = """
import time; t0 = time.perf_counter()
from acdrive.control.open_loop import ComplexProgram
from acdrive.machines.dfim import BODSON_DFIM
from acdrive.machines.dfim_part import DoublyFedMachine
from acdrive.plant.mechanics import Shaft
from acdrive.plant.sources import ThreePhaseSource
from acdrive.sim.system import System
grid = ThreePhaseSource("grid", V_pk=11.1, f=60.0)
dfim = DoublyFedMachine.from_params("dfim", BODSON_DFIM)
shaft = Shaft("shaft", J=BODSON_DFIM.J)
rotor = ComplexProgram("rotor")
system = System([grid, dfim, shaft, rotor], [
    (grid.out.v, dfim.inp.v_s), (rotor.out.v_ref, dfim.inp.v_r), (dfim.out.tau_e, shaft.inp.tau_e),
    (shaft.out.w, dfim.inp.w), (shaft.out.theta, dfim.inp.theta)])
t1 = time.perf_counter(); system.compile().run(0.01, 1e-4); t2 = time.perf_counter()
print(t1 - t0, t2 - t1)
"""

ENGINE_SNIPPET = """
import time; t0 = time.perf_counter()
import dataclasses
from acdrive.scenarios.loader import load_scenario
from acdrive.sim.setup import simulate
s = dataclasses.replace(load_scenario("bodson-step"), duration=0.01)
t1 = time.perf_counter(); simulate(s); t2 = time.perf_counter()
print(t1 - t0, t2 - t1)
"""


def timed(snippet: str, cache_dir: str) -> tuple[float, float]:
    """(import seconds, first-run seconds) in a fresh interpreter using ``cache_dir``."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir)
    out = subprocess.run(
        [sys.executable, "-c", snippet], capture_output=True, text=True, env=env, check=True
    )
    imp, first = (float(v) for v in out.stdout.split())
    return imp, first


def main() -> int:
    report: dict = {"benchmark": "system-start", "python": sys.version.split()[0]}
    for label, snippet in (("parts_system", SYSTEM_SNIPPET), ("dfim_engine", ENGINE_SNIPPET)):
        with tempfile.TemporaryDirectory() as cache:
            _, cold = timed(snippet, cache)
            imp_warm, warm = timed(snippet, cache)
        report[label] = {
            "first_process_first_run_s": cold,
            "second_process_first_run_s": warm,
            "second_process_import_s": imp_warm,
            "second_process_total_s": imp_warm + warm,
            "recompiled_in_second_process": warm > 0.5 * cold,
        }
    for key in ("first_run", "total"):
        report[f"ratio_second_process_{key}_parts_vs_engine"] = (
            report["parts_system"][f"second_process_{key}_s"]
            / report["dfim_engine"][f"second_process_{key}_s"]
        )
    print(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
