"""``acdrive identify --kind pm | dfim | mechanics``: the identifications other than the cage IM's,
from the logs of a measured test or, given a built-in machine's name instead of a log, from that
kind's tests simulated on its bench (``identify._builtin``: the same parts, sensors and plans as
the Python API; the seeds from ``--seed``) (``acdrive.identify``; docs/guide/identification.md).

``--dead-time-s`` (pm, dfim) is the PWM unit's programmed dead time, as for the cage IM: with
``--dc-log`` the fits compensate the voltage error with the sign the inverter saw and shift their
sample by half of it (``identify._impedance``).

* ``pm``: the source is the d-axis injection log, ``--q-log`` the q-axis one (rotor locked with
  that axis on phase a), ``--dc-log`` the DC steps (optional), ``--spin-log`` the short-circuit
  spin test (optional: psi_m), ``--pole-pairs`` required. With the spin log the file has the PM
  scenario's ``[machine.params]`` (R_s, L_d, L_q, psi_m, n_p; J to be added from the mechanics).
* ``dfim``: the source is the stator-open injection log from the rotor converter,
  ``--shorted-log`` the stator-shorted one, ``--dc-log`` the stator-open DC steps (optional),
  ``--stator-resistance-ohm`` (and its standard error) a stator resistance measured apart,
  without which M and L_s are not identifiable. With it and ``--pole-pairs`` the file has a DFIM
  machine table (R_s, R_r, L_s, L_r, M, n_p).
* ``mechanics``: the source is the speed-step log (``time [s]``, ``tau_e [N m]``,
  ``w [rad/s]``); the file has J, the viscous friction and the Coulomb friction.

A measured log's ``--base-frequency-hz``, ``--settle-s`` and ``--spin-settle-s`` default to those
of the kind's built-in benches (``identify._builtin.measured_window``), so a bench's own logs run
without them. Every estimate is printed and written with both 95 % intervals; a fit that does not
converge says so with its residual (exit 1); bad input is one line naming the field (exit 2).
"""

from __future__ import annotations

import sys

#: option -> the kinds it applies to (every other kind refuses it)
OPTIONS = {
    "q_log": ("pm",),
    "spin_log": ("pm",),
    "spin_settle_s": ("pm",),
    "shorted_log": ("dfim",),
    "stator_resistance_ohm": ("dfim",),
    "no_load_log": ("cage-im",),
    "no_load_frequency_hz": ("cage-im",),
    "link_voltage_v": ("cage-im",),
}

#: the Python arguments of the injection window -> the options that set them
WINDOW_OPTIONS = {"base_frequency": "--base-frequency-hz", "settle": "--settle-s"}


def _flag(name: str) -> str:
    return "--" + name.replace("_", "-")


def refuse_other_options(args) -> None:
    """An option of another kind than ``args.kind`` given: one line naming it."""
    from acdrive.errors import InputError

    for name, kinds in OPTIONS.items():
        if getattr(args, name, None) is not None and args.kind not in kinds:
            raise InputError(_flag(name), f"is for --kind {' / '.join(kinds)} only")
    if args.stator_resistance_std_ohm != 0.0 and args.kind != "dfim":
        raise InputError("--stator-resistance-std-ohm", "is for --kind dfim only")


#: options that name a measured log (a simulated test makes its own)
MEASURED_ONLY = ("dc_log", "q_log", "spin_log", "shorted_log")


def _measured(args) -> None:
    """Options of a measured log: the simulated inverter's device drop is refused; the PWM
    unit's programmed dead time is taken by the PM and DFIM fits (they shift their sample by
    half of it), not by --kind mechanics."""
    from acdrive.errors import InputError, require_nonnegative

    if args.device_drop_v != 0.0:
        raise InputError("--device-drop-v", "is for a simulated test only")
    require_nonnegative("--dead-time-s", args.dead_time_s)
    if args.kind == "mechanics" and args.dead_time_s != 0.0:
        raise InputError("--dead-time-s", "is not used by --kind mechanics")


