"""``acdrive identify``: a cage IM's parameters from standstill tests, with 95 % intervals.

``TEST_FILE_OR_SCENARIO`` is either the injection log of a measured test (``.csv``, ``.parquet``
or ``.mat``, columns ``time [s]``, ``v_a [V]``, ``i_a [A]``; ``--dc-log`` adds the DC-step log)
or the name of a built-in cage IM, whose standstill tests are then simulated on acdrive's
inverter-fed, locked-rotor bench (``identify._experiment``) with sensor noise and the dead time
and device drop given. A no-load run (``--no-load-log`` for a measured one; always for a
built-in machine, ``identify._no_load``) adds the magnetising inductance at the run's flux, which
the parameter file then uses. Prints the table (quantity, value, unit, the two 95 % intervals,
meaning) and what the data do and do not identify; writes the machine parameter file (``--out``).
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
    p.add_argument("--no-load-log", help="no-load run log (.csv / .parquet / .mat, with w [rad/s]) "
                   "of a measured test: L_M at the run's flux")  # fmt: skip
    p.add_argument("--no-load-frequency-hz", type=float, default=None,
                   help="frequency of the no-load run (Hz; default that of the built-in run)")  # fmt: skip
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


def _no_load(args, machine=None):
    """(no-load log or None, its frequency, its settling time) of the command: the measured
    ``--no-load-log``, or the built-in run on ``machine`` (simulated with the command's inverter
    and seed)."""
    import dataclasses

    from acdrive.errors import require_positive
    from acdrive.identify._no_load import NoLoadPlan, no_load_test, read_no_load_log

    plan = NoLoadPlan(t_d=args.dead_time_s, v_drop=args.device_drop_v)
    if args.no_load_frequency_hz is not None:
        frequency = require_positive("--no-load-frequency-hz", args.no_load_frequency_hz)
        plan = dataclasses.replace(plan, frequency=frequency)
    if machine is not None:
        return no_load_test(machine, plan, seed=2 * args.seed + 3), plan.frequency, plan.settle
    if args.no_load_log:
        return read_no_load_log(args.no_load_log, "--no-load-log"), plan.frequency, plan.settle
    return None, plan.frequency, plan.settle


def _logs(args, plan):
    """(injection log, DC log or None, pole pairs, base frequency, settle, machine simulated or
    None) of the command."""
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
        return injection, dc, args.pole_pairs, base, settle, None
    if args.source not in names(IMParams):
        raise InputError("TEST_FILE_OR_SCENARIO", f"neither a {' / '.join(LOG_SUFFIXES)} log nor "
                         f"a built-in cage IM (known: {', '.join(names(IMParams))})")  # fmt: skip
    for flag in ("dc_log", "no_load_log"):
        if getattr(args, flag):
            raise InputError(f"--{flag.replace('_', '-')}", "is for a measured test; a simulated "
                             "test makes its own")  # fmt: skip
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
            dc_test(machine, plan, seed=2 * args.seed), n_p, base, settle, machine)  # fmt: skip


def _rows(result, no_load=None):
    """(quantity, estimate): quantities dotted as the JSON output names them."""
    rows = [(f"inverse_gamma.{e.name}", e) for e in result.impedance.estimates]
    if no_load is not None:
        rows.append(("no_load.L_M", no_load.L_M))
    rows += [(f"t_circuit.{e.name}", e) for e in result.t_estimates]
    if result.dc is not None:
        dc = result.dc
        rows += [(f"dc_steps.{e.name}", e) for e in (dc.R_s, dc.voltage_error, dc.single_level)]
    return rows


def _json(result, path, no_load=None) -> dict:
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
    if no_load is not None:
        out["no_load"] = {"L_M": entry(no_load.L_M), "frequency_hz": no_load.frequency,
                          "slip": no_load.slip, "residual_a": no_load.residual}  # fmt: skip
    return out


def run(args) -> int:
    from acdrive._commands._table import format_value
    from acdrive.identify._experiment import StandstillPlan
    from acdrive.identify._fit import FitNotConverged
    from acdrive.identify._params_file import check_target, params_text, write_params
    from acdrive.identify._standstill import identifiability, identify_standstill

    target = check_target(args.out)  # before any work
    from acdrive.identify._no_load import fit_no_load

    plan = StandstillPlan()
    injection, dc, n_p, base, settle, machine = _logs(args, plan)
    no_load_log, frequency, no_load_settle = _no_load(args, machine)
    try:
        result = identify_standstill(injection, base, settle, dc=dc, n_p=n_p,
                                     split=args.leakage_split, seed=args.seed)  # fmt: skip
        no_load = None
        if no_load_log is not None:
            no_load = fit_no_load(no_load_log, frequency, no_load_settle, n_p, result.impedance,
                                  seed=args.seed + 2)  # fmt: skip
    except FitNotConverged as exc:
        sys.stderr.write(f"acdrive: error: {exc}\n")
        return 1
    path = write_params(target, params_text(result, args.source, no_load))
    if args.json:
        from acdrive._output import strict_json

        print(strict_json(_json(result, path, no_load), indent=2))
        return 0

    def interval(pair):
        return f"[{format_value(pair[0])}, {format_value(pair[1])}]"

    cells = [INTERVAL_HEADER] + [
        (name, format_value(e.value), e.unit, interval(e.jacobian), interval(e.bootstrap),
         e.meaning) for name, e in _rows(result, no_load)
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
    if no_load is not None:
        print(f"  no-load run at {no_load.frequency:g} Hz, slip {no_load.slip:.3g}: its L_M "
              "(at the run's flux) is the one the parameter file uses")  # fmt: skip
    print(f"wrote {path}")
    return 0
