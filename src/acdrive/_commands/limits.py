"""``acdrive limits``: torque limits of case 1 (Bodson (29)-(37)) at a given supply."""

from __future__ import annotations

import math

#: Accepted range of every flag (V, Hz, A): wide for this 11 V, 60 Hz, 6 A machine, and narrow
#: enough that no limit overflows (squares of 1e154 and more are infinite in float64).
FLAG_RANGE = (1e-6, 1e6)

#: The plain output's rows: JSON key -> (unit, meaning). Bodson case 1 (Q = 0), (29)-(37).
ROWS = {
    "tau_max_1": ("N m", "motoring: keeps the root of (24) real, Bodson (30)"),
    "tau_max_2": ("N m", "motoring: stator current at its limit, (32)"),
    "tau_max_3": ("N m", "motoring: rotor current at its limit, (33)-(37)"),
    "tau_lim": ("N m", "motoring torque limit, the smallest of the three"),
    "tau_min_2": ("N m", "generating: stator current at its limit, (32)"),
    "tau_min_3": ("N m", "generating: rotor current at its limit, (33)-(37)"),
    "tau_lim_generating": ("N m", "generating torque limit, the larger (nearer 0) of the two"),
    "rotor_limit_feasible": (
        "-",
        "the rotor current limit exceeds the magnetising current the supply needs",
    ),
}


def register(subparsers):
    p = subparsers.add_parser(
        "limits", help="torque limits of the built-in DFIM (Bodson (30), (32), (37))"
    )
    p.add_argument(
        "--voltage-pk",
        type=float,
        default=11.1,
        help="supply peak line-neutral voltage (V, 1e-6 to 1e6)",
    )
    p.add_argument(
        "--frequency", type=float, default=60.0, help="supply frequency (Hz, 1e-6 to 1e6)"
    )
    p.add_argument(
        "--current-limit-pk",
        type=float,
        default=6.0,
        help="stator and rotor current limit, peak (A, 1e-6 to 1e6)",
    )
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(handler=run)


def run(args) -> int:
    from acdrive._output import strict_json
    from acdrive.errors import require_between, require_positive
    from acdrive.machines._dfim import BODSON_DFIM, machine_vector, torque_limits_case1

    v_pk, f, i_pk = (
        require_between(flag, require_positive(flag, value), *FLAG_RANGE)
        for flag, value in (
            ("--voltage-pk", args.voltage_pk),
            ("--frequency", args.frequency),
            ("--current-limit-pk", args.current_limit_pk),
        )
    )
    from acdrive._frames import K_PEAK as scale  # Bodson (8)

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
        print(strict_json(out))  # never NaN / Infinity (null instead)
    else:
        from acdrive._commands._table import aligned

        print(
            f"Torque limits of the built-in DFIM (Bodson case 1, Q = 0) at {v_pk:g} V peak, "
            f"{f:g} Hz, current limit {i_pk:g} A peak"
        )
        print("\n".join(aligned((key, out[key], *ROWS[key]) for key in out)))
    return 0
