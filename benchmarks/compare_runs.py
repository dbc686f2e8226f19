"""Prove a refactor left the results unchanged: run every built-in scenario through the command
line (``acdrive run NAME --no-figures``) with strict IEEE arithmetic, keep the data files, and
compare two such snapshots signal by signal.

The command line is the comparison's interface on purpose: it stays the same while the modules
behind it move, so a snapshot taken on one commit compares with one taken on another.

    ACDRIVE_STRICT_MATH=1 is set by this script for the runs it starts.

    python benchmarks/compare_runs.py save SNAPSHOT_DIR [scenario ...]
    python benchmarks/compare_runs.py compare BEFORE_DIR AFTER_DIR

``compare`` prints JSON: per data file the worst column and its largest difference relative to
that column's peak magnitude, and exits 1 when any column differs by more than the tolerance
(1e-15 of its peak), when a file or column exists on one side only, or when the lengths differ.
Text columns (event names, modes) must be equal. Each scenario's ``summary.json`` is compared too:
every number within SUMMARY_REL_TOL relative, every text and flag equal, the same keys on both
sides; timing entries (wall or CPU time, compile time) are left out.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd

TOLERANCE = 1e-15
#: summary numbers are computed from the signals: equal signals give them to rounding
SUMMARY_REL_TOL = 1e-12
#: summary entries that measure the machine, not the result
TIMING_WORDS = ("wall", "cpu", "compile", "elapsed")
#: the console script installed beside this interpreter
ACDRIVE = str(Path(sys.executable).with_name("acdrive"))


def builtin_names() -> list[str]:
    from acdrive.scenarios import builtin_names

    return sorted(builtin_names())


def save(folder: Path, names: list[str]) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, ACDRIVE_STRICT_MATH="1")
    for name in names or builtin_names():
        cmd = [ACDRIVE, "run", name, "--no-figures", "--out", str(folder)]
        done = subprocess.run(cmd, check=False, env=env, capture_output=True, text=True)
        status = "ok" if done.returncode == 0 else f"exit {done.returncode}"
        print(f"{name}: {status}", file=sys.stderr)
        if done.returncode != 0:
            print(done.stderr, file=sys.stderr)


def _columns(path: Path) -> pd.DataFrame:
    return pd.read_parquet(path)


def compare_frames(a: pd.DataFrame, b: pd.DataFrame) -> dict:
    """Largest difference of each column relative to its peak magnitude (NaN-aware: a NaN on
    one side only counts as a difference of 1)."""
    if list(a.columns) != list(b.columns):
        return {"columns_differ": sorted(set(a.columns) ^ set(b.columns)) or "order"}
    if len(a) != len(b):
        return {"lengths_differ": [len(a), len(b)]}
    out = {}
    for c in a.columns:
        x, y = a[c].to_numpy(), b[c].to_numpy()
        if x.dtype.kind not in "fciub" or y.dtype.kind not in "fciub":
            out[c] = 0.0 if np.array_equal(x.astype(str), y.astype(str)) else 1.0
            continue
        x, y = x.astype(complex), y.astype(complex)
        nan_x, nan_y = np.isnan(x), np.isnan(y)
        if np.any(nan_x != nan_y):
            out[c] = 1.0
            continue
        ok = ~nan_x
        scale = max(np.max(np.abs(x[ok]), initial=0.0), np.max(np.abs(y[ok]), initial=0.0))
        diff = np.max(np.abs(x[ok] - y[ok]), initial=0.0)
        out[c] = float(diff / scale) if scale > 0 else float(diff)
    return out


def _flatten(x, path: str = "") -> dict:
    if isinstance(x, dict):
        return {k: v for key, val in x.items() for k, v in _flatten(val, f"{path}/{key}").items()}
    if isinstance(x, list):
        return {k: v for i, val in enumerate(x) for k, v in _flatten(val, f"{path}[{i}]").items()}
    return {path: x}


def compare_summaries(a: dict, b: dict) -> list[str]:
    """The summary entries that differ (timing entries left out)."""
    fa, fb = _flatten(a), _flatten(b)
    differ = []
    for key in sorted(set(fa) | set(fb)):
        if any(word in key.lower() for word in TIMING_WORDS):
            continue
        x, y = fa.get(key, "<missing>"), fb.get(key, "<missing>")
        numbers = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in (x, y))
        if numbers:
            same = x == y or abs(x - y) <= SUMMARY_REL_TOL * max(abs(x), abs(y))
        else:
            same = x == y
        if not same:
            differ.append(f"{key}: {x!r} -> {y!r}")
    return differ


def compare(before: Path, after: Path) -> int:
    files_a = {p.relative_to(before) for p in before.rglob("*.parquet")}
    files_b = {p.relative_to(after) for p in after.rglob("*.parquet")}
    report, failed = {}, False
    for rel in sorted(files_a | files_b, key=str):
        if rel not in files_a or rel not in files_b:
            report[str(rel)] = {"only_in": "before" if rel in files_a else "after"}
            failed = True
            continue
        diffs = compare_frames(_columns(before / rel), _columns(after / rel))
        numeric = {k: v for k, v in diffs.items() if isinstance(v, float)}
        if len(numeric) != len(diffs):
            report[str(rel)] = diffs
            failed = True
            continue
        worst = max(numeric, key=numeric.get)
        ok = numeric[worst] <= TOLERANCE
        failed |= not ok
        report[str(rel)] = {"worst_column": worst, "relative_difference": numeric[worst],
                            "within_tolerance": ok}  # fmt: skip
    for path in sorted(before.rglob("summary.json")):
        rel = path.relative_to(before)
        other = after / rel
        if not other.exists():
            report[str(rel)] = {"only_in": "before"}
            failed = True
            continue
        differ = compare_summaries(json.loads(path.read_text()), json.loads(other.read_text()))
        report[str(rel)] = {"entries_differ": differ[:20], "n_differ": len(differ)}
        failed |= bool(differ)
    print(json.dumps({"tolerance": TOLERANCE, "files": report, "all_within": not failed},
                     indent=2))  # fmt: skip
    return 1 if failed or not report else 0


def main(argv: list[str]) -> int:
    if len(argv) >= 2 and argv[0] == "save":
        save(Path(argv[1]), argv[2:])
        return 0
    if len(argv) == 3 and argv[0] == "compare":
        return compare(Path(argv[1]), Path(argv[2]))
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
