"""``acdrive stability``: small-signal stability of the whole DFIM speed drive.

``acdrive stability --mode {voltage,current} --speed-rpm S --load-nm T [--bandwidth A] --json``
linearises the closed loop at one operating point and prints its eigenvalues;
``acdrive stability --map [--out DIR] [--json]`` maps the stable and unstable regions over
speed x load for both modes at the given velocity bandwidth (default: the paper's 314 rad/s),
draws them (PNG) and reports the largest velocity bandwidth each mode tolerates on that grid;
``acdrive stability --scenario NAME [--speed-rpm S] [--load-nm T] [--model sampled]`` linearises
a DFIM scenario's own drive (motor 0 on its supply; default point: its final speed reference and
load), with every setting of the scenario;
``acdrive stability --bench [--json]`` evaluates the effects the paper's test bench may have had
(voltage command) and how large each must be to remove the instability.
Method and results: docs/stability.md.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

from acdrive._output import strict_json
from acdrive.errors import InputError, require_between, require_finite, require_positive

HELP = """Linearised closed loop of Bodson's DFIM speed drive (machine (9), torque law (20)+(22)
or rotor current loop (43)-(47), speed PI (25)-(27), mechanics (26)). --model continuous uses the
continuous-time law; --model sampled linearises the simulator's own sampled-data loop (5 kHz,
zero-order hold, encoder backward difference; --delay-samples 1 adds a computation delay)."""

PAPER_BANDWIDTH = 314.0  # a_D,VEL of Bodson IV-A [rad/s]
UPPER_BANDWIDTH = 20000.0  # search limit of the tolerated a_D,VEL [rad/s]

#: Accepted range of each numeric flag: generous for this 0.27 N m laboratory machine, and narrow
#: enough that the equilibrium and the linearisation stay within float64 (so an error names the
#: flag that is out of range, not a failed equilibrium).
RANGES = {
    "--bandwidth": (1e-3, 1e6),  # rad/s
    "--load-nm": (-1e3, 1e3),  # N m
    "--speed-filter-tau": (0.0, 10.0),  # s
    "--supply-resistance": (0.0, 1e3),  # ohm
    "--supply-inductance": (0.0, 10.0),  # H
    "--viscous-friction": (0.0, 1e3),  # N m s/rad
    "--inertia": (1e-9, 1e3),  # kg m^2
    "--rotor-resistance": (1e-6, 1e3),  # ohm
    "--converter-loss": (0.0, 1e3),  # V
}
MAX_GRID = 60  # speeds or loads of --map
DEFAULT_OUT = "stability-map"  # folder of --map's figure

#: the options of the linearised model of Bodson's drive (one point, --map): --scenario sets
#: its own drive up, --bench its own candidates
MODEL_OPTIONS = ("bandwidth", "speed_filter_tau", "supply_resistance", "supply_inductance",
                 "viscous_friction", "inertia", "rotor_resistance", "converter_loss")  # fmt: skip
#: the options of --map alone
MAP_OPTIONS = ("out", "grid")
#: each task's option (None: one operating point) -> (the options it leaves unused, why)
UNUSED = {
    "map": (("scenario", "mode", "speed_rpm", "load_nm"),
            "the map covers both commands over a grid of speeds and loads of Bodson's DFIM"),
    "bench": (("scenario", "mode", "speed_rpm", "load_nm", *MODEL_OPTIONS[1:], *MAP_OPTIONS),
              "the bench candidates are voltage-command variants of Bodson's drive at their own "
              "operating points (only --bandwidth, --model and --delay-samples act)"),
    "scenario": (("mode", "delay_samples", *MODEL_OPTIONS, *MAP_OPTIONS),
                 "the scenario's own drive is linearised with every setting of the scenario "
                 "(only --speed-rpm, --load-nm and --model act)"),
    None: (MAP_OPTIONS, "it belongs to --map"),
}
#: the value of each model option not given
MODEL_DEFAULTS = {"bandwidth": PAPER_BANDWIDTH, "speed_filter_tau": 0.0,
                  "supply_resistance": 0.0, "supply_inductance": 0.0, "viscous_friction": 0.0,
                  "converter_loss": 0.0, "delay_samples": 0, "mode": "voltage",
                  "out": DEFAULT_OUT, "grid": (13, 7)}  # fmt: skip


def _flag(name: str, value) -> float:
    """``value`` of the numeric flag ``name``, checked against ``RANGES``."""
    if name in ("--bandwidth", "--inertia", "--rotor-resistance"):
        require_positive(name, value)
    return require_between(name, value, *RANGES[name])


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "stability", help="drive stability (eigenvalues, map)", description=HELP
    )
    task = p.add_mutually_exclusive_group()
    task.add_argument("--map", action="store_true", help="map speed x load for both modes")
    task.add_argument("--bench", action="store_true", help="test-bench candidates (voltage mode)")
    p.add_argument(
        "--scenario", default=None,
        help="a DFIM scenario (built-in name or TOML path) to linearise as it is set up",
    )  # fmt: skip
    p.add_argument("--mode", choices=("voltage", "current"), default=None,
                   help="command of one operating point (voltage)")  # fmt: skip
    p.add_argument("--speed-rpm", type=float, default=None, help="shaft speed [rpm]")
    p.add_argument("--load-nm", type=float, default=None, help="load torque [N m] (0)")
    p.add_argument("--bandwidth", type=float, default=None, help="a_D,VEL [rad/s] (314)")
    p.add_argument("--model", choices=("continuous", "sampled"), default="continuous")
    p.add_argument("--delay-samples", type=int, default=None, help="0 or 1 (sampled model) (0)")
    p.add_argument("--speed-filter-tau", type=float, default=None, help="speed filter [s] (0)")
    p.add_argument("--supply-resistance", type=float, default=None, help="supply R [ohm] (0)")
    p.add_argument("--supply-inductance", type=float, default=None, help="supply L [H] (0)")
    p.add_argument("--viscous-friction", type=float, default=None, help="B [N m s/rad] (0)")
    p.add_argument("--inertia", type=float, default=None, help="true J [kg m^2] (design: 3.5e-4)")
    p.add_argument(
        "--rotor-resistance", type=float, default=None, help="true R_r [ohm] (controller: 0.94)"
    )
    p.add_argument(
        "--converter-loss", type=float, default=None,
        help="converter fundamental voltage loss [V] (0)",
    )  # fmt: skip
    p.add_argument(
        "--out", default=None,
        help=f"folder the --map figure is written into (created) ({DEFAULT_OUT})",
    )  # fmt: skip
    p.add_argument(
        "--grid", type=int, nargs=2, default=None, metavar=("N_SPEED", "N_LOAD"),
        help="map grid: speeds 0..2700 rpm, loads over 90%% of the torque window (13 7)",
    )  # fmt: skip
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(handler=run)


def _linearisation():
    """The linearisation this command studies: the default drive's (``acdrive.drives``)."""
    from acdrive.analysis._drive_linearisation import default_linearisation

    return default_linearisation()


