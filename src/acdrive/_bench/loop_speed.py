"""The specialised loop's speed against a baseline source tree, interleaved in one run.

Issue 21: the per-step speed of the specialised loop must not fall (steps per second of
``bodson-ramp`` and ``im-foc-speed`` within 3 % of today's, in the same run). "Today" is a
source tree the user names (``acdrive bench --only loop_speed --baseline-src DIR``, e.g. a
worktree of main): for each scenario, ``rounds`` rounds alternate the two trees (A B A B ...),
each a fresh process (``WORKER``, with ``PYTHONPATH`` set to the tree's ``src``) that loads the
scenario, loads or compiles its loop, runs it once to warm up and then ``reps`` times, timing
each run in its own process CPU time: the compiled loop alone (``loop``, the time inside the
compiled system's ``run``) and the whole drive run with its result (``run``). Per tree the
min / median / max steps per CPU second and the ratio of the medians, this tree over the
baseline (``benchmarks/compare_speed.py`` runs the same for any two trees).
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

SCENARIOS = ("bodson-ramp", "bodson-two-motors", "im-foc-speed")

WORKER = r"""
import json, sys, time
name, reps = sys.argv[1], int(sys.argv[2])
from acdrive.scenarios import load_scenario
try:
    from acdrive.drives.dfim._drive import DFIMDrive
    from acdrive.drives.cage_im._drive import IMDrive
except ImportError:
    from acdrive.sim._dfim_drive import DFIMDrive
    from acdrive.sim._im_drive import IMDrive
setup = load_scenario(name)
if hasattr(setup, "motors"):
    if setup.compare_modes:
        setup = setup.with_mode(setup.compare_modes[0])
    drive = DFIMDrive(setup)
else:
    drive = IMDrive(setup.runs()[0][1] if setup.runs() else setup)
compiled = drive.compile()
loop = []
run_loop = compiled.run


def timed_loop(*args, **kwargs):
    t0 = time.process_time()
    out = run_loop(*args, **kwargs)
    loop.append(time.process_time() - t0)
    return out


compiled.run = timed_loop
drive.run(compiled)
times, loop[:] = [], []
for _ in range(reps):
    t0 = time.process_time()
    drive.run(compiled)
    times.append(time.process_time() - t0)
steps = round(setup.duration / setup.sample_time)
print(json.dumps({"steps": steps, "cpu_s": times, "loop_cpu_s": loop}))
"""


def _measure(src: str, name: str, reps: int) -> tuple[int, list[float], list[float]]:
    env = dict(os.environ, PYTHONPATH=src)
    out = subprocess.run([sys.executable, "-c", WORKER, name, str(reps)], env=env, check=True,
                         capture_output=True, text=True).stdout  # fmt: skip
    data = json.loads(out.strip().splitlines()[-1])
    return data["steps"], data["cpu_s"], data["loop_cpu_s"]


def _stats(rates: dict) -> dict:
    """min / median / max per tree and the ratio after / before of the medians."""
    out = {
        side: {"min": min(r), "median": statistics.median(r), "max": max(r)}
        for side, r in rates.items()
    }
    out["ratio_after_before_median"] = out["after"]["median"] / out["before"]["median"]
    return out


def this_tree_src() -> str:
    """The ``src`` folder this acdrive is imported from (the parent of the package)."""
    import acdrive

    return str(Path(acdrive.__file__).resolve().parent.parent)


def compare_trees(before: str, after: str, names, rounds: int, reps: int, log=None) -> dict:
    """Per scenario in ``names``: ``rounds`` rounds alternating the ``before`` and ``after``
    source trees, ``reps`` timed runs each (module docstring); ``_stats`` of both measures."""
    say = log or (lambda _m: None)
    report = {"before": before, "after": after, "rounds": rounds, "reps": reps, "scenarios": {}}
    for name in names:
        rates = {"before": [], "after": []}
        loop_rates = {"before": [], "after": []}
        for r in range(rounds):
            for side, src in (("before", before), ("after", after)):
                say(f"loop speed, {name}, round {r + 1}/{rounds}: {side}")
                steps, cpu, loop = _measure(src, name, reps)
                rates[side] += [steps / t for t in cpu]
                loop_rates[side] += [steps / t for t in loop]
        report["scenarios"][name] = {"run": _stats(rates), "loop": _stats(loop_rates)}
    return report
