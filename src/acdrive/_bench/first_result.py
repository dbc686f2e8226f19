"""The first-result race against motulator 0.18 (issue 21, item 5): what a user waits for.

The matched averaged case of ``_bench.motulator_im`` (the same plant, controller structure,
sample time and 1.5 s of model time as the ``motulator_averaged`` case, built from the same
definitions), each simulator run as one **whole process from a clean start**: interpreter start,
imports, building the model, compiling or loading it (acdrive), simulating 1.5 s, the result in
memory. Each process is timed from outside in its own CPU time (``_bench.children``):

* ``acdrive_empty_cache``: acdrive with an empty cache: a fresh ``XDG_CACHE_HOME`` (so a fresh
  numba cache and any other acdrive cache) made for every run and deleted after it;
* ``motulator``: motulator 0.18 in its own virtualenv (``peers/motulator_im.py
  --first-result``), which compiles nothing;
* ``acdrive_warm_cache``: acdrive with a cache filled by one untimed run beforehand.

The three alternate, empty / motulator / warm, for ``rounds`` rounds (``windows.interleave``,
which records the machine's load over every window). Per round: acdrive's time over
motulator's (``time_ratio``) and its inverse (``speedup``); min, median and max over the rounds;
the verdicts from the medians: with an empty cache at most ``TARGETS["empty_cache_time_ratio_max"]``
times motulator's time, warm at least ``TARGETS["warm_speedup_min"]`` times faster.
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
from pathlib import Path

from acdrive._bench.children import ChildFailed, can_time_children, child_env, child_side, run_child
from acdrive._bench.windows import Clock, interleave, spread, summarise_windows

#: the issue's targets for the race
TARGETS = {"empty_cache_time_ratio_max": 1.0, "warm_speedup_min": 10.0}

SIDES = ("acdrive_empty_cache", "motulator", "acdrive_warm_cache")

#: acdrive's whole process: the matched averaged case built from ``_bench.motulator_im``'s
#: definitions, compiled or loaded, run for argv[1] seconds with the compared signals logged
ACDRIVE_CHILD = """\
import sys
from acdrive._bench.motulator_im import SUBSTEPS, T_S, log_ports, matched_acdrive_system
system, parts = matched_acdrive_system("averaged")
result = system.compile().run(float(sys.argv[1]), T_S, substeps=SUBSTEPS, log=log_ports(parts))
print(result.steps)
"""


def acdrive_command(model_time_s: float) -> list[str]:
    return [sys.executable, "-c", ACDRIVE_CHILD, repr(model_time_s)]


def motulator_command(peer: dict, model_time_s: float) -> list[str]:
    from acdrive._bench.venvs import PEER_SCRIPTS

    script = str(PEER_SCRIPTS / "motulator_im.py")
    return [peer["python"], script, "--first-result", "--converter", "averaged",
            "--seconds", repr(model_time_s)]  # fmt: skip


def verdicts(time_ratio_median, speedup_median) -> dict:
    """The race's two targets from the medians over the rounds (None where not measured)."""
    empty = None if time_ratio_median is None else bool(
        time_ratio_median <= TARGETS["empty_cache_time_ratio_max"]
    )  # fmt: skip
    warm = None if speedup_median is None else bool(speedup_median >= TARGETS["warm_speedup_min"])
    return {"empty_cache_at_most_1x_motulator": empty, "warm_cache_at_least_10x_faster": warm}


def summarise_race(windows: list[dict], cores: int) -> dict:
    """Per side the spread of its whole-process CPU time; per round acdrive's time over
    motulator's for each cache state, their spread, and the speedups (the inverse ratios)."""
    ran = {w["side"] for w in windows}
    pairs = {
        key: pair
        for key, pair in (
            ("empty_cache", ("acdrive_empty_cache", "motulator")),
            ("warm_cache", ("acdrive_warm_cache", "motulator")),
        )
        if set(pair) <= ran
    }
    s = summarise_windows(windows, pairs, cores)
    out: dict = {
        "cpu_s": {name: side["per_run_cpu_s"] for name, side in s["sides"].items()},
        "time_ratio": {},
        "speedup": {},
    }
    for key, r in s["ratios"].items():
        # summarise_windows' ratio is results per CPU second, acdrive's over motulator's:
        # motulator's time over acdrive's, i.e. the speedup
        out["speedup"][key] = {"per_round": r["per_round"], **spread(r["per_round"])}
        inverse = [1.0 / x for x in r["per_round"]]
        out["time_ratio"][key] = {"per_round": inverse, **spread(inverse)}
    for k in ("loaded_windows", "others_cpu_cores", "load_average_1min", "warning"):
        out[k] = s[k]
    return out


