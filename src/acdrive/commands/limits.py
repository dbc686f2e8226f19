"""``acdrive limits``: torque limits of case 1 (Bodson (29)-(37)) at a given supply."""

from __future__ import annotations

import json
import math


def register(subparsers):
    p = subparsers.add_parser(
        "limits", help="torque limits of the built-in DFIM (Bodson (30), (32), (37))"
    )
    p.add_argument(
        "--voltage-pk", type=float, default=11.1, help="supply peak line-neutral voltage (V)"
    )
    p.add_argument("--frequency", type=float, default=60.0, help="supply frequency (Hz)")
    p.add_argument(
        "--current-limit-pk",
        type=float,
        default=6.0,
        help="stator and rotor current limit, peak (A)",
    )
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(handler=run)


def run(args) -> int:
    from acdrive.errors import require_positive
    from acdrive.machines.dfim import BODSON_DFIM, machine_vector, torque_limits_case1

    v_pk = require_positive("--voltage-pk", args.voltage_pk)
    f = require_positive("--frequency", args.frequency)
    i_pk = require_positive("--current-limit-pk", args.current_limit_pk)
    from acdrive.frames import K_PEAK as scale  # Bodson (8)

    t1, t2, t3, m2, m3, feasible = torque_limits_case1(
        machine_vector(BODSON_DFIM), 2 * math.pi * f, scale * v_pk, scale * i_pk, scale * i_pk
    )
    out = {
        "tau_max_1": t1,
        "tau_max_2": t2,
        "tau_max_3": t3,
        "tau_lim": min(t1, t2, t3),
        "tau_min_2": m2,
        "tau_min_3": m3,
        "tau_lim_generating": max(m2, m3),
        "rotor_limit_feasible": bool(feasible),
    }
    if args.json:
        print(json.dumps(out))
    else:
        for k, v in out.items():
            print(f"{k:<20} {v:.4f}" if isinstance(v, float) else f"{k:<20} {v}")
    return 0
