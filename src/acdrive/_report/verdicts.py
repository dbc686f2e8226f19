"""Verdicts of the reproduction reports, each computed from its numbers against a stated tolerance.

Every helper compares a value with a reference (a printed number, a closed form, a bound) and
returns a ``Verdict``: whether the comparison holds and a sentence that names the verdict, the
difference and the tolerance, so that the sentence changes when the numbers do. The tolerances
themselves are named constants of the report modules that call these helpers.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass


@dataclass(frozen=True)
class Verdict:
    """``holds``: the comparison is within its tolerance; ``text``: the sentence printed."""

    holds: bool
    text: str

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


def _percent_or_ratio(x: float, tol: float, signed_: bool = True) -> tuple[str, str]:
    """Relative numbers in % for tolerances of 0.1 % and above, as plain ratios below."""
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


def within_rel(value, reference, tol: float, yes="agrees", no="differs") -> Verdict:
    """|value - reference| <= tol |reference| (real or complex)."""
    r = relative_difference(value, reference)
    ok = abs(r) <= tol
    shown, tol_shown = _percent_or_ratio(r, tol, not isinstance(value - reference, complex))
    return Verdict(ok, f"{yes if ok else no} (relative difference {shown}, tolerance {tol_shown})")


def error_within(
    err: float, tol: float, what: str = "max relative difference", yes="agrees", no="differs"
) -> Verdict:
    """An error measure already computed (e.g. a maximum over a frequency grid) <= tol."""
    ok = err <= tol
    return Verdict(ok, f"{yes if ok else no} ({what} {num(err, 2)}, tolerance {tol:g})")


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
    printed: str, value: float, yes="agrees to the printed digits", no="differs"
) -> Verdict:
    """``value`` rounds to the number printed as ``printed``: |value - printed| <= half a unit of
    its last digit (the tolerance, ``half_unit``)."""
    reference = float(printed.replace(",", ""))
    tol = half_unit(printed)
    d = value - reference
    ok = abs(d) <= tol
    rel = "" if ok or reference == 0 else f", {signed(100 * d / abs(reference), 2)} %"
    return Verdict(
        ok,
        f"{yes if ok else no} (difference {signed(d)}{rel}, tolerance {tol:g}: half a unit of the "
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
