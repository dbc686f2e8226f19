"""``acdrive bench``: the benchmark suite (``acdrive._bench.suite``) against motulator 0.18 and
gym-electric-motor 3.0.3, measured in one run on this machine, plus the ICAD timings."""

from __future__ import annotations

from acdrive._bench.suite import CASES as CASE_NAMES  # the suite names its cases once


def register(subparsers):
    p = subparsers.add_parser(
        "bench",
        help="benchmark suite: speed ratios against motulator and gym-electric-motor (both "
        "sides timed in interleaved process-CPU-time windows, with spread and load) with both "
        "sides' accuracy, and the ICAD timings (grid, point, `reproduce icad`)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON document to stdout")
    p.add_argument("--quick", action="store_true", help="short model times (a smoke test)")
    p.add_argument("--no-peers", action="store_true", help="measure acdrive only")
    p.add_argument("--no-reference", action="store_true", help="skip the accuracy references")
    p.add_argument(
        "--no-reference-cache",
        action="store_true",
        help="compute the accuracy references afresh, without reading or writing the on-disk "
        "cache ($XDG_CACHE_HOME/acdrive/bench-references)",
    )
    p.add_argument(
        "--baseline-src",
        metavar="DIR",
        help="src folder of the tree the loop_speed case compares the loop's steps/s against "
        "(e.g. a worktree of main)",
    )
    p.add_argument("--only", nargs="+", metavar="NAME", help=f"cases: {', '.join(CASE_NAMES)}")
    p.add_argument(
        "--peers-dir",
        help="folder of the peers' virtualenvs (default $XDG_CACHE_HOME/acdrive/peers or "
        "~/.cache/acdrive/peers)",
    )
    p.set_defaults(handler=run)


def run(args) -> int:
    import json
    import sys
    from pathlib import Path

    from acdrive._bench.common import finite
    from acdrive._bench.suite import Options, run_suite, table
    from acdrive.errors import InputError

    only = tuple(args.only or CASE_NAMES)
    for name in only:
        if name not in CASE_NAMES:
            raise InputError(
                "--only", f"each name must be one of {', '.join(CASE_NAMES)}, got {name!r}"
            )
    if args.peers_dir is not None and args.no_peers:
        raise InputError("--peers-dir", "does not apply with --no-peers: no peer is measured")
    if args.no_reference_cache and args.no_reference:
        raise InputError("--no-reference-cache", "does not apply with --no-reference: no "
                         "accuracy reference is computed")  # fmt: skip
    if args.baseline_src is not None and "loop_speed" not in only:
        raise InputError("--baseline-src", "does not apply with --only without loop_speed: only "
                         "the loop_speed case compares against a baseline tree")  # fmt: skip
    peers_dir = None
    if args.peers_dir is not None:
        if not args.peers_dir.strip():
            raise InputError("--peers-dir", "must be a folder path")
        peers_dir = Path(args.peers_dir).expanduser().resolve()
        if peers_dir.exists() and not peers_dir.is_dir():
            raise InputError("--peers-dir", f"{peers_dir} exists and is not a folder")

    def log(message: str) -> None:
        sys.stderr.write(message + "\n")
        sys.stderr.flush()

    baseline = None
    if args.baseline_src is not None:
        baseline = Path(args.baseline_src).expanduser().resolve()
        if not (baseline / "acdrive" / "__init__.py").is_file():
            raise InputError(
                "--baseline-src", f"must be a src folder holding acdrive/, got {baseline}"
            )

    options = Options(
        quick=args.quick,
        peers=not args.no_peers,
        reference=not args.no_reference,
        reference_cache=not args.no_reference_cache,
        only=only,
        peers_dir=peers_dir,
        baseline_src=baseline,
        log=log,
    )
    report = run_suite(options)
    if args.json:
        for warning in report["warnings"]:  # the table prints them itself
            log(f"acdrive: warning: {warning} (rule: see load_rule)")
        print(json.dumps(finite(report), indent=2, allow_nan=False))
    else:
        print(table(report))
    return 0
