"""Verdicts of the reproduction reports, each computed from its numbers against a stated tolerance.

Every helper compares a value with a reference (a printed number, a closed form, a bound) and
returns a ``Verdict``: whether the comparison holds and a sentence that names the verdict, the
difference and the tolerance, so that the sentence changes when the numbers do. The tolerances
themselves are named constants of the report modules that call these helpers.

Two kinds of check (``Verdict.kind``): a *result* compares what acdrive computes or simulates
with what the paper claims; an *input* check compares a setting acdrive took from the paper (a
scenario's DC link, a printed gain) with the printed number, i.e. the transcription. A headline
(``headline``) counts the two separately: an input check holding says nothing about the results.

A steady-state claim is judged only on a settled state (``settling``, ``when_settled``): if the
judged window still drifts by more than its tolerance, the verdict says "not settled".
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace

import numpy as np

#: ``Verdict.kind`` of a check of what acdrive computes or simulates against the paper
RESULT = "result"
#: ``Verdict.kind`` of a check of an input taken from the paper against the printed number
INPUT = "input"


@dataclass(frozen=True)
class Verdict:
    """``holds``: the comparison is within its tolerance; ``text``: the sentence printed;
    ``kind``: ``RESULT`` or ``INPUT`` (module docstring)."""

    holds: bool
    text: str
    kind: str = RESULT

    def __str__(self) -> str:
        return self.text

    def __bool__(self) -> bool:
        return self.holds


def num(x: float, digits: int = 3) -> str:
    """Compact unsigned-format number (``digits`` significant digits; inf / nan spelled out)."""
    x = float(x)
    if math.isnan(x):
        return "n/a"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return f"{x:.{digits}g}"


def signed(x: float, digits: int = 3) -> str:
    return ("+" if x >= 0 else "") + num(x, digits)


def relative_difference(value, reference) -> float:
    """(value - reference) / |reference| (real), or |value - reference| / |reference| (complex);
    relative to the larger magnitude when the reference is zero."""
    scale = abs(reference) if reference != 0 else max(abs(value), 1e-300)
    d = value - reference
    return float(d.real if not isinstance(d, complex) else abs(d)) / scale


#: A relative difference below this is floating-point round-off (a closed form against the state
#: space, an identity, two orders of the same sum): its digits, zero among them, change between
#: machines, libraries and even calls, so a report prints the bound "< 1e-12" and regenerates
#: identically. Every tolerance of the reports is above it.
ROUNDOFF_FLOOR = 1e-12


def below_floor(x: float, floor: float) -> bool:
    """A relative number smaller in magnitude than ``floor`` (exactly zero included: another
    machine may give 1e-16 for it): floating-point round-off, printed as the bound "< floor" so
    that a report regenerates identically (``floor`` = 0: never)."""
    return floor > 0.0 and abs(x) < floor


def _percent_or_ratio(
    x: float, tol: float, signed_: bool = True, floor: float = 0.0
) -> tuple[str, str]:
    """Relative numbers in % for tolerances of 0.1 % and above, as plain ratios below; a
    round-off-level number (``below_floor``) as "< floor"."""
    if below_floor(x, floor):
        return f"< {floor:g}", f"{100 * tol:g} %" if tol >= 1e-3 else f"{tol:g}"
    if tol >= 1e-3:
        return (signed(100 * x, 2) if signed_ else num(100 * abs(x), 2)) + " %", f"{100 * tol:g} %"
    return num(abs(x), 2), f"{tol:g}"


def within_abs(
    value: float, reference: float, tol: float, unit: str = "", yes="agrees", no="differs"
) -> Verdict:
    """|value - reference| <= tol."""
    d = value - reference
    ok = abs(d) <= tol
    return Verdict(
        ok, f"{yes if ok else no} (difference {signed(d)}{unit}, tolerance {num(tol)}{unit})"
    )


def within_rel(
    value, reference, tol: float, yes="agrees", no="differs", *, floor: float = 0.0
) -> Verdict:
    """|value - reference| <= tol |reference| (real or complex); a relative difference below
    ``floor`` is printed as the bound (``below_floor``)."""
    r = relative_difference(value, reference)
    ok = abs(r) <= tol
    shown, tol_shown = _percent_or_ratio(r, tol, not isinstance(value - reference, complex), floor)
    return Verdict(ok, f"{yes if ok else no} (relative difference {shown}, tolerance {tol_shown})")


def error_within(
    err: float,
    tol: float,
    what: str = "max relative difference",
    yes="agrees",
    no="differs",
    *,
    floor: float = 0.0,
) -> Verdict:
    """An error measure already computed (e.g. a maximum over a frequency grid) <= tol; a
    relative error below ``floor`` is printed as the bound (``below_floor``)."""
    ok = err <= tol
    shown = f"< {floor:g}" if below_floor(err, floor) else num(err, 2)
    return Verdict(ok, f"{yes if ok else no} ({what} {shown}, tolerance {tol:g})")


def half_unit(printed: str) -> float:
    """Half a unit of the last digit of a number as printed ("13.6" -> 0.05, "0.31e4" -> 50,
    "3,142" -> 0.5): the reading tolerance of a rounded printed value."""
    text = printed.strip().replace(",", "").lstrip("+-")
    m = re.fullmatch(r"(\d*)(?:\.(\d*))?(?:[eE]([+-]?\d+))?", text)
    if m is None or not (m.group(1) or m.group(2)):
        raise ValueError(f"not a printed number: {printed!r}")
    decimals = len(m.group(2) or "")
    exponent = int(m.group(3) or 0)
    return 0.5 * 10.0 ** (exponent - decimals)


def printed_digits(
    printed: str,
    value: float,
    yes="agrees to the printed digits",
    no="differs",
    *,
    floor: float = 0.0,
) -> Verdict:
    """``value`` rounds to the number printed as ``printed``: |value - printed| <= half a unit of
    its last digit (the tolerance, ``half_unit``); a difference below ``floor`` relative to the
    printed number is printed as that bound (``below_floor``)."""
    reference = float(printed.replace(",", ""))
    tol = half_unit(printed)
    d = value - reference
    ok = abs(d) <= tol
    rel = "" if ok or reference == 0 else f", {signed(100 * d / abs(reference), 2)} %"
    shown = (
        f"< {floor:g} relative"
        if reference != 0 and below_floor(d / reference, floor)
        else signed(d)
    )
    return Verdict(
        ok,
        f"{yes if ok else no} (difference {shown}{rel}, tolerance {tol:g}: half a unit of the "
        "last printed digit)",
    )


def at_least(value: float, bound: float, unit: str = "", yes="meets", no="misses") -> Verdict:
    """value >= bound (a specification or a printed lower bound); margin = value - bound."""
    ok = value >= bound
    return Verdict(
        ok,
        f"{yes if ok else no} (bound >= {num(bound, 4)}{unit}, margin {signed(value - bound)}{unit})",
    )


def at_most(value: float, bound: float, unit: str = "", yes="meets", no="misses") -> Verdict:
    """value <= bound (a specification or a printed upper bound); margin = bound - value."""
    ok = value <= bound
    return Verdict(
        ok,
        f"{yes if ok else no} (bound <= {num(bound, 4)}{unit}, margin {signed(bound - value)}{unit})",
    )


def ratio_at_least(value: float, reference: float, factor: float, yes: str, no: str) -> Verdict:
    """value >= factor x reference (e.g. one time scale a decade above another)."""
    ratio = value / reference if reference else math.inf
    ok = ratio >= factor
    return Verdict(ok, f"{yes if ok else no} (ratio {num(ratio)}, threshold {factor:g})")


# --- input checks and headlines ----------------------------------------------------------------


def transcription(verdict: Verdict) -> Verdict:
    """The same verdict marked as an input check (``INPUT``): a setting taken from the paper
    compared with the printed number."""
    return replace(verdict, kind=INPUT)


def headline(verdicts) -> str:
    """The report's headline sentence: result checks and input checks counted separately
    (``Verdict.kind``): "<n> of <m> result checks hold; <k> of <l> inputs taken from the paper
    agree with the printed numbers (...)", the second part only if there are input checks."""
    verdicts = list(verdicts)
    results = [v for v in verdicts if v.kind != INPUT]
    inputs = [v for v in verdicts if v.kind == INPUT]
    text = f"{sum(map(bool, results))} of {len(results)} result checks hold"
    if inputs:
        text += (
            f"; {sum(map(bool, inputs))} of {len(inputs)} inputs taken from the paper agree with "
            "the printed numbers (input checks: they test the transcription, not the results)"
        )
    return text


