"""Coverage study of the identifications beyond the cage IM's standstill one (issue 23, item 3):
each simulated test repeated with independent noise (seeds 0 .. N-1), each estimate's 95 %
intervals checked against the machine's own value; prints JSON.

    python benchmarks/coverage_identify.py [--repetitions 50] [--bootstrap 100] [--only KIND]

Per kind and parameter: the fraction of repetitions whose Jacobian and bootstrap intervals hold
the truth, the mean relative error (the bias) and the mean relative half-width of the Jacobian
interval. Kinds:

* ``standstill``: the cage IM's standstill tests (``acdrive.identify.coverage``) on the DeLorenzo
  and Ugalde-Loo IMs with a 2 us dead time and 1 V device drops, fitted with the compensation
  (DC-step U_err and the programmed dead time) and without it (the injection alone);

* ``dead_time``: the PM (BLY171D) d- and q-axis standstill tests and the DFIM's rotor-side
  tests with the same inverter (2 us, 1 V per device), compensated (DC-step U_err, the simulated
  sign and the programmed dead time, as for the cage IM) and uncompensated, at the ideal plan's
  tone amplitude and larger ones (``PM_DEAD_TIME_TONES``, ``DFIM_DEAD_TIME_TONES``);
* ``pm``: BLY171D, d- and q-axis injection with DC steps, then the short-circuit spin test;
* ``no_load``: the DeLorenzo IM's no-load run at 2 % slip on its standstill estimates, with the
  switching pattern's second-order term (the link voltage given) and without it;
* ``dfim``: Bodson's DFIM from its rotor converter, R_s given with a 1 % standard error;
* ``mechanics``: the BLY171D speed drive's speed steps with 2 mN m Coulomb friction.

Each repetition simulates its tests (seconds each on a shared machine); the whole study with 50
repetitions takes minutes.
"""

from __future__ import annotations

import argparse
import json
import math


def _record(table: dict, name: str, estimate, truth: float) -> None:
    row = table.setdefault(name, {"jacobian": 0, "bootstrap": 0, "error": 0.0, "width": 0.0})
    row["jacobian"] += estimate.covers(truth)
    row["bootstrap"] += estimate.covers(truth, "bootstrap")
    row["error"] += (estimate.value - truth) / truth
    row["width"] += estimate.half_width()


def pm(seed: int, bootstrap: int, table: dict) -> None:
    from acdrive.drives.pm import BLY171D as m
    from acdrive.identify import (
        SpinPlan,
        StandstillPlan,
        axis_test,
        dc_test,
        fit_spin,
        identify_pm_standstill,
        spin_test,
    )

    plan = StandstillPlan(dc_levels=(0.3, 0.6, 0.9), dc_step=0.5, base_frequency=2.0,
                          tone_amplitude=0.15, settle=0.5, v_dc=24.0)  # fmt: skip
    result = identify_pm_standstill(
        axis_test(m, plan, "d", seed=4 * seed + 1).log,
        axis_test(m, plan, "q", seed=4 * seed + 2).log, plan.base_frequency, plan.settle,
        dc=dc_test(m, plan, seed=4 * seed), seed=seed, bootstrap=bootstrap,
    )  # fmt: skip
    for e in result.estimates:
        _record(table, e.name, e, getattr(m, e.name))
    spin = SpinPlan()
    fit = fit_spin(spin_test(m, spin, seed=4 * seed + 3).log, m.n_p, spin.settle, result,
                   seed=seed, bootstrap=bootstrap)  # fmt: skip
    _record(table, "psi_m", fit.psi_m, m.psi_m)


_QUIET: dict = {}


