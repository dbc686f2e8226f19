"""Benchmark: full ICAD of the DeLorenzo IM with controller (20), 100 speeds x 2000 frequencies.

"Full ICAD" is gamma, both channels c_i, both h_i, k_i g_ii, gamma h_j, S_i, T_i and the
coupling (10), batched over the (speed, frequency) grid from state-space data
(``icad_response_arrays``). The peer is python-control's ``frequency_response`` computing only
the plant G(jw) of the same grid (one call per speed), timed in the same run. Prints JSON.

    python benchmarks/bench_icad.py [--repeat N]
"""

from __future__ import annotations

import argparse
import json
import platform
import time

import numpy as np

from acdrive.analysis.freqresp import LTI
from acdrive.analysis.icad import icad_response_arrays, stack_plants
from acdrive.analysis.plants import plants_for

N_SPEEDS, N_FREQ = 100, 2000


def best_of(fn, repeat: int) -> float:
    """Smallest wall time of ``repeat`` calls after one warm-up call [s]."""
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()

    speeds = np.linspace(0.0, 375.0, N_SPEEDS)
    w = np.logspace(0.0, 5.0, N_FREQ)
    k = LTI.paper_20()
    plants = plants_for("delorenzo-im", speeds)
    A, B, C, D, sp = stack_plants(plants)

    def ours():
        return icad_response_arrays(A, B, C, D, k, k, w, sp)

    t_build = best_of(lambda: stack_plants(plants_for("delorenzo-im", speeds)), 3)
    t_ours = best_of(ours, args.repeat)
    result = {
        "benchmark": "icad_delorenzo_paper20",
        "grid": {"speeds": N_SPEEDS, "frequencies": N_FREQ},
        "acdrive_full_icad_ms": round(1e3 * t_ours, 2),
        "acdrive_plant_build_ms": round(1e3 * t_build, 2),
        "target_ms": 50.0,
        "meets_target": t_ours <= 0.050,
        "python": platform.python_version(),
        "numpy": np.__version__,
    }
    try:
        import control
    except ImportError:  # pragma: no cover - optional peer
        result["peer"] = None
    else:
        systems = [control.ss(p.A, p.B, p.C, p.D) for p in plants]

        def peer():
            return [sys.frequency_response(w).complex for sys in systems]

        t_peer = best_of(peer, max(1, args.repeat // 3))
        G_peer = np.stack([np.moveaxis(g, -1, 0) for g in peer()])
        err = float(np.max(np.abs(ours().G - G_peer) / np.maximum(np.abs(G_peer), 1e-300)))
        result.update(
            {
                "peer": f"python-control {control.__version__} frequency_response (plant only)",
                "peer_plant_only_ms": round(1e3 * t_peer, 2),
                "speedup_vs_peer": round(t_peer / t_ours, 1),
                "max_rel_diff_plant_vs_peer": err,
            }
        )
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
