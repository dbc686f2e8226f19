"""``acdrive sweep FILE.toml``: run a parameter sweep (``acdrive.sweep``).

``acdrive sweep FILE.toml [--out DIR] [--scheduler tcp://host:port] [--timeout S] [--chunk N]
[--no-report] [--quiet]`` runs (or resumes: run the same command again) the sweep into
``DIR/<name>/`` with a progress bar on stderr, and prints that folder. FILE may also be the name
of a built-in sweep (``acdrive.sweep.builtin``).
"""

from __future__ import annotations

HELP = """Run a scenario over a grid or a seeded random set of parameter values, in chunks, into a
Parquet dataset (one file per chunk, written atomically; run the same command again to resume
after an interruption), then write report.md with figures. --scheduler sends the chunks to a
Dask cluster."""


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "sweep", help="run a scenario over a grid of parameter values", description=HELP
    )
    p.add_argument("sweep", help="sweep file (TOML) or built-in sweep name")
    p.add_argument(
        "--out", default="acdrive-sweeps", help="output folder (default: ./acdrive-sweeps/<name>)"
    )
    p.add_argument("--scheduler", default=None, help="Dask scheduler address, tcp://host:port")
    p.add_argument(
        "--timeout", type=float, default=10.0, help="seconds to reach the scheduler (10)"
    )
    p.add_argument("--chunk", type=int, default=None, help="variants per chunk (the file's)")
    p.add_argument("--no-report", action="store_true", help="skip report.md and figures")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(handler=run)


def run(args) -> int:
    import dataclasses
    import math

    from acdrive._output import require_out
    from acdrive.errors import InputError
    from acdrive.sweep._engine import run_sweep
    from acdrive.sweep._spec import MAX_CHUNK, load_sweep

    out = require_out("--out", args.out)  # before anything else: "" would mean "here"
    spec = load_sweep(args.sweep)
    if args.chunk is not None:
        if not 1 <= args.chunk <= MAX_CHUNK:
            raise InputError("--chunk", f"must be an integer from 1 to {MAX_CHUNK}")
        spec = dataclasses.replace(spec, chunk=args.chunk)
    if not (math.isfinite(args.timeout) and 0 < args.timeout <= 600):
        raise InputError("--timeout", "must be a number of seconds in (0, 600]")
    folder = run_sweep(spec, out, scheduler=args.scheduler, timeout=args.timeout,
                       progress=not args.quiet, report=not args.no_report)  # fmt: skip
    print(folder)
    return 0
