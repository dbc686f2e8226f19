"""Hurwitz tests for polynomials with real or complex coefficients, in floating point or exactly.

A polynomial is Hurwitz (stable) when all its roots lie in the open left half plane. Bodson
(15)-(17) decides this for the degree-2 complex polynomial Delta Z(s - j w_e) with the
determinant conditions of his reference [30]; here the test is general (any degree).

Coefficients are given highest power first (the ``numpy.roots`` order). Each coefficient may be
an int, float, complex, ``fractions.Fraction`` or a pair ``(re, im)`` (a Gaussian rational when
both are ints or Fractions). With ``exact=None`` the mode is chosen from the input: exact when
every number is an int or a Fraction, floating point otherwise. ``exact=True`` converts floats
to the Fractions of their exact binary values; no floating-point operation is then used.

Method of :func:`complex_hurwitz` (argument principle + Cauchy index + Sturm chain)
-----------------------------------------------------------------------------------
Let p(s) = sum_k c_k s^(n-k), c_0 != 0. Multiply p by conj(c_0) (by sign(c_0) if c_0 is real):
the roots do not change and the leading coefficient becomes real and positive. Put s = j w and
P(w) = j^(-n) p(j w) = A(w) + j B(w), with A, B real polynomials, deg A = n, deg B < n. A root
s_r of p maps to w_r = -j s_r, so Re s_r < 0 <=> Im w_r > 0. If P has no real root (p none on
the imaginary axis), the argument of P increases by pi (n_lhp - n_rhp) along the real w axis,
and because B/A -> 0 at both ends this change equals pi I(-B/A), where I is the Cauchy index
over the real line. Sturm's theorem gives I(f_1/f_0) = V(-inf) - V(+inf) for the chain
f_0 = A, f_1 = -B, f_(k+1) = -rem(f_(k-1), f_k), V counting sign changes along the chain.
Hence n_rhp = (n - I) / 2.

* Regular case (each f_k has degree n - k, chain of n + 1 members): I = n - 2 V where V is the
  number of sign changes among the leading coefficients ("first column"). So n_rhp = V and p is
  Hurwitz iff every leading coefficient is positive. This is the complex Routh array.
* Singular case (a degree drops by more than one, or the chain stops early): p is not Hurwitz
  (then I < n) and the counts still follow. The last chain member g = gcd(A, B) holds the roots
  P shares with its conjugate. Its non-real roots come in conjugate pairs (one root of p on
  each side of the imaginary axis: no change of the index); its real roots (multiplicity m,
  counted by Sturm sequences of g, gcd(g, g'), ...) are the imaginary-axis roots of p. Then
  n_rhp = (n - m - I) / 2 and n_imag = m.

Floating point: every computed chain coefficient carries a bound (the sum of the magnitudes
that were added into it); a value below ``rtol`` times its bound is taken as zero. When the
floating-point chain is regular its signs are trusted. Otherwise (the singular case, or a pivot
that cannot be told from zero) the test is redone in exact arithmetic on the binary values of
the coefficients, so no answer is ever a guess; ``marginal=True`` then reports that a pivot was
within rounding of zero: the polynomial is that close to the set where the counts change.

The reported ``determinants`` D_1..D_n are the leading principal minors of odd order 2k - 1 of
the matrix whose rows alternate the coefficients of f_1 (padded to degree n - 1) and f_0, each
pair shifted one column to the right (the Bilharz-Frank form; expanding Hurwitz's determinant
nabla_2k of the pair (f_0, f_1) along its first column gives lc(f_0) D_k; see Gantmacher,
Theory of Matrices II, ch. XV, on the Cauchy index). When no D_k is zero,
I = n - 2 V(1, D_1, ..., D_n), so n_rhp = V(1, D_1, ..., D_n) and p is Hurwitz iff every D_k > 0
(the tests check this against the chain and numpy roots). For
p = a_0 s^2 + (a_1 + j b_1) s + a_2 + j b_2 with a_0 > 0, D_1 = a_1 and D_2 is Bodson's
determinant Delta_2 of (17).

Method of :func:`routh_hurwitz`: the classical Routh array of a real polynomial (first column
sign changes = number of right-half-plane roots when no first-column entry is zero) and the
Hurwitz determinants H_1..H_n. On a zero in the first column the counts come from the exact
general chain above (in floating point, on the exact binary values of the coefficients).
"""

