"""Benchmark: control steps per second of the compiled DFIM drive simulation (issue 2 / 3).

Prints one JSON document. Speeds are quoted as ratios against peers measured in the same run:
acdrive's own slow path (the same loop driven from Python), and, when a peer virtualenv is
available (``--peer-python``, default benchmarks/.peer-venv or /tmp/peer), motulator and
gym-electric-motor (see benchmarks/peers/README.md).

    python benchmarks/bench_dfim.py [--scenarios bodson-ramp bodson-two-motors] [--repeats 3]
                                    [--peer-python PATH]

Several motors on one supply advance together: one control step counts all of them. Peers run in
their own virtualenv: python -m venv benchmarks/.peer-venv &&
benchmarks/.peer-venv/bin/pip install -r benchmarks/peers/requirements.txt
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
from acdrive.scenarios.loader import load_scenario
from acdrive.sim.setup import simulate
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


def run_peer(python: str, script: str, seconds: float) -> dict | None:
    try:
        out = subprocess.run(
            [python, str(HERE / "peers" / script), "--seconds", str(seconds)],
            capture_output=True,
            text=True,
            timeout=600,
        )
    except (OSError, subprocess.TimeoutExpired) as exc:
        return {"error": str(exc)}
    if out.returncode != 0:
        return {"error": out.stderr.strip().splitlines()[-1] if out.stderr.strip() else "failed"}
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenarios", nargs="+", default=["bodson-ramp", "bodson-two-motors"])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--peer-python", default=None)
    parser.add_argument("--peer-seconds", type=float, default=1.0)
    args = parser.parse_args()

    from acdrive.scenarios.loader import load_scenario
    from acdrive.sim.dfim_drive import simulate_slow
    from acdrive.sim.setup import n_steps, simulate

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

    # peers, measured in the same run; speedups are against the first scenario (one motor)
    short = dataclasses.replace(load_scenario(args.scenarios[0]), duration=0.2)
    t0 = time.perf_counter()
    simulate_slow(short)
    peers = {"acdrive-slow-path": {"steps_per_s": n_steps(short) / (time.perf_counter() - t0)}}
    peer_python = args.peer_python
    for candidate in (HERE / ".peer-venv" / "bin" / "python", Path("/tmp/peer/bin/python")):
        if peer_python is None and candidate.exists():
            peer_python = str(candidate)
    if peer_python:
        for name, script in (
            ("motulator", "motulator_steps.py"),
            ("gym-electric-motor", "gem_steps.py"),
        ):
            if (HERE / "peers" / script).exists():
                peers[name] = run_peer(peer_python, script, args.peer_seconds)
    for peer in peers.values():
        if peer and "steps_per_s" in peer:
            peer["acdrive_speedup"] = first["control_steps_per_s"] / peer["steps_per_s"]
    report["peers"] = peers
    print(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
