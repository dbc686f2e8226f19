"""``acdrive icad``: individual channel analysis of a machine's current subsystem.

``acdrive icad MACHINE --speed W [--controller NAME] [--json]`` analyses one operating speed;
``acdrive icad MACHINE --sweep [--out DIR]`` analyses a speed range and writes the figures into
the folder DIR (default ``icad-MACHINE``). DIR is written like ``acdrive run``'s output
(``acdrive._output.OutputFolder``): checked before any analysis (its last component must be a safe
name, an existing DIR must be a real folder), the figures are written into a hidden staging folder
beside it and swapped in whole, so an interruption leaves the complete old DIR or the new one.
"""

from __future__ import annotations

import math

from acdrive.errors import InputError, require_between, require_finite

#: The names of ``acdrive.analysis._plants.MACHINES`` and ``acdrive.analysis._icad``'s
#: ``CONTROLLER_NAMES`` and ``A_CUR_DEFAULT``, written out so that ``acdrive icad --help`` does not
#: import the analysis (scipy); tests/test_cli_habits.py checks they match.
MACHINES = ("ugalde-im-300w", "delorenzo-im", "delorenzo-im-13", "pmsg-2mw", "bodson-dfim")
CONTROLLER_NAMES = ("paper-20", "paper-pi", "imc-pi")
A_CUR_DEFAULT = 3142.0

HELP = f"""Individual channel analysis (ICAD) of a machine current subsystem with a diagonal
controller k_1 = k_2. Machines: {", ".join(MACHINES)}. Controllers: paper-20 (Amezquita-Brooks
et al. (20)), paper-pi (K_P = 360, K_I = 9000), imc-pi (K_P = L' a, K_I = R' a, Bodson (49)
style, a = --bandwidth). Default controller: paper-20 for induction motors, imc-pi for
pmsg-2mw and bodson-dfim. Speeds are electrical rotor speeds in rad/s. JSON margins that are
infinite (no crossing) or undefined are written as null."""

#: Default sweep ranges of electrical speed [rad/s] (the papers' operating ranges), by the class
#: name of the machine's parameters (IMParams, PMSGParams); any other machine (the DFIM) sweeps
#: DFIM_SWEEP.
SWEEP_RANGES = {"IMParams": (0.0, 375.0), "PMSGParams": (0.0, 2 * math.pi * 50.0)}
DFIM_SWEEP = (0.0, 1.5 * 2 * math.pi * 60.0)

#: Accepted ranges: |speed| <= MAX_SPEED rad/s (about 160 kHz electrical) and 0 or at least
#: MIN_SPEED (closer to 0 the plant matrices lose their structure to rounding), a bandwidth of
#: BANDWIDTH_RANGE rad/s, at most MAX_SWEEP_POINTS speeds in a sweep.
MAX_SPEED = 1e6
MIN_SPEED = 1e-6
BANDWIDTH_RANGE = (1e-6, 1e9)
MAX_SWEEP_POINTS = 100