def _source(args):
    """The bench (``identify._builtin``) of the built-in machine the source names, or None for
    a measured log; every check of the options that says which, before any work."""
    from pathlib import Path

    from acdrive._commands._identify_table import LOG_SUFFIXES
    from acdrive.errors import InputError
    from acdrive.identify._builtin import KIND_NOUN, builtin_bench, builtin_names

    if args.leakage_split != "equal":
        raise InputError("--leakage-split", "is for --kind cage-im only")
    if Path(args.source).suffix in LOG_SUFFIXES:
        _measured(args)
        return None
    known = builtin_names(args.kind)
    if args.source not in known:
        raise InputError("TEST_FILE_OR_SCENARIO", f"neither a {' / '.join(LOG_SUFFIXES)} log nor "
                         f"a built-in {KIND_NOUN[args.kind]} (known for --kind {args.kind}: "
                         f"{', '.join(known)})")  # fmt: skip
    for flag in MEASURED_ONLY:
        if getattr(args, flag):
            raise InputError(_flag(flag), "is for a measured test; a simulated test makes its own")
    return builtin_bench(args.kind, args.source, "TEST_FILE_OR_SCENARIO")


def _bench_plan(args, plan):
    """The standstill ``plan`` of a built-in bench with the command's dead time, device drop,
    base frequency and settling time, each checked (as the cage IM's simulated tests)."""
    import dataclasses

    from acdrive.errors import InputError, require_nonnegative
    from acdrive.plant._inverter import Inverter

    base, settle = _plan_window(args, plan)
    t_d = require_nonnegative("--dead-time-s", args.dead_time_s)
    v_drop = require_nonnegative("--device-drop-v", args.device_drop_v)
    try:
        Inverter("inverter", f_pwm=plan.f_pwm, t_d=t_d)
    except InputError as exc:
        raise InputError("--dead-time-s", exc.rule) from None
    try:
        return dataclasses.replace(plan, t_d=t_d, v_drop=v_drop, base_frequency=base,
                                   settle=settle)  # fmt: skip
    except InputError as exc:  # e.g. a settling time the plan cannot hold
        raise InputError(f"{args.source}: {exc.field}", exc.rule) from None


def _required(args, name: str):
    from acdrive.errors import InputError

    value = getattr(args, name)
    if value is None:
        raise InputError(_flag(name), f"is required for --kind {args.kind}")
    return value


def _plan_window(args, plan=None):
    """(base frequency, settle) of the injections: the options, else those of ``plan`` (a
    built-in bench's), else for a measured log those of the kind's benches
    (``identify._builtin.measured_window``)."""
    from acdrive.errors import require_nonnegative, require_positive
    from acdrive.identify._builtin import measured_window

    plan = measured_window(args.kind) if plan is None else plan
    base = plan.base_frequency if args.base_frequency_hz is None else args.base_frequency_hz
    settle = plan.settle if args.settle_s is None else args.settle_s
    return require_positive("--base-frequency-hz", base), require_nonnegative("--settle-s", settle)


def _pole_pairs(args, required: bool):
    from acdrive.errors import require_between

    if args.pole_pairs is None:
        return _required(args, "pole_pairs") if required else None
    require_between("--pole-pairs", args.pole_pairs, 1, 1000)
    return args.pole_pairs  # an int (argparse), which require_between returns as a float


def _measured_logs(args, second: str, pole_pairs_required: bool = False):
    """(pole pairs, base frequency, settling time, the source log, the ``second`` one (an args
    field, e.g. ``q_log``), the DC steps or None) of a measured standstill test."""
    from acdrive.identify._log import read_log

    n_p = _pole_pairs(args, pole_pairs_required)
    base, settle = _plan_window(args)
    first = read_log(args.source, "TEST_FILE_OR_SCENARIO")
    other = read_log(_required(args, second), _flag(second))
    dc = read_log(args.dc_log, "--dc-log") if args.dc_log else None
    return n_p, base, settle, first, other, dc


def _spin_settle(args, bench):
    """The time dropped at the start of each spin plateau: the option, else the bench's, else
    for a measured log that of the PM benches (``identify._builtin.measured_window``), checked."""
    from acdrive.errors import require_nonnegative
    from acdrive.identify._builtin import measured_window

    default = measured_window("pm").spin_settle if bench is None else bench.spin.settle
    settle = default if args.spin_settle_s is None else args.spin_settle_s
    require_nonnegative("--spin-settle-s", settle)
    if bench is not None and not settle < bench.spin.hold:
        from acdrive.errors import InputError

        raise InputError("--spin-settle-s", f"must be shorter than the built-in spin test's "
                         f"{bench.spin.hold:g} s plateaus")  # fmt: skip
    return settle


