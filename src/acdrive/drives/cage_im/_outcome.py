"""The runs of one cage-IM scenario (one per compared current controller) and its summary
(summary.json): ``run_im_scenario`` -> ``IMOutcome``, with the warnings a reader must know,
computed from the runs' numbers."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from acdrive._arguments import Instance, Table, checked
from acdrive.drives._outcome import Outcome
from acdrive.drives._registry import Setup
from acdrive.drives.cage_im._drive import IMDrive
from acdrive.drives.cage_im._result import IMDriveResult
from acdrive.drives.cage_im._setup import IMDriveSetup


@checked(
    setup=Instance(IMDriveSetup), results=Table(Instance(IMDriveResult)), summary=Table(empty=True),
)
@dataclass
class IMOutcome(Outcome):
    """The cage IM's ``Outcome``: the runs of one scenario (label -> result) and its summary
    (summary.json)."""

    setup: IMDriveSetup
    results: dict[str, IMDriveResult]
    summary: dict = field(default_factory=dict)

    @property
    def main(self) -> IMDriveResult:
        return next(iter(self.results.values()))


#: metrics compared between runs at the top level of summary.json, with a label inserted before
#: the unit suffix (``current_rms_error_a`` -> ``current_rms_error_<label>_a``)
COMPARED = {
    "current_rms_error_a": ("current_rms_error", "_a"),
    "peak_stator_current_a": ("peak_stator_current", "_a"),
}


@checked(setup=Setup())  # any drive's: require_setup names the drive
def run_im_scenario(setup: IMDriveSetup) -> IMOutcome:
    """Simulate every run of ``setup`` (compiled systems are shared between runs of the same
    topology) and summarise: the first run's metrics at the top level, every run's under
    ``runs``, and, with several runs, the compared metrics per label. Another drive's setup is
    an ``InputError`` on ``setup`` pointing to ``acdrive.drives.run_scenario``."""
    from acdrive.drives._registry import require_setup

    require_setup(setup, (IMDriveSetup,), "acdrive.drives.run_im_scenario")
    results = {}
    for label, run_setup in setup.runs():
        drive = IMDrive(run_setup)
        result = drive.run()
        result.label = label
        results[label] = result
    summaries = {label: r.summary for label, r in results.items()}
    first = next(iter(summaries.values()))
    summary = {
        "scenario": setup.name,
        "description": setup.description,
        "drive": "cage-im",
        "mode": setup.mode,
        "controller": first["controller"],
        "inverter": {
            "model": setup.inverter.model,
            "pwm_frequency_hz": setup.inverter.f_pwm,
            "carrier_samples": setup.carrier_samples,
            "dead_time_s": setup.inverter.dead_time,
            "device_drop_v": setup.inverter.device_drop,
        },
        "sample_time_s": setup.sample_time,
        "discretisation": setup.current_control.method,
        **first,
    }
    if len(results) > 1:
        for key, (stem, unit) in COMPARED.items():
            for label, s in summaries.items():
                summary[f"{stem}_{label}{unit}"] = s[key]
        for label, s in summaries.items():
            if "ramp" in s:
                summary[f"speed_ramp_error_{label}"] = s["ramp"]["speed_ramp_error_rad_s"]
                summary[f"ramp_slope_{label}_rad_s2"] = s["ramp"]["ramp_slope_rad_s2"]
    summary["runs"] = summaries
    summary["warnings"] = warnings_of(setup, results, summaries) + im_control_period_warnings(setup)
    if not summary["warnings"]:
        del summary["warnings"]
    if setup.note:
        summary["note"] = setup.note
    outcome = IMOutcome(setup=setup, results=results, summary=summary)
    # the simulated current steps beside the linear closed loop's, and every data column's unit
    from acdrive.drives.cage_im._step_comparison import step_summary

    summary.update(step_summary(outcome))
    summary["units"] = {c.name: c.unit for c in outcome.main.table_columns()}
    return outcome


def _span(result: IMDriveResult, flag: str) -> str:
    """When a per-sample event flag was raised, from the logged samples."""
    hits = np.flatnonzero(result.flags[flag])
    if hits.size == 0:
        return "between logged samples"
    return f"logged between {result.t[hits[0]]:.4g} s and {result.t[hits[-1]]:.4g} s"


def im_control_period_warnings(setup: IMDriveSetup) -> list[str]:
    """``drives.cage_im._period.im_control_period_warnings`` (imported when called)."""
    from acdrive.drives.cage_im._period import im_control_period_warnings as warnings

    return warnings(setup)


def warnings_of(setup: IMDriveSetup, results: dict, summaries: dict) -> list[str]:
    """What a reader must know about the runs, from their numbers: voltage saturation (with the
    DC link's shortfall where the flux reference at the speed reached needs more than it gives),
    overmodulation and current limiting, each with when it happened."""
    out = []
    n = max(1, round(setup.duration / setup.sample_time))
    for label, s in summaries.items():
        ev, result = s["events"], results[label]
        for key in ("speed_outcome", "position_outcome"):  # loss of control, no recovery
            out += s.get(key, {}).pop("warnings", [])
        if ev["current_controller_saturation"]:
            check = s.get("voltage_check")
            why = ""
            if check and check["needed_at_torque_limit_v"] > check["limit_v"]:
                why = (
                    f"; holding {check['flux_wb']:.3g} Wb at {check['speed_rad_s']:.0f} rad/s "
                    f"needs {check['needed_no_load_v']:.0f} V (no load) to "
                    f"{check['needed_at_torque_limit_v']:.0f} V (torque limit) of the "
                    f"{check['limit_v']:.0f} V the DC link gives (phase peak)"
                )
            out.append(
                f"{label}: the current controller's voltage command was limited to "
                f"v_dc/sqrt(2) on {ev['current_controller_saturation']} of {n} samples "
                f"({ev['current_controller_saturation'] / n:.1%}), {_span(result, 'saturated')}"
                + why
            )
        if ev.get("overmodulation"):
            out.append(
                f"{label}: the inverter limited its latched command (overmodulation) on "
                f"{ev['overmodulation']} samples, {_span(result, 'overmodulation')}"
            )
        if ev.get("current_limit"):
            out.append(
                f"{label}: the IFOC limited the stator current reference to "
                f"{setup.foc.i_max:g} A (space vector) on {ev['current_limit']} samples"
            )
    return out