#: The plain output's rows: JSON key -> (unit, meaning); each margin is the worse of the two
#: channels (docs/icad.md, "Margins and bandwidth"). Seed 001 is Ugalde-Loo et al., seed 002
#: Amezquita-Brooks et al.
ROWS = {
    "conditions.i": ("-", "structure condition i: the plant's eigenvalues in the open LHP"),
    "conditions.ii": ("-", "condition ii, seed 002 (a.1): gamma has no RHP pole"),
    "conditions.iii": ("-", "condition iii, seed 002 (a.3): gamma -> 0 as s -> inf"),
    "conditions.iv": (
        "-",
        "condition iv, seed 002 (a.2): gamma neither encircles nor meets (1, 0)",
    ),
    "gm_min_db": ("dB", "least gain margin gamma leaves, seed 002 (19) (induction motors)"),
    "msf_at_wr_db": ("dB", "|gamma| at w = w_r, seed 002 (18) (induction motors)"),
    "crossover_rad_s": ("rad/s", "highest gain crossover of the channel c_i"),
    "pm_deg": ("deg", "phase margin of c_i"),
    "gm_db": ("dB", "upward gain margin of c_i"),
    "gm_reduction_db": ("dB", "gain-reduction margin of c_i (conditionally stable loop)"),
    "bandwidth_rad_s": ("rad/s", "-3 dB bandwidth of c_i / (1 + c_i)"),
    "kg_pm_deg": ("deg", "phase margin of k_i g_ii"),
    "kg_gm_db": ("dB", "gain margin of k_i g_ii"),
    "structural_gm_db": ("dB", "structural gain margin of gamma"),
    "structural_gm_h_db": ("dB", "structural gain margin of gamma h_j"),
    "coupling_peak_db": ("dB", "peak coupling |y_i / r_j|"),
    "closed_loop_stable": ("-", "the closed loop with k_1 = k_2 is stable"),
    "b1": ("-", "seed 002 (b.1): both c_i and both h_i closed loops stable"),
    "b2": ("-", "seed 002 (b.2): gamma and gamma h_j neither encircle nor meet (1, 0)"),
    "encirclements.gamma": ("-", "encirclements of (1, 0) by gamma"),
    "encirclements.gamma_h": ("-", "encirclements of (1, 0) by gamma h_1, gamma h_2"),
    "encirclements.channels": ("-", "encirclements of -1 by c_1, c_2"),
}
#: Below a table holding a None value: what it means.
NOT_AVAILABLE_NOTE = "n/a: infinite (no crossing) or not defined for this machine (null in --json)"