def _pm(args, bench):
    """(groups, statement, facts, machine params or None, note) of --kind pm: from the measured
    logs, or from the tests simulated on ``bench`` (a built-in PM machine)."""
    import dataclasses

    from acdrive.identify._experiment import dc_test
    from acdrive.identify._pm import axis_test, identify_pm_standstill, pm_identifiability
    from acdrive.identify._spin import fit_spin, read_spin_log, spin_test

    if bench is None and not args.spin_log and args.spin_settle_s is not None:
        from acdrive.errors import InputError

        raise InputError("--spin-settle-s", "does not apply without --spin-log: it is the time "
                         "dropped at the start of each spin plateau")  # fmt: skip
    spin_settle = _spin_settle(args, bench)
    facts = {}
    if bench is None:
        n_p, base, settle, d, q, dc = _measured_logs(args, "q_log", pole_pairs_required=True)
        spin = read_spin_log(args.spin_log, "--spin-log") if args.spin_log else None
    else:
        n_p = _pole_pairs(args, False) or bench.machine.n_p
        plan = _bench_plan(args, bench.standstill)
        base, settle = plan.base_frequency, plan.settle
        spin_plan = dataclasses.replace(bench.spin, t_d=plan.t_d, v_drop=plan.v_drop,
                                        settle=spin_settle)  # fmt: skip
        m, seed = bench.machine, 4 * args.seed
        dc = dc_test(m, plan, seed=seed)
        d_test, q_test = axis_test(m, plan, "d", seed + 1), axis_test(m, plan, "q", seed + 2)
        spinning = spin_test(m, spin_plan, seed=seed + 3)
        d, q, spin = d_test.log, q_test.log, spinning.log
        facts |= {"q_test_lock_torque_nm": q_test.holding_torque,
                  "spin_test_braking_torque_nm": spinning.braking_torque}  # fmt: skip
    result = identify_pm_standstill(d, q, base, settle, dc=dc, seed=args.seed,
                                    dead_time=args.dead_time_s)  # fmt: skip
    groups = {"pm_standstill": result.estimates}
    statement = pm_identifiability(result)
    facts = {"residual_rms_a_d": result.d.residual_rms, "residual_rms_a_q": result.q.residual_rms,
             **facts}  # fmt: skip
    params, note = None, "no [machine.params]: the magnet flux needs --spin-log"
    if spin is not None:
        fit = fit_spin(spin, n_p, spin_settle, result, seed=args.seed + 3)
        groups["spin"] = (fit.psi_m,)
        facts["spin_residual"] = fit.residual
        statement = [
            *statement,
            "identified: psi_m from the short-circuit spin test, with the standstill R_s, L_d, L_q",
        ]
        params = {name: result.value(name) for name in ("R_s", "L_d", "L_q")}
        params |= {"psi_m": fit.psi_m.value, "n_p": n_p}
        note = ("[machine.params] is a pm scenario's machine table less J (the mechanics' "
                "test gives it): add J and copy it into a scenario")  # fmt: skip
    if dc is not None:
        groups["dc_steps"] = (result.dc.R_s, result.dc.voltage_error)
    return groups, statement, facts, params, note


def _dfim(args, bench):
    """As ``_pm`` for --kind dfim: the rotor-converter tests, stator open and shorted."""
    from acdrive.errors import require_nonnegative, require_positive
    from acdrive.identify._dfim import dfim_identifiability, dfim_test, identify_dfim

    R_s = args.stator_resistance_ohm
    if R_s is not None:
        require_positive("--stator-resistance-ohm", R_s)
    elif args.stator_resistance_std_ohm != 0.0:
        from acdrive.errors import InputError

        raise InputError("--stator-resistance-std-ohm", "does not apply without "
                         "--stator-resistance-ohm: it is that value's standard error")  # fmt: skip
    R_s_std = require_nonnegative("--stator-resistance-std-ohm", args.stator_resistance_std_ohm)
    if bench is None:
        n_p, base, settle, opened, shorted, dc = _measured_logs(args, "shorted_log")
    else:
        n_p = _pole_pairs(args, False) or bench.machine.n_p
        plan = _bench_plan(args, bench.standstill)
        base, settle = plan.base_frequency, plan.settle
        m, seed = bench.machine, 3 * args.seed
        dc = dfim_test(m, plan, "open", "dc", seed=seed)
        opened = dfim_test(m, plan, "open", "injection", seed=seed + 1)
        shorted = dfim_test(m, plan, "shorted", "injection", seed=seed + 2)
    result = identify_dfim(opened, shorted, base, settle, dc=dc, R_s=R_s, R_s_std=R_s_std,
                           seed=args.seed, dead_time=args.dead_time_s)  # fmt: skip
    groups = {"dfim": result.estimates}
    if dc is not None:
        groups["dc_steps"] = (result.dc.R_s, result.dc.voltage_error)
    facts = {"consistency_l_r_sigmas": result.consistency,
             "residual_rms_a_open": result.open.residual_rms,
             "residual_rms_a_shorted": result.shorted.residual_rms}  # fmt: skip
    missing = [
        what
        for what, given in (
            ("M and L_s need --stator-resistance-ohm", R_s),
            ("the table needs --pole-pairs", n_p),
        )
        if given is None
    ]
    params, note = None, f"no [machine.params]: {', '.join(missing)}"  # fmt: skip
    if R_s is not None and n_p is not None:
        params = {name: result.value(name) for name in ("R_s", "R_r", "L_s", "L_r", "M")}
        params["n_p"] = n_p
        note = "[machine.params] is a DFIM's electrical table (machines.DFIMParams less J)"
    return groups, dfim_identifiability(result), facts, params, note


