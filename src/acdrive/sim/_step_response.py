"""Step-response metrics of a speed loop, each defined and computed here once: after each change
of the speed reference, the rise time, overshoot, settling time and steady-state error; after
each step of the load torque, the dip and the recovery time.

The events are the changes the scenario declares in its speed-reference and load-torque profiles
(``events``), known before the run; none is guessed from a trace. A change is a run of
consecutive profile segments whose value moves (a step where a time repeats, a ramp over sloped
segments); a change at t = 0 of the load is the starting condition, not an event. Each event is
judged on the logged samples from its start t_a to the next event's start or the end of the run
(its window), whichever comes first. With r_0 and r_1 the reference before and after a
reference change, w the speed, w_ref its reference, and times counted from t_a:

* ``rise_time_s``: from the first sample at which (w - r_0) / (r_1 - r_0) reaches RISE_FROM
  (10 %) to the first at which it reaches RISE_TO (90 %) (None if it never does);
* ``overshoot_pct``: 100 max((w - r_1) / (r_1 - r_0)) over the window, at least 0 (the
  percentage of the step by which the speed passes its new reference);
* ``settling_time_s``: to the first sample after the last one outside the band
  |w - r_1| <= band x |r_1 - r_0| (``band``: BAND_FRACTION, 2 % of the step, unless given);
  None if the speed is outside the band at the window's end (not settled). The band is taken
  around the new reference, the final value of a loop with integral action; a loop that keeps
  an offset shows it in the steady-state error and may not settle;
* ``steady_state_error``: the mean of w_ref - w over the last STEADY_FRACTION of the window
  (``steady_fraction``).

After a load step (at a reference w_ref(t_a)):

* ``dip``: the largest |w_ref - w| over the window, with its time ``dip_at_s``;
* ``recovery_time_s``: to the first sample after the last one outside the band
  |w_ref - w| <= max(band x |w_ref(t_a)|, RECOVERY_MIN_RAD_S): the settling rule with the
  reference in place of the step size, floored at the DFIM's recovery floor
  (``sim._recovery.RECOVERY_MIN_RPM``) for a step at standstill; None if outside at the end.

Times are those of the logged samples (no interpolation between them): a figure is exact to one
logging period. The same per-sample rule runs on line in a batch (``step_response_update``, the
kernel of ``acdrive._reducer_parts``' step-response part) and on a run's logged samples
(``step_response_figures``, array operations giving the kernel's figures), so a summary and a
batch row agree. Speeds are in rad/s here; ``scale`` converts the speed figures (x 30/pi: rpm).
"""

from __future__ import annotations

import math

import numpy as np

from acdrive._jit import njit
from acdrive.core._signals import pack_table
from acdrive.errors import InputError, require_finite
from acdrive.sim._recovery import RECOVERY_MIN_RPM

#: the rise is timed between these fractions of the step (10 % to 90 %)
RISE_FROM, RISE_TO = 0.1, 0.9
#: the settling band, a fraction of the step (2 %); after a load step, of the reference
BAND_FRACTION = 0.02
#: the steady-state error is the mean over this last fraction of an event's window
STEADY_FRACTION = 0.1
#: the recovery band's floor after a load step [rad/s]: the DFIM's recovery floor, 2 rpm
RECOVERY_MIN_RAD_S = RECOVERY_MIN_RPM * math.pi / 30.0

#: kinds of event (the kernel's parameter ``kind``)
REFERENCE_CHANGE, LOAD_STEP = 1.0, 2.0
#: "not yet" of a time in the kernel's state (times are >= 0; states stay finite)
NOT_YET = -1.0

