"""The drive figures each section IV experiment of the Bodson reproduction report lists under its
verdicts, each printed with what it measures (``acdrive run``'s summary keys in brackets): the
speed error where tracking is expected, the largest speed error over every sample with where it
falls (inside the settling after a reference step, where it measures the step and not the
tracking, or where tracking is expected), and the peak phase currents against their limits.
None of them is a number of the paper.
"""

from __future__ import annotations

import numpy as np

from acdrive._report.limit_cycle_summary import Shown
from acdrive.drives.dfim._outcome import MODE_SUFFIX

#: The figures listed for each mode of a run: (summary key, what it measures, unit).
TRACKING_RMS = (
    "speed_rms_error_tracking_rpm",
    "speed error where tracking is expected, RMS",
    "rpm",
)
ROTOR_PEAK = ("peak_rotor_current_a", "peak rotor phase current over the run", "A")
STATOR_PEAK = ("peak_stator_current_a", "peak stator phase current over the run", "A")
#: How the summary's tracking rule begins (the line names the figure itself).
RULE_PREFIX = "speed error where tracking is expected: "


def largest_error_where(result, at_s: float, windows) -> str:
    """Where the largest speed error of the whole run (at ``at_s`` [s]) falls: inside one of the
    excluded ``windows`` (the settling after a reference change: then the reference's change
    across that window's start is given, the size of what the error measures), elsewhere outside
    the tracked samples (``tracking_mask``: e.g. the relay open), or where the speed is expected
    to track."""
    t = result.t
    i = int(np.argmin(np.abs(t - at_s)))
    for start, stop in windows:
        if start <= at_s <= stop:
            ref = result.reference_rpm()
            before = float(ref[max(int(np.searchsorted(t, start)) - 1, 0)])
            return (
                f"in the settling after the reference change at {start:.3g} s (the reference "
                f"goes from {before:.0f} to {float(ref[i]):.0f} rpm): it measures that change, "
                "not the tracking"
            )
    if not result.tracking_mask()[i]:
        return "where tracking is not expected (outside the tracked samples)"
    return "where tracking is expected"


def run_figure_lines(outcome, summary: dict) -> list[str]:
    """Report lines (Markdown bullets) of the run's figures from ``summary`` (the report's
    ``shown_summary`` of ``outcome``: limit-cycle numbers rounded to their spread), each with
    what it measures and its summary key."""
    setup = outcome.setup
    rotor_limit = max(m.controller.rotor_current_limit_pk for m in setup.motors)
    stator_limit = max(m.controller.stator_current_limit_pk for m in setup.motors)
    tracking = summary["speed_tracking"]
    windows = tracking.get("windows_s") or []
    at_s = summary["speed_max_abs_error_whole_run_at_s"]
    where = largest_error_where(outcome.main, float(at_s), windows)
    # the instant is given where it is known: not inside a step's settling (whose start is
    # given), and not in a run that limit-cycles (``Shown``: where the largest error falls in
    # the cycle moves)
    when = "" if isinstance(at_s, Shown) or where.startswith("in the settling") else (
        f" at {at_s:.3f} s"
    )
    first = next(iter(outcome.results))
    mode = f" ({first} command)" if len(outcome.results) > 1 else ""
    lines = [
        f"- {TRACKING_RMS[1]}{mode}: {summary[TRACKING_RMS[0]]:.3f} {TRACKING_RMS[2]} "
        f"(`{TRACKING_RMS[0]}`; {tracking['rule'].removeprefix(RULE_PREFIX)})",
        f"- largest speed error over every sample{mode}: "
        f"{summary['speed_max_abs_error_whole_run_rpm']:.3f} rpm{when}, {where} "
        "(`speed_max_abs_error_whole_run_rpm`)",
        f"- {ROTOR_PEAK[1]}{mode}: {summary[ROTOR_PEAK[0]]:.3f} A (limit {rotor_limit:g} A; "
        f"`{ROTOR_PEAK[0]}`)",
        f"- {STATOR_PEAK[1]}{mode}: {summary[STATOR_PEAK[0]]:.3f} A (limit {stator_limit:g} A; "
        f"`{STATOR_PEAK[0]}`)",
    ]
    if len(outcome.results) > 1:
        modes = [m for m in outcome.results if f"peak_rotor_current_{MODE_SUFFIX[m]}_a" in summary]
        lines.append(
            f"- {ROTOR_PEAK[1]} by mode: "
            + ", ".join(
                f"{m} command {summary[f'peak_rotor_current_{MODE_SUFFIX[m]}_a']:.3f} A "
                f"(`peak_rotor_current_{MODE_SUFFIX[m]}_a`)"
                for m in modes
            )
        )
        lines.append(
            f"- {TRACKING_RMS[1]} by mode: "
            + ", ".join(
                f"{m} command {summary[f'speed_rms_error_tracking_{MODE_SUFFIX[m]}_rpm']:.3f} rpm "
                f"(`speed_rms_error_tracking_{MODE_SUFFIX[m]}_rpm`)"
                for m in modes
            )
        )
    return lines