def no_load(seed: int, bootstrap: int, table: dict) -> None:
    import dataclasses

    import numpy as np

    from acdrive.identify import (
        CurrentSensor,
        NoLoadLog,
        NoLoadPlan,
        StandstillPlan,
        dc_test,
        fit_no_load,
        identify_standstill,
        injection_test,
        inverse_gamma,
        no_load_test,
    )
    from acdrive.identify._coverage import reading
    from acdrive.identify._experiment import measured_current
    from acdrive.machines import DELORENZO_IM as m

    plan = StandstillPlan()
    run = NoLoadPlan(slip=0.02)
    if not _QUIET:  # the bench is deterministic: simulate once, draw each seed's noise on it
        off = CurrentSensor(noise_std=0.0, offset=0.0, lsb=0.0)
        quiet = dataclasses.replace(plan, sensor=off)
        _QUIET.update(dc=dc_test(m, quiet), injection=injection_test(m, quiet),
                      no_load=no_load_test(m, dataclasses.replace(run, sensor=off)))  # fmt: skip
    standstill = identify_standstill(
        reading(_QUIET["injection"], plan.sensor, 3 * seed + 1), plan.base_frequency,
        plan.settle, dc=reading(_QUIET["dc"], plan.sensor, 3 * seed), n_p=m.n_p, seed=seed,
        bootstrap=bootstrap,
    )  # fmt: skip
    q = _QUIET["no_load"]
    current = measured_current(q.i_a, run.sensor, np.random.default_rng(3 * seed + 2))
    log = NoLoadLog(q.time, q.v_a, current, q.w, q.source)
    for name, v_dc in (("L_M", run.v_dc), ("L_M_without_pulse_moment", None)):
        fit = fit_no_load(log, run.frequency, run.settle, m.n_p, standstill.impedance,
                          seed=seed, bootstrap=bootstrap, v_dc=v_dc)  # fmt: skip
        _record(table, name, fit.L_M, inverse_gamma(m).L_M)


def dfim(seed: int, bootstrap: int, table: dict) -> None:
    from acdrive.identify import StandstillPlan, dfim_test, identify_dfim
    from acdrive.machines import BODSON_DFIM as m

    plan = StandstillPlan(dc_levels=(1.0, 2.0, 3.0), tone_amplitude=0.3, v_dc=30.0)
    result = identify_dfim(
        dfim_test(m, plan, "open", "injection", seed=3 * seed + 1),
        dfim_test(m, plan, "shorted", "injection", seed=3 * seed + 2),
        plan.base_frequency, plan.settle, dc=dfim_test(m, plan, "open", "dc", seed=3 * seed),
        R_s=m.R_s, R_s_std=0.01 * m.R_s, seed=seed, bootstrap=bootstrap,
    )  # fmt: skip
    truth = {"R_r": m.R_r, "L_r": m.L_r, "L_sigma_r": m.L_r - m.M**2 / m.L_s,
             "R_S": m.R_s * (m.M / m.L_s) ** 2, "L_M": m.M**2 / m.L_s, "M": m.M, "L_s": m.L_s}  # fmt: skip
    for e in result.estimates:
        if e.name in truth:
            _record(table, e.name, e, truth[e.name])


def mechanics(seed: int, bootstrap: int, table: dict) -> None:
    from acdrive.drives.pm import BLY171D as m
    from acdrive.drives.pm._machines import BLY171D_B
    from acdrive.identify import MechanicsPlan, fit_mechanics, speed_step_test

    scenario = {
        "drive": "pm",
        "machine": {"machine": "bly171d", "viscous_friction": BLY171D_B},
        "converter": {"model": "switching", "pwm_frequency_hz": 20000.0, "dc_link_voltage": 24.0},
        "control": {"current_limit_pk_a": 1.8, "current_bandwidth_rad_s": 2 * math.pi * 400,
                    "speed_bandwidth_rad_s": 200.0},
        "simulation": {"sample_time": 5e-5},
    }  # fmt: skip
    plan = MechanicsPlan(tau_c=2e-3)
    fit = fit_mechanics(speed_step_test(scenario, plan, seed=seed), seed=seed,
                        bootstrap=bootstrap)  # fmt: skip
    for e, truth in zip(fit.estimates, (m.J, BLY171D_B, plan.tau_c), strict=True):
        _record(table, e.name, e, truth)


#: the inverter of the standstill study: 2 us dead time, 1 V per device (U_err = 5.47 V at 5 kHz)
DEAD_TIME, DEVICE_DROP = 2e-6, 1.0