#: the kernel's parameters per event, one float each
EVENT_PARAMS = (
    ("kind", "", "1: a reference change, 2: a load step"),
    ("start", "s", "the event's start t_a"),
    ("stop", "s", "the next event's start or the end of the run"),
    ("steady_from", "s", "start of the steady-state window"),
    ("r0", "", "reference before the change (speed unit)"),
    ("r1", "", "reference after the change (speed unit)"),
    ("band", "", "half-width of the settling or recovery band (speed unit)"),
)
#: the kernel's state per event, one float each
EVENT_STATES = (
    ("t_rise_from", "s", "first time at RISE_FROM of the step (-1: not yet)"),
    ("t_rise_to", "s", "first time at RISE_TO of the step (-1: not yet)"),
    ("peak", "", "reference change: largest (w - r1)/(r1 - r0); load step: largest |w_ref - w|"),
    ("t_peak", "s", "its time"),
    ("t_inside", "s", "first sample after the last one outside the band (-1: outside now)"),
    ("n", "", "samples in the window"),
    ("sum_steady", "", "sum of w_ref - w over the steady-state window"),
    ("n_steady", "", "samples in the steady-state window"),
)
_NE_P, _NE_S = len(EVENT_PARAMS), len(EVENT_STATES)
_RISE_FROM, _RISE_TO, _PEAK, _T_PEAK, _INSIDE, _N, _SUM, _N_STEADY = range(_NE_S)

RULE = (
    f"each change of the speed reference (r_0 -> r_1) and each load-torque step, from its start to "
    f"the next one's or the end of the run: rise time {100 * RISE_FROM:g}-{100 * RISE_TO:g} % of "
    "the step; overshoot: largest excursion beyond r_1, % of the step; settling time: to the "
    "last entry into the band |w - r_1| <= {band} of |r_1 - r_0| (None: outside at the end); "
    "steady-state error: mean of w_ref - w over the last {steady} of the window; load step: dip = "
    "largest |w_ref - w|, recovery time: to the last entry into |w_ref - w| <= max({band} of "
    f"|w_ref|, {RECOVERY_MIN_RPM:g} rpm); times from the event's start, to the logged sample"
)


def check_band(field: str, value) -> float:
    """``value`` as float if it is a band fraction in (0, 1) (else InputError naming ``field``)."""
    value = require_finite(field, value)
    if not 0.0 < value < 1.0:
        raise InputError(field, f"must be a fraction above 0 and below 1, got {value:g}")
    return value


def rule(band: float = BAND_FRACTION, steady_fraction: float = STEADY_FRACTION) -> str:
    """The metrics' rule in words with its numbers (the module docstring's)."""
    return RULE.format(band=f"{100 * band:g} %", steady=f"{100 * steady_fraction:g} %")


def _changes(field: str, profile) -> list[tuple[float, float, float, float]]:
    """(start, end, value before, value after) of each run of consecutive segments of a profile
    (any form ``core._signals.pack_table`` takes) whose value moves."""
    table = pack_table(field, profile)
    n = int(table[0])
    times, values = table[1 : 1 + n], table[1 + n : 1 + 2 * n]
    out, i = [], 1
    while i < n:
        if values[i] != values[i - 1]:
            j = i
            while j + 1 < n and values[j + 1] != values[j]:
                j += 1
            out.append((float(times[i - 1]), float(times[j]), float(values[i - 1]),
                        float(values[j])))  # fmt: skip
            i = j + 1
        else:
            i += 1
    return out