def _flat(report: dict, prefix: str = "") -> dict:
    """``report`` with nested tables flattened to dotted keys (``conditions.i``)."""
    out = {}
    for key, value in report.items():
        if isinstance(value, dict):
            out.update(_flat(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


def table_lines(report: dict, rows: dict) -> list[str]:
    """The aligned table of ``report``'s quantities named in ``rows`` (JSON key -> unit,
    meaning), and the note on n/a values if any is None."""
    from acdrive._commands._table import aligned

    flat = _flat(report)
    lines = aligned((key, flat[key], *rows[key]) for key in rows if key in flat)
    if any(flat[key] is None for key in rows if key in flat):
        lines.append(NOT_AVAILABLE_NOTE)
    return lines


def check_speed(flag: str, value) -> float:
    """An electrical speed from the command line: finite, |w| <= MAX_SPEED, 0 or >= MIN_SPEED."""
    value = require_finite(flag, value)
    if abs(value) > MAX_SPEED:
        raise InputError(flag, f"must be within +-{MAX_SPEED:g} rad/s, got {value:g}")
    if 0.0 < abs(value) < MIN_SPEED:
        raise InputError(
            flag, f"must be 0 or at least {MIN_SPEED:g} rad/s in magnitude, got {value:g}"
        )
    return value


def register(subparsers) -> None:
    parser = subparsers.add_parser("icad", help="individual channel analysis", description=HELP)
    parser.add_argument("machine", help=f"one of {', '.join(MACHINES)}")
    mode = parser.add_mutually_exclusive_group(required=True)
    mode.add_argument("--speed", type=float, help="electrical rotor speed w_r [rad/s]")
    mode.add_argument("--sweep", action="store_true", help="sweep speed and write figures")
    parser.add_argument("--controller", choices=CONTROLLER_NAMES, help="built-in controller")
    parser.add_argument(
        "--bandwidth", type=float, default=None, help="a [rad/s] of imc-pi (3142)"
    )
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.add_argument(
        "--speeds",
        type=float,
        nargs=3,
        metavar=("START", "STOP", "N"),
        help=f"sweep N (1 to {MAX_SWEEP_POINTS}) speeds from START to STOP rad/s",
    )
    parser.add_argument(
        "--out",
        default=None,
        help="figure folder, replaced whole (default icad-MACHINE); its last component must be a "
        "plain name",
    )
    parser.add_argument("--no-verify", action="store_true", help="skip contour cross-checks")
    parser.set_defaults(handler=run)


def _num(x) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def single_report(machine: str, speed: float, controller: str, analysis) -> dict:
    """The JSON-ready report of one analysis (field names documented in docs/icad.md)."""
    from acdrive.analysis._icad import worst
    from acdrive.analysis._icad_closed_forms import gm_min, im_msf_magnitude_at_rotor_speed
    from acdrive.analysis._plants import machine_params
    from acdrive.machines._induction import IMParams

    params = machine_params(machine)
    c = analysis.conditions
    chans = analysis.channels
    is_im = isinstance(params, IMParams)
    return {
        "machine": machine,
        "speed_rad_s": speed,
        "controller": controller,
        "conditions": {"i": c.i, "ii": c.ii, "iii": c.iii, "iv": c.iv},
        "gm_min_db": _num(20 * math.log10(gm_min(params))) if is_im else None,
        "msf_at_wr_db": _num(20 * math.log10(im_msf_magnitude_at_rotor_speed(params, speed)))
        if is_im and speed != 0.0
        else None,
        "crossover_rad_s": _num(worst(ch.margins.crossover_rad_s for ch in chans)),
        "pm_deg": _num(worst(ch.margins.pm_deg for ch in chans)),
        "gm_db": _num(worst(ch.margins.gm_db for ch in chans)),
        "gm_reduction_db": _num(worst((ch.margins.gm_reduction_db for ch in chans), max)),
        "bandwidth_rad_s": _num(worst(ch.bandwidth_rad_s for ch in chans)),
        "kg_pm_deg": _num(worst(ch.kg_margins.pm_deg for ch in chans)),
        "kg_gm_db": _num(worst(ch.kg_margins.gm_db for ch in chans)),
        "structural_gm_db": _num(analysis.structural.gm_db),
        "structural_gm_h_db": _num(worst(ch.structural.gm_db for ch in chans)),
        "coupling_peak_db": _num(analysis.coupling_peak_db),
        "closed_loop_stable": analysis.closed_loop_stable,
        "b1": analysis.b1,
        "b2": analysis.b2,
        "encirclements": {
            "gamma": c.gamma_count.encirclements,
            "gamma_h": [ch.gamma_h_count.encirclements for ch in chans],
            "channels": [ch.channel_count.encirclements for ch in chans],
        },
    }


def run(args) -> int:
    from acdrive._output import strict_json
    from acdrive.analysis._icad import analyse, controller_for, default_controller_name
    from acdrive.analysis._plants import machine_params, plant_for

    if args.speeds is not None and not args.sweep:
        raise InputError(
            "--speeds", "sets the speeds of a sweep and needs --sweep (one analysis at one speed "
            "takes --speed)"
        )  # fmt: skip
    if args.out is not None and not args.sweep:
        raise InputError("--out", "does not apply with --speed: one analysis writes no figures "
                         "(--sweep writes them into --out)")  # fmt: skip
    params = machine_params(args.machine)
    name = args.controller or default_controller_name(params)
    if args.bandwidth is not None and name != "imc-pi":
        which = (f"--controller {name}" if args.controller
                 else f"{name} (the default --controller of {args.machine})")  # fmt: skip
        raise InputError("--bandwidth", f"does not apply with {which}: it sets a of imc-pi; "
                         "the papers' controllers have fixed gains")  # fmt: skip
    bandwidth = A_CUR_DEFAULT if args.bandwidth is None else args.bandwidth
    bandwidth = require_between("--bandwidth", bandwidth, *BANDWIDTH_RANGE)
    k = controller_for(name, params, bandwidth)
    if args.sweep:
        return _sweep(args, params, name, k)
    speed = check_speed("--speed", args.speed)
    analysis = analyse(plant_for(args.machine, speed), k, k, verify=not args.no_verify)
    report = single_report(args.machine, speed, name, analysis)
    if args.json:
        print(strict_json(report, indent=2))
    else:
        print(f"ICAD of {args.machine} at w_r = {speed:g} rad/s (electrical), controller {name}")
        print("\n".join(table_lines(report, ROWS)))
    return 0


def _figure_folder(out: str | None, machine: str):
    """The sweep's output folder: ``--out`` (or ``icad-MACHINE``), checked and staged before any
    analysis. ``--out`` names the folder itself, so its last component must be a safe name."""
    from pathlib import Path

    from acdrive._output import OutputFolder, require_out

    target = require_out("--out", out) if out is not None else Path(f"icad-{machine}")
    return OutputFolder(target.parent, target.name, field="--out", name_field="--out")


def _sweep(args, params, name, k) -> int:
    import numpy as np

    from acdrive._output import strict_json
    from acdrive._report.icad_figures import write_sweep_figures
    from acdrive.analysis._icad import analyse, summarize
    from acdrive.analysis._icad_frequency import icad_response
    from acdrive.analysis._plants import plant_for

    if args.speeds is not None:
        start, stop, n = args.speeds
        for v in (start, stop):
            v = require_finite("--speeds", v)
            if abs(v) > MAX_SPEED:
                raise InputError(
                    "--speeds", f"START and STOP must be within +-{MAX_SPEED:g} rad/s, got {v:g}"
                )
        if not (math.isfinite(n) and n == int(n) and 1 <= n <= MAX_SWEEP_POINTS):
            raise InputError(
                "--speeds", f"N must be an integer from 1 to {MAX_SWEEP_POINTS}, got {n:g}"
            )
        lo, hi, n = start, stop, int(n)
    else:
        lo, hi = SWEEP_RANGES.get(type(params).__name__, DFIM_SWEEP)
        n = 7
    speeds = np.linspace(lo, hi, n)
    speeds[np.abs(speeds) < MIN_SPEED] = 0.0  # rounding noise of linspace around 0
    with _figure_folder(args.out, args.machine) as output:  # --out checked before the analysis
        plants = [plant_for(args.machine, float(s)) for s in speeds]
        analyses = [analyse(p, k, k, verify=not args.no_verify) for p in plants]
        w = analyses[-1].response.w
        resp = icad_response(plants, k, k, w)
        title = f"{args.machine}, controller {name}"
        staged = write_sweep_figures(analyses, resp, output.staging, title=title)
        target = output.publish()
    paths = [target / p.relative_to(output.staging) for p in staged]
    summary = summarize(analyses)
    report = {
        "machine": args.machine,
        "controller": name,
        "speeds_rad_s": [float(s) for s in speeds],
        "all_conditions": summary.all_conditions,
        "closed_loop_stable": summary.closed_loop_stable,
        "worst": {
            key: _num(getattr(summary, key))
            for key in (
                "structural_gm_db",
                "structural_gm_h_db",
                "pm_deg",
                "gm_db",
                "kg_pm_deg",
                "kg_gm_db",
                "bandwidth_rad_s",
                "crossover_rad_s",
                "coupling_peak_db",
            )
        },
        "figures": [str(p) for p in paths],
    }
    if args.json:
        print(strict_json(report, indent=2))
    else:
        print(
            f"ICAD of {args.machine}, controller {name}, over {n} electrical speeds from "
            f"{speeds[0]:g} to {speeds[-1]:g} rad/s (worst over the speeds)"
        )
        rows = {
            "all_conditions": ("-", "structure conditions i-iv hold at every speed"),
            "closed_loop_stable": ("-", "the closed loop is stable at every speed"),
            **{f"worst.{key}": ROWS[key] for key in report["worst"]},
        }
        print("\n".join(table_lines(report, rows)))
        print("figures:")
        print("\n".join(f"  {path}" for path in report["figures"]))
    return 0