from __future__ import annotations

import itertools
import numbers
from dataclasses import dataclass, replace
from fractions import Fraction

import numpy as np

from acdrive._arguments import (
    COUNT0,
    FLAG,
    NONNEGATIVE,
    REAL,
    TEXT,
    Anything,
    Array,
    Either,
    Flag,
    Items,
    checked,
)
from acdrive.errors import InputError, require_nonnegative

__all__ = ["HurwitzResult", "complex_hurwitz", "is_hurwitz", "routh_hurwitz"]


#: the argument rule of polynomial coefficients (module docstring): an array of real or complex
#: numbers, or a list whose items are numbers (Fractions too) or (re, im) pairs
COEFFICIENTS = Either(
    Array(1, complex=True),
    Items(Either(REAL, Array(0, complex=True), Items(REAL))),
)


@checked(
    stable=FLAG, n_rhp=COUNT0, n_imag=COUNT0, marginal=FLAG,
    first_column=Items(Anything(), empty=True), determinants=Items(Anything(), empty=True),
    array=Items(Anything(), empty=True), exact=FLAG, method=TEXT,
)
@dataclass(frozen=True)
class HurwitzResult:
    """Outcome of a Hurwitz test.

    stable: True iff every root is in the open left half plane.
    n_rhp: number of roots with positive real part (with multiplicity).
    n_imag: number of roots on the imaginary axis (with multiplicity).
    marginal: floating-point input only: a pivot was zero within ``rtol`` of rounding, so the
        counts were computed exactly from the binary values of the coefficients; they are
        exact for those values, but a relative perturbation of about ``rtol`` may change them.
    first_column: leading coefficients of the chain (complex test) or first column of the Routh
        array (real test), as far as it could be built.
    determinants: Bilharz-Frank determinants D_1..D_n (complex) or Hurwitz determinants H_1..H_n
        (real).
    array: the rows used (chain polynomials f_0, f_1, ... highest power first, or Routh rows).
    exact: True when the counts were computed with Fractions only.
    method: "complex-sturm" or "routh".
    """

    stable: bool
    n_rhp: int
    n_imag: int
    marginal: bool
    first_column: tuple
    determinants: tuple
    array: tuple
    exact: bool
    method: str


# --- input ---------------------------------------------------------------------------------


def _is_exact_number(x) -> bool:
    return isinstance(x, (int, np.integer, Fraction)) and not isinstance(x, bool)


def _is_real_number(x) -> bool:
    return isinstance(x, (numbers.Real, np.integer, np.floating)) and not isinstance(x, bool)


def _split(field: str, c):
    """Return (re, im) of one coefficient without converting it."""
    if isinstance(c, (tuple, list)):
        if len(c) != 2 or not all(_is_real_number(v) for v in c):
            raise InputError(field, "a pair must be (re, im) of two real numbers")
        return c[0], c[1]
    if _is_real_number(c):
        return c, 0
    if isinstance(c, (complex, np.complexfloating)):
        return float(c.real), float(c.imag)
    raise InputError(field, f"must be a number or an (re, im) pair, got {type(c).__name__}")


def _convert(field: str, v, exact: bool):
    if exact:
        if isinstance(v, (float, np.floating)):
            if not np.isfinite(v):
                raise InputError(field, "must be finite (not NaN or infinite)")
            return Fraction(float(v))
        return Fraction(int(v)) if isinstance(v, np.integer) else Fraction(v)
    v = float(v)
    if not np.isfinite(v):
        raise InputError(field, "must be finite (not NaN or infinite)")
    return v