def _model(args, mode: str):
    from acdrive.machines._dfim import BODSON_DFIM

    DriveModel = _linearisation().DriveModel

    bandwidth = _flag("--bandwidth", args.bandwidth)
    B = _flag("--viscous-friction", args.viscous_friction)
    machine = dataclasses.replace(BODSON_DFIM, B=B)
    if args.inertia is not None:
        machine = dataclasses.replace(machine, J=_flag("--inertia", args.inertia))
    if args.rotor_resistance is not None:
        R_r = _flag("--rotor-resistance", args.rotor_resistance)
        machine = dataclasses.replace(machine, R_r=R_r)
    if args.delay_samples not in (0, 1):
        raise InputError("--delay-samples", "must be 0 or 1")
    return DriveModel(
        mode=mode,
        machine=machine,
        controller_params=BODSON_DFIM,
        design_inertia=BODSON_DFIM.J,
        speed_bandwidth=bandwidth,
        supply_resistance=_flag("--supply-resistance", args.supply_resistance),
        supply_inductance=_flag("--supply-inductance", args.supply_inductance),
        speed_filter_tau=_flag("--speed-filter-tau", args.speed_filter_tau),
        delay_samples=args.delay_samples,
        converter_loss=_flag("--converter-loss", args.converter_loss),
    )


