"""``acdrive sweep SWEEP``: run a parameter sweep (``acdrive.sweep``).

``acdrive sweep SWEEP [--out DIR] [--scheduler tcp://host:port] [--timeout S] [--chunk N]
[--no-report] [--quiet]`` runs (or resumes: run the same command again) the sweep into
``DIR/<sweep name>/`` (default ``DIR`` ``./acdrive-sweeps``, as ``acdrive run`` writes
``DIR/<scenario name>/``) with a progress bar on stderr, and prints that folder. SWEEP is a sweep
file (TOML) or the name of a built-in sweep (``acdrive.sweep.builtin``); ``acdrive sweep --list``
names the built-in sweeps with their size and description, and ``acdrive sweep --show NAME``
prints one of them, a sweep file to copy and edit. Interrupted (SIGINT, SIGTERM), the
command prints one line with the exact command that resumes the sweep (absolute paths, so it
works from any folder) before the CLI's own ``interrupted`` line.
"""

from __future__ import annotations

HELP = """Run a scenario over a grid or a seeded random set of parameter values, in chunks, into a
Parquet dataset (one file per chunk, written atomically; run the same command again to resume
after an interruption: an interrupted sweep prints that command), then write report.md with
figures. --scheduler sends the chunks to a Dask cluster. --list names the built-in sweeps,
--show NAME prints one (a sweep file to start from)."""

DEFAULT_OUT = "acdrive-sweeps"
DEFAULT_TIMEOUT = 10.0  # seconds to reach a Dask scheduler
#: the options of running a sweep, unused by --list and --show
RUN_OPTIONS = ("out", "scheduler", "timeout", "chunk")
#: the switches of running a sweep, unused by --list and --show
RUN_SWITCHES = ("no_report", "quiet")


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "sweep", help="run a scenario over a grid of parameter values", description=HELP
    )
    p.add_argument("sweep", nargs="?", help="sweep file (TOML) or built-in sweep name (see --list)")
    p.add_argument(
        "--list", action="store_true", help="name the built-in sweeps with a line on each"
    )
    p.add_argument(
        "--show", metavar="NAME", default=None,
        help="print the TOML file of one built-in sweep (a sweep file to start from)",
    )
    p.add_argument(
        "--out",
        default=None,
        help=f"the sweep is written to DIR/<sweep name>/ (default DIR: ./{DEFAULT_OUT}); a "
        "folder there that acdrive did not write is refused",
        metavar="DIR",
    )
    p.add_argument("--scheduler", default=None, help="Dask scheduler address, tcp://host:port")
    p.add_argument(
        "--timeout", type=float, default=None,
        help=f"seconds to reach the --scheduler ({DEFAULT_TIMEOUT:g})",
    )
    p.add_argument("--chunk", type=int, default=None, help="variants per chunk (the file's)")
    p.add_argument("--no-report", action="store_true", help="skip report.md and figures")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(handler=run)


def list_builtin() -> list[str]:
    """One aligned line per built-in sweep: name, sampling and size, base scenario, description
    (the sweep file's ``description``, first sentence)."""
    from acdrive.sweep import _variants as V
    from acdrive.sweep._spec import builtin_sweeps, load_sweep

    specs = [load_sweep(name) for name in builtin_sweeps()]
    width = max((len(s.name) for s in specs), default=0)
    lines = []
    for s in specs:
        first = s.description.split("; ")[0].split(". ")[0].rstrip(".")
        size = f"{s.method} of {V.count(s)} variants on {s.base}"
        lines.append(f"{s.name:<{width}}  {size}: {first}")
    return lines


def show_builtin(args) -> None:
    """Print the TOML file of the built-in sweep ``--show NAME`` as it is stored; a name that is
    no built-in sweep, or an option that runs a sweep beside it, is refused."""
    from acdrive._commands._options import flag, refuse_unused
    from acdrive.errors import InputError
    from acdrive.sweep._spec import builtin_sweeps, read_sweep_text

    names = builtin_sweeps()
    if args.show not in names:
        raise InputError("--show", f"must be one of {', '.join(names)}, got '{args.show}'")
    why = "it prints a built-in sweep, running none"
    if args.sweep is not None:
        raise InputError("--show", "prints a built-in sweep and takes no SWEEP")
    if args.list:
        raise InputError("--list", f"does not apply with --show: {why}")
    refuse_unused(args, RUN_OPTIONS, "--show", why)
    for switch in RUN_SWITCHES:
        if getattr(args, switch):
            raise InputError(flag(switch), f"does not apply with --show: {why}")
    print(read_sweep_text(args.show)[0], end="")


