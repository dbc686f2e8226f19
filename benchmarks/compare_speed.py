"""Steps per CPU-second of the compiled drive loop on two source trees, measured in the same run:
a refactor above the engine must not slow the loop.

    python benchmarks/compare_speed.py BEFORE_SRC AFTER_SRC [scenario ...] [--rounds R] [--reps K]

BEFORE_SRC and AFTER_SRC are ``src`` folders of two checkouts (e.g. a worktree of the previous
main). For each scenario, R rounds alternate the two trees (A B A B ...), each round a fresh
process that loads the scenario, loads or compiles its loop, runs it once to warm up and then K
times, timing each run in process CPU time. Prints JSON: per scenario and tree the min / median
/ max steps per CPU-second over all timed runs, and the ratio after / before of the medians,
for the compiled loop alone (``loop``: the time inside the compiled system's ``run``) and for the
whole drive run with its result (``run``).

    python benchmarks/compare_speed.py BEFORE_SRC AFTER_SRC [scenario ...] --machine-code

compares instead the machine code of the compiled loop of the two trees
(``acdrive._bench.loop_speed.compare_machine_code``): per scenario the instruction count and the
number of differing lines.
"""

from __future__ import annotations

import json
import sys

from acdrive._bench.loop_speed import SCENARIOS, compare_machine_code, compare_trees


def main(argv: list[str]) -> int:
    rounds, reps = 4, 3
    if "--rounds" in argv:
        i = argv.index("--rounds")
        rounds = int(argv[i + 1])
        del argv[i : i + 2]
    if "--reps" in argv:
        i = argv.index("--reps")
        reps = int(argv[i + 1])
        del argv[i : i + 2]
    machine_code = "--machine-code" in argv
    if machine_code:
        argv.remove("--machine-code")
    before, after, *names = argv
    if machine_code:
        print(json.dumps(compare_machine_code(before, after, names or SCENARIOS), indent=2))
        return 0
    report = compare_trees(before, after, names or SCENARIOS, rounds, reps)
    print(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
