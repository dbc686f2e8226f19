"""Whole-process CPU time of ``acdrive run bodson-ramp``, warm and after an empty cache, against
the targets of issue 21 item 3 (a benchmark, never a test: it prints what it measures).

    python benchmarks/bench_command.py [--runs N] [--cold-runs M] [--scenario NAME]
                                       [--baseline OTHER_CHECKOUT/src] [--json]

What is measured, each in a fresh process started by this script and timed by the kernel's
account of that process alone (``os.wait4``: user + system CPU time of the child, its own
children included once they are waited for):

* **warm**: ``acdrive run SCENARIO --out TMP`` (data, summary.json, figures) and the same with
  ``--no-figures``, N times each, interleaved (with, without, with, ...) after one untimed run
  of each that fills the compile cache; targets 1.0 and 0.6 CPU-s (issue 21 item 3). With
  ``--baseline SRC`` the same runs of another checkout (``SRC`` first on PYTHONPATH; it keeps a
  compile cache of its own, keyed by its sources) are interleaved with them: before and after
  measured under the same load.
* **cold**: the first ``acdrive run SCENARIO`` (with its figures) after an empty cache
  (``XDG_CACHE_HOME`` a fresh temporary folder, ``NUMBA_CACHE_DIR`` unset), M times; target
  6 s wall on an idle machine. Its CPU time is given too: on a loaded machine the wall time
  grows with the load, the CPU time much less.
* **durations** (``--durations``): ``acdrive run --no-figures`` of copies of SCENARIO lasting
  1, 10 and 100 s (its ``simulation.duration`` replaced), N times each, interleaved: the
  process's CPU seconds per simulated second at each duration, the spread of those (target: the
  largest at most 1.2 times the smallest, issue 39 item 4), and the CPU per simulated second
  beyond the 1 s run, ``(cpu(D) - cpu(1 s)) / (D - 1 s)``, which leaves out what every process
  pays once. The log each run keeps is the default (``acdrive.sim._log_plan``).
* **floors**: the libraries' own costs, each a process of its own, N times: the
  interpreter (``python -c pass``), ``import numpy``, ``import numba``, ``import numba`` and
  one call of a function numba loads from its on-disk cache (the first such load initialises
  numba's CPU target: its lowering registries, which import ``scipy.linalg`` to find BLAS),
  the same ending as acdrive's console script ends (``gc.freeze``, ``acdrive.cli.command``),
  ``import pyarrow.parquet`` and matplotlib's ``Figure`` with the Agg canvas.

Every target has its measured value (the median of its runs, with min and max) and ``met``,
computed as ``median <= target``. The load average before and after and the number of CPUs are
recorded beside them: on a machine shared with other work the CPU time of a process rises too
(shared caches and cores), so a figure taken under load is an upper bound of the idle one.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: whole-process CPU seconds of a warm run (with figures: issue 39 item 5; without: issue 21
#: item 3), wall seconds of the first run (issue 21 item 3), and the largest over the smallest
#: CPU per simulated second from 1 s to 100 s (issue 39 item 4)
TARGETS = {
    "warm_run_with_figures_cpu_s": 0.6,
    "cpu_per_simulated_second_spread": 1.2,
    "warm_run_no_figures_cpu_s": 0.6,
    "first_run_empty_cache_wall_s": 6.0,
}
#: the console script installed beside this interpreter
ACDRIVE = str(Path(sys.executable).with_name("acdrive"))

#: a module whose one function numba compiles once and then loads from its cache
_NUMBA_CACHED = """from numba import njit


@njit(cache=True)
def f(x):
    return x + 1.0


