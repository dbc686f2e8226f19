"""``acdrive identify``: a cage IM's parameters from standstill tests, with 95 % intervals.

``TEST_FILE_OR_SCENARIO`` is either the injection log of a measured test (``.csv``, ``.parquet``
or ``.mat``, columns ``time [s]``, ``v_a [V]``, ``i_a [A]``; ``--dc-log`` adds the DC-step log)
or the name of a built-in cage IM, whose standstill tests are then simulated on acdrive's
inverter-fed, locked-rotor bench (``identify._experiment``) with sensor noise and the dead time
and device drop given. ``--kind pm | dfim | mechanics`` does the same for the other tests
(``_identify_kinds``; a built-in PM machine, DFIM or speed drive of ``identify._builtin``). A no-load run (``--no-load-log`` for a measured one; always for a
built-in machine, ``identify._no_load``) adds the magnetising inductance at the run's flux, which
the parameter file then uses; its link voltage (``--link-voltage-v`` or the log's ``v_dc [V]``
column) adds the PWM pulses' second-order term to that fit. Prints the table (quantity, value, unit, the two 95 % intervals,
meaning) and what the data do and do not identify; writes the machine parameter file (``--out``).
"""

from __future__ import annotations

import sys

from acdrive._commands._identify_table import LOG_SUFFIXES, print_table

#: what ``--kind`` names: the cage IM's standstill (and no-load) tests, or those of
#: ``_identify_kinds``
KINDS = ("cage-im", "pm", "dfim", "mechanics")


def register(subparsers):
    from acdrive.identify._circuit import LEAKAGE_SPLITS

    p = subparsers.add_parser(
        "identify",
        help="machine parameters from logged tests (cage IM, PM, DFIM, mechanics) with 95-percent intervals",
    )
    p.add_argument("source", metavar="TEST_FILE_OR_SCENARIO",
                   help="injection log (.csv / .parquet / .mat) or a built-in machine whose tests "
                   "of --kind are simulated")  # fmt: skip
    p.add_argument("--dc-log", help="DC-step log (.csv / .parquet / .mat) of a measured test")
    p.add_argument("--no-load-log", help="no-load run log (.csv / .parquet / .mat, with w [rad/s]) "
                   "of a measured test: L_M at the run's flux")  # fmt: skip
    p.add_argument("--no-load-frequency-hz", type=float, default=None,
                   help="frequency of the no-load run (Hz; default that of the built-in run)")  # fmt: skip
    p.add_argument("--link-voltage-v", type=float, default=None,
                   help="DC-link voltage of a measured no-load run (V): models the PWM pulses' "
                   "second-order term (else a v_dc [V] column of the log, else left out)")  # fmt: skip
    p.add_argument("--base-frequency-hz", type=float, default=None,
                   help="step between the injected tones (Hz; default that of the built-in "
                   "tests of --kind)")  # fmt: skip
    p.add_argument("--settle-s", type=float, default=None,
                   help="time dropped at the start of the injection log (s; default that of the "
                   "built-in tests of --kind)")  # fmt: skip
    p.add_argument("--pole-pairs", type=int, default=None,
                   help="pole pairs (not identifiable at standstill; required for a measured log)")  # fmt: skip
    p.add_argument("--leakage-split", choices=tuple(LEAKAGE_SPLITS), default="equal",
                   help="assumed split of the leakage for the T-circuit written (default equal)")  # fmt: skip
    p.add_argument("--dead-time-s", type=float, default=0.0,
                   help="the inverter's dead time (s): simulated on a built-in machine; for a "
                   "measured cage-IM, PM or DFIM log the PWM unit's setting, whose shift of "
                   "the sample instant the fit includes [0]")  # fmt: skip
    p.add_argument("--device-drop-v", type=float, default=0.0,
                   help="simulated test: the inverter's device drop (V) [0]")  # fmt: skip
    p.add_argument("--seed", type=int, default=0,
                   help="seed of the simulated sensor noise and of the bootstrap [0]")  # fmt: skip
    p.add_argument("--out", default="identified-machine.toml",
                   help="machine parameter file to write (TOML) [identified-machine.toml]")  # fmt: skip
    p.add_argument("--json", action="store_true", help="print JSON instead of the table")
    p.add_argument("--kind", choices=KINDS, default="cage-im",
                   help="what the measured logs identify: cage-im [default], pm, dfim or "
                   "mechanics (docs/guide/identification.md)")  # fmt: skip
    p.add_argument("--q-log", help="pm: q-axis injection log (the source is the d-axis one)")
    p.add_argument("--spin-log", help="pm: short-circuit spin-test log (with w [rad/s]): psi_m")
    p.add_argument("--spin-settle-s", type=float, default=None,
                   help="pm: time dropped at the start of each spin plateau (s; default that of "
                   "the built-in spin tests)")  # fmt: skip
    p.add_argument("--shorted-log",
                   help="dfim: stator-shorted injection log (the source is the stator-open one)")  # fmt: skip
    p.add_argument("--stator-resistance-ohm", type=float, default=None,
                   help="dfim: stator resistance measured apart (fixes M and L_s)")  # fmt: skip
    p.add_argument("--stator-resistance-std-ohm", type=float, default=0.0,
                   help="dfim: standard error of --stator-resistance-ohm [0]")  # fmt: skip
    p.set_defaults(handler=run)


