"""``acdrive run [SCENARIO]``: simulate a scenario, write data, figures and summary.json.

The output goes to ``<--out>/<scenario name>/`` (printed at the end): the data as Parquet (the
default), CSV or MATLAB ``.mat`` (``--format``) with ``columns.md`` (every column's unit and
description, ``acdrive.columns``), the figures and summary.json. The headline printed is computed
from the summary: the speed tracking error where tracking is expected
(``acdrive.sim._metrics``: the intended reference steps and their settling are excluded, and
said so), the same over the whole run, peak currents against their limits, events.
"""

from __future__ import annotations

from acdrive._output import OutputFolder
from acdrive.columns import DEFAULT_FORMAT, FORMATS, print_headline

DEFAULT_SCENARIO = "bodson-ramp"
DEFAULT_OUT = "acdrive-out"


def register(subparsers):
    p = subparsers.add_parser("run", help="simulate a scenario (default: the Bodson Fig. 4 ramp)")
    p.add_argument(
        "scenario",
        nargs="?",
        default=DEFAULT_SCENARIO,
        help="built-in scenario name (see `acdrive scenarios`) or a TOML file",
    )
    p.add_argument(
        "--out",
        default=DEFAULT_OUT,
        metavar="DIR",
        help=f"parent folder: the output is written to DIR/<scenario name>/ (default ./{DEFAULT_OUT})",
    )
    p.add_argument(
        "--format",
        choices=tuple(FORMATS),
        default=DEFAULT_FORMAT,
        help=f"data file format (default {DEFAULT_FORMAT}); units and descriptions of the columns "
        "are in columns.md beside it",
    )
    p.add_argument("--no-figures", action="store_true", help="skip the figures")
    p.set_defaults(handler=run)


def tracking_row(tracking: dict) -> str:
    """The headline's speed tracking figures, from a ``speed_tracking`` summary."""
    if tracking["rms_error_rpm"] is None:
        return "not expected anywhere in this run (" + tracking["rule"] + ")"
    windows = tracking["windows_s"]
    excluded = (
        "; settling after reference steps excluded: "
        + ", ".join(f"{a:.3g}-{b:.3g} s" for a, b in windows)
        if windows
        else ""
    )
    return (
        f"{tracking['rms_error_rpm']:.2f} rpm RMS, largest {tracking['max_abs_error_rpm']:.2f} rpm "
        f"at {tracking['max_abs_error_at_s']:.3f} s, over {tracking['tracked_fraction']:.0%} of "
        f"the run{excluded}"
    )


def whole_run_row(summary: dict) -> str:
    """The headline's whole-run speed error figures (motor 1, the first mode), from the
    summary's ``speed_*_whole_run_*`` keys."""
    return (
        f"{summary['speed_rms_error_whole_run_rpm']:.2f} rpm RMS, largest "
        f"{summary['speed_max_abs_error_whole_run_rpm']:.2f} rpm at "
        f"{summary['speed_max_abs_error_whole_run_at_s']:.3f} s (every sample, the settling after "
        "reference steps included)"
    )


def run(args) -> int:
    from acdrive._progress import Progress
    from acdrive.scenarios._loader import load_scenario

    setup = load_scenario(args.scenario)  # validates everything before any output exists
    from acdrive.sim._im_drive import IMDriveSetup

    if isinstance(setup, IMDriveSetup):  # a cage induction motor drive: its own outputs
        from acdrive._commands.im_run import run_im

        return run_im(args, setup)
    from acdrive._report.drive_outputs import write_outcome
    from acdrive.sim import _codegen as codegen
    from acdrive.sim._outcome import MODE_SUFFIX, run_scenario

    n_runs = len(setup.compare_modes) or 1
    with (
        OutputFolder(args.out, setup.name) as output,  # --out checked before the simulation
        Progress(n_runs + 1, f"run {setup.name}") as bar,
    ):
        first = [True]

        def on_run(mode):
            if not first[0]:
                bar.advance()
            first[0] = False
            bar.phase(f"simulating ({mode} command)")

        outcome = run_scenario(setup, on_run=on_run)
        codegen.record_compile_times()
        bar.advance()
        bar.phase("writing data" + (" and figures" if not args.no_figures else ""))
        write_outcome(outcome, output.staging, figures=not args.no_figures, fmt=args.format)
        target = output.publish()
        bar.advance()
    summary = outcome.summary
    wall = sum(r.wall_time for r in outcome.results.values())
    n = len(setup.motors)
    print(
        f"scenario {setup.name}: {setup.duration:g} s simulated in {wall:.2f} s ({n} motor{'s' * (n > 1)})"
    )
    rotor_limit = max(m.controller.rotor_current_limit_pk for m in setup.motors)
    stator_limit = max(m.controller.stator_current_limit_pk for m in setup.motors)
    if len(outcome.results) > 1:
        rows = [
            (
                f"speed tracking, {mode}",
                tracking_row(summary[f"speed_tracking_{MODE_SUFFIX[mode]}"]),
            )
            for mode in outcome.results
        ]
    else:
        rows = [("speed tracking", tracking_row(summary["speed_tracking"]))]
    rows.append(("speed error, whole run", whole_run_row(summary)))
    rows += [
        (
            "peak rotor current",
            f"{summary['peak_rotor_current_a']:.2f} A (limit {rotor_limit:g} A)",
        ),
        (
            "peak stator current",
            f"{summary['peak_stator_current_a']:.2f} A (limit {stator_limit:g} A)",
        ),
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
    print_headline(rows, summary, target, args.format)
    return 0