f(1.0)
"""

FLOORS = {
    "python_start": ["-c", "pass"],
    "import_numpy": ["-c", "import numpy"],
    "import_numba": ["-c", "import numba"],
    "import_pyarrow_parquet": ["-c", "import pyarrow.parquet"],
    "import_matplotlib_figure_agg": [
        "-c",
        (
            "from matplotlib.figure import Figure; "
            "from matplotlib.backends.backend_agg import FigureCanvasAgg"
        ),
    ],
}


def timed(cmd: list[str], env: dict | None = None, cwd: str | None = None) -> dict:
    """Run ``cmd`` to its end; its CPU seconds (user + system, from ``os.wait4``), its wall
    seconds and its exit code. Its output is discarded; a failure is raised with its stderr."""
    start = time.perf_counter()
    proc = subprocess.Popen(
        cmd, env=env, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
    )
    stderr = proc.stderr.read()
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    proc.returncode = os.waitstatus_to_exitcode(status)
    proc.stderr.close()
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} exited {proc.returncode}: {stderr.strip()}")
    return {"cpu_s": usage.ru_utime + usage.ru_stime, "wall_s": wall}


def spread(values: list[float]) -> dict:
    """min / median / max of ``values`` and how many there are."""
    return {
        "min": min(values),
        "median": statistics.median(values),
        "max": max(values),
        "n": len(values),
    }


def verdict(name: str, values: list[float]) -> dict:
    """The spread of ``values`` with the target ``TARGETS[name]`` and ``met`` (median <= target)."""
    out = spread(values)
    out["target"] = TARGETS[name]
    out["met"] = out["median"] <= TARGETS[name]
    return out


def load() -> dict:
    one, five, fifteen = os.getloadavg()
    return {"1min": one, "5min": five, "15min": fifteen}


def warm_runs(scenario: str, runs: int, out: Path, baseline: str | None = None) -> dict:
    """N interleaved runs with and without figures, after one untimed run of each; with
    ``baseline`` (the ``src`` folder of another acdrive checkout, put first on PYTHONPATH) the
    same runs of that code interleaved with them (this, baseline, this, baseline, ...)."""
    arguments = {"with": ["run", scenario, "--out", str(out)]}
    arguments["without"] = [*arguments["with"], "--no-figures"]
    sides = {"this": ([ACDRIVE], None)}
    if baseline is not None:
        path = os.pathsep.join(p for p in (baseline, os.environ.get("PYTHONPATH")) if p)
        # the baseline's own entry point: the console script of this checkout may not exist there
        entry = [sys.executable, "-c", "import sys; from acdrive.cli import main; sys.exit(main())"]
        sides["baseline"] = (entry, dict(os.environ, PYTHONPATH=path))
    for entry, env in sides.values():
        for args in arguments.values():
            timed([*entry, *args], env=env)  # fills the compile cache if empty; not counted
    times = {(side, kind): [] for side in sides for kind in arguments}
    for _ in range(runs):
        for kind, args in arguments.items():
            for side, (entry, env) in sides.items():
                times[side, kind].append(timed([*entry, *args], env=env)["cpu_s"])
    out = {
        "warm_run_with_figures_cpu_s": verdict(
            "warm_run_with_figures_cpu_s", times["this", "with"]
        ),
        "warm_run_no_figures_cpu_s": verdict("warm_run_no_figures_cpu_s", times["this", "without"]),
    }
    if baseline is not None:
        out["baseline_warm_run_with_figures_cpu_s"] = spread(times["baseline", "with"])
        out["baseline_warm_run_no_figures_cpu_s"] = spread(times["baseline", "without"])
    return out


#: simulated seconds of the ``--durations`` runs
DURATIONS_S = (1.0, 10.0, 100.0)


def duration_runs(scenario: str, runs: int, scratch: Path) -> dict:
    """``acdrive run --no-figures`` of copies of ``scenario`` lasting each of ``DURATIONS_S``
    (module docstring), after one untimed run of each."""
    import re

    from acdrive.scenarios._loader import builtin_names, builtin_text

    text = builtin_text(scenario) if scenario in builtin_names() else Path(scenario).read_text()
    files = {}
    for duration in DURATIONS_S:
        copy, n = re.subn(r"(?m)^duration\s*=.*$", f"duration = {duration!r}", text, count=1)
        if n != 1:
            raise SystemExit(f"--durations: no 'duration = ...' line in {scenario}")
        files[duration] = scratch / f"duration-{duration:g}s.toml"
        files[duration].write_text(copy)
    command = {d: [ACDRIVE, "run", str(f), "--no-figures", "--out", str(scratch / "durations")]
               for d, f in files.items()}  # fmt: skip
    for cmd in command.values():
        timed(cmd)
    cpu = {d: [] for d in DURATIONS_S}
    for _ in range(runs):
        for d, cmd in command.items():
            cpu[d].append(timed(cmd)["cpu_s"])
    median = {d: statistics.median(v) for d, v in cpu.items()}
    per_second = {d: median[d] / d for d in DURATIONS_S}
    first = DURATIONS_S[0]
    out = {
        "cpu_s": {f"{d:g}": spread(v) for d, v in cpu.items()},
        "cpu_per_simulated_second": {f"{d:g}": per_second[d] for d in DURATIONS_S},
        "cpu_per_simulated_second_beyond_first": {
            f"{d:g}": (median[d] - median[first]) / (d - first) for d in DURATIONS_S[1:]
        },
    }
    largest, smallest = max(per_second.values()), min(per_second.values())
    out["cpu_per_simulated_second_spread"] = {
        "value": largest / smallest,
        "target": TARGETS["cpu_per_simulated_second_spread"],
        "met": largest / smallest <= TARGETS["cpu_per_simulated_second_spread"],
    }
    return out


def cold_runs(scenario: str, runs: int, out: Path) -> dict:
    """The first run after an empty cache, ``runs`` times, each with a cache folder of its own."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("NUMBA_CACHE_DIR", "ACDRIVE_NUMBA_CACHE_DIR")}  # fmt: skip
    wall, cpu = [], []
    for _ in range(runs):
        with tempfile.TemporaryDirectory(prefix="acdrive-cold-cache-") as cache:
            env["XDG_CACHE_HOME"] = cache
            t = timed([ACDRIVE, "run", scenario, "--out", str(out)], env=env)
        wall.append(t["wall_s"])
        cpu.append(t["cpu_s"])
    return {
        "first_run_empty_cache_wall_s": verdict("first_run_empty_cache_wall_s", wall),
        "first_run_empty_cache_cpu_s": spread(cpu),
    }


