"""Fair timing of two simulators: interleaved windows of similar length in process CPU time.

A simulator's speed on a shared machine depends on what else runs. The suite therefore never
compares a best-of-few wall time of a 3 ms run with one of a 10 s run. It times **windows**:

* a *side* is a callable ``window(runs) -> {"cpu_s", "steps_per_run"}`` that runs its case
  ``runs`` times back to back and returns the process CPU time (``time.process_time`` in the
  process that ran it: acdrive's own for acdrive, the peer's own, measured inside its subprocess
  and reported back, for a peer) and the control steps of one run;
* the peer's window is one run of its case; acdrive's short run is repeated ``runs`` times so
  that its window lasts about as long as the peer's (``runs_for_target``, from a calibration
  window of each side), and its per-run time is the window's CPU time / ``runs``;
* the windows are interleaved, A B A B ... (``interleave``), ``rounds`` times, so that both sides
  see the same machine over the same minutes; each round gives one ratio (acdrive's steps per
  CPU second over the peer's in that round), and the report gives the spread (``spread``:
  min, median, max) of each side's per-run time and of the ratio; the headline ratio is the
  median of the rounds' ratios;
* the machine's load is recorded at every window (``timed_window``): the 1-minute load average at
  its end and the CPU time used by *other* processes over it (all CPUs' busy time from
  ``/proc/stat`` minus the benchmark's own CPU time, as a number of cores). ``LOAD_RULE`` flags a
  window as loaded; the suite prints a warning naming the loaded windows.

Everything that reads a clock takes a ``Clock`` so that tests run the logic on fake timers.
"""

from __future__ import annotations

import math
import os
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass, field

#: the rule by which a window counts as loaded (``is_loaded``)
LOAD_RULE = (
    "a window is loaded when the other processes used more than (cores - 1) cores on average "
    "over it (all CPUs' busy time from /proc/stat minus the benchmark's own process CPU time, "
    "over the window's wall time), or, where /proc/stat is missing, when the 1-minute load "
    "average at its end exceeds the number of cores (the benchmark's single running thread "
    "counts 1 of it): then the benchmark did not have a core to itself"
)


def proc_stat_busy() -> float | None:
    """Busy CPU seconds of all CPUs since boot (``/proc/stat``: every field of the ``cpu``
    line but idle and iowait, guest time being part of user time), or None where absent."""
    try:
        with open("/proc/stat", encoding="ascii") as f:
            fields = f.readline().split()
    except OSError:
        return None
    if not fields or fields[0] != "cpu":
        return None
    ticks = [int(x) for x in fields[1:9]]  # user nice system idle iowait irq softirq steal
    busy = sum(ticks) - ticks[3] - ticks[4]
    return busy / os.sysconf("SC_CLK_TCK")


def children_cpu() -> float:
    """CPU seconds of this process's ended and waited-for children (``os.times``): the forked
    workers that prepare a batch's variants (``acdrive._forked_map``) count to the batch."""
    t = os.times()
    return t.children_user + t.children_system


def load_average_1min() -> float | None:
    try:
        return round(os.getloadavg()[0], 2)
    except (AttributeError, OSError):
        return None


@dataclass
class Clock:
    """Where the timing reads its clocks (real by default; tests pass fakes): ``cpu`` this
    process's CPU time, ``children`` that of its waited-for children, ``wall`` a monotonic
    clock, ``busy`` all CPUs' busy seconds (None if unknown), ``load`` the 1-minute load average
    (None if unknown), ``cores`` the CPU count."""

    cpu: Callable[[], float] = time.process_time
    children: Callable[[], float] = children_cpu
    wall: Callable[[], float] = time.perf_counter
    busy: Callable[[], float | None] = proc_stat_busy
    load: Callable[[], float | None] = load_average_1min
    cores: int = field(default_factory=lambda: os.cpu_count() or 1)


def is_loaded(others_cores: float | None, load_1min: float | None, cores: int) -> bool | None:
    """``LOAD_RULE``: True if the other processes took more than ``cores - 1`` cores (or, with
    no /proc/stat figure, the load average exceeds ``cores``); None if neither is known."""
    if others_cores is not None:
        return bool(others_cores > cores - 1)
    if load_1min is not None:
        return bool(load_1min > cores)
    return None


def spread(values) -> dict:
    """min, median, max and count of ``values`` (None entries dropped; all None if empty)."""
    v = [float(x) for x in values if x is not None]
    if not v:
        return {"min": None, "median": None, "max": None, "n": 0}
    return {"min": min(v), "median": statistics.median(v), "max": max(v), "n": len(v)}