# --- steady state ------------------------------------------------------------------------------


@dataclass(frozen=True)
class Settling:
    """A signal over a judging window: its ``mean``, its ``drift`` (least-squares slope times the
    window length ``window_s``: how far the signal moves across the window) and whether
    |drift| <= ``tolerance`` (``settled``)."""

    settled: bool
    mean: float
    drift: float
    window_s: float
    tolerance: float

    def describe(self, unit: str = "") -> str:
        state = "settled" if self.settled else "not settled"
        return (
            f"{state} (drift {signed(self.drift)}{unit} over the last {num(self.window_s)} s, "
            f"tolerance {num(self.tolerance)}{unit})"
        )


def window_drift(t, x, window_s: float | None = None) -> tuple[float, float, float]:
    """(mean, drift, window length [s]) of ``x(t)`` over its last ``window_s`` seconds (all of
    ``t`` if None): the drift is the least-squares slope of ``x`` over the window times the
    window length, how far ``x`` moves across it."""
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    if t.shape != x.shape or t.ndim != 1 or t.size == 0:
        raise ValueError("t and x must be one-dimensional arrays of the same non-zero length")
    if window_s is not None:
        keep = t >= t[-1] - window_s
        t, x = t[keep], x[keep]
    span = float(t[-1] - t[0])
    if span <= 0.0:
        raise ValueError("the judging window needs two samples at different times")
    slope = float(np.polyfit(t - t[0], x, 1)[0])
    return float(np.mean(x)), slope * span, span


