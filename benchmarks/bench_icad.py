"""Full ICAD of the DeLorenzo IM with controller (20), 100 speeds x 2,000 frequencies.

A thin wrapper: the implementation is ``acdrive._bench.icad``, part of the benchmark suite. Same
as ``acdrive bench --json --only icad``; the JSON's ``icad_ms`` is the full ICAD's best time and
``cases.icad.peer`` python-control's plant-only frequency response on the same grid.
"""

import sys

from acdrive.cli import main

if __name__ == "__main__":
    raise SystemExit(main(["bench", "--json", "--only", "icad", *sys.argv[1:]]))
