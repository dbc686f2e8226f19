"""``acdrive robustness SCENARIO``: a robustness map of plant-parameter errors.

``acdrive robustness SCENARIO [--map grid|monte-carlo] [--params R_s,R_r,...,paper]
[--points N] [--variants N] [--low F] [--high F] [--severity-max S] [--seed N] [--resolution R]
[--tracking-tolerance X] [--current-tolerance X] [--duration S] [--linear|--no-linear]
[--out DIR] [--json]`` runs ``acdrive.robustness.robustness_map`` and prints its findings (or
the JSON of every row with ``--json``); ``--out`` writes map.json, report.md and map.png.
Every option is checked before any simulation; a bad one is one line naming it, exit 2.
"""

from __future__ import annotations

import argparse
import contextlib

HELP = """Map how robust a drive is to parameter errors: the simulated plant's parameters
multiplied by factors (R_s, R_r, L_s, L_r, L_m, J, and the combined perturbation of
Amezquita-Brooks et al. sec. VIII as the axis 'paper'), the controllers kept on the nominal
design, every variant run in the compiled batch loop and judged by the drive's stated
tolerances on tracking, current limits and stability, with the linearised prediction beside."""


def register(subparsers) -> None:
    from acdrive.robustness._map import DEFAULT_POINTS, DEFAULT_VARIANTS, KINDS, PAPER, PARAMETERS

    p = subparsers.add_parser("robustness", help="robustness map of parameter errors (grid or Monte Carlo, batch engine)",
                              description=HELP)  # fmt: skip
    p.add_argument("scenario", metavar="SCENARIO", help="built-in scenario name or TOML path")
    p.add_argument("--map", choices=KINDS, default=None, help="grid (default) or monte-carlo")
    p.add_argument("--params", default=None,
                   help=f"comma-separated axes of {','.join((*PARAMETERS, PAPER))} (default: every "
                        "one the drive perturbs; monte-carlo: the single parameters)")  # fmt: skip
    p.add_argument("--points", type=int, default=None,
                   help=f"grid points per axis [{DEFAULT_POINTS}]")  # fmt: skip
    p.add_argument("--variants", type=int, default=None,
                   help=f"monte-carlo variants, the nominal included [{DEFAULT_VARIANTS}]")  # fmt: skip
    p.add_argument("--low", type=float, default=None, help="smallest factor [0.5]")
    p.add_argument("--high", type=float, default=None, help="largest factor [2]")
    p.add_argument("--severity-max", type=float, default=None,
                   help="largest severity s of the paper axis (factors PAPER^s) [2]")  # fmt: skip
    p.add_argument("--seed", type=int, default=None, help="monte-carlo seed [1]")
    p.add_argument("--resolution", type=float, default=None,
                   help="a grid's boundaries are bisected until the passing and the breaking "
                        "variant are this close, in |ln f| (severity on the paper axis) [0.001]")  # fmt: skip
    p.add_argument("--tracking-tolerance", type=float, default=None,
                   help="tracking criterion's fraction (default: the drive's)")  # fmt: skip
    p.add_argument("--current-tolerance", type=float, default=0.05,
                   help="fraction a peak current may exceed its limit [0.05]")  # fmt: skip
    p.add_argument("--duration", type=float, default=None,
                   help="override simulation.duration of every variant (s)")  # fmt: skip
    p.add_argument("--linear", action=argparse.BooleanOptionalAction, default=None,
                   help="linearised prediction per variant (default: grid yes, monte-carlo no)")  # fmt: skip
    p.add_argument("--estimates", default=None, metavar="PARAMS_FILE",
                   help="instead of a map: run the scenario with its controllers designed on this "
                        "machine parameter file (e.g. from acdrive identify) and on the truth, "
                        "side by side")  # fmt: skip
    p.add_argument("--out", default=None, help="folder to write map.json, report.md, map.png into")
    p.add_argument("--json", action="store_true", help="print the map as JSON")
    p.set_defaults(handler=run)


#: the Python arguments of MapSpec, robustness_map and design_comparison -> their options
FLAGS = {"kind": "--map", "params": "--params", "spec.params": "--params", "points": "--points",
         "variants": "--variants", "low": "--low", "high": "--high",
         "severity_max": "--severity-max", "seed": "--seed", "resolution": "--resolution",
         "tracking_tolerance": "--tracking-tolerance",
         "current_tolerance": "--current-tolerance", "estimates": "--estimates"}  # fmt: skip


