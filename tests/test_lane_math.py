"""Sine, cosine and magnitude as arithmetic, every compiled tier's (sim._lane_math): the
reduction's constants are pi/2, the results stay within 2 ulp of the C library over the angles
a long simulation reaches, the identities hold, and a rebound kernel really uses them."""

import math
from decimal import Decimal, getcontext
from fractions import Fraction

import numpy as np
import pytest
from numba import njit

from acdrive.sim._lane_math import (
    LANE_MATH,
    lane_abs,
    lane_cos,
    lane_sin,
    lane_sqrt,
    magnitude,
    sincos,
    square_root,
)
from acdrive.sim._rebind import rebound_kernel
from acdrive.sim._sincos_constants import EXACT_REDUCTION_LIMIT, PIO2_PARTS

# pi to 110 digits (a fact, independent of the module's constants)
_PI = ("3.1415926535897932384626433832795028841971693993751058209749445923078164062862089986280"
       "348253421170679821480865")  # fmt: skip


def _significant_bits(x: float) -> int:
    mantissa = Fraction(x)
    while mantissa.denominator != 1:
        mantissa *= 2
    n = mantissa.numerator
    while n % 2 == 0:
        n //= 2
    return n.bit_length()


def test_the_four_parts_add_up_to_pi_over_two_and_the_first_three_multiply_exactly():
    getcontext().prec = 120
    half_pi = Fraction(Decimal(_PI) / 2)
    assert abs(sum(Fraction(p) for p in PIO2_PARTS) - half_pi) < Fraction(1, 10**42)
    # 27 significant bits: k * part is exact for every whole |k| < 2^26
    assert all(_significant_bits(p) <= 27 for p in PIO2_PARTS[:3])
    k = 2.0**26 - 1.0
    for p in PIO2_PARTS[:3]:
        assert Fraction(k * p) == Fraction(k) * Fraction(p)


@pytest.mark.parametrize("scale", [1.0, 10.0, 1e3, 1e5, EXACT_REDUCTION_LIMIT])
def test_within_two_ulp_of_the_c_library(scale):
    x = np.random.default_rng(int(math.log10(scale))).uniform(-scale, scale, 20_000)
    got = np.array([sincos(v) for v in x])
    for column, reference in ((0, np.cos(x)), (1, np.sin(x))):
        ulp = np.spacing(np.abs(reference))
        assert (np.abs(got[:, column] - reference) <= 2.0 * ulp).all()


def test_exact_values_symmetries_and_quadrants():
    assert sincos(0.0) == (1.0, 0.0)
    for x in (0.3, 1.2, 2.9, 4.4, 6.0, 123.456, 7.5e6):
        c, s = sincos(x)
        c_neg, s_neg = sincos(-x)
        assert c_neg == c and s_neg == -s  # even and odd: the reduction is symmetric
        assert abs(c * c + s * s - 1.0) < 4e-16
    # one point in each quadrant: the signs and the swap of the two series
    for x, signs in ((0.5, (1, 1)), (2.0, (-1, 1)), (3.5, (-1, -1)), (5.5, (1, -1))):
        c, s = sincos(x)
        assert (np.sign(c), np.sign(s)) == signs
    for bad in (math.inf, -math.inf, math.nan):
        assert all(math.isnan(v) for v in sincos(bad))


def test_magnitude_is_within_one_ulp_of_hypot():
    rng = np.random.default_rng(3)
    parts = rng.normal(size=(20_000, 2)) * 10.0 ** rng.uniform(-100, 100, size=(20_000, 1))
    for re, im in parts:
        reference = math.hypot(re, im)
        assert abs(magnitude(complex(re, im)) - reference) <= math.ulp(reference)


def test_lane_forms_fall_back_to_numpy_for_what_they_do_not_cover():
    @njit
    def use(x, z, a):
        return lane_sin(x), lane_cos(x), lane_abs(z), lane_abs(-x), lane_sin(a)

    a = np.array([0.1, 0.2])
    s, c, m, r, arr = use(0.7, 3.0 + 4.0j, a)
    assert (c, s) == sincos(0.7) and m == 5.0 and r == 0.7
    assert np.array_equal(arr, np.sin(a))


def test_a_rebound_kernel_computes_with_the_lane_forms():
    from acdrive.machines._dfim_part import dfim_project

    original = njit(dfim_project.py_func)
    rebound = njit(rebound_kernel(dfim_project.py_func, LANE_MATH))
    p = np.zeros(8)
    p[5] = 2.0  # n_p
    angles = np.random.default_rng(5).uniform(-1e4, 1e4, 2_000)
    lane, libm = [], []
    for theta in angles:
        x1, x2 = np.zeros(7), np.zeros(7)
        x1[4] = x2[4] = theta
        original(x1, p)
        rebound(x2, p)
        libm.append(x1[5:7].copy())
        lane.append(x2[5:7].copy())
    lane, libm = np.array(lane), np.array(libm)
    assert (np.abs(lane - libm) <= 2.0 * np.spacing(np.abs(libm))).all()
    # the rebound kernel does not call the C library: some results differ in the last bit
    assert (lane != libm).any()
    expected = np.array([sincos(2.0 * t) for t in angles])
    assert np.array_equal(lane, expected)


def test_square_root_is_numpy_s_sqrt_bit_for_bit_and_nan_below_zero():
    @njit(error_model="numpy")
    def both(x):
        return lane_sqrt(x), np.sqrt(x), square_root(x)

    for x in np.random.default_rng(11).uniform(0.0, 1e6, 5_000).tolist() + [0.0, 2.0, 1e-300]:
        lane, numpy_root, instruction = both(x)
        assert lane == numpy_root == instruction
    assert all(math.isnan(v) for v in both(-1.0))


def _with_math(y, x):
    """A user's kernel that calls Python's ``math``."""
    y[0], y[1], y[2] = math.cos(x), math.sin(x), math.sqrt(abs(x))


def _with_numpy(y, x):
    """The same kernel through numpy."""
    y[0], y[1], y[2] = np.cos(x), np.sin(x), np.sqrt(abs(x))


def test_a_kernel_calling_pythons_math_computes_as_one_calling_numpy():
    """The C translation maps ``math.cos`` and ``np.cos`` (sin, sqrt) to the same functions, so the
    compiled tiers must too: rebound, the two kernels agree bit for bit, also where the lane forms
    and the C library part in the last bit."""
    via_math = njit(rebound_kernel(_with_math, LANE_MATH))
    via_numpy = njit(rebound_kernel(_with_numpy, LANE_MATH))
    plain = njit(_with_math)
    a, b, c = np.zeros(3), np.zeros(3), np.zeros(3)
    parted = 0
    for x in np.random.default_rng(7).uniform(-1e4, 1e4, 2_000):
        via_math(a, x)
        via_numpy(b, x)
        plain(c, x)
        assert np.array_equal(a, b), x
        parted += not np.array_equal(a, c)
    assert parted > 0  # the C library's results differ somewhere: the comparison can tell