def runs_for_target(per_run_cpu_s: float, target_cpu_s: float) -> int:
    """How many repetitions of a run of ``per_run_cpu_s`` fill a window of ``target_cpu_s``
    (at least 1)."""
    if per_run_cpu_s <= 0.0 or not math.isfinite(per_run_cpu_s):
        raise ValueError("per-run CPU time must be positive and finite")
    return max(1, round(target_cpu_s / per_run_cpu_s))


def calibrate(window, clock: Clock, min_cpu_s: float) -> float:
    """Per-run CPU time of a side: windows of 1, 2, 4, ... runs until one lasts ``min_cpu_s``
    of CPU time (short runs are below the clocks' resolution alone)."""
    runs = 1
    while True:
        got = window(runs)
        if got["cpu_s"] >= min_cpu_s or runs >= 1 << 20:
            return got["cpu_s"] / runs
        runs *= 2


def timed_window(name: str, window, runs: int, clock: Clock) -> dict:
    """One window of side ``name``: ``runs`` runs, its CPU time per run (reported by the side),
    wall time, and the load over it (``LOAD_RULE``). The benchmark's own CPU time over the
    window is the side's reported CPU time, or for a side run elsewhere the CPU time of its
    whole window (``process_cpu_s``, building included) plus this process's."""
    wall0, busy0, cpu0 = clock.wall(), clock.busy(), clock.cpu()
    got = window(runs)
    wall1, busy1, cpu1 = clock.wall(), clock.busy(), clock.cpu()
    wall = wall1 - wall0
    if got.get("in_process"):
        own = got["cpu_s"]
    else:  # the peer's whole window (model building included, if it says) and the suite's wait
        own = got.get("process_cpu_s", got["cpu_s"]) + (cpu1 - cpu0)
    others = None
    if busy0 is not None and busy1 is not None and wall > 0.0:
        others = max(0.0, (busy1 - busy0) - own) / wall
    load = clock.load()
    per_run = got["cpu_s"] / runs
    steps = got["steps_per_run"]
    return {
        "side": name,
        "runs": runs,
        "cpu_s": got["cpu_s"],
        "per_run_cpu_s": per_run,
        "steps_per_run": steps,
        "steps_per_cpu_s": steps / per_run if per_run > 0.0 else None,
        "wall_s": wall,
        "cpu_share_of_wall": got["cpu_s"] / wall if wall > 0.0 else None,
        "others_cpu_cores": others,
        "load_average_1min": load,
        "loaded": is_loaded(others, load, clock.cores),
    }


def interleave(sides: dict, runs: dict, rounds: int, clock: Clock, log=None) -> list[dict]:
    """``rounds`` rounds, each one window of every side in ``sides``' order (A B A B ...);
    ``runs[name]`` runs per window. Returns the windows in the order they ran."""
    say = log or (lambda _m: None)
    out = []
    for r in range(rounds):
        for name, window in sides.items():
            say(f"round {r + 1}/{rounds}: {name} ({runs[name]} run{'s' * (runs[name] > 1)})")
            w = timed_window(name, window, runs[name], clock)
            w["round"] = r
            out.append(w)
    return out


def summarise_windows(windows: list[dict], pairs: dict, cores: int) -> dict:
    """Per side: the spread of per-run CPU time and steps per CPU second. Per pair
    ``key: (numerator, denominator)``: the rounds' ratios (numerator's steps per CPU second over
    the denominator's in the same round), their spread and the headline ``ratio`` (the median).
    The loaded windows (``LOAD_RULE``) and a warning naming them, None if there are none."""
    by_side: dict[str, dict[int, dict]] = {}
    for w in windows:
        by_side.setdefault(w["side"], {})[w["round"]] = w
    out: dict = {"sides": {}, "ratios": {}}
    for name, ws in by_side.items():
        out["sides"][name] = {
            "runs_per_window": sorted({w["runs"] for w in ws.values()}),
            "per_run_cpu_s": spread(w["per_run_cpu_s"] for w in ws.values()),
            "steps_per_cpu_s": spread(w["steps_per_cpu_s"] for w in ws.values()),
            "window_cpu_s": spread(w["cpu_s"] for w in ws.values()),
        }
    for key, (num, den) in pairs.items():
        a, b = by_side.get(num, {}), by_side.get(den, {})
        per_round = [
            a[r]["steps_per_cpu_s"] / b[r]["steps_per_cpu_s"]
            for r in sorted(a)
            if r in b and a[r]["steps_per_cpu_s"] and b[r]["steps_per_cpu_s"]
        ]
        s = spread(per_round)
        out["ratios"][key] = {"of": [num, den], "per_round": per_round, **s, "ratio": s["median"]}
    loaded = [f"{w['side']}#{w['round'] + 1}" for w in windows if w["loaded"]]
    others = spread(w["others_cpu_cores"] for w in windows)
    load = spread(w["load_average_1min"] for w in windows)
    out.update(
        loaded_windows=loaded,
        load_rule=LOAD_RULE,
        cores=cores,
        others_cpu_cores=others,
        load_average_1min=load,
        warning=load_warning(loaded, len(windows), others, load, cores),
    )
    return out


