"""The lines ``acdrive run`` prints for a cage induction motor drive run (``drive = "cage-im"``),
each computed from the summary the run wrote (``drives.cage_im._outputs``)."""

from __future__ import annotations

from acdrive.sim._step_response import headline_rows
from acdrive.sim._timing import simulated_in


def _rows(summary: dict, setup) -> list[tuple[str, str]]:
    """Headline rows from the numbers of the summary (nothing here is a fixed verdict)."""
    rows = []
    runs = summary["runs"]
    several = len(runs) > 1
    for label, run in runs.items():
        who = f"{label} ({run['controller']})" if several else run["controller"]
        rel = run["current_rms_error_relative"]
        rows.append(
            (
                f"current RMS error, {who}",
                (
                    f"{run['current_rms_error_a']:.3g} A ({rel:.1%} of the "
                    f"{run['current_rms_reference_a']:.3g} A reference) from "
                    f"{run['metrics_from_s']:g} s"
                ),
            )
        )
        if "ramp" in run:
            r = run["ramp"]
            rows.append(
                (
                    f"speed ramp, {who}",
                    (
                        f"error {r['speed_ramp_error_rad_s']:.3g} rad/s RMS, slope "
                        f"{r['ramp_slope_rad_s2']:.0f} rad/s^2 (ideal tau_max/J "
                        f"{r['ideal_slope_rad_s2']:.0f})"
                    ),
                )
            )
        tracking = run.get("speed_tracking")
        if tracking is not None and tracking["rms_error_rad_s"] is not None:
            rows.append(
                (
                    f"speed tracking, {who}",
                    (
                        f"{tracking['rms_error_rad_s']:.3g} rad/s RMS, largest "
                        f"{tracking['max_abs_error_rad_s']:.3g} rad/s at "
                        f"{tracking['max_abs_error_at_s']:.3f} s, over "
                        f"{tracking['tracked_fraction']:.0%} of the run (speed step settling "
                        "excluded: speed_tracking.rule)"
                    ),
                )
            )
        if "step_response" in run:
            rows += headline_rows(run["step_response"], "rad_s", f"{label}: " if several else "")
        if "speed_final_rad_s" in run:
            text = (
                f"{run['speed_final_rad_s']:.2f} rad/s for "
                f"{run['speed_reference_final_rad_s']:.2f} rad/s"
            )
            for change in run["load_changes"]:
                if "max_deviation_rad_s" in change:
                    text += (
                        f"; load change at {change['time_s']:g} s: "
                        f"{change['max_deviation_rad_s']:+.3g} rad/s"
                    )
            rows.append((f"final speed, {who}", text))
        if "position_final_rad" in run:
            text = f"error {run['position_final_error_rad']:.3g} rad"
            for change in run["load_changes"]:
                if "max_deviation_rad" in change:
                    text += (
                        f"; load change at {change['time_s']:g} s: "
                        f"{change['max_deviation_rad']:+.3g} rad"
                    )
            rows.append((f"final position, {who}", text))
        for key, unit in (("speed_outcome", "rpm"), ("position_outcome", "rad")):
            for d in run.get(key, {}).get("disturbances", []):
                name = f"after {d['what']} at {d['start_s']:g} s" + (
                    f", {label}" if several else ""
                )
                rows.append((name, _recovery_words(d, unit)))
        if f"step_overshoot_{label}" in summary:
            rows.append(
                (
                    f"step overshoot, {who}",
                    (
                        f"{summary[f'step_overshoot_{label}']:.1%} (linear ICAD model "
                        f"{summary[f'linear_step_overshoot_{label}']:.1%})"
                    ),
                )
            )
        events = ", ".join(f"{k} {v}" for k, v in run["events"].items() if v) or "none"
        rows.append((f"events (samples), {label}" if several else "events (samples)", events))
    return rows


def _recovery_words(d: dict, unit: str) -> str:
    """One disturbance's judgement (``sim._recovery``) in words: largest error, recovery."""
    from acdrive.sim._metrics import RPM_PER_RAD_S

    what = "speed" if unit == "rpm" else "position"
    largest = d[f"largest_{what}_error_{unit}"]
    if largest is None:
        return "not judged (no tracked sample after it)"
    text = f"largest {what} error {largest:.3g} {unit}"
    if unit == "rpm":  # the IM's other speeds are in rad/s
        text += f" ({largest / RPM_PER_RAD_S:.3g} rad/s)"
    text += f" at {d['largest_at_s']:.3f} s; "
    if d["recovered"]:
        text += (
            f"recovered in {d['recovery_time_s']:.3f} s (within {d[f'band_{unit}']:.3g} {unit} "
            f"from {d['recovered_at_s']:.3f} s on)"
        )
    elif d["recovered"] is False:
        text += f"not recovered (beyond {d[f'band_{unit}']:.3g} {unit} to the end)"
    else:
        text += "recovery not decided (back in the band too shortly before the window ends)"
    lost = [f"{k.split('_')[0]} from {d[k]:.3f} s" for k in ("reversal_at_s", "stall_at_s")
            if d.get(k) is not None]  # fmt: skip
    return text + (f"; {', '.join(lost)}" if lost else "")


def headline(outcome, summary: dict) -> tuple[str, list[tuple[str, str]]]:
    """(first line, rows) of ``acdrive run``'s headline of a cage-IM ``outcome`` whose written
    summary is ``summary``."""
    setup = outcome.setup
    timing = simulated_in(outcome.results.values())
    n = len(outcome.results)
    inv = setup.inverter
    first = (
        f"scenario {setup.name}: {setup.duration:g} s {timing} "
        f"({n} run{'s' * (n > 1)}, mode {setup.mode}, {inv.model} inverter at "
        f"{inv.f_pwm:g} Hz, sampling {1.0 / setup.sample_time:g} Hz)"
    )
    return first, _rows(summary, setup)
