"""``acdrive identify``: a cage IM's parameters from standstill tests, with 95 % intervals.

``TEST_FILE_OR_SCENARIO`` is either the injection log of a measured test (``.csv``, ``.parquet``
or ``.mat``, columns ``time [s]``, ``v_a [V]``, ``i_a [A]``; ``--dc-log`` adds the DC-step log)
or the name of a built-in cage IM, whose standstill tests are then simulated on acdrive's
inverter-fed, locked-rotor bench (``identify._experiment``) with sensor noise and the dead time
and device drop given. Prints the table (quantity, value, unit, the two 95 % intervals, meaning)
and what the data do and do not identify; writes the machine parameter file (``--out``).
"""

from __future__ import annotations

import sys

LOG_SUFFIXES = (".csv", ".parquet", ".mat")
#: the intervals printed beside each value
INTERVAL_HEADER = (
    "quantity",
    "value",
    "unit",
    "95% CI (Jacobian)",
    "95% CI (bootstrap)",
    "meaning",
)


def register(subparsers):
    from acdrive.identify._circuit import LEAKAGE_SPLITS

    p = subparsers.add_parser(
        "identify",
        help="cage IM parameters from standstill tests (DC steps, multisine) with 95-percent intervals",
    )
    p.add_argument("source", metavar="TEST_FILE_OR_SCENARIO",
                   help="injection log (.csv / .parquet / .mat) or a built-in cage IM to simulate")  # fmt: skip
    p.add_argument("--dc-log", help="DC-step log (.csv / .parquet / .mat) of a measured test")
    p.add_argument("--base-frequency-hz", type=float, default=None,
                   help="step between the injected tones (Hz; default that of the built-in test)")  # fmt: skip
    p.add_argument("--settle-s", type=float, default=None,
                   help="time dropped at the start of the injection log (s; default the built-in test's)")  # fmt: skip
    p.add_argument("--pole-pairs", type=int, default=None,
                   help="pole pairs (not identifiable at standstill; required for a measured log)")  # fmt: skip
    p.add_argument("--leakage-split", choices=tuple(LEAKAGE_SPLITS), default="equal",
                   help="assumed split of the leakage for the T-circuit written (default equal)")  # fmt: skip
    p.add_argument("--dead-time-s", type=float, default=0.0,
                   help="simulated test: the inverter's dead time (s) [0]")  # fmt: skip
    p.add_argument("--device-drop-v", type=float, default=0.0,
                   help="simulated test: the inverter's device drop (V) [0]")  # fmt: skip
    p.add_argument("--seed", type=int, default=0,
                   help="seed of the simulated sensor noise and of the bootstrap [0]")  # fmt: skip
    p.add_argument("--out", default="identified-machine.toml",
                   help="machine parameter file to write (TOML) [identified-machine.toml]")  # fmt: skip
    p.add_argument("--json", action="store_true", help="print JSON instead of the table")
    p.set_defaults(handler=run)


def _logs(args, plan):
    """(injection log, DC log or None, pole pairs, base frequency, settle) of the command."""
    from pathlib import Path

    from acdrive.errors import InputError, require_between, require_nonnegative, require_positive
    from acdrive.identify._experiment import dc_test, injection_test
    from acdrive.identify._log import read_log
    from acdrive.machines._induction import IMParams
    from acdrive.machines._registry import MACHINES, names

    base = plan.base_frequency if args.base_frequency_hz is None else args.base_frequency_hz
    require_positive("--base-frequency-hz", base)
    settle = plan.settle if args.settle_s is None else args.settle_s
    require_nonnegative("--settle-s", settle)
    if args.pole_pairs is not None:
        require_between("--pole-pairs", args.pole_pairs, 1, 1000)
    if Path(args.source).suffix in LOG_SUFFIXES:
        for flag in ("dead_time_s", "device_drop_v"):
            if getattr(args, flag) != 0.0:
                raise InputError(f"--{flag.replace('_', '-')}", "is for a simulated test only")
        if args.pole_pairs is None:
            raise InputError("--pole-pairs", "is required for a measured log (a standstill test "
                             "cannot tell it)")  # fmt: skip
        injection = read_log(args.source, "TEST_FILE_OR_SCENARIO")
        dc = read_log(args.dc_log, "--dc-log") if args.dc_log else None
        return injection, dc, args.pole_pairs, base, settle
    if args.source not in names(IMParams):
        raise InputError("TEST_FILE_OR_SCENARIO", f"neither a {' / '.join(LOG_SUFFIXES)} log nor "
                         f"a built-in cage IM (known: {', '.join(names(IMParams))})")  # fmt: skip
    if args.dc_log:
        raise InputError("--dc-log", "is for a measured test; a simulated test makes its own")
    machine = MACHINES[args.source]
    import dataclasses

    t_d = require_nonnegative("--dead-time-s", args.dead_time_s)
    v_drop = require_nonnegative("--device-drop-v", args.device_drop_v)
    plan = dataclasses.replace(plan, t_d=t_d, v_drop=v_drop, base_frequency=base, settle=settle)
    from acdrive.plant._inverter import Inverter

    try:
        Inverter("inverter", f_pwm=plan.f_pwm, t_d=plan.t_d)
    except InputError as exc:
        raise InputError("--dead-time-s", exc.rule) from None
    n_p = machine.n_p if args.pole_pairs is None else args.pole_pairs
    return (injection_test(machine, plan, seed=2 * args.seed + 1),
            dc_test(machine, plan, seed=2 * args.seed), n_p, base, settle)  # fmt: skip


