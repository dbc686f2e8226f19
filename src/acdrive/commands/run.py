"""``acdrive run [SCENARIO]``: simulate a scenario, write data, figures and summary.json."""

from __future__ import annotations

import json
import shutil
import tempfile
from pathlib import Path

from acdrive.errors import InputError

DEFAULT_SCENARIO = "bodson-ramp"


def register(subparsers):
    p = subparsers.add_parser("run", help="simulate a scenario (default: the Bodson Fig. 4 ramp)")
    p.add_argument(
        "scenario",
        nargs="?",
        default=DEFAULT_SCENARIO,
        help="built-in scenario name (see `acdrive scenarios`) or a TOML file",
    )
    p.add_argument(
        "--out", default="acdrive-out", help="output folder (default: ./acdrive-out/<scenario>)"
    )
    p.add_argument("--no-figures", action="store_true", help="skip the figures")
    p.set_defaults(handler=run)


def run(args) -> int:
    from acdrive.report.dfim_figures import write_drive_figures
    from acdrive.scenarios.loader import load_scenario
    from acdrive.sim.setup import simulate

    setup = load_scenario(args.scenario)  # validates everything before any output exists
    out_root = Path(args.out)
    if out_root.exists() and not out_root.is_dir():
        raise InputError("--out", f"'{out_root}' exists and is not a folder")
    result = simulate(setup)
    summary = result.summary()
    motor = setup.motors[0]
    sync_rpm = 60.0 * float(setup.supply.frequency_hz[1][0]) / motor.machine.n_p
    summary["gains"] = {
        "K_P": motor.controller.gains.K_P,
        "K_I": motor.controller.gains.K_I,
        "K_F": motor.controller.gains.K_F,
    }
    # write into a temporary folder beside the target, then move it in place: never half-written
    out_root.mkdir(parents=True, exist_ok=True)
    target = out_root / setup.name
    staging = Path(tempfile.mkdtemp(prefix=f".{setup.name}-", dir=out_root))
    try:
        result.save(staging)
        if not args.no_figures:
            write_drive_figures(result, staging, sync_rpm)
        (staging / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
        if target.exists():
            shutil.rmtree(target)
        staging.rename(target)
    finally:
        if staging.exists():
            shutil.rmtree(staging)
    print(
        f"scenario {setup.name}: {setup.duration:g} s simulated in {result.wall_time:.2f} s "
        f"({len(setup.motors)} motor{'s' if len(setup.motors) > 1 else ''})"
    )
    rows = [
        ("speed RMS tracking error", f"{summary['speed_rms_error_rpm']:.2f} rpm"),
        ("max |speed error|", f"{summary['speed_max_abs_error_rpm']:.1f} rpm"),
        ("peak rotor current", f"{summary['peak_rotor_current_a']:.2f} A (limit 6 A)"),
        ("peak stator current", f"{summary['peak_stator_current_a']:.2f} A"),
        (
            "limit events (samples)",
            ", ".join(f"{k} {v}" for k, v in summary["limit_events"].items() if v) or "none",
        ),
    ]
    for label, value in rows:
        print(f"  {label:<26} {value}")
    print(f"wrote {target}/ (data.csv, data.parquet, summary.json, figures)")
    return 0