def _params(text: str | None, kind: str) -> tuple:
    from acdrive.errors import InputError

    if text is None:
        return None  # MapSpec's default: every parameter, and on a grid the paper axis
    names = tuple(t.strip() for t in text.split(","))
    if any(not n for n in names):
        raise InputError("--params", "must be comma-separated names without empty entries")
    return names


#: the options of a map, unused by --estimates (a design comparison runs the scenario twice)
MAP_OPTIONS = ("map", "params", "points", "variants", "low", "high", "severity_max", "seed",
               "resolution", "linear", "out")  # fmt: skip


def _map_defaults() -> dict:
    """The values of the map options not given."""
    from acdrive.robustness._map import DEFAULT_POINTS, DEFAULT_RESOLUTION, DEFAULT_VARIANTS

    return {"map": "grid", "points": DEFAULT_POINTS, "variants": DEFAULT_VARIANTS, "low": 0.5,
            "high": 2.0, "severity_max": 2.0, "seed": 1, "resolution": DEFAULT_RESOLUTION}


def _overrides(args) -> dict:
    """The scenario overrides of the options (``--duration``), each checked under its flag."""
    from acdrive.errors import require_positive

    if args.duration is None:
        return {}
    return {"simulation.duration": require_positive("--duration", args.duration)}


@contextlib.contextmanager
def _typed_names(args):
    """Errors on a scenario field an option set (``--duration``, ``--estimates``) name the
    option: the user typed it, not the field."""
    from acdrive.errors import InputError

    try:
        yield
    except InputError as exc:
        field = exc.field
        if args.duration is not None and field == "simulation.duration":
            field = "--duration"
        elif args.estimates is not None and (field == "estimates"
                                             or field.endswith("design.machine_file")):  # fmt: skip
            field = "--estimates"
        if field == exc.field:
            raise
        raise InputError(field, exc.rule) from None


def _compare(args) -> int:
    from acdrive._commands._options import refuse_unused
    from acdrive._output import strict_json
    from acdrive.errors import named_as
    from acdrive.robustness._design import design_comparison

    refuse_unused(args, MAP_OPTIONS, "--estimates", "it compares two designs of the scenario, "
                  "no map is run (use --json to keep the comparison)")  # fmt: skip
    overrides = _overrides(args)
    with _typed_names(args), named_as(FLAGS):
        c = design_comparison(args.scenario, args.estimates,
                              tracking_tolerance=args.tracking_tolerance,
                              current_tolerance=args.current_tolerance, overrides=overrides)  # fmt: skip
    print(strict_json(c.to_json(), indent=1) if args.json else "\n".join(c.lines()))
    return 0


def run(args) -> int:
    from pathlib import Path

    from acdrive._output import OutputFolder, strict_json
    from acdrive.errors import named_as
    from acdrive.robustness._map import MapSpec, robustness_map
    from acdrive.robustness._report import report_lines, write_into

    if args.estimates is not None:
        return _compare(args)
    from acdrive._commands._options import refuse_unused

    kind = args.map or "grid"
    if kind == "grid":
        refuse_unused(args, ("variants", "seed"), "a grid map (--map grid, the default)",
                      "--variants and --seed draw a --map monte-carlo")  # fmt: skip
    else:
        refuse_unused(args, ("points", "severity_max", "resolution"), "--map monte-carlo",
                      "--points, --severity-max and --resolution set the axes of a grid")  # fmt: skip
    for dest, value in _map_defaults().items():
        if getattr(args, dest) is None:
            setattr(args, dest, value)
    with named_as(FLAGS):
        spec = MapSpec(kind=args.map, params=_params(args.params, args.map), points=args.points,
                       variants=args.variants, low=args.low, high=args.high,
                       severity_max=args.severity_max, seed=args.seed,
                       resolution=args.resolution)  # fmt: skip
    overrides = _overrides(args)
    with contextlib.ExitStack() as stack:
        stack.enter_context(_typed_names(args))
        folder = None
        if args.out is not None:  # --out is checked here, before any simulation
            name = f"{Path(args.scenario).stem}-robustness"
            folder = stack.enter_context(OutputFolder(args.out, name))
        with named_as(FLAGS):
            m = robustness_map(args.scenario, spec, tracking_tolerance=args.tracking_tolerance,
                               current_tolerance=args.current_tolerance, linear=args.linear,
                               overrides=overrides)  # fmt: skip
        if folder is not None:
            write_into(m, folder.staging)
            folder.publish()
    if args.json:
        print(strict_json(m.to_json(), indent=1))
    else:
        print("\n".join(report_lines(m)[1:]))
    return 0
