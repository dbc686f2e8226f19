"""The native loop's speed, compile time and results under candidate C compiler flags, measured
interleaved in one run: how ``sim._native.NATIVE_CFLAGS`` is chosen.

    python benchmarks/native_flags.py [scenario ...] [--rounds R] [--reps K]

Each candidate is the optimisation level and target of the native library; every candidate
keeps ``-std=c99 -ffp-contract=off -fPIC -pipe`` (no fused multiply-adds: the bit-equality of
the tiers rests on it). For each scenario, R rounds run the candidates in turn (A B C ... A B C
...), each a fresh process that builds the library with that candidate's flags (in a cache of
its own, so the first build is timed as a compile), runs the scenario's drive once to warm up
and then K times in the native tier, timing the compiled loop in process CPU time. Prints JSON:
per scenario and candidate the min / median / max control steps per CPU-second of the loop, the
median over the current flags' median, the compile's CPU seconds (``cc`` as a child process)
and whether the logged data equal the current flags' bit for bit.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

SCENARIOS = ("bodson-ramp", "im-foc-speed", "pm-bly171d-speed")
#: name -> the flags that replace ``-O1`` (the current choice is "O1")
CANDIDATES = {
    "O1": ("-O1",),
    "O2": ("-O2",),
    "O3": ("-O3",),
    "O2-native": ("-O2", "-march=native"),
    "O3-native": ("-O3", "-march=native"),
}
CURRENT = "O1"

WORKER = r"""
import hashlib, json, os, resource, sys, time
level = tuple(os.environ["ACDRIVE_BENCH_LEVEL"].split())
from acdrive.sim import _native
_native.NATIVE_CFLAGS = tuple(f for f in _native.NATIVE_CFLAGS if not f.startswith("-O")) + level
import acdrive.sim._compiled as compiled_module
from acdrive.drives import run_scenario
from acdrive.scenarios import load_scenario

name, reps = sys.argv[1], int(sys.argv[2])
setup = load_scenario(name)
calls = []  # per run_scenario: (steps, loop CPU-s, tiers, data) of each compiled run
original = compiled_module.CompiledSystem.run


def timed(self, *args, **kwargs):
    t0 = time.process_time()
    out = original(self, *args, **kwargs)
    calls[-1].append((out.steps, time.process_time() - t0, out.tier, out.data.tobytes()))
    return out


compiled_module.CompiledSystem.run = timed
before = resource.getrusage(resource.RUSAGE_CHILDREN)
calls.append([])
run_scenario(setup)
after = resource.getrusage(resource.RUSAGE_CHILDREN)
for _ in range(reps):
    calls.append([])
    run_scenario(setup)
first = calls[0]
print(json.dumps({
    "steps": sum(c[0] for c in first),
    "loop_cpu_s": [sum(c[1] for c in call) for call in calls[1:]],
    "compile_cpu_s": (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime),
    "tiers": sorted({c[2] for call in calls for c in call}),
    "digest": hashlib.sha256(b"".join(c[3] for c in first)).hexdigest(),
}))
"""


def _measure(src: str, name: str, flags: tuple, reps: int, cache: str) -> dict:
    env = dict(os.environ, PYTHONPATH=src, XDG_CACHE_HOME=cache,
               ACDRIVE_BENCH_LEVEL=" ".join(flags), ACDRIVE_LOOP_TIER="native")  # fmt: skip
    done = subprocess.run([sys.executable, "-c", WORKER, name, str(reps)], env=env,
                          capture_output=True, text=True, check=True)  # fmt: skip
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv: list[str]) -> int:
    rounds, reps = 3, 3
    for option in ("--rounds", "--reps"):
        if option in argv:
            i = argv.index(option)
            value = int(argv[i + 1])
            del argv[i : i + 2]
            rounds, reps = (value, reps) if option == "--rounds" else (rounds, value)
    names = argv or list(SCENARIOS)
    src = str(Path(__file__).resolve().parents[1] / "src")
    report = {"cpu": _cpu(), "rounds": rounds, "reps": reps, "scenarios": {}}
    with tempfile.TemporaryDirectory(prefix="acdrive-flags-") as scratch:
        for name in names:
            rates = {c: [] for c in CANDIDATES}
            compiles = {c: [] for c in CANDIDATES}
            digests = {c: set() for c in CANDIDATES}
            for r in range(rounds):
                for candidate, flags in CANDIDATES.items():
                    cache = str(Path(scratch) / f"{name}-{candidate}-{r}")
                    out = _measure(src, name, flags, reps, cache)
                    if out["tiers"] != ["native"]:
                        raise SystemExit(f"{name} did not run natively: {out['tiers']}")
                    rates[candidate] += [out["steps"] / s for s in out["loop_cpu_s"] if s > 0]
                    compiles[candidate].append(out["compile_cpu_s"])
                    digests[candidate].add(out["digest"])
            base = statistics.median(rates[CURRENT])
            report["scenarios"][name] = {
                c: {
                    "flags": " ".join(CANDIDATES[c]),
                    "steps_per_cpu_s": {"min": min(v), "median": statistics.median(v),
                                        "max": max(v)},  # fmt: skip
                    "median_over_current": statistics.median(v) / base,
                    "compile_cpu_s_median": statistics.median(compiles[c]),
                    "data_equal_to_current": digests[c] == digests[CURRENT],
                }
                for c, v in rates.items()
            }
    print(json.dumps(report, indent=2))
    return 0


def _cpu() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                flags = Path("/proc/cpuinfo").read_text()
                isa = "AVX-512" if "avx512f" in flags else ("AVX2" if "avx2" in flags else "SSE")
                return f"{line.split(':', 1)[1].strip()} ({isa}, {os.cpu_count()} cores)"
    except OSError:
        pass
    return "unknown"


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
