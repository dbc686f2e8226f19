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
    p.set_defaults(handler=run)


def run(args) -> int:
    from acdrive._progress import Progress
    from acdrive.drives import for_setup
    from acdrive.scenarios._loader import load_scenario
    from acdrive.sim import _codegen as codegen

    setup = load_scenario(args.scenario)  # validates everything before any output exists
    drive = for_setup(setup)
    n_runs = drive.runs(setup)
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
