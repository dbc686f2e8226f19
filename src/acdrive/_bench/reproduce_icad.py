"""``acdrive reproduce icad`` as whole processes: the CPU time of the command that regenerates the
ICAD report (docs/reproduction/icad.md, its figures), the analysis's longest user-facing run.

Each run is a child process timed from outside (``_bench.children``: user + system CPU time of
the child and every thread it ran, from ``os.wait4``), writing into a fresh folder that is
deleted after. The first run uses an empty cache folder (it compiles every kernel of the
analysis); the warm runs then use that cache, as a user's second run does. The target reads the
median of the warm runs.
"""

from __future__ import annotations

import os
import shutil
import tempfile

from acdrive._bench.children import ChildFailed, can_time_children, child_env, run_child
from acdrive._bench.common import load_average
from acdrive._bench.windows import spread

#: the warm run's CPU time the suite checks against [CPU-s]
TARGET_CPU_S = 20.0


def run_reproduce_once(cache_home: str, work: str) -> dict:
    """One whole ``acdrive reproduce icad`` writing into a fresh folder under ``work`` (deleted
    after): ``run_child``'s answer."""
    from acdrive._bench.targets import acdrive_command

    out = tempfile.mkdtemp(prefix="out-", dir=work)
    try:
        cmd = [*acdrive_command(), "reproduce", "icad", "--out", out]
        return run_child(cmd, child_env(dict(os.environ), cache_home), cwd=work)
    finally:
        shutil.rmtree(out, ignore_errors=True)  # made just above for this run


def reproduce_icad(rounds: int, log=None) -> dict:
    """One run on an empty cache, then ``rounds`` warm runs on that cache: CPU and wall time
    (min / median / max of the warm runs) and the load averages (1, 5, 15 min) after each."""
    say = log or (lambda _m: None)
    if not can_time_children():
        return {"not_measured": "this platform has no os.wait4 (a child's own CPU time)"}
    work = tempfile.mkdtemp(prefix="acdrive_reproduce_icad_")
    try:
        home = os.path.join(work, "cache")
        os.mkdir(home)
        say("reproduce icad: empty cache")
        first = run_reproduce_once(home, work)
        warm, loads = [], []
        for r in range(max(rounds, 1)):
            say(f"reproduce icad, warm run {r + 1}/{max(rounds, 1)}")
            warm.append(run_reproduce_once(home, work))
            loads.append(load_average())
    except ChildFailed as exc:
        return {"not_measured": str(exc)}
    finally:
        shutil.rmtree(work, ignore_errors=True)  # this measurement's own folder (mkdtemp)
    return {
        "command": "acdrive reproduce icad --out <fresh folder>",
        "empty_cache": {k: first[k] for k in ("cpu_s", "user_s", "system_s", "wall_s")},
        "warm_cpu_s": spread(g["cpu_s"] for g in warm),
        "warm_wall_s": spread(g["wall_s"] for g in warm),
        "warm_load_averages": loads,
        "cpus": os.cpu_count(),
        "target_cpu_s": TARGET_CPU_S,
    }