def _mechanics(args, bench):
    """As ``_pm`` for --kind mechanics: the speed staircase of a PM speed drive."""
    from acdrive.errors import InputError
    from acdrive.identify._mechanics import (
        fit_mechanics,
        mechanics_identifiability,
        read_mechanics_log,
        speed_step_test,
    )

    for flag in ("pole_pairs", "base_frequency_hz", "settle_s", "dc_log"):
        if getattr(args, flag) is not None:
            raise InputError(_flag(flag), "is not used by --kind mechanics")
    if bench is None:
        log = read_mechanics_log(args.source, "TEST_FILE_OR_SCENARIO")
    else:
        for flag in ("dead_time_s", "device_drop_v"):
            if getattr(args, flag) != 0.0:
                raise InputError(_flag(flag), "is not used by --kind mechanics (the built-in "
                                 "speed drive's scenario declares its converter)")  # fmt: skip
        log = speed_step_test(bench.scenario(args.source), bench.plan, seed=args.seed)
    fit = fit_mechanics(log, seed=args.seed)
    note = ("[identification.mechanics] J and B are a scenario's [machine] J and "
            "viscous_friction; the Coulomb friction has no scenario field yet")  # fmt: skip
    facts = {"residual_rms_rad_s": fit.residual_rms, "degrees_of_freedom": fit.dof}
    return {"mechanics": fit.estimates}, mechanics_identifiability(fit), facts, None, note


def run_kind(args, target) -> int:
    """Identify ``args.kind`` from its measured logs or a built-in machine's simulated tests;
    print the table and write the file."""
    from acdrive._commands._identify_table import print_table
    from acdrive._commands._options import typed_names
    from acdrive.identify._fit import FitNotConverged
    from acdrive.identify._params_file import estimates_text, write_params

    refuse_other_options(args)
    bench = _source(args)
    try:
        with typed_names(WINDOW_OPTIONS):
            groups, statement, facts, params, note = {"pm": _pm, "dfim": _dfim,
                                                      "mechanics": _mechanics}[args.kind](args, bench)  # fmt: skip
    except FitNotConverged as exc:
        sys.stderr.write(f"acdrive: error: {exc}\n")
        return 1
    path = write_params(target, estimates_text(args.kind, args.source, groups, statement, params,
                                               note, facts))  # fmt: skip
    rows = [(f"{group}.{e.name}", e) for group, estimates in groups.items() for e in estimates]
    if args.json:
        from acdrive._output import strict_json

        def entry(e):
            return {"value": e.value, "unit": e.unit, "ci95_jacobian": list(e.jacobian),
                    "ci95_bootstrap": list(e.bootstrap), "meaning": e.meaning}  # fmt: skip

        print(strict_json({"kind": args.kind, "estimates": {q: entry(e) for q, e in rows},
                           "statement": statement, **facts, "machine_params": params,
                           "written": str(path)}, indent=2))  # fmt: skip
        return 0
    print_table(f"Identification ({args.kind}) of {args.source}", rows)
    for name, value in facts.items():
        print(f"  {name}: {value:.4g}" if isinstance(value, float) else f"  {name}: {value}")
    for line in statement:
        print(f"  {line}")
    print(f"  {note}")
    print(f"wrote {path}")
    return 0