def _rows(result):
    """(quantity, estimate): quantities dotted as the JSON output names them."""
    rows = [(f"inverse_gamma.{e.name}", e) for e in result.impedance.estimates]
    rows += [(f"t_circuit.{e.name}", e) for e in result.t_estimates]
    if result.dc is not None:
        dc = result.dc
        rows += [(f"dc_steps.{e.name}", e) for e in (dc.R_s, dc.voltage_error, dc.single_level)]
    return rows


def _json(result, path) -> dict:
    from acdrive.identify._standstill import identifiability

    def entry(e):
        return {"value": e.value, "unit": e.unit, "ci95_jacobian": list(e.jacobian),
                "ci95_bootstrap": list(e.bootstrap), "meaning": e.meaning}  # fmt: skip

    fit = result.impedance
    out = {
        "inverse_gamma": {e.name: entry(e) for e in fit.estimates},
        "t_circuit": {e.name: entry(e) for e in result.t_estimates},
        "leakage_split": result.split,
        "n_p": result.n_p,
        "residual_rms_a": fit.residual_rms,
        "residual_relative": fit.residual_relative,
        "tones_hz": list(fit.spectrum.frequency),
        "statement": identifiability(result),
        "written": str(path),
    }
    if result.dc is not None:
        dc = result.dc
        out["dc_steps"] = {e.name: entry(e) for e in (dc.R_s, dc.voltage_error, dc.single_level)}
    return out


def run(args) -> int:
    from acdrive._commands._table import format_value
    from acdrive.identify._experiment import StandstillPlan
    from acdrive.identify._fit import FitNotConverged
    from acdrive.identify._params_file import check_target, params_text, write_params
    from acdrive.identify._standstill import identifiability, identify_standstill

    target = check_target(args.out)  # before any work
    plan = StandstillPlan()
    injection, dc, n_p, base, settle = _logs(args, plan)
    try:
        result = identify_standstill(injection, base, settle, dc=dc, n_p=n_p,
                                     split=args.leakage_split, seed=args.seed)  # fmt: skip
    except FitNotConverged as exc:
        sys.stderr.write(f"acdrive: error: {exc}\n")
        return 1
    path = write_params(target, params_text(result, args.source))
    if args.json:
        from acdrive._output import strict_json

        print(strict_json(_json(result, path), indent=2))
        return 0

    def interval(pair):
        return f"[{format_value(pair[0])}, {format_value(pair[1])}]"

    cells = [INTERVAL_HEADER] + [
        (name, format_value(e.value), e.unit, interval(e.jacobian), interval(e.bootstrap),
         e.meaning) for name, e in _rows(result)
    ]  # fmt: skip
    widths = [max(len(row[i]) for row in cells) for i in range(5)]
    print(f"Standstill identification of {args.source}")
    for row in cells:
        print("  ".join(f"{c:<{w}}" if i != 1 else f"{c:>{w}}"
                        for i, (c, w) in enumerate(zip(row[:5], widths, strict=True)))
              + "  " + row[5])  # fmt: skip
    fit = result.impedance
    print(f"residual: {format_value(fit.residual_rms)} A rms over {fit.spectrum.frequency.size} "
          f"tones ({format_value(fit.residual_relative)} of the currents), {fit.dof} degrees of freedom")  # fmt: skip
    for line in identifiability(result):
        print(f"  {line}")
    print(f"wrote {path}")
    return 0
