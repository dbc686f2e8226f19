"""What happened to the speed at each disturbance of a DFIM run and at its end.

The disturbances are known from the scenario before the run (``disturbances``, after t = 0): a
supply voltage, frequency or phase EMF that departs from its starting value (a sag, a frequency
step, a collapsed phase) until it returns, a DC link that drops, a load torque that steps, a relay
closed by force, current sensors that fail. Each is judged from its start to the next
disturbance's start or the end of the run, on the samples where tracking is expected
(``sim._metrics.TrackingRule``: the intended reference steps' settling and an open relay are not
judged):

* ``largest_speed_error_rpm`` and when;
* recovery: the speed error back within the band max(min(RECOVERY_P99_FACTOR x the 99th
  percentile of |error| over the PRE_WINDOW_S of tracked samples before the start,
  RECOVERY_REFERENCE_FRACTION x |reference| at the start), RECOVERY_MIN_RPM) and staying there
  to the end of the judged window, held at least HOLD_S (else not decided: ``recovered`` None);
  ``recovery_time_s`` is counted from the disturbance's start;
* reversal: the speed's sign opposite to the reference's, both above REVERSAL_MIN_RPM, held
  HOLD_S; stall: |speed| below STALL_FRACTION x |reference| with |reference| above
  STALL_MIN_REFERENCE_RPM, held HOLD_S.

The end of the run (its last END_FRACTION) is judged for reversal and stall the same way. A
reversal or a stall is a loss of control, stated as a warning by that name (``warnings``), never
as an oscillation.
"""

from __future__ import annotations

import math

import numpy as np

from acdrive.sim._metrics import RPM_PER_RAD_S

RECOVERY_P99_FACTOR = 2.0
RECOVERY_MIN_RPM = 2.0
#: the band is at most this fraction of the reference: a drive that was not tracking before
#: the disturbance does not get a band as wide as its error
RECOVERY_REFERENCE_FRACTION = 0.05
PRE_WINDOW_S = 0.5
HOLD_S = 0.05
REVERSAL_MIN_RPM = 5.0
STALL_FRACTION = 0.05
STALL_MIN_REFERENCE_RPM = 20.0
END_FRACTION = 0.1

RULE = (
    f"recovered: |speed error| back within max(min({RECOVERY_P99_FACTOR:g} x its 99th percentile "
    f"over the {PRE_WINDOW_S:g} s before the disturbance, {RECOVERY_REFERENCE_FRACTION:.0%} of "
    f"|reference|), {RECOVERY_MIN_RPM:g} rpm) and staying there to the next disturbance or the "
    f"end of the run (at least {HOLD_S * 1e3:g} ms; recovery time from the disturbance's start); "
    f"reversal: speed and reference of opposite signs, both beyond {REVERSAL_MIN_RPM:g} rpm; "
    f"stall: |speed| below {STALL_FRACTION:.0%} of |reference| (beyond "
    f"{STALL_MIN_REFERENCE_RPM:g} rpm); each held {HOLD_S * 1e3:g} ms; judged where tracking is "
    "expected (speed_tracking.rule)"
)


def _departures(profile, what: str, unit: str) -> list[dict]:
    """The intervals where a piecewise-linear profile (times, values) departs from its starting
    value: (start, end or None if it never returns) with the value reached farthest away."""
    times, values = (np.asarray(x, dtype=float) for x in profile)
    v0 = float(values[0])
    tol = 1e-12 * max(abs(v0), 1.0)
    out, i = [], 1
    while i < values.size:
        if abs(values[i] - v0) > tol:
            j = i
            while j < values.size and abs(values[j] - v0) > tol:
                j += 1
            far = values[i:j][np.argmax(np.abs(values[i:j] - v0))]
            end = float(times[j]) if j < values.size else None
            out.append({"what": f"{what} {v0:g} -> {far:g} {unit}".rstrip(),
                        "start_s": float(times[i - 1]), "cleared_s": end})  # fmt: skip
            i = j
        i += 1
    return out


def _steps(profile, what: str, unit: str) -> list[dict]:
    """Every change of a profile, each a disturbance that stays (a load step)."""
    times, values = (np.asarray(x, dtype=float) for x in profile)
    out = []
    for i in range(1, values.size):
        if values[i] != values[i - 1]:
            out.append({"what": f"{what} {values[i - 1]:g} -> {values[i]:g} {unit}",
                        "start_s": float(times[i - 1]), "cleared_s": None})  # fmt: skip
    return out


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


def _held(t: np.ndarray, condition: np.ndarray) -> float | None:
    """The first time ``condition`` starts a stretch of consecutive samples lasting HOLD_S."""
    padded = np.concatenate([[False], condition, [False]])
    edges = np.flatnonzero(np.diff(padded.astype(np.int8)))
    dt = t[1] - t[0] if t.size > 1 else 0.0
    for a, b in zip(edges[0::2], edges[1::2], strict=True):
        if (b - a) * dt >= HOLD_S * (1 - 1e-9):
            return float(t[a])
    return None


def lost_control(t, w_rpm, ref_rpm, judged) -> dict:
    """``reversal_at_s`` and ``stall_at_s`` (module docstring; None if neither) over the
    ``judged`` samples."""
    reversed_ = (
        judged
        & (np.sign(w_rpm) == -np.sign(ref_rpm))
        & (np.abs(w_rpm) > REVERSAL_MIN_RPM)
        & (np.abs(ref_rpm) > REVERSAL_MIN_RPM)
    )
    stalled = (
        judged
        & (np.abs(ref_rpm) > STALL_MIN_REFERENCE_RPM)
        & (np.abs(w_rpm) < STALL_FRACTION * np.abs(ref_rpm))
    )
    return {"reversal_at_s": _held(t, reversed_), "stall_at_s": _held(t, stalled)}