def events(speed_reference, loads: dict, duration: float, band: float = BAND_FRACTION,
           steady_fraction: float = STEADY_FRACTION, speed_unit: str = "rad/s",
           speed_scale: float = 1.0) -> list[dict]:  # fmt: skip
    """The events of a run of ``duration`` [s] (module docstring) by start time: ``kind``
    ("reference change" or "load step"), ``what`` (words, speeds x ``speed_scale`` in
    ``speed_unit``), ``start_s``, ``stop_s`` (the window's end), ``steady_from_s``, ``r0``,
    ``r1`` [rad/s] (the reference before and after; a load step: the reference at its start
    twice) and ``band`` [rad/s], from the profiles ``speed_reference`` [rad/s] and ``loads``
    (what -> (profile, unit), e.g. {"load torque": (profile, "N m")}; empty: no load steps, e.g.
    a held shaft)."""
    band = check_band("band", band)
    steady_fraction = check_band("steady_fraction", steady_fraction)
    reference = _changes("speed_reference", speed_reference)
    table = pack_table("speed_reference", speed_reference)
    n = int(table[0])
    found = []
    for a, b, r0, r1 in reference:
        shape = "step" if b == a else f"ramp over {b - a:g} s"
        found.append({"kind": "reference change", "start_s": a, "r0": r0, "r1": r1,
                      "band": band * abs(r1 - r0),
                      "what": f"speed reference {shape} {r0 * speed_scale:.5g} -> "
                              f"{r1 * speed_scale:.5g} {speed_unit}"})  # fmt: skip
    load_steps = [(a, l0, l1, what, unit) for what, (profile, unit) in loads.items()
                  for a, _, l0, l1 in _changes(what, profile)]  # fmt: skip
    for a, l0, l1, what, unit in load_steps:
        if a <= 0.0:
            continue  # the starting condition: no state before it to recover to
        # the reference at the step (the right-hand value where it jumps there)
        r = float(np.interp(a, table[1 : 1 + n], table[1 + n : 1 + 2 * n]))
        after = table[1 + n : 1 + 2 * n][table[1 : 1 + n] == a]
        r = float(after[-1]) if after.size else r
        found.append({"kind": "load step", "start_s": a, "r0": r, "r1": r,
                      "band": max(band * abs(r), RECOVERY_MIN_RAD_S),
                      "what": f"{what} step {l0:g} -> {l1:g} {unit}"})  # fmt: skip
    found = sorted((e for e in found if e["start_s"] < duration), key=lambda e: e["start_s"])
    for i, e in enumerate(found):
        stop = found[i + 1]["start_s"] if i + 1 < len(found) else float(duration)
        e["stop_s"] = stop
        e["steady_from_s"] = stop - steady_fraction * (stop - e["start_s"])
    return found


def event_params(found: list[dict]) -> np.ndarray:
    """The kernel's flat parameters (``EVENT_PARAMS`` per event) of ``events``' list."""
    kind = {"reference change": REFERENCE_CHANGE, "load step": LOAD_STEP}
    return np.array(
        [x for e in found for x in (kind[e["kind"]], e["start_s"], e["stop_s"],
                                    e["steady_from_s"], e["r0"], e["r1"], e["band"])],
        dtype=float,
    )  # fmt: skip


def initial_state(n_events: int) -> np.ndarray:
    """The kernel's state before the first sample: every time "not yet", sums zero."""
    s = np.zeros(n_events * _NE_S)
    for j in range(n_events):
        s[j * _NE_S + _RISE_FROM] = s[j * _NE_S + _RISE_TO] = NOT_YET
        s[j * _NE_S + _T_PEAK] = s[j * _NE_S + _INSIDE] = NOT_YET
    return s