def standstill(repetitions: int, bootstrap: int) -> dict:
    from acdrive.identify import StandstillPlan, coverage
    from acdrive.machines import DELORENZO_IM, UGALDE_IM_300W

    plan = StandstillPlan(t_d=DEAD_TIME, v_drop=DEVICE_DROP)
    out = {}
    for label, machine in (("delorenzo", DELORENZO_IM), ("ugalde", UGALDE_IM_300W)):
        for compensate in (True, False):
            study = coverage(machine, plan, repetitions, bootstrap=bootstrap,
                             compensate=compensate)  # fmt: skip
            key = f"{label}_{'compensated' if compensate else 'uncompensated'}"
            out[key] = {
                name: {"coverage_jacobian": study.jacobian[name],
                       "coverage_bootstrap": study.bootstrap[name],
                       "mean_relative_error": study.bias[name],
                       "mean_relative_half_width": study.half_width[name]}
                for name in study.jacobian
            }  # fmt: skip
    return out


def _voltage_error(plan) -> float:
    """U_err = 4/3 (t_d f_pwm v_dc + v_drop) on phase a (``identify._dc``, ``plant._inverter``)."""
    return 4.0 / 3.0 * (plan.t_d * plan.f_pwm * plan.v_dc + plan.v_drop)


def _dead_time_setups():
    """(label, machine, plan with the standstill study's inverter, identify(logs, compensate,
    seed, bootstrap), tests, truth) of the PM and DFIM studies, one per tone amplitude: the
    ideal-inverter plan's (``pm``, ``dfim`` above) and larger ones. The DC levels are the ideal
    plan's raised by U_err, so the plateaus carry the same currents."""
    import dataclasses

    from acdrive.drives.pm import BLY171D
    from acdrive.identify import StandstillPlan, identify_dfim, identify_pm_standstill
    from acdrive.machines import BODSON_DFIM as D

    pm_plan = StandstillPlan(dc_levels=(0.3, 0.6, 0.9), dc_step=0.5, base_frequency=2.0,
                             tone_amplitude=0.15, settle=0.5, v_dc=24.0, t_d=DEAD_TIME,
                             v_drop=DEVICE_DROP)  # fmt: skip
    dfim_plan = StandstillPlan(dc_levels=(1.0, 2.0, 3.0), tone_amplitude=0.3, v_dc=30.0,
                               t_d=DEAD_TIME, v_drop=DEVICE_DROP)  # fmt: skip

    def raised(plan, amplitude):
        U = _voltage_error(plan)
        return dataclasses.replace(plan, tone_amplitude=amplitude,
                                   dc_levels=tuple(v + U for v in plan.dc_levels))  # fmt: skip

    def pm_identify(plan):
        def run(logs, compensate, seed, bootstrap):
            return identify_pm_standstill(
                logs["d"], logs["q"], plan.base_frequency, plan.settle,
                dc=logs["dc"] if compensate else None, seed=seed, bootstrap=bootstrap,
                dead_time=plan.t_d if compensate else 0.0, check=compensate,
            ).estimates  # fmt: skip

        return run

    def dfim_identify(plan):
        def run(logs, compensate, seed, bootstrap):
            return identify_dfim(
                logs["open"], logs["shorted"], plan.base_frequency, plan.settle,
                dc=logs["dc"] if compensate else None, seed=seed, bootstrap=bootstrap,
                dead_time=plan.t_d if compensate else 0.0, check=compensate,
            ).estimates  # fmt: skip

        return run

    pm_truth = {"R_s": BLY171D.R_s, "L_d": BLY171D.L_d, "L_q": BLY171D.L_q}
    dfim_truth = {"R_r": D.R_r, "L_r": D.L_r, "L_sigma_r": D.L_r - D.M**2 / D.L_s,
                  "R_S": D.R_s * (D.M / D.L_s) ** 2, "L_M": D.M**2 / D.L_s}  # fmt: skip
    for amplitude in PM_DEAD_TIME_TONES:
        plan = raised(pm_plan, amplitude)
        yield f"pm_bly171d_{amplitude:g}V", BLY171D, plan, pm_identify(plan), "pm", pm_truth
    for amplitude in DFIM_DEAD_TIME_TONES:
        plan = raised(dfim_plan, amplitude)
        yield f"dfim_bodson_{amplitude:g}V", D, plan, dfim_identify(plan), "dfim", dfim_truth


#: tone amplitudes [V] of the dead-time studies: the ideal-inverter plan's and larger ones, up to
#: where the injection dominates U_err (1.65 V on the 24 V BLY171D bench, 1.73 V on the DFIM's)
PM_DEAD_TIME_TONES = (0.15, 0.9, 1.8)
DFIM_DEAD_TIME_TONES = (0.3, 1.5, 2.5)


