"""What happened to each DFIM motor's speed at each disturbance of a run and at its end: the
disturbances known from the scenario (a supply voltage, frequency or phase EMF that departs from
its starting value until it returns, a DC link that drops, a load torque that steps, a relay
closed by force, current sensors that fail), each judged by ``sim._recovery.judge_speed``."""

from __future__ import annotations

import math

from acdrive.sim._metrics import RPM_PER_RAD_S
from acdrive.sim._recovery import RULE, _departures, _steps, judge_speed
from acdrive.sim._step_response import events, step_response


def disturbances(setup) -> list[dict]:
    """The disturbances of a DFIM ``setup`` (module docstring), by start time: ``what``,
    ``start_s``, ``cleared_s`` (None: it stays) and ``motor`` (None: the shared supply)."""
    s = setup.supply
    found = [
        *({**d, "motor": None} for d in _departures(s.voltage_pk, "supply voltage", "V peak")),
        *({**d, "motor": None} for d in _departures(s.frequency_hz, "supply frequency", "Hz")),
    ]
    if s.phase_scales is not None:
        for phase, scale in zip("abc", s.phase_scales, strict=True):
            found += [{**d, "motor": None}
                      for d in _departures(scale, f"supply phase {phase} EMF x", "")]  # fmt: skip
    for k, m in enumerate(setup.motors):
        if m.dc_link_profile is not None:
            found += [{**d, "motor": k} for d in _departures(m.dc_link_profile, "DC link", "V")]
        found += [{**d, "motor": k} for d in _steps(m.load_torque, "load torque", "N m")]
        for time, what in ((m.relay_forced_close_time, "stator relay closed by force"),
                           (m.current_sensor_fault_time, "current sensors fail")):  # fmt: skip
            if math.isfinite(time):
                found.append({"what": what, "start_s": float(time), "cleared_s": None, "motor": k})
    # a step at t = 0 is the starting condition: there is no state before it to recover to
    found = [d for d in found if 0.0 < d["start_s"] < setup.duration]
    return sorted(found, key=lambda d: d["start_s"])


def speed_outcome(result, rules_masks: list, setup, who: str = "") -> dict:
    """``disturbances`` (each with its per-motor ``judge_speed`` figures: a motor is judged on
    the shared supply's disturbances and its own, each up to the next of those), ``end_of_run``
    (per motor), the ``rule``, and the ``warnings`` (``who`` names the run in them, e.g.
    "voltage command, ") of a DFIM ``result``."""
    found = disturbances(setup)
    for d in found:
        d["motors"] = {}
    warnings, end = [], []
    for k in range(result.n_motors):
        mine = [d for d in found if d["motor"] in (None, k)]
        judged = judge_speed(
            result.t, result.signal("w", k) * RPM_PER_RAD_S,
            result.signal("w_ref", k) * RPM_PER_RAD_S, rules_masks[k],
            [(d["what"], d["start_s"]) for d in mine], f"{who}motor {k + 1}",
        )  # fmt: skip
        for d, a in zip(mine, judged["disturbances"], strict=True):
            d["motors"][f"motor {k + 1}"] = a
        warnings += judged["warnings"]
        end.append(judged["end_of_run"])
    return {"rule": RULE, "disturbances": found, "end_of_run": end, "warnings": warnings}


def step_events(setup, k: int) -> list[dict]:
    """The speed-reference changes and load steps of motor ``k`` of a DFIM ``setup``
    (``sim._step_response.events``, described in rpm)."""
    m = setup.motors[k]
    return events(m.speed_reference, {"load torque": (m.load_torque, "N m")}, setup.duration,
                  speed_unit="rpm", speed_scale=RPM_PER_RAD_S)  # fmt: skip


def step_outcome(result, setup, k: int) -> dict:
    """Motor ``k``'s ``step_response`` (``sim._step_response``) of a DFIM ``result``, in rpm."""
    return step_response(result.t, result.signal("w", k), result.signal("w_ref", k),
                         step_events(setup, k), scale=RPM_PER_RAD_S, unit="rpm")  # fmt: skip
