"""``acdrive run [SCENARIO]``: simulate a scenario, write data, figures and summary.json.

The output goes to ``<--out>/<scenario name>/`` (printed at the end): the data as Parquet (the
default), CSV or MATLAB ``.mat`` (``--format``) with ``columns.md`` (every column's unit and
description, ``acdrive.columns``), the figures and summary.json. The scenario's drive
(``acdrive.drives``: its ``drive = "..."``, the DFIM if absent) runs it, writes its files and
computes the headline printed from the summary.
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
    p.add_argument(
        "--log-every",
        metavar="K",
        help="log every K-th control sample (an integer >= 1; default: the scenario's "
        "simulation.log_every, else every sample of a run of at most 100,000 samples and every "
        "k-th of a longer one so that at most 100,000 are kept)",
    )
    p.set_defaults(handler=run)


def run(args) -> int:
    from acdrive._progress import Progress
    from acdrive.drives import for_setup
    from acdrive.scenarios._loader import build_setup, read_scenario
    from acdrive.sim import _codegen as codegen

    data = read_scenario(args.scenario)
    setup = build_setup(data)  # validates everything before any output exists
    drive = for_setup(setup)
    setup, plan = _log_choice(args.log_every, data, setup, drive)
    n_runs = drive.runs(setup)
    if plan is not None:
        runs = f"; each of {n_runs} runs" if n_runs > 1 else ""
        print(f"running {setup.name}: {setup.duration:g} s, {plan.n_steps:,} samples{runs}; "
              f"{plan.describe()}", flush=True)  # fmt: skip
    with (
        OutputFolder(args.out, setup.name) as output,  # --out checked before the simulation
        Progress(n_runs + 1, f"run {setup.name}") as bar,
    ):
        first = [True]

        def on_run(label):
            if not first[0]:
                bar.advance()
            first[0] = False
            bar.phase(f"simulating ({label})")

        outcome = drive.run(setup, on_run=on_run)
        if plan is not None:  # the log this command chose, stated with the run's summary
            outcome.summary["log"] = plan.summary()
        codegen.record_compile_times()
        bar.advance()
        bar.phase("writing data" + (" and figures" if not args.no_figures else ""))
        summary = drive.write(outcome, output.staging, figures=not args.no_figures, fmt=args.format)
        target = output.publish()
        bar.advance()
    line, rows = drive.headline(outcome, summary)
    print(line)
    print_headline(rows, summary, target, args.format)
    return 0


def _log_choice(flag, data: dict, setup, drive):
    """(setup with the chosen ``log_every``, its ``LogPlan``; None where the drive cannot tell
    its log before the run). ``--log-every`` wins over the scenario's ``simulation.log_every``,
    which wins over the default the scenario loader applied."""
    import dataclasses

    from acdrive.errors import InputError
    from acdrive.sim._compiled import LOG_BUDGET_BYTES
    from acdrive.sim._log_plan import LogPlan, run_steps

    chosen_by = "default"
    simulation = data.get("simulation")
    if isinstance(simulation, dict) and "log_every" in simulation:
        chosen_by = "simulation.log_every"
    has_log_every = hasattr(setup, "log_every")
    if flag is not None:
        if not has_log_every:
            raise InputError("--log-every", f"scenario {setup.name!r} has no log to thin (its "
                             "runs log what they compare)")  # fmt: skip
        try:
            every = int(flag)
        except ValueError:
            raise InputError("--log-every", f"must be an integer >= 1, got {flag!r}") from None
        if every < 1:
            raise InputError("--log-every", f"must be an integer >= 1, got {flag!r}")
        steps = run_steps(setup.duration, setup.sample_time)
        if every > steps:
            raise InputError("--log-every", f"must not exceed the run's {steps} control samples, "
                             f"got {every}")  # fmt: skip
        setup = dataclasses.replace(setup, log_every=every)
        chosen_by = "--log-every"
    width = drive.log_width(setup) if has_log_every else None
    if width is None:
        return setup, None
    plan = LogPlan(run_steps(setup.duration, setup.sample_time), setup.log_every, *width,
                   chosen_by=chosen_by)  # fmt: skip
    if plan.bytes > LOG_BUDGET_BYTES:
        field = "--log-every" if chosen_by == "--log-every" else "simulation.log_every"
        raise InputError(field, f"the log would take {plan.bytes / 1024**3:.3g} GB (limit "
                         f"{LOG_BUDGET_BYTES / 1024**3:g} GB): log every k-th sample with a "
                         "larger k")  # fmt: skip
    return setup, plan
