"""``acdrive run [SCENARIO]``: simulate a scenario, write data, figures and summary.json."""

from __future__ import annotations

from acdrive.output import OutputFolder

DEFAULT_SCENARIO = "bodson-ramp"


def register(subparsers):
    p = subparsers.add_parser("run", help="simulate a scenario (default: the Bodson Fig. 4 ramp)")
    p.add_argument(
        "scenario",
        nargs="?",
        default=DEFAULT_SCENARIO,
        help="built-in scenario name (see `acdrive scenarios`) or a TOML file",
    )
    p.add_argument(
        "--out", default="acdrive-out", help="output folder (default: ./acdrive-out/<scenario>)"
    )
    p.add_argument("--no-figures", action="store_true", help="skip the figures")
    p.set_defaults(handler=run)


def run(args) -> int:
    from acdrive.report.drive_outputs import write_outcome
    from acdrive.scenarios.loader import load_scenario
    from acdrive.sim.outcome import run_scenario

    setup = load_scenario(args.scenario)  # validates everything before any output exists
    from acdrive.sim.im_drive import IMDriveSetup

    if isinstance(setup, IMDriveSetup):  # a cage induction motor drive: its own outputs
        from acdrive.commands.im_run import run_im

        return run_im(args, setup)
    with OutputFolder(args.out, setup.name) as output:  # --out checked before the simulation
        outcome = run_scenario(setup)
        summary = outcome.summary
        write_outcome(outcome, output.staging, figures=not args.no_figures)
        target = output.publish()
    wall = sum(r.wall_time for r in outcome.results.values())
    n = len(setup.motors)
    print(
        f"scenario {setup.name}: {setup.duration:g} s simulated in {wall:.2f} s ({n} motor{'s' * (n > 1)})"
    )
    rotor_limit = max(m.controller.rotor_current_limit_pk for m in setup.motors)
    rows = [
        ("speed RMS tracking error", f"{summary['speed_rms_error_rpm']:.2f} rpm"),
        ("max |speed error|", f"{summary['speed_max_abs_error_rpm']:.1f} rpm"),
        ("peak rotor current", f"{summary['peak_rotor_current_a']:.2f} A (limit {rotor_limit:g} A)"),
        ("peak stator current", f"{summary['peak_stator_current_a']:.2f} A"),
    ]
    for key in ("peak_rotor_current_vc_a", "peak_rotor_current_cc_a"):
        if key in summary:
            rows.append((key.replace("_", " ").replace(" a", " (A)"), f"{summary[key]:.2f}"))
    if "synchronisation" in summary and summary["synchronisation"].get("relay_closed"):
        sync = summary["synchronisation"]
        rows.append(
            (
                "relay closed at",
                (
                    f"{sync['closing_time_s']:.3f} s, stator current peak "
                    f"{sync['closing_stator_current_peak_a']:.2f} A"
                ),
            )
        )
    events = ", ".join(f"{k} {v}" for k, v in summary["limit_events"].items() if v) or "none"
    rows.append(("events (samples)", events))
    for label, value in rows:
        print(f"  {label:<26} {value}")
    if "finding" in summary:
        print(f"  finding: {summary['finding']}")
    for warning in summary.get("warnings", []):
        print(f"  warning: {warning}")
    if "note" in summary:
        print(f"  note: {summary['note']}")
    print(f"wrote {target}/ (data.csv, data.parquet, summary.json, figures)")
    return 0