def _pairs(values) -> list[list[float]]:
    return [[float(v.real), float(v.imag)] for v in values]


def _task(args) -> str | None:
    """The task the options choose ("map", "bench", "scenario", None: one operating point);
    an option the task does not use is refused (``_options.refuse_unused``), and every option
    not given takes its default (``MODEL_DEFAULTS``)."""
    from acdrive._commands._options import refuse_unused

    task = "map" if args.map else "bench" if args.bench else None
    if task is None and args.scenario is not None:
        task = "scenario"
    unused, why = UNUSED[task]
    refuse_unused(args, unused, f"--{task}" if task else "one operating point (--speed-rpm)", why)
    for dest, value in MODEL_DEFAULTS.items():
        if getattr(args, dest) is None:
            setattr(args, dest, value)
    return task


def run(args) -> int:
    task = _task(args)
    if task == "map":
        return _map(args)
    if task == "bench":
        return _bench(args)
    if task == "scenario":
        return _scenario(args)
    lin = _linearisation()
    RAD_S_PER_RPM, OperatingPoint = lin.RAD_S_PER_RPM, lin.OperatingPoint
    check_point, linearize = lin.check_point, lin.linearize

    if args.speed_rpm is None:
        raise InputError("--speed-rpm", "is required (or give --map or --scenario)")
    model = _model(args, args.mode)
    speed = require_finite("--speed-rpm", args.speed_rpm) * RAD_S_PER_RPM
    load = _flag("--load-nm", 0.0 if args.load_nm is None else args.load_nm)
    point = OperatingPoint(speed, load)
    try:
        check_point(model, point)
        r = linearize(model, point, args.model)
    except InputError as exc:
        name = {"speed": "--speed-rpm", "load_torque": "--load-nm"}.get(exc.field, exc.field)
        raise InputError(name, exc.rule) from None
    return _print_point(args, r, args.mode, model.speed_bandwidth, args.speed_rpm)


def _scenario(args) -> int:
    """Linearise the scenario's own drive (``linearize(setup, point)``)."""
    from acdrive.drives import for_setup
    from acdrive.scenarios._loader import load_scenario

    try:
        setup = load_scenario(args.scenario)
    except InputError as exc:  # the scenario was typed as --scenario
        field = "--scenario" if exc.field == "scenario" else exc.field
        raise InputError(field, exc.rule) from None
    try:
        lin = for_setup(setup).linearisation()
    except InputError as exc:
        raise InputError(
            "--scenario", f"must be a scenario of a linearised drive: {exc.rule}"
        ) from None
    RAD_S_PER_RPM, OperatingPoint, linearize = lin.RAD_S_PER_RPM, lin.OperatingPoint, lin.linearize
    motor = setup.motors[0]
    speed = float(motor.speed_reference[1][-1])
    if args.speed_rpm is not None:
        speed = require_finite("--speed-rpm", args.speed_rpm) * RAD_S_PER_RPM
    load = (
        float(motor.load_torque[1][-1])
        if args.load_nm is None
        else _flag("--load-nm", args.load_nm)
    )
    try:
        r = linearize(setup, OperatingPoint(speed, load), args.model)
    except InputError as exc:
        name = {"speed": "--speed-rpm", "load_torque": "--load-nm"}.get(exc.field, exc.field)
        raise InputError(name, exc.rule) from None
    g = motor.controller.gains
    return _print_point(args, r, motor.controller.mode, 2.0 * g.K_I / g.K_P, speed / RAD_S_PER_RPM)


def _print_point(args, r, mode: str, bandwidth: float, speed_rpm: float) -> int:
    """The result of one operating point, as JSON or aligned lines."""
    out = {
        "mode": mode,
        "model": args.model,
        "speed_rpm": speed_rpm,
        "load_nm": r.point.load_torque,
        "bandwidth_rad_s": bandwidth,
        "max_real_part": r.max_real_part,
        "stable": r.stable,
        "dominant": [r.dominant.real, r.dominant.imag],
        "torque_command_nm": r.torque_command,
        "within_torque_limits": r.within_limits,
        "eigenvalues": _pairs(r.eigenvalues),
    }
    if args.json:
        print(strict_json(out))
    else:
        for key in ("mode", "model", "speed_rpm", "load_nm", "bandwidth_rad_s"):
            print(f"{key:22s} {out[key]}")
        print(f"{'stable':22s} {r.stable}")
        print(f"{'max_real_part':22s} {r.max_real_part:.3f} 1/s")
        print("eigenvalues [1/s]:")
        for s in r.eigenvalues:
            print(f"  {s.real:12.3f} {s.imag:+12.3f}j")
    return 0