def _quiet_logs(machine, plan, tests: str) -> dict:
    """The tests' noise-free logs (the bench is deterministic: each repetition draws its own
    sensor noise on them, ``identify._coverage.reading``)."""
    import dataclasses

    from acdrive.identify import CurrentSensor, axis_test, dc_test, dfim_test

    quiet = dataclasses.replace(plan, sensor=CurrentSensor(noise_std=0.0, offset=0.0, lsb=0.0))
    if tests == "pm":
        return {"d": axis_test(machine, quiet, "d").log, "q": axis_test(machine, quiet, "q").log,
                "dc": dc_test(machine, quiet)}  # fmt: skip
    return {"open": dfim_test(machine, quiet, "open", "injection"),
            "shorted": dfim_test(machine, quiet, "shorted", "injection"),
            "dc": dfim_test(machine, quiet, "open", "dc")}  # fmt: skip


def dead_time(repetitions: int, bootstrap: int) -> dict:
    """The PM standstill and DFIM rotor-side tests with the standstill study's inverter (2 us dead
    time, 1 V per device), fitted with the compensation (the DC steps' U_err, the simulated sign
    and the programmed dead time) and without it (the injections alone, as if the inverter were
    ideal, identifiability rules off so the bias shows). A repetition whose compensated fit is
    refused (an interval wider than +-50 %, or no convergence) is counted under ``refused`` and
    left out of the fractions."""
    from acdrive.errors import InputError
    from acdrive.identify import FitNotConverged
    from acdrive.identify._coverage import reading

    out = {}
    for label, machine, plan, identify, tests, truth in _dead_time_setups():
        logs = _quiet_logs(machine, plan, tests)
        for compensate in (True, False):
            table: dict = {}
            refused = 0
            for seed in range(repetitions):
                noisy = {name: reading(log, plan.sensor, len(logs) * seed + j)
                         for j, (name, log) in enumerate(logs.items())}  # fmt: skip
                try:
                    estimates = identify(noisy, compensate, seed, bootstrap)
                except (InputError, FitNotConverged):
                    refused += 1
                    continue
                for e in estimates:
                    _record(table, e.name, e, truth[e.name])
            n = repetitions - refused
            key = f"{label}_{'compensated' if compensate else 'uncompensated'}"
            out[key] = {"voltage_error_v": _voltage_error(plan), "dc_levels_v": plan.dc_levels,
                        "peak_current_a": max(float(abs(logs[k].i_a).max()) for k in logs),
                        "refused": refused}  # fmt: skip
            out[key] |= {
                name: {"coverage_jacobian": row["jacobian"] / n,
                       "coverage_bootstrap": row["bootstrap"] / n,
                       "mean_relative_error": row["error"] / n,
                       "mean_relative_half_width": row["width"] / n}
                for name, row in table.items()
            }  # fmt: skip
    return out


KINDS = {
    "standstill": None,
    "dead_time": None,
    "pm": pm,
    "no_load": no_load,
    "dfim": dfim,
    "mechanics": mechanics,
}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repetitions", type=int, default=50)
    parser.add_argument("--bootstrap", type=int, default=100)
    parser.add_argument("--only", choices=tuple(KINDS), default=None)
    args = parser.parse_args(argv)
    out = {"repetitions": args.repetitions, "bootstrap": args.bootstrap, "level": 0.95,
           "kinds": {}}  # fmt: skip
    for kind, study in KINDS.items():
        if args.only not in (None, kind):
            continue
        if study is None:
            run = standstill if kind == "standstill" else dead_time
            out["kinds"].update(run(args.repetitions, args.bootstrap))
            continue
        table: dict = {}
        for seed in range(args.repetitions):
            study(seed, args.bootstrap, table)
        n = args.repetitions
        out["kinds"][kind] = {
            name: {"coverage_jacobian": row["jacobian"] / n,
                   "coverage_bootstrap": row["bootstrap"] / n,
                   "mean_relative_error": row["error"] / n,
                   "mean_relative_half_width": row["width"] / n}
            for name, row in table.items()
        }  # fmt: skip
    print(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
