"""acdrive's sine, cosine and magnitude in the exported C (``acd_sincos`` and ``acd_cabs`` of
``sim._ccode._prelude``, the double build) give the numbers of the compiled kernels'
(``sim._lane_math``) bit for bit, so a native run and a numba run agree to the bit; the float
build keeps the C library's functions."""

import ctypes
import subprocess

import numpy as np
import pytest

from acdrive.sim import _native
from acdrive.sim._ccode._prelude import HELPERS, PRELUDE
from acdrive.sim._lane_math import magnitude, sincos

needs_cc = pytest.mark.skipif(_native.compiler() is None, reason="no C compiler on this machine")

_DRIVER = r"""
void many_sincos(const double *x, double *c, double *s, long n)
{
    for (long i = 0; i < n; i++) {
        c[i] = acd_cos(x[i]);
        s[i] = acd_sin(x[i]);
    }
}

void many_cabs(const double *re, const double *im, double *out, long n)
{
    for (long i = 0; i < n; i++) {
        out[i] = acd_cabs(acd_c(re[i], im[i]));
    }
}
"""


def _library(tmp_path):
    """The prelude, the helpers and a driver, compiled with the native tier's flags."""
    source, library = tmp_path / "lane.c", tmp_path / "lane.so"
    source.write_text(f"#include <math.h>\n{PRELUDE}\n{HELPERS}\n{_DRIVER}")
    subprocess.run([_native.compiler(), *_native.NATIVE_CFLAGS, "-o", str(library), str(source),
                    "-lm"], check=True, capture_output=True)  # fmt: skip
    return ctypes.CDLL(str(library))


def _angles() -> np.ndarray:
    rng = np.random.default_rng(17)
    quarter = np.pi / 2 * np.arange(-400, 401)
    return np.concatenate([
        rng.uniform(-4.0, 4.0, 20_000),
        rng.uniform(-1e4, 1e4, 20_000),  # a 50 Hz angle after 30 s of simulated time
        10.0 ** rng.uniform(-300, 8, 5_000) * rng.choice([-1.0, 1.0], 5_000),
        quarter, np.nextafter(quarter, np.inf), np.nextafter(quarter, -np.inf),  # quadrant edges
        [0.0, -0.0, 1e8, -1e8, 1e12, np.pi / 4, -np.pi / 4],
    ])  # fmt: skip


def _pointer(a: np.ndarray):
    return a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


@needs_cc
def test_c_sine_and_cosine_equal_the_kernels_bit_for_bit(tmp_path):
    x = _angles()
    c, s = np.empty_like(x), np.empty_like(x)
    _library(tmp_path).many_sincos(_pointer(x), _pointer(c), _pointer(s), ctypes.c_long(x.size))
    expected = np.array([sincos(v) for v in x])
    assert np.array_equal(c, expected[:, 0]) and np.array_equal(s, expected[:, 1])
    # and they are sine and cosine: within 2 ulp of the C library where the reduction is exact
    near = np.abs(x) <= 1e8
    assert np.all(np.abs(s[near] - np.sin(x[near])) <= 2 * np.spacing(np.abs(np.sin(x[near]))))
    assert np.all(np.abs(c[near] - np.cos(x[near])) <= 2 * np.spacing(np.abs(np.cos(x[near]))))


@needs_cc
def test_c_magnitude_equals_the_kernels_bit_for_bit(tmp_path):
    rng = np.random.default_rng(3)
    scale = 10.0 ** rng.uniform(-100, 100, 30_000)
    re, im = rng.normal(size=30_000) * scale, rng.normal(size=30_000) * scale
    out = np.empty_like(re)
    _library(tmp_path).many_cabs(_pointer(re), _pointer(im), _pointer(out), ctypes.c_long(re.size))
    expected = np.array([magnitude(complex(a, b)) for a, b in zip(re, im, strict=True)])
    assert np.array_equal(out, expected)
    assert np.all(np.abs(out - np.hypot(re, im)) <= np.spacing(np.hypot(re, im)))


@needs_cc
def test_the_float_build_keeps_the_c_library(tmp_path):
    """-DACDRIVE_FLOAT: ACD_SIN is sinf (newlib's on the Cortex-M4F), and acd_sincos is not
    compiled at all (the double series would be wrong in float)."""
    source = tmp_path / "float.c"
    use = "float f(float x) { return ACD_SIN(x) + acd_cabs(acd_c(x, x)); }"
    source.write_text(f"#include <math.h>\n{PRELUDE}\n{HELPERS}\n{use}")
    done = subprocess.run([_native.compiler(), "-std=c99", "-DACDRIVE_FLOAT", "-E", str(source)],
                          check=True, capture_output=True, text=True)  # fmt: skip
    body = done.stdout.split("float f(float x)")[1]
    assert "sinf(x)" in body and "acd_sincos" not in done.stdout