def _parse(coeffs, exact: bool | None, real_only: bool):
    """Coefficients -> (list of (re, im), exact flag); validates."""
    if isinstance(coeffs, np.ndarray):
        coeffs = coeffs.tolist()
    try:
        items = list(coeffs)
    except TypeError:
        raise InputError("coeffs", "must be a sequence of coefficients") from None
    if not items:
        raise InputError("coeffs", "must hold at least one coefficient")
    pairs = [_split(f"coeffs[{k}]", c) for k, c in enumerate(items)]
    if exact is None:
        exact = all(_is_exact_number(v) for pair in pairs for v in pair)
    out = []
    for k, (re, im) in enumerate(pairs):
        re = _convert(f"coeffs[{k}]", re, exact)
        im = _convert(f"coeffs[{k}]", im, exact)
        if real_only and im != 0:
            raise InputError(f"coeffs[{k}]", "must be real for the real Routh-Hurwitz test")
        out.append((re, im))
    if out[0] == (0, 0):
        raise InputError("coeffs[0]", "leading coefficient must be nonzero")
    return out, bool(exact)


# --- real polynomial helpers (lists, highest power first; Fractions or floats) -------------


def _strip(p, bounds=None, rtol=0.0):
    """Drop leading zeros. Float mode (rtol > 0): values below rtol x bound count as zero.

    Returns (p, bounds, near) where near tells that a dropped value was a computed one (nonzero
    bound), i.e. a zero that cannot be told from rounding.
    """
    if rtol:
        p = [0.0 if abs(x) <= rtol * b else x for x, b in zip(p, bounds)]
    k = 0
    while k < len(p) and p[k] == 0:
        k += 1
    near = bool(rtol) and any(b > 0 for b in bounds[:k])
    return p[k:], (bounds[k:] if rtol else None), near


def _rem(f, fb, g, gb, rtol):
    """Remainder of f / g, with magnitude bounds propagated in float mode (rtol > 0)."""
    r = list(f)
    bound = list(fb) if rtol else None
    dg = len(g) - 1
    for i in range(len(f) - dg):
        q = r[i] / g[0]
        for j in range(len(g)):
            r[i + j] -= q * g[j]
            if rtol:
                bound[i + j] += abs(q) * gb[j]
    start = len(f) - dg
    return _strip(r[start:], bound[start:] if rtol else None, rtol)


def _chain(f0, f1, rtol=0.0, b0=None, b1=None):
    """Sturm chain f_0, f_1, f_(k+1) = -rem(f_(k-1), f_k) (nonzero members only).

    Returns (chain, near): near is True when a float pivot could not be told from zero.
    """
    chain, bounds, near = [f0], [b0], False
    if f1:
        chain.append(f1)
        bounds.append(b1)
        while True:
            r, rb, flag = _rem(chain[-2], bounds[-2], chain[-1], bounds[-1], rtol)
            near = near or flag
            if not r:
                break
            chain.append([-x for x in r])
            bounds.append(rb)
    return chain, near


def _sign(x) -> int:
    return (x > 0) - (x < 0)


def _variations(signs) -> int:
    signs = [s for s in signs if s != 0]
    return sum(1 for a, b in itertools.pairwise(signs) if a != b)


def _cauchy_index(chain) -> int:
    """V(-inf) - V(+inf) of a Sturm chain: the Cauchy index of f_1/f_0 over the real line."""
    at_plus = [_sign(p[0]) for p in chain]
    at_minus = [_sign(p[0]) * (-1) ** (len(p) - 1) for p in chain]
    return _variations(at_minus) - _variations(at_plus)


def _derivative(p):
    n = len(p) - 1
    return [c * (n - k) for k, c in enumerate(p[:-1])]


def _real_roots_with_multiplicity(g) -> int:
    """Number of real roots of g counted with multiplicity (exact arithmetic).

    Sturm: distinct real roots of h = V(-inf) - V(+inf) of the chain (h, h', ...). A root of
    multiplicity mu of g is a root of multiplicity mu - 1 of gcd(g, g'), so summing the distinct
    counts of g, gcd(g, g'), gcd(gcd, gcd'), ... counts each root mu times.
    """
    total = 0
    h = g
    while len(h) > 1:
        chain, _ = _chain(h, _derivative(h))
        total += _cauchy_index(chain)
        h = chain[-1]
    return total


