"""Complex and real Hurwitz tests against numpy roots, exactly, and on Bodson (15)-(18)."""

import itertools
from fractions import Fraction as F

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from acdrive.analysis import complex_hurwitz, is_hurwitz, routh_hurwitz
from acdrive.errors import InputError

MARGIN = 1e-6  # reject polynomials with a root this close to the imaginary axis


def sign_changes(values):
    s = [np.sign(v) for v in values if v != 0]
    return sum(1 for a, b in itertools.pairwise(s) if a != b)


def reference_counts(coeffs):
    """(n_rhp, near_axis) from numpy roots."""
    roots = np.roots(np.asarray(coeffs, dtype=complex))
    if roots.size == 0:
        return 0, False
    return int(np.sum(roots.real > 0)), bool(np.min(np.abs(roots.real)) < MARGIN)


def exact_pairs(coeffs):
    return [(F(complex(c).real), F(complex(c).imag)) for c in coeffs]


# coefficients are 0 or of magnitude >= 1e-3: a moderate dynamic range, as float mode assumes
part = st.floats(-10.0, 10.0, allow_nan=False).map(lambda x: 0.0 if abs(x) < 1e-3 else x)
cplx = st.builds(complex, part, part)
lead = st.builds(complex, part, part).filter(lambda z: abs(z) > 0.1)


@st.composite
def complex_poly(draw, max_degree=8):
    n = draw(st.integers(1, max_degree))
    return [draw(lead)] + [draw(cplx) for _ in range(n)]


@st.composite
def real_poly(draw, max_degree=8):
    n = draw(st.integers(1, max_degree))
    first = draw(part.filter(lambda x: abs(x) > 0.1))
    return [first] + [draw(part) for _ in range(n)]


@settings(max_examples=300, deadline=None)
@given(complex_poly())
def test_complex_float_mode_matches_numpy_roots(coeffs):
    n_rhp, near = reference_counts(coeffs)
    assume(not near)
    r = complex_hurwitz(coeffs)
    assert r.n_rhp == n_rhp and r.n_imag == 0
    assert r.stable == (n_rhp == 0)


@settings(max_examples=60, deadline=None)
@given(complex_poly(max_degree=6))
def test_complex_exact_mode_matches_float_mode_and_numpy(coeffs):
    n_rhp, near = reference_counts(coeffs)
    assume(not near)
    exact = complex_hurwitz(exact_pairs(coeffs))
    assert exact.exact and not exact.marginal
    assert exact.n_rhp == n_rhp and exact.n_imag == 0 and exact.stable == (n_rhp == 0)
    approx = complex_hurwitz(coeffs)
    assert (approx.n_rhp, approx.stable) == (exact.n_rhp, exact.stable)
    if not approx.exact:  # regular float chain: same signs as the exact one
        assert [np.sign(x) for x in approx.first_column] == [np.sign(x) for x in exact.first_column]
    # exact=True on float input converts the binary values exactly: same answer
    assert complex_hurwitz(coeffs, exact=True).first_column == exact.first_column


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.tuples(st.floats(0.01, 5.0), st.floats(-5.0, 5.0)), min_size=1, max_size=8),
    st.data(),
)
def test_complex_from_roots(left_roots, data):
    """Polynomials built from chosen roots: k of them moved to the right half plane."""
    k = data.draw(st.integers(0, len(left_roots)))
    roots = [complex(-a, b) for a, b in left_roots]
    roots = [-r.conjugate() if idx < k else r for idx, r in enumerate(roots)]
    scale = data.draw(cplx.filter(lambda z: abs(z) > 0.1))
    coeffs = scale * np.poly(roots)
    r = complex_hurwitz(coeffs)
    assert r.n_rhp == k and r.n_imag == 0 and r.stable == (k == 0)