def ratio_spread(r: dict) -> dict:
    """A ratio's spread (min, median, max, rounds) without its per-round list."""
    return {k: r[k] for k in ("min", "median", "max", "n")}


def load_warning(loaded: list, n_windows: int, others: dict, load: dict, cores: int):
    """The warning line for loaded windows (``LOAD_RULE``), None if no window was loaded."""
    if not loaded:
        return None
    head = f"machine loaded in {len(loaded)} of {n_windows} timed windows ({', '.join(loaded)})"
    if others["max"] is not None:
        return (
            f"{head}: other processes used up to {others['max']:.2f} of {cores} cores "
            f"(median {others['median']:.2f}); the CPU-time figures are less affected than wall "
            "times would be, but caches and frequency are shared"
        )
    return f"{head}: 1-minute load average up to {load['max']} on {cores} cores"


def local_side(run_once, clock: Clock):
    """A side run in this process: ``run_once()`` returns the control steps of one run."""

    def window(runs: int) -> dict:
        c0 = clock.cpu()
        steps = None
        for _ in range(runs):
            steps = run_once()
        return {"cpu_s": clock.cpu() - c0, "steps_per_run": steps, "in_process": True}

    return window


def time_sides(
    local: dict,
    peers: dict,
    pairs: dict,
    rounds: int,
    clock: Clock,
    solo_window_cpu_s: float,
    min_calibration_cpu_s: float,
    log=None,
) -> dict:
    """Time acdrive's ``local`` sides (name -> ``local_side`` window) against the ``peers``'
    (name -> window run by the peer's process). The first peer's calibration window (one run,
    also its warm-up) sets the target window length (``solo_window_cpu_s`` with no peer); each
    local side is calibrated (``calibrate``) and repeats its run to fill that target, as does each
    further peer from its calibration window. The
    rounds run the first local side, the peers, then the other local sides. Returns the
    method, calibration, every window and ``summarise_windows``' spreads, ratios and load."""
    calibration: dict = {}
    runs: dict = {}
    for name, window in peers.items():
        calibration[name] = {"runs": 1, "cpu_s": window(1)["cpu_s"]}
        runs[name] = 1
    target = calibration[next(iter(peers))]["cpu_s"] if peers else solo_window_cpu_s
    for name in list(peers)[1:]:  # a faster peer repeats its run to fill the first one's window
        runs[name] = runs_for_target(calibration[name]["cpu_s"], target)
        calibration[name]["runs_for_target"] = runs[name]
    for name, window in local.items():
        per_run = calibrate(window, clock, min(min_calibration_cpu_s, target))
        calibration[name] = {"per_run_cpu_s": per_run}
        runs[name] = runs_for_target(per_run, target)
    names = list(local)
    order = {n: None for n in [*names[:1], *peers, *names[1:]]}
    sides = {n: (local.get(n) or peers[n]) for n in order}
    windows = interleave(sides, runs, rounds, clock, log)
    return {
        "method": timing_method(rounds),
        "rounds": rounds,
        "target_window_cpu_s": target,
        "target_from": next(iter(peers), None) or "solo_window_cpu_s",
        "runs_per_window": runs,
        "calibration": calibration,
        "windows": windows,
        **summarise_windows(windows, pairs, clock.cores),
    }


def timing_method(rounds: int) -> str:
    """One sentence for the JSON: how the case was timed."""
    return (
        f"{rounds} rounds of interleaved windows (acdrive, peer, ...), each window timed in the "
        "process CPU time of the process that ran it (time.process_time; the peer's measured "
        "inside its own subprocess); the peer runs its case once per window, acdrive repeats its "
        "run to fill a window of about the peer's length and its per-run time is window CPU "
        "time / runs; ratio per round = acdrive's steps per CPU second / the peer's, headline "
        "= median over the rounds"
    )
