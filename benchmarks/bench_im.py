"""The matched cage-induction-motor cases against motulator 0.18 (averaged converter and PWM).

A thin wrapper: the implementation is the benchmark suite, ``acdrive._bench.motulator_im``
(see ``acdrive bench --help`` and docs/design.md, "Benchmark suite"). Same as

    acdrive bench --json --only motulator_averaged motulator_pwm [--quick] [--no-peers] ...

Extra arguments are passed on to ``acdrive bench``.
"""

import sys

from acdrive.cli import main

if __name__ == "__main__":
    cases = ["--only", "motulator_averaged", "motulator_pwm"]
    raise SystemExit(main(["bench", "--json", *cases, *sys.argv[1:]]))
