"""Sine, cosine, square root and the magnitude of a space vector without C library calls: the
elementary functions of every compiled tier, which vectorise in the lockstep lane loops.

In the lockstep batch loop (``sim._lockstep_source``) a kernel runs once per lane in a loop that
LLVM vectorises only if every operation in it has a vector form. ``np.sin`` and ``np.cos`` are
calls into the C library, one per lane even where the loop around them vectorises, and
``np.abs`` of a complex number is a call to ``hypot``, which keeps a lane loop of the sampled
controllers scalar. Measured on bodson-ramp (docs/speed.md, "The batch loops"): libm's
``sincos`` and ``hypot`` took about a quarter of a lockstep step.

Here the same functions are written as arithmetic only:

* ``sincos(x)``: x reduced by the nearest multiple k of pi/2 in four parts (Cody and Waite's
  reduction: pi/2 split into ``PIO2_PARTS``, the first three of 27 significant bits, so that
  k times each is exact for |k| < 2^26, that is |x| < 1e8), then the Taylor series of sine
  (to r^17) and cosine (to r^18) on |r| <= pi/4, where the first omitted term is below 1e-19,
  and the quadrant k mod 4 chosen by arithmetic (a swap and two signs), not by branches.
  Within 2 ulp of the C library's correctly rounded results up to |x| = 1e8
  (``tests/test_lane_math.py``), not always the same bits.
* ``magnitude(z)``: sqrt(re^2 + im^2), within 1 ulp of ``hypot`` for |z| between 1e-150 and
  1e150 (every voltage, current and flux in SI units); it has no guard against overflow.
* ``square_root(x)``: the ``llvm.sqrt`` instruction, numpy's result bit for bit.

``LANE_MATH`` is the rebinding table (``sim._rebind``) that makes a kernel call these instead of
numpy's: its ``np`` becomes ``LANE_NUMPY``, numpy's namespace with ``sin``, ``cos``, ``abs`` and
``sqrt`` replaced, and its ``math`` becomes ``LANE_PYTHON_MATH`` (``sin``, ``cos``, ``sqrt``).
Every compiled tier uses it: the generated loops rebind each kernel they
inline (``sim._loop_source``, the single and the lockstep loops, and ``sim._kernels``, a
kind's kernels compiled alone), and the exported C and the native tier compute the same (the double
build's ``acd_sincos`` and ``acd_cabs``, ``sim._ccode._prelude``, with these constants from
``sim._sincos_constants``). So a single run, a lockstep lane and a native run agree bit for bit.
Python code outside the compiled loops (designs, analyses, reports) keeps numpy's functions.
"""

from __future__ import annotations

import math
import types

import numpy as np
from llvmlite import ir
from numba import njit
from numba import types as nb_types
from numba.extending import intrinsic, overload

from acdrive.sim._sincos_constants import (
    COSINE_TERMS,
    PIO2_PARTS,
    QUADRANT_LIMIT,
    SINE_TERMS,
    TWO_OVER_PI,
)

_P1, _P2, _P3, _P4 = PIO2_PARTS
_S3, _S5, _S7, _S9, _S11, _S13, _S15, _S17 = SINE_TERMS
_C4, _C6, _C8, _C10, _C12, _C14, _C16, _C18 = COSINE_TERMS

_strict = njit(cache=True, error_model="numpy")


@_strict
def sincos(x):
    """(cos x, sin x) by arithmetic only (module docstring); NaN for an infinite or NaN x."""
    k = np.floor(x * TWO_OVER_PI + 0.5)  # a float: whole, and inf or NaN with x
    r = (((x - k * _P1) - k * _P2) - k * _P3) - k * _P4
    r2 = r * r
    s = r + r * r2 * (_S3 + r2 * (_S5 + r2 * (_S7 + r2 * (_S9 + r2 * (_S11 + r2 * (
        _S13 + r2 * (_S15 + r2 * _S17)))))))  # fmt: skip
    c = 1.0 - 0.5 * r2 + r2 * r2 * (_C4 + r2 * (_C6 + r2 * (_C8 + r2 * (_C10 + r2 * (
        _C12 + r2 * (_C14 + r2 * (_C16 + r2 * _C18)))))))  # fmt: skip
    # quadrant k mod 4, from k's last two bits (k is converted only where it fits an integer,
    # which a NaN does not; for a non-finite x, r is NaN already):
    # cos x = (c, -s, -c, s), sin x = (s, c, -s, -c)
    q = int(k) & 3 if abs(k) < QUADRANT_LIMIT else 0
    odd = (q & 1) == 1
    cos_part = s if odd else c
    sin_part = c if odd else s
    sin_sign = 1.0 - 2.0 * ((q >> 1) & 1)
    cos_sign = 1.0 - 2.0 * (((q + 1) >> 1) & 1)
    return cos_part * cos_sign, sin_part * sin_sign