def resume_command(args) -> str:
    """The shell command that runs this sweep again into the same folder (so resumes it): the
    options given, with the sweep file and ``--out`` as absolute paths."""
    import os
    import shlex

    from acdrive.sweep._spec import builtin_sweeps

    source = args.sweep if args.sweep in builtin_sweeps() else os.path.abspath(args.sweep)
    words = ["acdrive", "sweep", source, "--out", os.path.abspath(args.out)]
    if args.scheduler:
        words += ["--scheduler", args.scheduler, "--timeout", f"{args.timeout:g}"]
    words += ["--no-report"] * args.no_report + ["--quiet"] * args.quiet
    return shlex.join(words)  # a resume keeps the first run's chunk size: no --chunk


def run(args) -> int:
    import dataclasses
    import math
    import sys

    from acdrive._commands._options import flag, refuse_unused
    from acdrive._output import require_out
    from acdrive.errors import InputError, Terminated, call_interruptible, named_as
    from acdrive.sweep._engine import run_sweep, sweep_progress
    from acdrive.sweep._spec import MAX_CHUNK, load_sweep

    if args.show is not None:
        show_builtin(args)
        return 0
    if args.list:
        if args.sweep is not None:
            raise InputError("--list", "names the built-in sweeps and takes no SWEEP")
        refuse_unused(args, RUN_OPTIONS, "--list", "it names the built-in sweeps, running none")
        for switch in RUN_SWITCHES:
            if getattr(args, switch):
                raise InputError(flag(switch), "does not apply with --list: it names the "
                                 "built-in sweeps, running none")  # fmt: skip
        print("\n".join(list_builtin()))
        return 0
    if args.sweep is None:
        raise InputError("sweep", "give a sweep file (TOML) or a built-in sweep name (--list)")
    if args.timeout is not None and args.scheduler is None:
        raise InputError("--timeout", "does not apply without --scheduler: it bounds the wait "
                         "for a Dask scheduler")  # fmt: skip
    args.out = DEFAULT_OUT if args.out is None else args.out
    args.timeout = DEFAULT_TIMEOUT if args.timeout is None else args.timeout
    out = require_out("--out", args.out)  # before anything else: "" would mean "here"
    with named_as({"source": "sweep"}):
        spec = load_sweep(args.sweep)
    if args.chunk is not None:
        if not 1 <= args.chunk <= MAX_CHUNK:
            raise InputError("--chunk", f"must be an integer from 1 to {MAX_CHUNK}")
        spec = dataclasses.replace(spec, chunk=args.chunk)
    if not (math.isfinite(args.timeout) and 0 < args.timeout <= 600):
        raise InputError(
            "--timeout", f"must be a number of seconds in (0, 600], got {args.timeout:g}"
        )
    command = resume_command(args)
    try:
        with named_as({"out": "--out", "scheduler": "--scheduler", "timeout": "--timeout"}):
            folder = call_interruptible(
                lambda: run_sweep(spec, out, scheduler=args.scheduler, timeout=args.timeout,
                                  progress=not args.quiet, report=not args.no_report,
                                  command=command)
            )  # fmt: skip
    except (KeyboardInterrupt, Terminated):
        state = sweep_progress(out / spec.name)
        done = f"{state[0]} of {state[1]} variants done; " if state else ""
        sys.stderr.write(f"acdrive: sweep {spec.name} stopped ({done}resume with: {command})\n")
        raise
    refuse_all_invalid(args.sweep, folder)
    print(folder)
    return 0


def refuse_all_invalid(source: str, folder) -> None:
    """An ``InputError`` on ``sweep`` if no variant of the finished sweep in ``folder`` is valid
    (every one refused by the scenario loader, so nothing was simulated): the count, the first
    variant's reason, and where the table keeps every reason. The folder stays (acdrive wrote it;
    its table and report are the record of each refusal)."""
    from pathlib import Path

    import pyarrow.dataset as ds

    from acdrive.errors import InputError

    table = ds.dataset(Path(folder) / "table", format="parquet").to_table(
        columns=["variant", "valid", "reason"]
    )
    valid = table.column("valid").to_pylist()
    if not valid or any(valid):
        return
    first = min(range(len(valid)), key=table.column("variant").to_pylist().__getitem__)
    raise InputError(
        "sweep",
        f"none of the {len(valid)} variants of {source} is valid (nothing was simulated; variant "
        f"{table.column('variant')[first].as_py()}: {table.column('reason')[first].as_py()}); "
        f"every reason is in {Path(folder) / 'table'}",
    )