@njit(cache=True, error_model="numpy", inline="always")
def step_response_update(t, w, w_ref, p, s):
    """Take one logged sample (time ``t`` [s], speed ``w``, its reference ``w_ref``) into the
    state ``s`` of every event whose window holds it (``p``: ``event_params``)."""
    for j in range(p.size // _NE_P):
        q = _NE_P * j
        k = _NE_S * j
        if p[q + 1] <= t < p[q + 2]:
            e = w_ref - w
            s[k + _N] += 1.0
            if t >= p[q + 3]:
                s[k + _SUM] += e
                s[k + _N_STEADY] += 1.0
            over = abs(e)  # a load step
            off = over
            if p[q] == REFERENCE_CHANGE:
                x = (w - p[q + 4]) / (p[q + 5] - p[q + 4])
                if s[k + _RISE_FROM] < 0.0 and x >= RISE_FROM:
                    s[k + _RISE_FROM] = t
                if s[k + _RISE_TO] < 0.0 and x >= RISE_TO:
                    s[k + _RISE_TO] = t
                over = x - 1.0
                off = abs(w - p[q + 5])
            if s[k + _T_PEAK] < 0.0 or over > s[k + _PEAK]:
                s[k + _PEAK] = over
                s[k + _T_PEAK] = t
            if off > p[q + 6]:
                s[k + _INSIDE] = NOT_YET
            elif s[k + _INSIDE] < 0.0:
                s[k + _INSIDE] = t


def state_from_samples(t, w, w_ref, p) -> np.ndarray:
    """The state ``step_response_update`` leaves after taking the logged samples in order,
    computed with array operations (a summary needs no compiled code;
    ``tests/test_step_response.py`` checks equality with the kernel)."""
    t, w, w_ref = (np.asarray(x, dtype=float) for x in (t, w, w_ref))
    n = p.size // _NE_P
    s = initial_state(n)
    for j in range(n):
        kind, a, c, steady, r0, r1, band = p[_NE_P * j : _NE_P * (j + 1)]
        k = _NE_S * j
        inside = (t >= a) & (t < c)
        tt, ww, ee = t[inside], w[inside], w_ref[inside] - w[inside]
        if tt.size == 0:
            continue
        s[k + _N] = tt.size
        steady_mask = tt >= steady
        s[k + _SUM] = np.cumsum(ee[steady_mask])[-1] if steady_mask.any() else 0.0
        s[k + _N_STEADY] = np.count_nonzero(steady_mask)
        if kind == REFERENCE_CHANGE:
            x = (ww - r0) / (r1 - r0)
            for slot, level in ((_RISE_FROM, RISE_FROM), (_RISE_TO, RISE_TO)):
                hit = np.flatnonzero(x >= level)
                if hit.size:
                    s[k + slot] = tt[hit[0]]
            over, off = x - 1.0, np.abs(ww - r1)
        else:
            over = off = np.abs(ee)
        m = int(np.argmax(over))
        s[k + _PEAK], s[k + _T_PEAK] = over[m], tt[m]
        out = np.flatnonzero(off > band)
        if out.size == 0:
            s[k + _INSIDE] = tt[0]
        elif out[-1] + 1 < tt.size:
            s[k + _INSIDE] = tt[out[-1] + 1]
        else:
            s[k + _INSIDE] = NOT_YET
    return s


def figures(found: list[dict], s: np.ndarray, scale: float, unit: str) -> list[dict]:
    """Per event of ``found`` (``events``), its words and its figures (module docstring) from
    the final state ``s``: speeds x ``scale`` with the key suffix ``unit`` (``rpm``, ``rad_s``);
    a figure the window does not hold (no sample, not reached, not settled) is None."""
    out = []
    for j, e in enumerate(found):
        k = _NE_S * j
        judged = s[k + _N] > 0
        row = {"what": e["what"], "kind": e["kind"], "start_s": e["start_s"],
               "judged_until_s": e["stop_s"]}  # fmt: skip
        settled = float(s[k + _INSIDE] - e["start_s"]) if judged and s[k + _INSIDE] >= 0 else None
        steady = float(s[k + _SUM] / s[k + _N_STEADY] * scale) if s[k + _N_STEADY] else None
        if e["kind"] == "reference change":
            overshoot = float(100.0 * max(s[k + _PEAK], 0.0)) if judged else None
            rise = (
                float(s[k + _RISE_TO] - s[k + _RISE_FROM])
                if s[k + _RISE_FROM] >= 0 and s[k + _RISE_TO] >= 0
                else None
            )
            row |= {
                f"step_{unit}": (e["r1"] - e["r0"]) * scale,
                "rise_time_s": rise,
                "overshoot_pct": overshoot,
                "peak_at_s": float(s[k + _T_PEAK]) if overshoot else None,
                f"settling_band_{unit}": e["band"] * scale,
                "settling_time_s": settled,
                f"steady_state_error_{unit}": steady,
            }
        else:
            row |= {
                f"dip_{unit}": float(s[k + _PEAK] * scale) if judged else None,
                "dip_at_s": float(s[k + _T_PEAK]) if judged else None,
                f"recovery_band_{unit}": e["band"] * scale,
                "recovery_time_s": settled,
                f"steady_state_error_{unit}": steady,
            }
        out.append(row)
    return out


def step_response(t, w, w_ref, found: list[dict], scale: float = 1.0, unit: str = "rad_s",
                  band: float = BAND_FRACTION,
                  steady_fraction: float = STEADY_FRACTION) -> dict:  # fmt: skip
    """A summary's ``step_response`` of the logged speed ``w`` and reference ``w_ref`` [rad/s]
    at times ``t`` [s] for the ``events`` ``found`` (made with the same ``band`` and
    ``steady_fraction``): the ``rule`` with its numbers, ``band_fraction``,
    ``steady_fraction`` and per event its ``figures``."""
    s = state_from_samples(t, w, w_ref, event_params(found))
    return {"rule": rule(band, steady_fraction), "band_fraction": band,
            "steady_fraction": steady_fraction,
            "events": figures(found, s, scale, unit)}  # fmt: skip


#: the keys of an event's ``figures`` that the scenario states rather than the run measures
SCENARIO_FACTS = ("what", "kind", "start_s", "judged_until_s")


def flat(step: dict, unit: str) -> dict:
    """One row's columns of a ``step_response``: per reference change k (1, 2, ... in time
    order) ``speed_step<k>_<figure>``, per load step ``load_step<k>_<figure>``; the figures of
    ``figures`` (None as NaN) without what the scenario states (SCENARIO_FACTS, the step and
    the band: the same for every variant of a sweep unless its profiles vary)."""
    out, counts = {}, {"reference change": 0, "load step": 0}
    for e in step["events"]:
        counts[e["kind"]] += 1
        prefix = ("speed_step" if e["kind"] == "reference change" else "load_step") + str(
            counts[e["kind"]]
        )
        for key, value in e.items():
            if key in SCENARIO_FACTS or key.endswith((f"band_{unit}", f"step_{unit}")):
                continue
            out[f"{prefix}_{key}"] = math.nan if value is None else float(value)
    return out


def headline_rows(step: dict, unit: str, label: str = "") -> list[tuple[str, str]]:
    """The headline rows (name, text) of a ``step_response`` in ``unit`` ("rpm" or "rad_s"):
    one per event, its figures with the band they were judged by."""
    shown = unit.replace("_", "/")

    def num(value, fmt, suffix=""):
        return "never" if value is None else f"{value:{fmt}}{suffix}"

    rows = []
    for e in step["events"]:
        name = f"{label}{e['what']} at {e['start_s']:g} s"
        err = e[f"steady_state_error_{unit}"]
        steady = f"steady-state error {num(err, '.3g', ' ' + shown)}"
        if e["kind"] == "reference change":
            text = (
                f"rise {num(e['rise_time_s'], '.4g', ' s')}, overshoot "
                f"{num(e['overshoot_pct'], '.2f', ' %')}, settled within "
                f"+-{e[f'settling_band_{unit}']:.3g} {shown} ({100 * step['band_fraction']:g} % of "
                f"the step) after {num(e['settling_time_s'], '.4g', ' s')}, {steady}"
            )
        else:
            text = (
                f"dip {num(e[f'dip_{unit}'], '.3g', ' ' + shown)} at "
                f"{num(e['dip_at_s'], '.4g', ' s')}, back within "
                f"+-{e[f'recovery_band_{unit}']:.3g} {shown} after "
                f"{num(e['recovery_time_s'], '.4g', ' s')}, {steady}"
            )
        rows.append((name, text))
    return rows