def lane_sin(x):
    """sin for the lane loops: ``sincos`` for a float, numpy's ``sin`` for anything else."""
    return np.sin(x)


def lane_cos(x):
    """cos for the lane loops: ``sincos`` for a float, numpy's ``cos`` for anything else."""
    return np.cos(x)


def lane_abs(x):
    """|x| for the lane loops: ``magnitude`` for a complex number, numpy's ``abs`` otherwise."""
    return np.abs(x)


@overload(lane_sin, jit_options={"error_model": "numpy"})
def _lane_sin(x):
    if isinstance(x, nb_types.Float):
        return lambda x: sincos(x)[1]
    return lambda x: np.sin(x)


@overload(lane_cos, jit_options={"error_model": "numpy"})
def _lane_cos(x):
    if isinstance(x, nb_types.Float):
        return lambda x: sincos(x)[0]
    return lambda x: np.cos(x)


@intrinsic
def square_root(typingctx, x):
    """The correctly rounded square root of a float64 as LLVM's ``llvm.sqrt`` (one instruction,
    NaN below zero). numba's ``math.sqrt`` and ``np.sqrt`` give the same number but, without
    fast math, through the C library's ``sqrt`` for its ``errno``: a call that keeps a lane
    loop scalar."""
    if not isinstance(x, nb_types.Float) or x.bitwidth != 64:
        return None

    def codegen(context, builder, signature, args):
        function = builder.module.declare_intrinsic("llvm.sqrt", [ir.DoubleType()])
        return builder.call(function, args)

    return nb_types.float64(nb_types.float64), codegen


@_strict
def magnitude(z):
    """|z| = sqrt(re^2 + im^2) (module docstring: no overflow guard)."""
    return square_root(z.real * z.real + z.imag * z.imag)


@overload(lane_abs, jit_options={"error_model": "numpy"})
def _lane_abs(x):
    if isinstance(x, nb_types.Complex):
        return lambda x: magnitude(x)
    return lambda x: np.abs(x)


def lane_sqrt(x):
    """sqrt for the lane loops: for a float, ``square_root`` (the same correctly rounded result
    as numpy's, NaN below zero as there), numpy's ``sqrt`` otherwise."""
    return np.sqrt(x)


@overload(lane_sqrt, jit_options={"error_model": "numpy"})
def _lane_sqrt(x):
    if isinstance(x, nb_types.Float):
        return lambda x: square_root(float(x))
    return lambda x: np.sqrt(x)


#: numpy's namespace with the lane forms of sin, cos, abs and sqrt, for a kernel's ``np``
LANE_NUMPY = types.ModuleType("acdrive.sim._lane_numpy", "numpy with the lane forms of sin, "
                              "cos, abs and sqrt (acdrive.sim._lane_math)")  # fmt: skip
LANE_NUMPY.__dict__.update({k: v for k, v in np.__dict__.items() if not k.startswith("__")})
LANE_NUMPY.sin, LANE_NUMPY.cos, LANE_NUMPY.abs = lane_sin, lane_cos, lane_abs
LANE_NUMPY.sqrt = lane_sqrt

#: Python's ``math`` with the lane forms of sin, cos and sqrt: a kernel may call either module,
#: and the C translation maps both to the same functions (``sim._ccode._translate``)
LANE_PYTHON_MATH = types.ModuleType("acdrive.sim._lane_python_math", "math with the lane forms "
                                    "of sin, cos and sqrt (acdrive.sim._lane_math)")  # fmt: skip
LANE_PYTHON_MATH.__dict__.update({k: v for k, v in math.__dict__.items() if not k.startswith("__")})
LANE_PYTHON_MATH.sin, LANE_PYTHON_MATH.cos, LANE_PYTHON_MATH.sqrt = lane_sin, lane_cos, lane_sqrt

#: the rebinding table (``sim._rebind``): a kernel's numpy becomes ``LANE_NUMPY``, its ``math``
#: ``LANE_PYTHON_MATH``
LANE_MATH = {id(np): LANE_NUMPY, id(math): LANE_PYTHON_MATH}