def floors(runs: int, scratch: Path) -> dict:
    """CPU seconds of the processes acdrive cannot make cheaper (module docstring)."""
    module = scratch / "numba_cached.py"
    module.write_text(_NUMBA_CACHED)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(scratch / "numba-cache"))
    commands = {name: [sys.executable, *args] for name, args in FLOORS.items()}
    commands["import_numba_and_load_one_cached_function"] = [sys.executable, str(module)]
    # the same with the exit acdrive's console script takes (acdrive.cli.command: gc.freeze)
    commands["import_numba_and_load_one_cached_function_frozen_exit"] = [
        sys.executable,
        "-c",
        f"import sys, gc; sys.path.insert(0, {str(scratch)!r}); import numba_cached; gc.freeze()",
    ]
    timed(commands["import_numba_and_load_one_cached_function"], env=env)  # compiles it once
    out = {}
    for name, cmd in commands.items():
        out[name] = spread([timed(cmd, env=env)["cpu_s"] for _ in range(runs)])
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenario", default="bodson-ramp")
    parser.add_argument("--runs", type=int, default=5, help="warm runs of each kind (default 5)")
    parser.add_argument(
        "--cold-runs", type=int, default=1, help="runs after an empty cache (default 1; 0: none)"
    )
    parser.add_argument(
        "--baseline",
        metavar="SRC",
        help="the src folder of another acdrive checkout (e.g. a git worktree of main): its warm "
        "runs are timed interleaved with this one's",
    )
    parser.add_argument(
        "--durations",
        action="store_true",
        help="also time copies of the scenario lasting 1, 10 and 100 s (CPU per simulated second)",
    )
    parser.add_argument("--json", action="store_true", help="print JSON only")
    args = parser.parse_args(argv)
    if args.runs < 1 or args.cold_runs < 0:
        parser.error("--runs must be at least 1 and --cold-runs at least 0")
    report = {
        "scenario": args.scenario,
        "acdrive": ACDRIVE,
        "python": sys.version.split()[0],
        "cpus": os.cpu_count(),
        "load_before": load(),
        "rule": "met = median <= target; CPU seconds are user + system of the whole process "
        "(os.wait4); wall seconds from start to exit",
    }
    with tempfile.TemporaryDirectory(prefix="acdrive-bench-command-") as scratch:
        scratch = Path(scratch)
        report["warm"] = warm_runs(args.scenario, args.runs, scratch / "out", args.baseline)
        if args.cold_runs:
            report["cold"] = cold_runs(args.scenario, args.cold_runs, scratch / "out")
        if args.durations:
            report["durations"] = duration_runs(args.scenario, args.runs, scratch)
        report["floors_cpu_s"] = floors(args.runs, scratch)
    report["load_after"] = load()
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    print(f"acdrive run {args.scenario}: {os.cpu_count()} CPUs, load average before "
          f"{report['load_before']['1min']:.2f}, after {report['load_after']['1min']:.2f}")  # fmt: skip
    results = {**report["warm"], **report.get("cold", {})}
    for name, r in results.items():
        met = "met" if r.get("met") else "NOT met"
        target = f" target {r['target']:g} -> {met}" if "target" in r else ""
        print(f"  {name:<34} min {r['min']:.3f}  median {r['median']:.3f}  max {r['max']:.3f}"
              f"  (n={r['n']}){target}")  # fmt: skip
    if "durations" in report:
        durations = report["durations"]
        print("  CPU per simulated second (median process CPU / duration; beyond the 1 s run):")
        for d, value in durations["cpu_per_simulated_second"].items():
            beyond = durations["cpu_per_simulated_second_beyond_first"].get(d)
            extra = f"  beyond 1 s {beyond * 1e3:.2f} ms" if beyond is not None else ""
            print(f"    {d:>4} s  {value * 1e3:.2f} ms{extra}")
        r = durations["cpu_per_simulated_second_spread"]
        met = "met" if r["met"] else "NOT met"
        print(f"    largest / smallest {r['value']:.2f}  target {r['target']:g} -> {met}")
    print("  floors (CPU s, median):")
    for name, r in report["floors_cpu_s"].items():
        print(f"    {name:<44} {r['median']:.3f}  (min {r['min']:.3f}, max {r['max']:.3f})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
