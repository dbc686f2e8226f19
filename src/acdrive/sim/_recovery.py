"""How a speed (or position) came through each disturbance of a run and its end: the rules every
drive's summary judges by.

The disturbances are known from the scenario before the run (after t = 0); each drive lists its
own (``drives.dfim._recovery.disturbances``, ``drives.cage_im._recovery.im_disturbances``, from
the profile helpers ``_departures`` and ``_steps`` here). ``judge_speed`` takes the logged times, speed and reference [rpm], the
tracking mask and the (what, start) of each disturbance reaching that shaft, and judges each from
its start to the next one's start or the end of the run, on the samples where tracking is
expected (``sim._metrics.TrackingRule``: the intended reference steps' settling and an open relay
are not judged):

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

``judge_position`` judges a position loop's error after each disturbance by the same recovery rule
(band floor POSITION_RECOVERY_MIN_RAD instead of RECOVERY_MIN_RPM; no reversal or stall: a
position drive at rest has a zero speed reference).
"""

from __future__ import annotations

import math

import numpy as np

from acdrive.sim._metrics import (
    SETTLE_TIME_CONSTANTS,
    SLEW_MARGIN,
    reference_change_windows,
)

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
#: a position loop's recovery band floor [rad] (0.01 rad, 0.57 degrees), as RECOVERY_MIN_RPM
POSITION_RECOVERY_MIN_RAD = 0.01

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
POSITION_RULE = (
    f"recovered: |position error| back within max(min({RECOVERY_P99_FACTOR:g} x its 99th "
    f"percentile over the {PRE_WINDOW_S:g} s before the disturbance, "
    f"{RECOVERY_REFERENCE_FRACTION:.0%} of |position reference|), {POSITION_RECOVERY_MIN_RAD:g} "
    f"rad) and staying there to the next disturbance or the end of the run (at least "
    f"{HOLD_S * 1e3:g} ms; recovery time from the disturbance's start); not judged within "
    f"{SLEW_MARGIN:g} x |d theta| / w_max + {SETTLE_TIME_CONSTANTS:g} / K_theta of a position "
    "reference step (windows_s)"
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


def _recovery(t, err, judged, before, start: float, cap: float, floor: float) -> dict:
    """The band max(min(RECOVERY_P99_FACTOR x p99 of ``err`` over ``before``, ``cap``),
    ``floor``), the largest ``err`` over the ``judged`` samples and when, and whether, when and
    how long after ``start`` it came back within the band and stayed there (module docstring)."""
    p99 = float(np.percentile(err[before], 99)) if before.any() else None
    band = max(min(RECOVERY_P99_FACTOR * p99, cap) if p99 is not None else cap, floor)
    out = {"pre_p99_error": p99, "band": band}
    if not judged.any():
        return {**out, "largest_error": None, "largest_at_s": None, "recovered": None,
                "recovered_at_s": None, "recovery_time_s": None}  # fmt: skip
    idx = np.flatnonzero(judged)
    k = idx[int(np.argmax(err[idx]))]
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
    return {**out, "largest_error": float(err[k]), "largest_at_s": float(t[k]),
            "recovered": recovered, "recovered_at_s": at_s if recovered else None,
            "recovery_time_s": (at_s - start) if recovered else None}  # fmt: skip


def assess(t, w_rpm, ref_rpm, mask, start: float, stop: float) -> dict:
    """The figures of the module docstring for the speed ``w_rpm`` against ``ref_rpm`` [rpm] at
    times ``t`` [s] from ``start`` to ``stop`` [s], judged on the ``mask`` (tracked) samples."""
    err = np.abs(ref_rpm - w_rpm)
    before = mask & (t >= start - PRE_WINDOW_S) & (t < start)
    judged = mask & (t >= start) & (t < stop)
    at = int(np.searchsorted(t, start)) if t.size else 0
    cap = RECOVERY_REFERENCE_FRACTION * abs(float(ref_rpm[min(at, t.size - 1)]))
    r = _recovery(t, err, judged, before, start, cap, RECOVERY_MIN_RPM)
    lost = (
        lost_control(t, w_rpm, ref_rpm, judged)
        if judged.any()
        else {"reversal_at_s": None, "stall_at_s": None}
    )
    return {
        "judged_until_s": float(min(stop, t[-1])),
        "pre_p99_error_rpm": r["pre_p99_error"],
        "band_rpm": r["band"],
        "largest_speed_error_rpm": r["largest_error"],
        "largest_at_s": r["largest_at_s"],
        "recovered": r["recovered"],
        "recovered_at_s": r["recovered_at_s"],
        "recovery_time_s": r["recovery_time_s"],
        **lost,
    }


def judge_speed(t, w_rpm, ref_rpm, mask, found, subject: str) -> dict:
    """What happened to one shaft: ``disturbances``, the ``assess`` figures of each (``what``,
    ``start_s``) in ``found`` (those reaching this shaft, by start time) from its start to the
    next one's or the end of the run; ``end_of_run``: final speed, reference and error [rpm],
    reversal and stall over the last END_FRACTION; ``warnings``: a loss of control (reversal or
    stall) by that name, a speed that did not recover, each naming ``subject`` (e.g. "motor 1",
    "voltage command, motor 2", "paper-20")."""
    t, w_rpm, ref_rpm = (np.asarray(x, dtype=float) for x in (t, w_rpm, ref_rpm))
    mask = np.asarray(mask, dtype=bool)
    end_time = float(t[-1]) if t.size else 0.0
    judged, warnings = [], []
    for i, (what, start) in enumerate(found):
        stop = found[i + 1][1] if i + 1 < len(found) else math.inf
        a = assess(t, w_rpm, ref_rpm, mask, start, stop)
        judged.append(a)
        when = f"after the {what} at {start:g} s"
        if a["reversal_at_s"] is not None or a["stall_at_s"] is not None:
            warnings.append(_loss_words(subject, w_rpm, ref_rpm, a, when))
        elif a["recovered"] is False:
            warnings.append(
                f"{subject}: the speed did not recover {when}: the error stayed beyond "
                f"{a['band_rpm']:.3g} rpm (largest {a['largest_speed_error_rpm']:.1f} rpm at "
                f"{a['largest_at_s']:.3f} s) until {a['judged_until_s']:.3f} s"
            )
    last = mask & (t >= end_time - END_FRACTION * end_time)
    lost = lost_control(t, w_rpm, ref_rpm, last)
    end = {"final_speed_rpm": float(w_rpm[-1]), "final_reference_rpm": float(ref_rpm[-1]),
           "final_error_rpm": float(ref_rpm[-1] - w_rpm[-1]), **lost}  # fmt: skip
    already = any(x.startswith(f"loss of control: {subject} ") for x in warnings)
    if not already and (lost["reversal_at_s"] is not None or lost["stall_at_s"] is not None):
        warnings.append(_loss_words(subject, w_rpm, ref_rpm, lost, "at the end of the run"))
    return {"disturbances": judged, "end_of_run": end, "warnings": warnings}


def _loss_words(subject: str, w_rpm, ref_rpm, a: dict, when: str) -> str:
    what = []
    if a["reversal_at_s"] is not None:
        what.append(f"the speed reversed against its reference from {a['reversal_at_s']:.3f} s")
    if a["stall_at_s"] is not None:
        what.append(f"the shaft stalled from {a['stall_at_s']:.3f} s")
    return (
        f"loss of control: {subject} {when}: {' and '.join(what)}; it ends at {w_rpm[-1]:.0f} "
        f"rpm against a {ref_rpm[-1]:.0f} rpm reference"
    )


def position_tracking_windows(position_reference, w_max: float, K_theta: float) -> tuple:
    """(start, end) [s] after each position reference change faster than the loop can follow:
    the speed-loop rule of ``sim._metrics.reference_change_windows`` with the slew rate w_max
    [rad/s] (the position loop's speed limit) in place of tau / J, and SETTLE_TIME_CONSTANTS /
    K_theta [s] to settle (the P position loop's pole, the inner speed loop being faster)."""
    times, values = position_reference
    return reference_change_windows(times, values, 1.0, w_max, SETTLE_TIME_CONSTANTS / K_theta)


def judge_position(t, theta, theta_ref, mask, found) -> list[dict]:
    """The position error |theta_ref - theta| [rad] after each (what, start) of ``found``, by
    the recovery rule of the speed (module docstring) with the band floor
    POSITION_RECOVERY_MIN_RAD, on the ``mask`` samples (outside ``position_tracking_windows``)."""
    t = np.asarray(t, dtype=float)
    mask = np.asarray(mask, dtype=bool)
    err = np.abs(np.asarray(theta_ref, dtype=float) - np.asarray(theta, dtype=float))
    out = []
    for i, (_, start) in enumerate(found):
        stop = found[i + 1][1] if i + 1 < len(found) else math.inf
        before = mask & (t >= start - PRE_WINDOW_S) & (t < start)
        judged = mask & (t >= start) & (t < stop)
        at = min(int(np.searchsorted(t, start)), t.size - 1)
        cap = RECOVERY_REFERENCE_FRACTION * abs(float(theta_ref[at]))
        r = _recovery(t, err, judged, before, start, cap, POSITION_RECOVERY_MIN_RAD)
        out.append({
            "judged_until_s": float(min(stop, t[-1])),
            "pre_p99_error_rad": r["pre_p99_error"],
            "band_rad": r["band"],
            "largest_position_error_rad": r["largest_error"],
            "largest_at_s": r["largest_at_s"],
            "recovered": r["recovered"],
            "recovered_at_s": r["recovered_at_s"],
            "recovery_time_s": r["recovery_time_s"],
        })  # fmt: skip
    return out


#: why a position run's summary judges the position after a disturbance and not the speed
POSITION_SPEED_NOT_JUDGED = (
    "the speed reference of a position run is the position loop's own output (zero at rest), "
    "not a target: a load is rejected when the position error recovers, judged instead"
)