@settings(max_examples=200, deadline=None)
@given(complex_poly(max_degree=7))
def test_bilharz_determinants_count_rhp_roots(coeffs):
    """Gantmacher/Bilharz: n_rhp = sign changes of (1, D_1, ..., D_n) when no D_k is zero."""
    n_rhp, near = reference_counts(coeffs)
    assume(not near)
    r = complex_hurwitz(coeffs)
    d = r.determinants
    assert len(d) == len(coeffs) - 1
    assume(all(abs(x) > 1e-9 * max(1.0, max(abs(y) for y in d)) for x in d))
    assert sign_changes([1.0, *d]) == n_rhp
    assert r.stable == all(x > 0 for x in d)


@settings(max_examples=300, deadline=None)
@given(real_poly())
def test_routh_matches_numpy_and_complex_test(coeffs):
    n_rhp, near = reference_counts(coeffs)
    assume(not near)
    r = routh_hurwitz(coeffs)
    c = complex_hurwitz(coeffs)
    assert r.n_rhp == n_rhp and r.stable == (n_rhp == 0) and c.n_rhp == n_rhp
    if len(r.first_column) == len(coeffs) and all(x != 0 for x in r.first_column):
        # classical facts: first-column sign changes; Hurwitz determinants all > 0 iff stable
        assert sign_changes(r.first_column) == n_rhp
        assert r.stable == all(h > 0 for h in r.determinants)


@settings(max_examples=60, deadline=None)
@given(real_poly(max_degree=8))
def test_routh_exact_mode(coeffs):
    n_rhp, near = reference_counts(coeffs)
    assume(not near)
    exact = routh_hurwitz([F(x) for x in coeffs])
    assert exact.exact and exact.n_rhp == n_rhp
    approx = routh_hurwitz(coeffs)
    assert approx.n_rhp == exact.n_rhp
    if not approx.exact:
        assert [np.sign(a) for a in approx.first_column] == [np.sign(b) for b in exact.first_column]


def test_known_polynomials():
    stable = np.polymul([1, 1], [1, 3 + 2j])  # (s + 1)(s + 3 + 2j)
    assert complex_hurwitz(stable).stable
    assert complex_hurwitz(exact_pairs(stable)).stable
    # s - 1j + 0.1 has its root at -0.1 + 1j: stable; s - 0.1 - 1j (root 0.1 + 1j) is not
    assert complex_hurwitz([1, 0.1 - 1j]).stable
    r = complex_hurwitz([1, (F(-1, 10), F(-1))])
    assert not r.stable and r.n_rhp == 1
    # a complex pair that is not conjugate: (s + 1 - 2j)(s - 1 - 3j)
    r = complex_hurwitz(np.polymul([1, 1 - 2j], [1, -1 - 3j]))
    assert (r.stable, r.n_rhp) == (False, 1)
    assert routh_hurwitz([1, 6, 11, 6]).stable  # (s+1)(s+2)(s+3)
    assert routh_hurwitz([F(1), F(6), F(11), F(6)]).stable
    assert routh_hurwitz([-1, -6, -11, -6]).stable  # sign of the leading coefficient irrelevant
    assert routh_hurwitz([2]).stable and complex_hurwitz([1j]).stable  # no roots at all


def test_imaginary_axis_roots_exact_and_float():
    r = routh_hurwitz([1, 0, 1])  # s^2 + 1
    assert (r.stable, r.n_rhp, r.n_imag, r.marginal) == (False, 0, 2, False)
    r = routh_hurwitz([1.0, 0.0, 1.0])  # the zeros are in the data: exact fallback, not marginal
    assert (r.stable, r.n_rhp, r.n_imag, r.marginal, r.exact) == (False, 0, 2, False, True)
    r = complex_hurwitz([1.0, 0.0, 1.0])
    assert (r.stable, r.n_rhp, r.n_imag, r.marginal, r.exact) == (False, 0, 2, False, True)
    # (s - j)(s + 1): one root on the axis
    r = complex_hurwitz([1, (1, -1), (0, -1)])
    assert (r.stable, r.n_rhp, r.n_imag) == (False, 0, 1)
    # (s - j)^2 (s - 2)(s + 3): double root on the axis, one right-half-plane root
    p = np.polymul(np.polymul([1, -1j], [1, -1j]), np.polymul([1, -2], [1, 3]))
    r = complex_hurwitz(exact_pairs(p))
    assert (r.stable, r.n_rhp, r.n_imag) == (False, 1, 2)
    # s = 0 is on the axis
    assert complex_hurwitz([1, 0]).n_imag == 1 and routh_hurwitz([1, 0]).n_imag == 1
    assert is_hurwitz([1.0, 0.0, 1.0]) is False and is_hurwitz([1, 0, 1]) is False
    assert is_hurwitz([1.0, 1.0, 1.0]) is True


