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

``compare_machine_code`` compares instead the machine code of the compiled loop of two trees
(numba's assembly of ``run``, with symbol names, labels, comments and assembler directives
removed): identical instructions run at the same speed, so a timing difference between them is
code placement and machine noise, not the change (two checkouts of one source were measured 7 %
apart).
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

SCENARIOS = ("bodson-ramp", "bodson-two-motors", "im-foc-speed")
#: the loop measured is numba's specialised one (``acdrive.sim._tier``)
SPECIALISED = {"ACDRIVE_LOOP_TIER": "specialised"}

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


MACHINE_CODE_WORKER = (
    WORKER.split("compiled = drive.compile()")[0]
    + r"""
import re
compiled = drive.compile()
drive.run(compiled)
run = compiled.module.run
asm = run.inspect_asm(run.signatures[0])
DIRECTIVE = re.compile(r"^\s*\.(file|loc|ident|section|size|type|globl|weak|p2align|text|cfi_\w+)\b")
lines = []
for line in asm.splitlines():
    line = re.sub(r"acdrive_system_[0-9a-f]+", "SYS", line)
    line = re.sub(r"_ZN[0-9A-Za-z_$]+", "SYM", line)
    line = re.sub(r"\.L[A-Za-z0-9_.$]+", "LABEL", line)
    line = line.split("#")[0].rstrip()
    if line and not DIRECTIVE.match(line):
        lines.append(line)
print(json.dumps({"instructions": lines}))
"""
)


def _machine_code(src: str, name: str) -> list[str]:
    """The normalised assembly lines of the compiled loop ``run`` of scenario ``name`` in the
    tree ``src``, compiled in a fresh numba cache so both trees compile alike."""
    import tempfile

    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, PYTHONPATH=src, NUMBA_CACHE_DIR=cache, ACDRIVE_COMPILE_NOTICE="0",
                   **SPECIALISED)  # fmt: skip
        out = subprocess.run([sys.executable, "-c", MACHINE_CODE_WORKER, name, "0"], env=env,
                             check=True, capture_output=True, text=True).stdout  # fmt: skip
    return json.loads(out.strip().splitlines()[-1])["instructions"]


def compare_machine_code(before: str, after: str, names) -> dict:
    """Per scenario: instruction lines of each tree and how many differ (difflib)."""
    import difflib

    report = {}
    for name in names:
        a, b = _machine_code(before, name), _machine_code(after, name)
        changed = sum(
            1 for line in difflib.unified_diff(a, b, lineterm="", n=0)
            if line[:1] in "+-" and not line.startswith(("+++", "---"))
        )  # fmt: skip
        report[name] = {"lines_before": len(a), "lines_after": len(b), "differing_lines": changed,
                        "identical": a == b}  # fmt: skip
    return report


def _measure(src: str, name: str, reps: int) -> tuple[int, list[float], list[float]]:
    env = dict(os.environ, PYTHONPATH=src, **SPECIALISED)
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
