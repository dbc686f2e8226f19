"""Summary figures of one PM speed-drive run, each computed here once from the logged signals.

Windows: "run" is every logged sample; "final" is the last ``FINAL_FRACTION`` of the run (a
steady-state figure is only meaningful if the run has settled there, which the scenario's
duration must allow). Currents are given as phase peaks (|i| / sqrt(3/2)); the voltage margin is
1 - |v_wanted| / (V_dc / sqrt(2)) with v_wanted the current controller's command before the limit
(negative: the current controller limited its command). Event totals are samples: the
converter's limit (``saturated`` of the averaged converter, ``overmodulation`` of the inverter),
the current controller's own limit |v| <= V_dc / sqrt(2), the reference's
current and voltage limits and the speed controller's torque limit. Two speeds mark the end of
MTPA at full current (``PMDriveSetup``, at the run's current limit, DC link and margin): the
machine's base speed (``base_speed_rad_s``, ``_design.base_speed``: the steady-state voltage
equation) and the lower speed where the drive's conservative voltage bound (V) makes its
references leave MTPA (``voltage_bound_speed_rad_s``, ``_design.voltage_bound_speed``); the
speed ratio is the mean speed of the final window over the base speed (above 1: the run ends in
field weakening). A figure over the whole run ("min", "max", "peak") is an extreme, often a
transient's (a step's); its steady value is the "final" figure beside it: the d current and the
voltage command's use of the references' limit m V_dc / sqrt(2) are given both ways, the
extreme with its instant (``..._time_s``; before ``final_window_from_s``: a transient's).
The speed error RMS and largest |error| are taken over the whole run, the intended reference
steps included; how the speed answers each step of its reference and of the load (rise time,
overshoot, settling time, steady-state error, load-step dip and recovery) is ``step_response``
(``sim._step_response``, in rad/s).
"""

from __future__ import annotations

import numpy as np

from acdrive._frames import K_PEAK
from acdrive.drives.pm._build import build
from acdrive.drives.pm._setup import PMDriveSetup
from acdrive.sim._step_response import events, step_response

#: the final window: the last 10 % of the run
FINAL_FRACTION = 0.1


def signals(setup: PMDriveSetup, result, log: dict | None = None) -> dict:
    """The logged signals of ``result`` by the names of ``log`` (name -> port), the run's
    ``build(setup).log``; rebuilt from ``setup`` only when the caller does not hold it."""
    if log is None:
        log = build(setup).log
    return {name: result.signal(port) for name, port in log.items()}


def final_window(t: np.ndarray) -> np.ndarray:
    """Mask of the last FINAL_FRACTION of the run."""
    return t >= t[-1] - FINAL_FRACTION * (t[-1] - t[0])


def summary(setup: PMDriveSetup, result, log: dict | None = None) -> dict:
    """Speed tracking, currents, torque and the voltage-limit margin (module docstring); ``log``
    as for ``signals``."""
    s = signals(setup, result, log)
    t = result.t
    final = final_window(t)
    error = s["w_ref"] - s["w"]
    v_max = setup.V_dc / np.sqrt(2.0)
    margin = 1.0 - np.abs(s["v_dq_wanted"]) / v_max
    base = setup.base_speed
    voltage_use = np.abs(s["v_dq_wanted"]) / (setup.voltage_margin * v_max)
    speed_final = float(np.mean(s["w"][final]))
    return {
        "speed_error_rms_rad_s": float(np.sqrt(np.mean(error**2))),
        "speed_error_max_rad_s": float(np.max(np.abs(error))),
        "speed_error_final_rad_s": float(np.mean(error[final])),
        "speed_max_rad_s": float(np.max(s["w"])),
        "speed_final_rad_s": speed_final,
        "base_speed_rad_s": float(base),
        "voltage_bound_speed_rad_s": float(setup.voltage_bound_speed),
        "speed_final_to_base_ratio": speed_final / base,
        "current_peak_a": float(np.max(np.abs(s["i_s"])) / K_PEAK),
        "current_limit_peak_a": float(setup.i_max_peak),
        "i_d_min_a": float(np.min(s["i_dq"].real) / K_PEAK),
        "i_d_min_time_s": float(t[np.argmin(s["i_dq"].real)]),
        "i_d_final_a": float(np.mean(s["i_dq"].real[final]) / K_PEAK),
        "torque_final_n_m": float(np.mean(s["tau_e"][final])),
        "torque_peak_n_m": float(np.max(np.abs(s["tau_e"]))),
        "voltage_margin_min": float(np.min(margin)),
        "voltage_use_max": float(np.max(voltage_use)),
        "voltage_use_max_time_s": float(t[np.argmax(voltage_use)]),
        "voltage_use_final": float(np.mean(voltage_use[final])),
        "final_window_from_s": float(t[final][0]),
        "voltage_limited_fraction": float(np.mean(margin < 0.0)),
        **event_totals(result),
        "step_response": step_response(t, s["w"], s["w_ref"], step_events(setup)),
    }


def step_events(setup: PMDriveSetup) -> list[dict]:
    """The speed-reference changes and load steps of ``setup`` (``sim._step_response.events``)."""
    return events(setup.speed_reference, {"load torque": (setup.load, "N m")}, setup.duration)


def event_totals(result) -> dict:
    """Samples in which each limit acted (module docstring)."""
    converter = result.events["converter"]
    reference = result.events["torque_reference"]
    return {
        "converter_limited_samples": converter.get("saturated", converter.get("overmodulation")),
        "current_controller_limited_samples": result.events["current"]["saturated"],
        "current_limited_samples": reference["current_limit"],
        "voltage_limited_samples": reference["voltage_limit"],
        "beyond_reach_samples": reference["beyond_reach"],
        "torque_limited_samples": result.events["speed_pi"]["torque_limit"],
    }
