"""``acdrive reproduce PAPER [--out DIR]``: regenerate a paper's reproduction report.

Each paper maps to a module ``acdrive._report.<name>_reproduction`` exposing
``write_report(out_dir) -> Path``; a paper whose module does not exist yet is a one-line error
with exit code 2.

The report is ``DIR/<stem>.md`` beside its figure folder ``DIR/<stem>/`` (the stem is the
paper's name unless ``STEMS`` gives another); ``DIR`` is ``./acdrive-out`` unless ``--out`` says
otherwise, as for ``acdrive run``. The committed reports in ``docs/reproduction/`` are regenerated
with an explicit ``--out docs/reproduction``. Both entries are written like
``acdrive run``'s output (``acdrive._output.OutputEntries``): DIR and the two entries are checked
before any computation (an existing ``<paper>.md`` must be a file and ``<paper>`` a folder, never
a symbolic link), the writer works in a hidden staging folder inside DIR, and the two entries are
swapped in together with SIGINT/SIGTERM blocked, so an interruption leaves the complete old report
or the complete new one. Nothing else in DIR is touched.
"""

from __future__ import annotations

import importlib
import sys

#: Paper name -> report module (written by its owner; may not exist yet).
REPORTS = {
    "icad": "acdrive._report.icad_reproduction",
    "bodson": "acdrive._report.bodson_reproduction",
    "im": "acdrive._report.im_reproduction",
}
#: Default --out: the folder every acdrive command writes into unless told otherwise (the same as
#: ``acdrive run``'s; never the project's docs/, which a user's run must not overwrite).
DEFAULT_OUT = "acdrive-out"
#: Paper name -> report file stem, where it is not the paper's name.
STEMS = {"im": "im-current-control"}

HELP = """Recompute every number and figure of a paper's analysis and write a Markdown report
(DIR/<paper>.md, figures in DIR/<paper>/; default DIR ./acdrive-out) with the printed value
beside acdrive's and the reason for each difference. The committed reports are regenerated with
--out docs/reproduction. Papers: icad (Ugalde-Loo et al. and Amezquita-Brooks et al.), bodson, im
(Amezquita-Brooks et al. secs. VI-VIII, im-current-control.md)."""


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "reproduce", help="regenerate a reproduction report", description=HELP
    )
    parser.add_argument("paper", choices=sorted(REPORTS), help="which paper(s)")
    parser.add_argument(
        "--out",
        default=DEFAULT_OUT,
        metavar="DIR",
        help=f"output folder (default ./{DEFAULT_OUT}): DIR/<paper>.md and DIR/<paper>/ are "
        "replaced together; nothing else in DIR is touched",
    )
    parser.set_defaults(handler=run)


def run(args) -> int:
    module_name = REPORTS[args.paper]
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        if exc.name != module_name:
            raise
        sys.stderr.write(f"acdrive: error: reproduce {args.paper}: report not available yet\n")
        return 2
    from acdrive._output import FILE, FOLDER, OutputEntries

    stem = STEMS.get(args.paper, args.paper)
    entries = {f"{stem}.md": FILE, stem: FOLDER}
    from acdrive._progress import Progress

    with (
        OutputEntries(args.out, entries, field="--out", name_field="paper") as output,
        Progress(1, f"reproduce {args.paper}") as bar,
    ):
        bar.phase("recomputing every number and figure")
        staged = module.write_report(output.staging)  # --out checked before the computation
        output.publish()
        bar.advance()
    print(output.target(staged))  # the report; its figures are in the folder beside it
    return 0