def assess(result, mask: np.ndarray, motor: int, start: float, stop: float) -> dict:
    """The figures of the module docstring for motor ``motor`` of ``result`` from ``start`` to
    ``stop`` [s], judged on the ``mask`` (tracked) samples."""
    t = result.t
    w = result.signal("w", motor) * RPM_PER_RAD_S
    ref = result.signal("w_ref", motor) * RPM_PER_RAD_S
    err = np.abs((result.signal("w_ref", motor) - result.signal("w", motor)) * RPM_PER_RAD_S)
    before = mask & (t >= start - PRE_WINDOW_S) & (t < start)
    inside = (t >= start) & (t < stop)
    judged = mask & inside
    p99 = float(np.percentile(err[before], 99)) if before.any() else None
    at = int(np.searchsorted(t, start)) if t.size else 0
    ref_at = abs(float(ref[min(at, t.size - 1)]))
    cap = RECOVERY_REFERENCE_FRACTION * ref_at
    band = max(min(RECOVERY_P99_FACTOR * p99, cap) if p99 is not None else cap, RECOVERY_MIN_RPM)
    out = {"judged_until_s": float(min(stop, t[-1])), "pre_p99_error_rpm": p99, "band_rpm": band}
    if not judged.any():
        return {**out, "largest_speed_error_rpm": None, "largest_at_s": None, "recovered": None,
                "recovered_at_s": None, "recovery_time_s": None, "reversal_at_s": None,
                "stall_at_s": None}  # fmt: skip
    idx = np.flatnonzero(judged)
    k = idx[int(np.argmax(err[idx]))]
    out["largest_speed_error_rpm"] = float(err[k])
    out["largest_at_s"] = float(t[k])
    outside = idx[err[idx] > band]
    if outside.size == 0:  # never left the band
        recovered, at_s = True, start
    else:
        after = idx[idx > outside[-1]]  # in the band from here to the end of the window
        if after.size == 0:
            recovered, at_s = False, None
        elif t[idx[-1]] - t[after[0]] >= HOLD_S * (1 - 1e-9):
            recovered, at_s = True, float(t[after[0]])
        else:  # back in the band too shortly before the window ends to tell
            recovered, at_s = None, None
    out.update(
        recovered=recovered,
        recovered_at_s=at_s if recovered else None,
        recovery_time_s=(at_s - start) if recovered else None,
        **lost_control(t, w, ref, judged),
    )
    return out


def speed_outcome(result, rules_masks: list, setup, who: str = "") -> dict:
    """``disturbances`` (each with its per-motor ``assess`` figures), ``end_of_run`` (per
    motor: final speed, reference and error, reversal and stall over the last END_FRACTION),
    the ``rule``, and the ``warnings``: a loss of control (reversal or stall) by that name, a
    speed that did not recover (``who`` names the run in them, e.g. "voltage command, ")."""
    t = result.t
    end_time = float(t[-1]) if t.size else 0.0
    found = disturbances(setup)
    warnings = []
    for i, d in enumerate(found):
        stop = found[i + 1]["start_s"] if i + 1 < len(found) else math.inf
        motors = range(result.n_motors) if d["motor"] is None else [d["motor"]]
        d["motors"] = {}
        for k in motors:
            a = assess(result, rules_masks[k], k, d["start_s"], stop)
            d["motors"][f"motor {k + 1}"] = a
            when = f"after the {d['what']} at {d['start_s']:g} s"
            if a["reversal_at_s"] is not None or a["stall_at_s"] is not None:
                warnings.append(_loss_words(result, k, a, when, who))
            elif a["recovered"] is False:
                warnings.append(
                    f"{who}motor {k + 1}: the speed did not recover {when}: the error stayed beyond "
                    f"{a['band_rpm']:.3g} rpm (largest {a['largest_speed_error_rpm']:.1f} rpm at "
                    f"{a['largest_at_s']:.3f} s) until {a['judged_until_s']:.3f} s"
                )
    end = []
    for k in range(result.n_motors):
        w = result.signal("w", k) * RPM_PER_RAD_S
        ref = result.signal("w_ref", k) * RPM_PER_RAD_S
        last = rules_masks[k] & (t >= end_time - END_FRACTION * end_time)
        lost = lost_control(t, w, ref, last)
        end.append({"final_speed_rpm": float(w[-1]), "final_reference_rpm": float(ref[-1]),
                    "final_error_rpm": float(ref[-1] - w[-1]), **lost})  # fmt: skip
        already = any(x.startswith(f"loss of control: {who}motor {k + 1} ") for x in warnings)
        if not already and (lost["reversal_at_s"] is not None or lost["stall_at_s"] is not None):
            warnings.append(_loss_words(result, k, lost, "at the end of the run", who))
    return {"rule": RULE, "disturbances": found, "end_of_run": end, "warnings": warnings}


def _loss_words(result, k: int, a: dict, when: str, who: str) -> str:
    w = result.signal("w", k)[-1] * RPM_PER_RAD_S
    ref = result.signal("w_ref", k)[-1] * RPM_PER_RAD_S
    what = []
    if a["reversal_at_s"] is not None:
        what.append(f"the speed reversed against its reference from {a['reversal_at_s']:.3f} s")
    if a["stall_at_s"] is not None:
        what.append(f"the shaft stalled from {a['stall_at_s']:.3f} s")
    return (
        f"loss of control: {who}motor {k + 1} {when}: {' and '.join(what)}; it ends at {w:.0f} rpm "
        f"against a {ref:.0f} rpm reference"
    )