def _det(rows):
    """Determinant by Gaussian elimination with row pivoting (exact for Fractions)."""
    a = [list(r) for r in rows]
    n = len(a)
    det = 1
    for col in range(n):
        piv = max(range(col, n), key=lambda r: abs(a[r][col]))
        if a[piv][col] == 0:
            return a[piv][col]
        if piv != col:
            a[col], a[piv] = a[piv], a[col]
            det = -det
        det = det * a[col][col]
        for r in range(col + 1, n):
            m = a[r][col] / a[col][col]
            if m != 0:
                for c in range(col, n):
                    a[r][c] -= m * a[col][c]
    return det


def _leading_minors(matrix, orders):
    return tuple(_det([row[:k] for row in matrix[:k]]) for k in orders)


# --- complex test --------------------------------------------------------------------------


def _gmul(x, y):
    return (x[0] * y[0] - x[1] * y[1], x[0] * y[1] + x[1] * y[0])


def _complex_chain(c, exact: bool, rtol: float):
    """f_0, f_1 of the module docstring from the coefficients, then the chain."""
    one = Fraction(1) if exact else 1.0
    zero = 0 * one
    x0, y0 = c[0]
    scale = (one if x0 > 0 else -one, zero) if y0 == 0 else (x0, -y0)
    j_pow = [(one, zero), (zero, -one), (-one, zero), (zero, one)]  # j^(-k), k mod 4
    d = [_gmul(_gmul(ck, scale), j_pow[k % 4]) for k, ck in enumerate(c)]
    f0 = [dk[0] for dk in d]
    f1_full = [-dk[1] for dk in d[1:]]
    if exact:
        f1, b1, near = _strip(f1_full)
        b0 = None
    elif y0 == 0:  # scaling by +-1 is exact: the input values carry no rounding
        f1, _, near = _strip(f1_full)
        b0 = [abs(v) for v in f0]
        b1 = [abs(v) for v in f1]
    else:
        # |x0 xk| + |y0 yk| <= |c0| |ck| (Cauchy-Schwarz): a bound for both parts of d_k
        size = abs(complex(*scale))
        b0 = [size * abs(complex(*ck)) for ck in c]
        f0 = [0.0 if abs(v) <= rtol * b else v for v, b in zip(f0, b0)]
        f1, b1, near = _strip(f1_full, b0[1:], rtol)
    chain, near_chain = _chain(f0, f1, rtol, b0, b1)
    return chain, f0, f1_full, near or near_chain