@pytest.mark.parametrize("delta", [1e-12, -1e-12])
def test_pivot_within_rounding_is_flagged_and_counted_exactly(delta):
    # s^3 + s^2 + s + 1 + delta: Routh first column 1, 1, -delta, 1 + delta. The third entry
    # comes from 1 - (1 + delta), a cancellation: float mode cannot trust its sign
    coeffs = [1.0, 1.0, 1.0, 1.0 + delta]
    expected = 2 if delta > 0 else 0
    for test in (routh_hurwitz, complex_hurwitz):
        r = test(coeffs)
        assert r.marginal and r.exact
        assert (r.n_rhp, r.n_imag, r.stable) == (expected, 0, expected == 0)
        assert not test(coeffs, rtol=1e-14).marginal  # a tighter tolerance trusts the floats
        assert test(coeffs, rtol=1e-14).n_rhp == expected


def test_zero_in_first_column_without_axis_roots():
    # s^4 + s^3 + 2 s^2 + 2 s + 3: Routh first column hits 0 (epsilon case); 2 RHP roots
    coeffs = [1, 1, 2, 2, 3]
    n_rhp, near = reference_counts(coeffs)
    assert not near
    r = routh_hurwitz(coeffs)
    assert (r.n_rhp, r.n_imag, r.stable) == (n_rhp, 0, False)
    assert routh_hurwitz([float(c) for c in coeffs]).n_rhp == n_rhp
    # (s^2 - 1)(s^2 + s + 1)... roots symmetric about the origin: row of zeros, no axis root
    p = np.polymul([1, 0, -1], [1, 2, 5]).astype(int).tolist()
    r = routh_hurwitz(p)
    assert (r.n_rhp, r.n_imag) == (1, 0)
    r = complex_hurwitz(p)
    assert (r.n_rhp, r.n_imag) == (1, 0)


@pytest.mark.parametrize(
    "coeffs",
    [
        [],
        [0, 1, 2],
        [0.0, 1.0],
        [(0, 0), 1],
        [float("nan"), 1],
        [1, float("inf")],
        ["x", 1],
        [(1, 2, 3), 1],
        5,
    ],
)
def test_bad_input(coeffs):
    with pytest.raises(InputError):
        complex_hurwitz(coeffs)
    with pytest.raises(InputError):
        routh_hurwitz(coeffs)


def test_bad_tolerance():
    for test in (complex_hurwitz, routh_hurwitz):
        with pytest.raises(InputError):
            test([1.0, 2.0], rtol=-1.0)
        with pytest.raises(InputError):
            test([1.0, 2.0], rtol=float("nan"))


def test_real_test_rejects_complex_coefficients():
    with pytest.raises(InputError):
        routh_hurwitz([1, 1j])
    with pytest.raises(InputError):
        routh_hurwitz([1, (F(1), F(1, 3))])


# --- Bodson (13), (15)-(18) on the example machine --------------------------------------------

BODSON = {  # Bodson III-D example machine, exact rationals
    "R_s": F(66, 100),
    "R_r": F(94, 100),
    "L_s": F(131, 10000),
    "L_r": F(98, 10000),
    "M": F(97, 10000),
    "n_p": 2,
}


def bodson_coefficients(w, R_s, R_r, L_s, L_r, M, n_p):
    """Bodson (16): coefficients of (15), Delta Z(s - j w_e)."""
    a0 = L_s * L_r - M**2
    a1 = L_s * R_r + L_r * R_s
    a2 = R_s * R_r
    b1 = -n_p * w * a0
    b2 = -n_p * w * L_r * R_s
    return a0, a1, a2, b1, b2