def _map(args) -> int:
    from acdrive._output import OutputFile
    from acdrive._progress import Progress

    n_speed, n_load = args.grid
    if not (1 <= n_speed <= MAX_GRID and 1 <= n_load <= MAX_GRID):
        raise InputError("--grid", f"N_SPEED and N_LOAD must be from 1 to {MAX_GRID}")
    models = {mode: _model(args, mode) for mode in ("voltage", "current")}  # checked first
    # --out checked (a folder, or creatable and writable; a file of the figure's name must be
    # acdrive's own) before any analysis, as `run` does
    with OutputFile(args.out, _figure_name(args), field="--out") as output:
        report, maps = _map_report(args, models, Progress(7, "stability map"))
        _draw(maps, output.path, args)
        path = output.publish()
    out = {
        "bandwidth_rad_s": args.bandwidth,
        "model": args.model,
        "speeds_rpm": [float(s) for s in maps["voltage"].speeds_rpm],
        "modes": report,
        "figure": str(path),
    }
    if args.json:
        print(strict_json(out, indent=2))
    else:
        print(f"a_D,VEL = {args.bandwidth:g} rad/s, {args.model} model; figure {path}")
        for mode, r in report.items():
            print(
                f"{mode:8s} unstable at {r['unstable_points']}/{r['points']} points "
                f"(worst Re s = {r['worst_max_real_part']:+.1f} 1/s at {r['worst_speed_rpm']:.0f} rpm, "
                f"{r['worst_load_nm']:+.3f} N m); tolerates a_D,VEL up to "
                f"{r['max_stable_bandwidth_rad_s']:.0f} rad/s "
                f"({r['max_stable_bandwidth_zero_load_rad_s']:.0f} rad/s without load)"
            )
    return 0


def _figure_name(args) -> str:
    return f"stability-map-{args.model}-a{math.floor(args.bandwidth)}.png"


def _map_report(args, models, bar) -> tuple[dict, dict]:
    """(report per mode, StabilityMap per mode) of ``acdrive stability --map``."""
    import numpy as np

    lin = _linearisation()
    default_grid, max_stable_bandwidth = lin.default_grid, lin.max_stable_bandwidth
    stability_map = lin.stability_map
    n_speed, n_load = args.grid
    maps, report = {}, {}
    for mode, model in models.items():
        speeds, loads = default_grid(model, n_speed, n_load)
        bar.phase(f"{mode} command: {n_speed} x {n_load} operating points")
        m = stability_map(model, speeds, loads, args.model)
        bar.advance()
        maps[mode] = m
        fields = {f.name: getattr(model, f.name) for f in dataclasses.fields(model)}
        fields = {k: v for k, v in fields.items() if k not in ("mode", "speed_bandwidth")}
        bar.phase(f"{mode} command: largest stable a_D,VEL")
        tolerated = max_stable_bandwidth(
            mode, speeds, loads, kind=args.model, upper=UPPER_BANDWIDTH, **fields
        )
        bar.advance()
        bar.phase(f"{mode} command: largest stable a_D,VEL without load")
        unloaded = max_stable_bandwidth(
            mode, speeds, [0.0], kind=args.model, upper=UPPER_BANDWIDTH, **fields
        )
        bar.advance()
        graded = np.where(m.feasible, m.max_real_part, -np.inf)
        worst = np.unravel_index(np.argmax(graded), graded.shape)
        report[mode] = {
            "stable_everywhere": m.all_stable,
            "unstable_points": int(np.count_nonzero(~m.stable & m.feasible)),
            "points": int(np.count_nonzero(m.feasible)),
            "worst_max_real_part": float(m.max_real_part[worst]),
            "worst_speed_rpm": float(speeds[worst[0]]),
            "worst_load_nm": float(loads[worst[1]]),
            "max_stable_bandwidth_rad_s": tolerated,
            "max_stable_bandwidth_zero_load_rad_s": unloaded,
        }
    bar.phase("drawing")
    bar.close()
    return report, maps