def _bilharz_determinants(f0, f1_full, zero):
    n = len(f0) - 1
    size = 2 * n - 1
    matrix = []
    for i in range(size):
        src = f1_full if i % 2 == 0 else f0
        row = [zero] * size
        for k, v in enumerate(src):
            if i // 2 + k < size:
                row[i // 2 + k] = v
        matrix.append(row)
    return _leading_minors(matrix, range(1, size + 1, 2))


@checked(coeffs=COEFFICIENTS, exact=Flag(optional=True), rtol=NONNEGATIVE)
def complex_hurwitz(coeffs, *, exact: bool | None = None, rtol: float = 1e-9) -> HurwitzResult:
    """Hurwitz test of a polynomial with complex coefficients (any degree); see module docstring.

    ``coeffs``: highest power first. ``rtol``: float mode only, relative size below which a
    computed chain coefficient is taken as zero. Generalises Bodson (15)-(17).
    """
    rtol = require_nonnegative("rtol", rtol)
    c, exact = _parse(coeffs, exact, real_only=False)
    n = len(c) - 1
    chain, f0, f1_full, near = _complex_chain(c, exact, 0.0 if exact else rtol)
    regular = len(chain) == n + 1 and all(len(p) == n + 1 - k for k, p in enumerate(chain))
    if not exact and not regular:
        result = complex_hurwitz(_parse(coeffs, True, real_only=False)[0], exact=True)
        return replace(result, marginal=near)
    common = {
        "first_column": tuple(p[0] for p in chain),
        "determinants": _bilharz_determinants(f0, f1_full, 0 * f0[0]),
        "array": tuple(tuple(p) for p in chain),
        "exact": exact,
        "method": "complex-sturm",
        "marginal": False,
    }
    if regular:
        v = _variations([_sign(p[0]) for p in chain])
        return HurwitzResult(stable=v == 0, n_rhp=v, n_imag=0, **common)
    index = _cauchy_index(chain)
    m = _real_roots_with_multiplicity(chain[-1])
    n_rhp, odd = divmod(n - m - index, 2)
    assert odd == 0 and n_rhp >= 0, "Cauchy index inconsistent with the degree"
    return HurwitzResult(stable=n_rhp == 0 and m == 0, n_rhp=n_rhp, n_imag=m, **common)


# --- real test -----------------------------------------------------------------------------


@checked(coeffs=COEFFICIENTS, exact=Flag(optional=True), rtol=NONNEGATIVE)
def routh_hurwitz(coeffs, *, exact: bool | None = None, rtol: float = 1e-9) -> HurwitzResult:
    """Routh-Hurwitz test of a polynomial with real coefficients (any degree).

    Builds the Routh array (rows s^n, s^(n-1), ...) and the Hurwitz determinants H_1..H_n
    (leading principal minors of the matrix with entries a_(2j-i), 1-based). With a_0 > 0 the
    polynomial is Hurwitz iff every first-column entry (equivalently every H_k) is positive,
    and the number of right-half-plane roots is the number of sign changes in the first column.
    ``rtol``: float mode only, relative size below which a computed entry is taken as zero.
    """
    rtol = require_nonnegative("rtol", rtol)
    c, exact = _parse(coeffs, exact, real_only=True)
    a = [re for re, _ in c]
    if a[0] < 0:
        a = [-x for x in a]
    n = len(a) - 1
    zero = a[0] * 0
    width = n // 2 + 1
    rows = [r + [zero] * (width - len(r)) for r in (a[0::2], a[1::2])][: n + 1]
    bounds = [[abs(x) for x in r] for r in rows]
    near = False
    while len(rows) < n + 1 and rows[-1][0] != 0:
        (prev, cur), (pb, cb) = rows[-2:], bounds[-2:]
        ratio = prev[0] / cur[0]
        new = [prev[j + 1] - ratio * cur[j + 1] for j in range(width - 1)] + [zero]
        nb = [pb[j + 1] + abs(ratio) * cb[j + 1] for j in range(width - 1)] + [0.0]
        if not exact:
            near = near or (abs(new[0]) <= rtol * nb[0] and nb[0] > 0)
            new = [0.0 if abs(x) <= rtol * b else x for x, b in zip(new, nb)]
        rows.append(new)
        bounds.append(nb)
    first_column = tuple(r[0] for r in rows)
    singular = len(rows) < n + 1 or any(x == 0 for x in first_column)
    if singular and not exact:
        result = routh_hurwitz(_parse(coeffs, True, real_only=True)[0], exact=True)
        return replace(result, marginal=near)

    hurwitz = [
        [a[2 * j - i] if 0 <= 2 * j - i <= n else zero for j in range(1, n + 1)]
        for i in range(1, n + 1)
    ]
    common = {
        "first_column": first_column,
        "determinants": _leading_minors(hurwitz, range(1, n + 1)),
        "array": tuple(tuple(r) for r in rows),
        "exact": exact,
        "method": "routh",
        "marginal": False,
    }
    if not singular:
        v = _variations([_sign(x) for x in first_column])
        return HurwitzResult(stable=v == 0, n_rhp=v, n_imag=0, **common)
    general = complex_hurwitz([(x, zero) for x in a], exact=True)
    return HurwitzResult(
        stable=general.stable, n_rhp=general.n_rhp, n_imag=general.n_imag, **common
    )


@checked(coeffs=COEFFICIENTS, exact=Flag(optional=True))
def is_hurwitz(coeffs, *, exact: bool | None = None) -> bool:
    """True iff every root of the polynomial (real or complex coefficients) has Re < 0."""
    return complex_hurwitz(coeffs, exact=exact).stable
