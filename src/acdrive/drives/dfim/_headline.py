"""The lines ``acdrive run`` prints for a DFIM drive run, each computed from its summary: the speed
tracking error where tracking is expected (``acdrive.sim._metrics``: the intended reference steps
and their settling are excluded, and said so), motor 1's step responses
(``acdrive.sim._step_response``), the speed error over the whole run, peak currents against
their limits, the relay's closing, events."""

from __future__ import annotations

from acdrive.drives.dfim._outcome import MODE_SUFFIX
from acdrive.sim._step_response import headline_rows
from acdrive.sim._timing import simulated_in


def tracking_row(tracking: dict) -> str:
    """The headline's speed tracking figures, from a ``speed_tracking`` summary."""
    if tracking["rms_error_rpm"] is None:
        return "not expected anywhere in this run (" + tracking["rule"] + ")"
    windows = tracking["windows_s"]
    excluded = (
        "; settling after reference steps excluded: "
        + ", ".join(f"{a:.3g}-{b:.3g} s" for a, b in windows)
        if windows
        else ""
    )
    return (
        f"{tracking['rms_error_rpm']:.2f} rpm RMS, largest {tracking['max_abs_error_rpm']:.2f} rpm "
        f"at {tracking['max_abs_error_at_s']:.3f} s, over {tracking['tracked_fraction']:.0%} of "
        f"the run{excluded}"
    )


def whole_run_row(summary: dict) -> str:
    """The headline's whole-run speed error figures (motor 1, the first mode), from the
    summary's ``speed_*_whole_run_*`` keys."""
    return (
        f"{summary['speed_rms_error_whole_run_rpm']:.2f} rpm RMS, largest "
        f"{summary['speed_max_abs_error_whole_run_rpm']:.2f} rpm at "
        f"{summary['speed_max_abs_error_whole_run_at_s']:.3f} s (every sample, the settling after "
        "reference steps included)"
    )


def headline(outcome, summary: dict) -> tuple[str, list[tuple[str, str]]]:
    """(first line, rows) of ``acdrive run``'s headline of a DFIM ``outcome`` whose written
    summary is ``summary``."""
    setup = outcome.setup
    timing = simulated_in(outcome.results.values())
    n = len(setup.motors)
    first = f"scenario {setup.name}: {setup.duration:g} s {timing} ({n} motor{'s' * (n > 1)})"
    rotor_limit = max(m.controller.rotor_current_limit_pk for m in setup.motors)
    stator_limit = max(m.controller.stator_current_limit_pk for m in setup.motors)
    if len(outcome.results) > 1:
        rows = [
            (
                f"speed tracking, {mode}",
                tracking_row(summary[f"speed_tracking_{MODE_SUFFIX[mode]}"]),
            )
            for mode in outcome.results
        ]
    else:
        rows = [("speed tracking", tracking_row(summary["speed_tracking"]))]
    for mode in outcome.results:
        key = "step_response" if len(outcome.results) == 1 else f"step_response_{MODE_SUFFIX[mode]}"
        label = f"{mode}: " if len(outcome.results) > 1 else ""
        rows += headline_rows(summary[key], "rpm", label)
    rows.append(("speed error, whole run", whole_run_row(summary)))
    rows += [
        (
            "peak rotor current",
            f"{summary['peak_rotor_current_a']:.2f} A (limit {rotor_limit:g} A)",
        ),
        (
            "peak stator current",
            f"{summary['peak_stator_current_a']:.2f} A (limit {stator_limit:g} A)",
        ),
    ]
    for key in ("peak_rotor_current_vc_a", "peak_rotor_current_cc_a"):
        if key in summary:
            rows.append((key.replace("_", " ").replace(" a", " (A)"), f"{summary[key]:.2f}"))
    if "synchronisation" in summary and summary["synchronisation"].get("relay_closed"):
        sync = summary["synchronisation"]
        rows.append(
            (
                "relay closed at",
                (
                    f"{sync['closing_time_s']:.3f} s, stator current peak "
                    f"{sync['closing_stator_current_peak_a']:.2f} A"
                ),
            )
        )
    events = ", ".join(f"{k} {v}" for k, v in summary["limit_events"].items() if v) or "none"
    rows.append(("events (samples)", events))
    return first, rows