def _bench(args) -> int:
    lin = _linearisation()
    bench_candidates, evaluate_candidate = lin.bench_candidates, lin.evaluate_candidate
    stabilising_thresholds = lin.stabilising_thresholds

    bandwidth = _flag("--bandwidth", args.bandwidth)
    results = [evaluate_candidate(c) for c in bench_candidates(bandwidth)]
    if args.delay_samples not in (0, 1):
        raise InputError("--delay-samples", "must be 0 or 1")
    thresholds = stabilising_thresholds(
        bandwidth, kind=args.model, delay_samples=args.delay_samples
    )

    def num(x):
        return float(x) if math.isfinite(x) else None

    out = {
        "bandwidth_rad_s": bandwidth,
        "threshold_model": args.model,
        "threshold_delay_samples": args.delay_samples,
        "candidates": [
            {
                "name": r.candidate.name,
                "model": r.candidate.kind,
                "max_real_part_900rpm_0nm": r.max_real_part_900,
                "worst_zero_load": r.worst_zero_load,
                "worst_grid": r.worst_grid,
                "stable_zero_load": r.stable_zero_load,
                "stable_grid": r.stable_grid,
            }
            for r in results
        ],
        "thresholds": [
            {"name": t.name, "unit": t.unit, "zero_load": num(t.zero_load), "grid": num(t.grid)}
            for t in thresholds
        ],
    }
    if args.json:
        print(strict_json(out, indent=2))
        return 0
    print(f"voltage command, a_D,VEL = {bandwidth:g} rad/s: max Re(s) [1/s]")
    print(f"{'candidate':58s} {'900rpm':>8s} {'no load':>8s} {'grid':>8s}")
    for r in results:
        print(
            f"{r.candidate.name:58s} {r.max_real_part_900:8.1f} {r.worst_zero_load:8.1f} "
            f"{r.worst_grid:8.1f}"
        )
    print(
        f"smallest value that makes the drive stable (no load / grid; {args.model} model, "
        f"delay {args.delay_samples}):"
    )
    for t in thresholds:
        print(f"  {t.name:28s} {t.zero_load:10.4g} / {t.grid:10.4g} {t.unit}")
    return 0


def _draw(maps, path: Path, args) -> Path:
    """Draw the two modes' maps side by side into the PNG file ``path`` (with acdrive's mark)."""
    import matplotlib
    import numpy as np

    from acdrive._output import png_metadata

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True, constrained_layout=True)
    limit = max(float(np.nanmax(np.abs(m.max_real_part), initial=1.0)) for m in maps.values())
    for ax, (mode, m) in zip(axes, maps.items()):
        X, Y = np.meshgrid(m.loads_nm, m.speeds_rpm)
        pc = ax.pcolormesh(
            X, Y, m.max_real_part, cmap="RdBu_r", vmin=-limit, vmax=limit, shading="nearest"
        )
        if np.any(m.stable) and np.any(~m.stable):
            ax.contour(X, Y, m.max_real_part, levels=[0.0], colors="k", linewidths=1.5)
        ax.plot(X[~m.stable & m.feasible], Y[~m.stable & m.feasible], "kx", ms=4, label="unstable")
        ax.plot(X[m.stable & m.feasible], Y[m.stable & m.feasible], "k.", ms=3, label="stable")
        if not np.all(m.feasible):
            ax.plot(X[~m.feasible], Y[~m.feasible], "s", mfc="none", mec="0.5", ms=5,
                    label="outside limits")  # fmt: skip
        ax.set_title(f"{mode} command, a_D,VEL = {args.bandwidth:g} rad/s ({args.model})")
        ax.set_xlabel("load torque [N m]")
        ax.legend(loc="upper right", fontsize=8)
    axes[0].set_ylabel("speed [rpm]")
    fig.colorbar(pc, ax=axes, label="max Re(s) [1/s]")
    fig.savefig(path, dpi=120, metadata=png_metadata("acdrive stability --map"))
    plt.close(fig)
    return path