def _no_load(args, machine=None):
    """(no-load log or None, its frequency, its settling time) of the command: the measured
    ``--no-load-log``, or the built-in run on ``machine`` (simulated with the command's inverter
    and seed)."""
    import dataclasses

    from acdrive.errors import require_positive
    from acdrive.identify._no_load import NoLoadPlan, no_load_test, read_no_load_log

    plan = NoLoadPlan(t_d=args.dead_time_s, v_drop=args.device_drop_v)
    if machine is None and not args.no_load_log and args.no_load_frequency_hz is not None:
        from acdrive.errors import InputError

        raise InputError("--no-load-frequency-hz", "does not apply without --no-load-log: a "
                         "measured test has no no-load run to set it for")  # fmt: skip
    if args.no_load_frequency_hz is not None:
        frequency = require_positive("--no-load-frequency-hz", args.no_load_frequency_hz)
        plan = dataclasses.replace(plan, frequency=frequency)
    if machine is not None:
        return no_load_test(machine, plan, seed=2 * args.seed + 3), plan.frequency, plan.settle
    if args.no_load_log:
        return read_no_load_log(args.no_load_log, "--no-load-log"), plan.frequency, plan.settle
    return None, plan.frequency, plan.settle


def _link_voltage(args, no_load_log, machine) -> float | None:
    """The link voltage [V] whose pulses the no-load model includes: the simulated run's, or of a
    measured log ``--link-voltage-v`` and the log's ``v_dc`` column, which must agree
    (``identify._no_load.link_voltage``); None for the held-voltage model."""
    from acdrive.identify._no_load import NoLoadPlan, link_voltage

    if no_load_log is None:
        return None
    if machine is not None:  # a simulated run's link voltage is known
        return NoLoadPlan().v_dc
    return link_voltage(no_load_log, args.link_voltage_v, "--link-voltage-v")