def warm_cache_warnings(warm_home: str) -> list[str]:
    """A warning if the warm cache holds more than one numba folder: acdrive keys that folder by
    its sources, so its sources changed during the race and the warm runs compiled again."""
    folders = sorted(p.name for p in Path(warm_home, "acdrive").glob("numba-*"))
    if len(folders) <= 1:
        return []
    message = (
        f"the warm cache holds {len(folders)} numba folders ({', '.join(folders)}): acdrive's "
        "sources changed during the race, so warm runs compiled again; re-run on a quiet tree"
    )
    return [message]


def run_race(
    peer: dict, rounds: int, model_time_s: float, log=None, clock: Clock | None = None
) -> dict:
    """The race (module docstring); ``peer`` is ``venvs.ensure_venv``'s answer for motulator.
    Without motulator, acdrive's two sides are still timed and the ratios are None."""
    say = log or (lambda _m: None)
    clock = clock or Clock()
    out: dict = {
        "case": "motulator_averaged (acdrive._bench.motulator_im.matched_acdrive_system)",
        "model_time_s": model_time_s,
        "rounds": rounds,
        "method": (
            "whole processes from a clean start (interpreter, imports, build, compile or load, "
            f"{model_time_s:g} s of model time, result in memory), each timed by its own CPU "
            "time (os.wait4 of the child: user + system), interleaved acdrive with an empty "
            "cache, motulator, acdrive with a warm cache, for every round; ratios per round, "
            "verdicts from the medians"
        ),
        "targets": TARGETS,
    }
    if not can_time_children():
        out["not_measured"] = "this platform has no os.wait4 (a child's own CPU time)"
        out["verdicts"] = verdicts(None, None)
        return out
    base = dict(os.environ)
    work = tempfile.mkdtemp(prefix="acdrive_race_")
    runs: dict[str, list] = {name: [] for name in SIDES}
    try:
        warm_home = os.path.join(work, "warm-cache")
        os.mkdir(warm_home)

        def empty_cache_run():
            home = tempfile.mkdtemp(prefix="empty-cache-", dir=work)
            try:
                return run_child(acdrive_command(model_time_s), child_env(base, home), cwd=work)
            finally:
                shutil.rmtree(home, ignore_errors=True)  # made just above for this run

        def warm_cache_run():
            return run_child(acdrive_command(model_time_s), child_env(base, warm_home), cwd=work)

        sides = {"acdrive_empty_cache": child_side(empty_cache_run, runs["acdrive_empty_cache"])}
        if peer.get("available"):
            from acdrive._bench.venvs import clean_env

            def motulator_run():
                return run_child(motulator_command(peer, model_time_s), clean_env(), cwd=work)

            sides["motulator"] = child_side(motulator_run, runs["motulator"])
        else:
            out["motulator"] = {"available": False, "reason": peer.get("reason", "not run")}
        sides["acdrive_warm_cache"] = child_side(warm_cache_run, runs["acdrive_warm_cache"])
        say("first-result race: filling the warm cache (one untimed acdrive run)")
        warm_up = {"acdrive_fill_warm_cache": warm_cache_run()}
        if "motulator" in sides:
            say("first-result race: one untimed motulator run (warm-up)")
            warm_up["motulator"] = motulator_run()
        out["warm_up_cpu_s"] = {k: v["cpu_s"] for k, v in warm_up.items()}
        windows = interleave(sides, dict.fromkeys(sides, 1), rounds, clock, say)
        out["warnings"] = warm_cache_warnings(warm_home)
    except ChildFailed as exc:
        out["not_measured"] = str(exc)
        out["verdicts"] = verdicts(None, None)
        return out
    finally:
        shutil.rmtree(work, ignore_errors=True)  # the race's own folder (mkdtemp above)
    out["results"] = {
        name: {
            "control_steps": sorted({r["stdout_last"] for r in got}),
            "wall_s": spread(r["wall_s"] for r in got),
            "max_rss_mb": spread(r["max_rss_mb"] for r in got),
        }
        for name, got in runs.items()
        if got
    }
    out["windows"] = windows
    out.update(summarise_race(windows, clock.cores))
    ratio = out["time_ratio"].get("empty_cache", {}).get("median")
    speedup = out["speedup"].get("warm_cache", {}).get("median")
    out["verdicts"] = verdicts(ratio, speedup)
    return out
