"""Compare the parts-built DFIM drive (``acdrive.drives.dfim._drive``) with the previous engine
(frozen in ``benchmarks/previous_engine``) on the nine built-in scenarios it knows (``ORIGINAL``; the
fault scenarios added later use parts it does not have): prints JSON with, per scenario and mode,
the largest difference of each logged signal relative to that signal's peak magnitude.

Run: ACDRIVE_STRICT_MATH=1 python benchmarks/compare_engines.py [scenario ...]

With ACDRIVE_STRICT_MATH=1 both are compiled with strict IEEE arithmetic (``acdrive._jit``), so any
difference comes from the order of operations in the two sources alone; with the default
fast-math build the compiler's contraction choices differ between the two (last-bit differences
that a quantised encoder can turn into one count now and then).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from previous_engine import simulate_previous_engine

from acdrive._jit import STRICT_MATH
from acdrive.drives.dfim import _drive as dfim_drive
from acdrive.drives.dfim._result import LOG_NAMES
from acdrive.scenarios import load_scenario

TOLERANCE = 1e-12
#: the built-in scenarios the previous engine can run (its parts: balanced source, fixed DC link,
#: relay commanded by the synchroniser)
ORIGINAL = (
    "bodson-mixed-steps", "bodson-ramp", "bodson-ramp-ideal", "bodson-sensor-fault", "bodson-step",
    "bodson-sync", "bodson-three-motors", "bodson-two-motors", "bodson-varying-supply",
)  # fmt: skip


def compare(a, b) -> dict:
    out = {}
    for j, name in enumerate(LOG_NAMES):
        x, y = a.signals[:, :, j], b.signals[:, :, j]
        scale = max(np.max(np.abs(x)), np.max(np.abs(y)), 1e-300)
        out[name] = float(np.max(np.abs(x - y)) / scale)
    return out


def main(names):
    report = {}
    for name in names or ORIGINAL:
        setup = load_scenario(name)
        modes = setup.compare_modes or (None,)
        for mode in modes:
            s = setup.with_mode(mode) if mode else setup
            old = simulate_previous_engine(s)
            new = dfim_drive.simulate(s)
            diffs = compare(old, new)
            worst = max(diffs, key=diffs.get)
            report[f"{name}{'/' + mode if mode else ''}"] = {
                "worst_signal": worst,
                "worst_relative_difference": diffs[worst],
                "within_tolerance": diffs[worst] <= TOLERANCE,
                "old_wall_s": old.wall_time,
                "new_wall_s": new.wall_time,
            }
    print(
        json.dumps(
            {"strict_math": STRICT_MATH, "tolerance": TOLERANCE, "scenarios": report}, indent=2
        )
    )


if __name__ == "__main__":
    main(sys.argv[1:])