def delta_z(w_e, w, R_s, R_r, L_s, L_r, M, n_p):
    """Delta Z(s) from (10)-(13) by complex polynomial arithmetic (independent of (16))."""
    z_s = R_s + 1j * w_e * L_s
    z_r = R_r + 1j * (w_e - n_p * w) * L_r
    z_ms = 1j * w_e * M
    z_mr = 1j * (w_e - n_p * w) * M
    return np.polysub(np.polymul([L_s, z_s], [L_r, z_r]), np.polymul([M, z_mr], [M, z_ms]))


SPEEDS = [-2000.0, -377.0, -100.0, -1.0, 0.0, 0.5, 60.0, 188.5, 377.0, 1000.0, 1e4]


@pytest.mark.parametrize("w", SPEEDS)
def test_bodson_fact_electrical_model_stable(w):
    p = {k: float(v) for k, v in BODSON.items()}
    a0, a1, a2, b1, b2 = bodson_coefficients(w, **p)
    shifted = [a0, complex(a1, b1), complex(a2, b2)]
    for w_e in (0.0, 2 * np.pi * 60, -150.0):
        dz = delta_z(w_e, w, **p)
        # (15)-(16) is Delta Z(s - j w_e), computed here by substitution into (13)
        sub = np.poly1d(dz)(np.poly1d([1.0, -1j * w_e])).coeffs
        assert np.allclose(sub, shifted, rtol=1e-9, atol=1e-12)
        # the shift moves roots along the imaginary axis only: both are Hurwitz
        assert complex_hurwitz(dz).stable
        assert np.all(np.roots(dz).real < 0)
    r = complex_hurwitz(shifted)
    assert r.stable and not r.marginal and r.n_rhp == 0
    assert r.determinants[0] == pytest.approx(a1)


@pytest.mark.parametrize("w", [F(0), F(1, 3), F(-377), F(1885, 10), F(10**4)])
def test_bodson_determinant_17_equals_closed_form_18(w):
    R_s, R_r, L_s, L_r, M, n_p = (BODSON[k] for k in ("R_s", "R_r", "L_s", "L_r", "M", "n_p"))
    a0, a1, a2, b1, b2 = bodson_coefficients(w, R_s, R_r, L_s, L_r, M, n_p)
    # (17): | a1 0 -b2 ; a0 a2 -b1 ; 0 b2 a1 | expanded along the first column
    det17 = a1 * (a2 * a1 + b1 * b2) - a0 * (0 * a1 + b2 * b2)
    sigma_ls_lr = L_s * L_r - M**2
    npw2 = (n_p * w) ** 2
    first_line = (
        (L_s * R_r + L_r * R_s) ** 2 * R_s * R_r
        + (L_s * R_r + L_r * R_s) * npw2 * sigma_ls_lr * (L_r * R_s)
        - sigma_ls_lr * npw2 * (L_r * R_s) ** 2
    )
    second_line = (L_s * R_r + L_r * R_s) ** 2 * R_s * R_r + (
        L_s * L_r * R_s * R_r
    ) * npw2 * sigma_ls_lr
    assert det17 == first_line == second_line > 0
    r = complex_hurwitz([a0, (a1, b1), (a2, b2)])
    assert r.exact and r.stable
    assert r.determinants == (a1, det17)  # D_1 = a1 and D_2 = Delta_2 of (17)


def test_bodson_conditions_fail_when_they_should():
    # negative rotor resistance (a1 < 0 or Delta_2 < 0): the test must see the instability
    a0, a1, a2, b1, b2 = bodson_coefficients(F(300), **{**BODSON, "R_r": F(-94, 100)})
    r = complex_hurwitz([a0, (a1, b1), (a2, b2)])
    assert not r.stable
    roots = np.roots([float(a0), complex(a1, b1), complex(a2, b2)])
    assert r.n_rhp == int(np.sum(roots.real > 0)) >= 1
