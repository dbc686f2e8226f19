"""How far acdrive's matched cage-IM case is from motulator 0.18's, and which controller
difference accounts for how much (``acdrive._bench.matched_differences.remaining_differences``).

motulator runs the case as its example has it, then with acdrive's speed PI law (clamping
anti-windup at the fixed torque limit) in place of its own (back-calculation on the torque the
current limit realises), and with its own PI clipped at acdrive's fixed torque limit before the
current limit (what a back-calculating speed PI at a fixed limit would leave). Each line prints the largest speed and current
differences to acdrive's run relative to motulator's peaks, the speed difference per phase, and
the variant's own distance from motulator's example.
Needs motulator's virtualenv (``acdrive bench`` makes it; ``--peers-dir`` as there):

    python benchmarks/bench_matched_im.py [--seconds 1.5] [--converter averaged] [--json]
"""

import argparse
import json
import sys
from pathlib import Path

from acdrive._bench.matched_differences import remaining_differences
from acdrive._bench.motulator_im import CONVERTERS, DURATION
from acdrive._bench.venvs import MOTULATOR, default_peers_dir, ensure_venv


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=DURATION)
    parser.add_argument("--converter", choices=CONVERTERS, default="averaged")
    parser.add_argument("--peers-dir", type=Path, default=None)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    log = lambda m: print(m, file=sys.stderr)  # noqa: E731
    peer = ensure_venv(MOTULATOR, args.peers_dir or default_peers_dir(), log)
    if not peer["available"]:
        print(f"motulator not available: {peer['reason']}", file=sys.stderr)
        return 1
    out = remaining_differences(peer, args.seconds, args.converter, log)
    if args.json:
        print(json.dumps(out, indent=1))
        return 0
    rpm = 60.0 / (2.0 * 3.141592653589793)
    for name, d in out["variants"].items():
        phases = ", ".join(
            f"{k} {v['max_abs_rad_s'] * rpm:.3g} rpm" for k, v in d["speed_by_phase"].items()
        )
        own = d["vs_motulators_example"]
        print(
            f"{name:<22} to acdrive: speed {d['speed_max_rel_to_peak']:.2e}, current "
            f"{d['current_max_rel_to_peak']:.2e} of the peak; largest |dw| by phase: {phases}; "
            f"to motulator's example: speed {own['speed_max_abs_rad_s'] * rpm:.3g} rpm "
            f"({own['speed_max_rel_to_peak']:.2e} of the peak)"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