def judge_settling(
    drift: float, window_s: float, tolerance: float, mean: float = math.nan
) -> Settling:
    """Settled when |drift| <= ``tolerance`` (the unit of the signal); ``window_drift`` gives
    ``mean``, ``drift`` and ``window_s`` (a verdict that needs only the state need not pass the
    mean)."""
    return Settling(abs(drift) <= tolerance, float(mean), float(drift), float(window_s), tolerance)


def settling(t, x, tolerance: float, window_s: float | None = None) -> Settling:
    """Is ``x(t)`` settled over its last ``window_s`` seconds (all of ``t`` if None)?

    Settled when the drift over the window (``window_drift``: least-squares slope times the
    window length) is at most ``tolerance`` in magnitude; the mean over the same window is then
    the settled value. For an exponential approach with time constant tau the distance still to
    go is tau times the slope, so with a window at least as long as the slowest time constant
    the drift bounds that distance too; a ripple whose period is much shorter than the window
    adds almost nothing to the slope.
    """
    mean, drift, span = window_drift(t, x, window_s)
    return judge_settling(drift, span, tolerance, mean)


def when_settled(verdict: Verdict, settlings: dict[str, Settling], unit: str = "") -> Verdict:
    """``verdict`` if every named state it judges is settled, otherwise a verdict that does not
    hold and says "not settled", naming each drifting state, its drift and the tolerance."""
    drifting = {name: s for name, s in settlings.items() if not s.settled}
    if not drifting:
        return verdict
    return Verdict(
        False,
        "not settled: "
        + "; ".join(f"{name} {s.describe(unit)}" for name, s in drifting.items())
        + " (a steady-state claim is judged only on a settled state)",
        verdict.kind,
    )