def _check_link_voltage_option(args) -> None:
    """--link-voltage-v belongs to a measured no-load log: one line otherwise."""
    from pathlib import Path

    from acdrive.errors import InputError

    if args.link_voltage_v is None:
        return
    if Path(args.source).suffix not in LOG_SUFFIXES:
        raise InputError("--link-voltage-v", "is for a measured no-load log; the simulated run's "
                         "link voltage is the bench's")  # fmt: skip
    if not args.no_load_log:
        raise InputError("--link-voltage-v", "needs --no-load-log (it is the no-load run's link)")


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
        if args.device_drop_v != 0.0:
            raise InputError("--device-drop-v", "is for a simulated test only")
        require_nonnegative("--dead-time-s", args.dead_time_s)  # the PWM unit's setting
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
    if result.current_offset is not None:
        rows.append((f"offsets.{result.current_offset.name}", result.current_offset))
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
        "residual_over_noise_floor": fit.residual_ratio,
        "noise_floor_a": fit.noise_rms,
        "current_delay_s": fit.delay,
        "warnings": list(fit.warnings),
        "tones_hz": list(fit.spectrum.frequency),
        "statement": identifiability(result),
        "written": str(path),
    }
    if result.dc is not None:
        dc = result.dc
        out["dc_steps"] = {e.name: entry(e) for e in (dc.R_s, dc.voltage_error, dc.single_level)}
    if result.current_offset is not None:
        out["offsets"] = {result.current_offset.name: entry(result.current_offset)}
    if no_load is not None:
        out["no_load"] = {"L_M": entry(no_load.L_M), "frequency_hz": no_load.frequency,
                          "slip": no_load.slip, "residual_a": no_load.residual,
                          "link_voltage_v": no_load.link_voltage}  # fmt: skip
    return out


def run(args) -> int:
    from acdrive._commands._identify_kinds import WINDOW_OPTIONS
    from acdrive._commands._options import typed_names
    from acdrive._commands._table import format_value
    from acdrive.identify._experiment import StandstillPlan
    from acdrive.identify._fit import FitNotConverged
    from acdrive.identify._params_file import check_target, params_text, write_params
    from acdrive.errors import InputError
    from acdrive.identify._standstill import identifiability, identify_standstill

    if args.seed < 0:  # numpy's generators take seeds >= 0
        raise InputError("--seed", f"must be an integer >= 0, got {args.seed}")
    target = check_target(args.out)  # before any work
    if args.kind != "cage-im":
        from acdrive._commands._identify_kinds import run_kind

        return run_kind(args, target)
    from acdrive._commands._identify_kinds import refuse_other_options

    refuse_other_options(args)
    from acdrive.identify._no_load import fit_no_load

    _check_link_voltage_option(args)
    plan = StandstillPlan()
    injection, dc, n_p, base, settle, machine = _logs(args, plan)
    no_load_log, frequency, no_load_settle = _no_load(args, machine)
    v_dc = _link_voltage(args, no_load_log, machine)
    try:
        with typed_names({**WINDOW_OPTIONS, "dc": "--dc-log"}):
            result = identify_standstill(injection, base, settle, dc=dc, n_p=n_p,
                                         split=args.leakage_split, seed=args.seed,
                                         dead_time=args.dead_time_s)  # fmt: skip
        no_load = None
        if no_load_log is not None:
            no_load = fit_no_load(no_load_log, frequency, no_load_settle, n_p, result.impedance,
                                  seed=args.seed + 2, v_dc=v_dc)  # fmt: skip
    except FitNotConverged as exc:
        sys.stderr.write(f"acdrive: error: {exc}\n")
        return 1
    path = write_params(target, params_text(result, args.source, no_load))
    if args.json:
        from acdrive._output import strict_json

        print(strict_json(_json(result, path, no_load), indent=2))
        return 0

    print_table(f"Standstill identification of {args.source}", _rows(result, no_load))
    fit = result.impedance
    print(f"residual: {format_value(fit.residual_rms)} A rms over {fit.spectrum.frequency.size} "
          f"tones ({format_value(fit.residual_relative)} of the currents), {fit.dof} degrees of freedom")  # fmt: skip
    for line in identifiability(result):
        print(f"  {line}")
    if no_load is not None:
        print(f"  no-load run at {no_load.frequency:g} Hz, slip {no_load.slip:.3g}: its L_M "
              "(at the run's flux) is the one the parameter file uses")  # fmt: skip
        if no_load.link_voltage is None:
            print("  no-load model: voltage held over each PWM period (no link voltage: "
                  "--link-voltage-v or a v_dc [V] column adds the pulses' second-order term)")  # fmt: skip
        else:
            print(f"  no-load model: the PWM pulses' second-order term from a "
                  f"{no_load.link_voltage:.6g} V link")  # fmt: skip
    print(f"wrote {path}")
    return 0
