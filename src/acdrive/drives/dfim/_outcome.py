"""Running a scenario: one or several simulations, their headline figures and their files.

``run_scenario`` runs a ``DriveSetup`` (once, or once per controller mode for comparisons) and
returns a ``ScenarioOutcome``: the results and the summary (summary.json);
``acdrive.drives.dfim._outputs.write_outcome`` saves data, figures and summary.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from acdrive._arguments import Function, Instance, Table, checked
from acdrive.drives._outcome import Outcome
from acdrive.drives._registry import Setup
from acdrive.drives.dfim._period import control_period_warnings
from acdrive._reducer_parts import OVER_LIMIT_TOLERANCE
from acdrive.drives.dfim._recovery import speed_outcome, step_outcome
from acdrive.drives.dfim._result import DriveResult
from acdrive.drives.dfim._setup import DriveSetup, simulate
from acdrive.drives.dfim._tracking import tracking_rule
from acdrive.sim._metrics import (
    LATE_WINDOW_S,
    OSCILLATION_BAND_HZ,
    OSCILLATION_FINDING_RPM,
    PERIOD_CORRELATION_MIN,
    RPM_PER_RAD_S,
    limit_cycle,
    speed_tracking,
)

MODE_SUFFIX = {"voltage": "vc", "current": "cc"}


def synchronisation_summary(result: DriveResult, setup: DriveSetup, motor: int = 0) -> dict | None:
    """Relay closing time, stator current transient after closing, and the encoder alignment.

    The transient is the largest peak stator phase current within 0.1 s of closing (Bodson (8)),
    also given as a fraction of the stator current limit. ``theta_adj_error_rad`` is theta_adj
    minus the encoder's electrical offset n_p x offset, wrapped to (-pi, pi]: what the
    synchroniser left unidentified (a few hundredths of a radian after a synchronised closing: the
    phase errors of the law it compensates, converter loss and hold). With a
    ``relay_forced_close_time`` the summary adds that time and ``closed_by_force``: whether the
    relay was still open by the synchroniser's command then.
    """
    closed = result.signal("relay_closed", motor)
    m = setup.motors[motor]
    if not m.controller.sync.enabled:
        return None
    if not closed.any():
        return {"relay_closed": False}
    i = int(np.argmax(closed > 0))
    # the logged relay state is the plant's at t_k, read with the command held from the previous
    # sample: the contact closed at the sample before the first closed row (exact with log_every
    # = 1, within one logging interval otherwise)
    t_close = float(result.t[i]) - result.sample_time
    after = (result.t >= result.t[i]) & (result.t < result.t[i] + 0.1)
    peak = float(np.max(result.peak("i_s_mag", motor)[after]))
    expected = math.remainder(m.machine.n_p * m.encoder_offset, 2 * math.pi)
    theta_adj = float(result.signal("theta_adj", motor)[i])
    forced = (
        {
            "relay_forced_close_time_s": m.relay_forced_close_time,
            "closed_by_force": _closed_by_force(result, setup, motor),
        }
        if math.isfinite(m.relay_forced_close_time)
        else {}
    )
    return {
        "relay_closed": True,
        **forced,
        "closing_time_s": t_close,
        "closing_stator_current_peak_a": peak,
        "closing_current_fraction_of_limit": peak / m.controller.stator_current_limit_pk,
        "voltage_mismatch_at_closing": float(result.signal("v_mismatch", motor)[max(i - 1, 0)]),
        "theta_adj_rad": theta_adj,
        "encoder_offset_electrical_rad": expected,
        "theta_adj_error_rad": math.remainder(theta_adj - expected, 2 * math.pi),
        "m_adj": float(result.signal("m_adj", motor)[i]),
    }


def _late_oscillation(results: dict) -> tuple | None:
    """(mode, motor, limit-cycle figures, whole-run RMS) of the first limit cycle shown
    (``sim._metrics.limit_cycle``) over the last ``LATE_WINDOW_S`` of a run, or None."""
    for mode, result in results.items():
        tail = result.t >= result.t[-1] - LATE_WINDOW_S * (1 - 1e-9)
        end = DriveResult(result.name, result.t[tail], result.signals[tail], result.sample_time,
                          result.final_state, tracking=result.tracking)  # fmt: skip
        for k in range(result.n_motors):
            err = (end.signal("w_ref", k) - end.signal("w", k)) * RPM_PER_RAD_S
            cycle = limit_cycle(end.t, err, end.tracking_mask(k))
            if cycle["speed_limit_cycle"]:
                return mode, k, cycle, result.speed_oscillation(k)[0]
    return None


def _cycle_words(cycle: dict) -> str:
    """How a limit cycle was shown: band RMS over the threshold and its period repeating."""
    low, high = OSCILLATION_BAND_HZ
    return (
        f"{cycle['speed_oscillation_rms_rpm']:.1f} rpm RMS at about "
        f"{cycle['speed_oscillation_hz']:.0f} Hz in the {low:g}-{high:g} Hz band, above the "
        f"{OSCILLATION_FINDING_RPM:g} rpm threshold to the end of the tracked stretch "
        f"({cycle['speed_oscillation_end_rms_rpm']:.1f} rpm over its last {LATE_WINDOW_S:g} s), "
        "its period repeating: autocorrelation "
        f"{cycle['speed_oscillation_period_correlation']:.2f} at one period, at least "
        f"{PERIOD_CORRELATION_MIN:g}"
    )


def _open_relay_reasons(result: DriveResult, motor: int = 0) -> str:
    """Why a synchroniser may not have closed the relay, from the events of the run: a saturated
    rotor converter (the open-stator voltage of (28) at this speed needs more than the DC link
    gives) or a lost supply (synchronising suspended)."""
    events = result.events(motor)
    reasons = ""
    if events["converter_saturation"]:
        reasons += (
            f"; the rotor converter was saturated on {events['converter_saturation']} samples: "
            "the rotor voltage that builds the grid's voltage on the open stator at this speed "
            "(Bodson (28)) is beyond what the DC link gives"
        )
    if events["supply_lost"]:
        reasons += f"; the supply was lost on {events['supply_lost']} samples"
    return reasons


def _closed_by_force(result: DriveResult, setup: DriveSetup, k: int) -> bool:
    """True if motor k's relay was closed by ``relay_forced_close_time`` while its synchroniser
    still held it open (the synchroniser's command, column ``phase``, open at that sample)."""
    t_force = setup.motors[k].relay_forced_close_time
    if not math.isfinite(t_force) or t_force > result.t[-1]:
        return False
    at = int(np.argmax(result.t >= t_force))
    return bool(result.signal("phase", k)[at] == 0.0)


def _forced_close_warning(result: DriveResult, setup: DriveSetup, k: int) -> str:
    """The relay of motor k closed by force (``_closed_by_force``): when, how far from
    synchronised, what the synchroniser left unidentified and where the speed ended up."""
    m = setup.motors[k]
    closed = result.signal("relay_closed", k)
    i = int(np.argmax(closed > 0))
    mismatch = float(result.signal("v_mismatch", k)[max(i - 1, 0)])
    expected = m.machine.n_p * m.encoder_offset
    error = math.remainder(float(result.signal("theta_adj", k)[i]) - expected, 2 * math.pi)
    tail = result.t >= 0.9 * result.t[-1]
    speed_error = float(np.max(np.abs(result.reference_rpm(k) - result.speed_rpm(k))[tail]))
    return (
        f"motor {k + 1}: relay closed by force at relay_forced_close_time = "
        f"{m.relay_forced_close_time:g} s, unsynchronised: |v_s - v_g| was {mismatch:.0%} of the "
        f"grid voltage just before; theta_adj then differs from the encoder's electrical offset by "
        f"{error:+.3f} rad and the synchroniser cannot identify it any more (the stator carries "
        f"the grid's voltage); speed error over the last 10 % of the run up to "
        f"{speed_error:.1f} rpm"
    )


def tracking_windows(result: DriveResult, setup: DriveSetup, motor: int = 0) -> dict:
    """Where the speed of motor ``motor`` is expected to track its reference, and how well it
    did: ``speed_tracking`` of ``sim._metrics`` under the scenario's ``tracking_rule`` (the
    ``rule`` with its numbers, the excluded ``windows_s``, the ``tracked_fraction`` and the RMS
    and largest |error| [rpm] over the tracked samples with when the largest occurred; None for
    the three if no sample is tracked)."""
    rule = tracking_rule(setup, motor)
    closed = result.signal("relay_closed", motor)
    return speed_tracking(result.t, result.signal("w", motor), result.signal("w_ref", motor),
                          closed, rule)[1]  # fmt: skip


@checked(
    setup=Instance(DriveSetup), results=Table(Instance(DriveResult)), summary=Table(empty=True),
)
@dataclass
class ScenarioOutcome(Outcome):
    """The DFIM's ``Outcome``: its runs (one per compared mode) and summary."""

    setup: DriveSetup
    results: dict[str, DriveResult]  # label -> result ("main", or one per compared mode)
    summary: dict = field(default_factory=dict)

    @property
    def main(self) -> DriveResult:
        return next(iter(self.results.values()))


def synchronous_rpm(setup: DriveSetup) -> float:
    return 60.0 * float(setup.supply.frequency_hz[1][0]) / setup.motors[0].machine.n_p


@checked(setup=Setup(), on_run=Function(optional=True))
def run_scenario(setup: DriveSetup, on_run=None) -> ScenarioOutcome:
    """Simulate the DFIM ``setup`` (once per mode if it compares modes) and summarise.
    ``on_run(mode)``, if given, is called before each simulation (a progress display). Another
    drive's setup is an ``InputError`` on ``setup`` pointing to ``acdrive.drives.run_scenario``
    (the registry's, which runs any drive's and calls this one for a DFIM)."""
    from acdrive.drives._registry import require_setup

    require_setup(setup, (DriveSetup,), "acdrive.drives.dfim.run_scenario")
    runs = (
        [(mode, setup.with_mode(mode)) for mode in setup.compare_modes]
        if setup.compare_modes
        else [(setup.motors[0].controller.mode, setup)]
    )
    results = {}
    for mode, run_setup in runs:
        if on_run is not None:
            on_run(mode)
        results[mode] = simulate(run_setup)
    summaries = {mode: result.summary for mode, result in results.items()}  # once each
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
            summary[f"speed_rms_error_tracking_{suffix}_rpm"] = s["speed_rms_error_tracking_rpm"]
            summary[f"speed_tracking_{suffix}"] = s["speed_tracking"]
            summary[f"limit_events_{suffix}"] = s["limit_events"]
    a_vel = motor.controller.gains.K_P / (2 * motor.machine.J)
    eigen = (
        "the linearised whole drive's eigenvalues at an operating point: `acdrive stability` "
        "(docs/stability.md)"
    )
    for mode, s in summaries.items():
        cycles = [m for m in s["motors"] if m["speed_limit_cycle"]]
        if cycles:
            worst = max(cycles, key=lambda m: m["speed_oscillation_rms_rpm"])
            summary["finding"] = (
                f"{mode} command: the speed oscillates in a limit cycle ({_cycle_words(worst)}) "
                f"at a_D,VEL = {a_vel:.0f} rad/s; {eigen}"
            )
            break
    if "finding" not in summary:
        late = _late_oscillation(results)
        if late is not None:
            mode, k, cycle, whole = late
            summary["finding"] = (
                f"{mode} command: the speed oscillates in a limit cycle at the end of the run "
                f"(motor {k + 1}: {_cycle_words(cycle)}, over its last {LATE_WINDOW_S:g} s; "
                f"{whole:.1f} rpm over the whole run): an oscillation that starts late or is "
                f"still growing, at a_D,VEL = {a_vel:.0f} rad/s; {eigen}"
            )
    # the bench converter's first-harmonic voltage loss per motor (dead time and device drops,
    # plant._converter / machines._dfim_part), which the scenario notes refer to
    summary["converter_fundamental_loss_v"] = [
        float(m.converter.fundamental_loss(m.dc_link_voltage)) for m in setup.motors
    ]
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
                # a loop holding its current at the limit passes it by its ripple and rounding
                if e["peak_a"] > e["limit_a"] * (1.0 + OVER_LIMIT_TOLERANCE):
                    what = "rotor" if name == "i_r_mag" else "stator"
                    warnings.append(
                        f"{mode} command, motor {k + 1}: {what} current above its "
                        f"{e['limit_a']:g} A limit by more than the "
                        f"{100 * OVER_LIMIT_TOLERANCE:g} % tolerance: peak {e['peak_a']:.2f} A "
                        f"({100 * (e['peak_a'] / e['limit_a'] - 1):+.2f} %), above the limit on "
                        f"{e['samples_above']} logged samples, first at {e['first_time_s']:.3f} s"
                    )
        summary["limit_excursions"][mode] = per_motor
    for mode, result in results.items():  # what happened at each disturbance and at the end
        masks = [result.tracking_mask(k) for k in range(result.n_motors)]
        who = f"{mode} command, " if len(results) > 1 else ""
        speed = speed_outcome(result, masks, setup, who)
        warnings += speed.pop("warnings")
        key = "speed_outcome" if len(results) == 1 else f"speed_outcome_{MODE_SUFFIX[mode]}"
        summary[key] = speed
    for mode, result in results.items():  # each motor's step responses (suffix: the batch's)
        key = "step_response" if len(results) == 1 else f"step_response_{MODE_SUFFIX[mode]}"
        for k in range(result.n_motors):
            summary[key + ("" if k == 0 else f"_m{k}")] = step_outcome(result, setup, k)
    sync = synchronisation_summary(first, setup)
    if sync is not None:
        summary["synchronisation"] = sync
        if not sync["relay_closed"]:
            warnings.append(
                f"the synchroniser never closed the relay in {setup.duration:g} s: the stator "
                "stayed open and the speed was not controlled" + _open_relay_reasons(first)
            )
    for k in range(len(setup.motors)):
        if _closed_by_force(first, setup, k):
            warnings.append(_forced_close_warning(first, setup, k))
    warnings.extend(control_period_warnings(setup))
    if warnings:
        summary["warnings"] = warnings
    fallback = first.first_event_time("sensor_fallback")
    if fallback is not None:
        summary["sensor_fallback_time_s"] = fallback
    outcome = ScenarioOutcome(setup=setup, results=results, summary=summary)
    # where a rotor converter has dead time or device drops: the steady-state stator reactive
    # power and torque-command offset it causes (drives.dfim._converter_effect)
    from acdrive.drives.dfim import _converter_effect

    side_effect = _converter_effect.summary(outcome)  # None with ideal converters
    if side_effect is not None:
        summary["converter_side_effect"] = side_effect
    return outcome
