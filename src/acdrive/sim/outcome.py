"""Running a scenario: one or several simulations, their headline figures and their files.

``run_scenario`` runs a ``DriveSetup`` (once, or once per controller mode for comparisons) and
returns a ``ScenarioOutcome``: the results and the summary (summary.json);
``acdrive.report.drive_outputs.write_outcome`` saves data, figures and summary.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from acdrive.sim.result import OSCILLATION_BAND_HZ, DriveResult
from acdrive.sim.setup import DriveSetup, simulate

MODE_SUFFIX = {"voltage": "vc", "current": "cc"}
#: speed-error RMS in the 20-200 Hz band above which the summary states a limit-cycle finding
OSCILLATION_FINDING_RPM = 1.0


def synchronisation_summary(result: DriveResult, setup: DriveSetup, motor: int = 0) -> dict | None:
    """Relay closing time, stator current transient after closing, and the encoder alignment.

    The transient is the largest peak stator phase current within 0.1 s of closing (Bodson (8)),
    also given as a fraction of the stator current limit.
    """
    closed = result.signal("relay_closed", motor)
    m = setup.motors[motor]
    if not m.controller.sync.enabled:
        return None
    if not closed.any():
        return {"relay_closed": False}
    i = int(np.argmax(closed > 0))
    after = (result.t >= result.t[i]) & (result.t < result.t[i] + 0.1)
    peak = float(np.max(result.peak("i_s_mag", motor)[after]))
    expected = math.remainder(m.machine.n_p * m.encoder_offset, 2 * math.pi)
    return {
        "relay_closed": True,
        "closing_time_s": float(result.t[i]),
        "closing_stator_current_peak_a": peak,
        "closing_current_fraction_of_limit": peak / m.controller.stator_current_limit_pk,
        "voltage_mismatch_at_closing": float(result.signal("v_mismatch", motor)[max(i - 1, 0)]),
        "theta_adj_rad": float(result.signal("theta_adj", motor)[i]),
        "encoder_offset_electrical_rad": expected,
        "m_adj": float(result.signal("m_adj", motor)[i]),
    }


@dataclass
class ScenarioOutcome:
    setup: DriveSetup
    results: dict[str, DriveResult]  # label -> result ("main", or one per compared mode)
    summary: dict = field(default_factory=dict)

    @property
    def main(self) -> DriveResult:
        return next(iter(self.results.values()))


def synchronous_rpm(setup: DriveSetup) -> float:
    return 60.0 * float(setup.supply.frequency_hz[1][0]) / setup.motors[0].machine.n_p


def run_scenario(setup: DriveSetup) -> ScenarioOutcome:
    """Simulate ``setup`` (once per mode if it compares modes) and summarise."""
    if setup.compare_modes:
        results = {mode: simulate(setup.with_mode(mode)) for mode in setup.compare_modes}
    else:
        results = {setup.motors[0].controller.mode: simulate(setup)}
    summaries = {mode: result.summary() for mode, result in results.items()}  # once each
    first_mode, first = next(iter(results.items()))
    summary = dict(summaries[first_mode])
    motor = setup.motors[0]
    K_PC, K_IC = motor.controller.current_gains(motor.machine)
    summary["mode"] = first_mode
    summary["gains"] = {
        "K_P": motor.controller.gains.K_P,
        "K_I": motor.controller.gains.K_I,
        "K_F": motor.controller.gains.K_F,
        "K_PC": K_PC,
        "K_IC": K_IC,
        "R_T": motor.controller.R_T,
    }
    if len(results) > 1:
        for mode, s in summaries.items():
            suffix = MODE_SUFFIX[mode]
            summary[f"peak_rotor_current_{suffix}_a"] = s["peak_rotor_current_a"]
            summary[f"speed_rms_error_{suffix}_rpm"] = s["speed_rms_error_rpm"]
            summary[f"limit_events_{suffix}"] = s["limit_events"]
    for mode, s in summaries.items():
        worst = max(s["motors"], key=lambda m: m["speed_oscillation_rms_rpm"])
        if worst["speed_oscillation_rms_rpm"] > OSCILLATION_FINDING_RPM:
            low, high = OSCILLATION_BAND_HZ
            summary["finding"] = (
                f"{mode} command: the speed oscillates ({worst['speed_oscillation_rms_rpm']:.1f} rpm "
                f"RMS at about {worst['speed_oscillation_hz']:.0f} Hz in the {low:g}-{high:g} Hz band, above the "
                f"{OSCILLATION_FINDING_RPM:g} rpm threshold) at a_D,VEL = "
                f"{motor.controller.gains.K_P / (2 * motor.machine.J):.0f} rad/s; the linearised "
                "whole drive's eigenvalues at an operating point: `acdrive stability` (docs/stability.md)"
            )
            break
    if setup.note:
        summary["note"] = setup.note
    warnings = []
    summary["limit_excursions"] = {}
    for mode, result in results.items():
        per_motor = []
        for k, m in enumerate(setup.motors):
            limits = {
                "i_r_mag": m.controller.rotor_current_limit_pk,
                "i_s_mag": m.controller.stator_current_limit_pk,
            }
            excursions = result.limit_excursions(k, limits)
            per_motor.append(excursions)
            for name, e in excursions.items():
                if e["samples_above"]:
                    what = "rotor" if name == "i_r_mag" else "stator"
                    warnings.append(
                        f"{mode} command, motor {k + 1}: {what} current above its "
                        f"{e['limit_a']:g} A limit on {e['samples_above']} logged samples, peak "
                        f"{e['peak_a']:.2f} A, first at {e['first_time_s']:.3f} s"
                    )
        summary["limit_excursions"][mode] = per_motor
    sync = synchronisation_summary(first, setup)
    if sync is not None:
        summary["synchronisation"] = sync
        if not sync["relay_closed"]:
            warnings.append(
                f"the synchroniser never closed the relay in {setup.duration:g} s: the stator "
                "stayed open and the speed was not controlled"
            )
    if warnings:
        summary["warnings"] = warnings
    fallback = first.first_event_time("sensor_fallback")
    if fallback is not None:
        summary["sensor_fallback_time_s"] = fallback
    return ScenarioOutcome(setup=setup, results=results, summary=summary)
