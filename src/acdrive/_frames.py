"""Three-phase <-> complex space vectors in the power-invariant scaling of Bodson (1)-(8).

Bodson = M. Bodson, "Speed Control for Doubly-Fed Induction Motors With and Without Current
Feedback", section II-B.

A three-phase set (a, b, c) becomes one complex number

    x = sqrt(2/3) exp(-j theta_e) (a + alpha b + alpha^2 c),   alpha = exp(j 2 pi / 3)   (1)

which is the two-phase (alpha-beta) vector written as a complex number and seen from a frame
turned by theta_e. The factor sqrt(2/3) keeps power invariant: v i* = P + jQ (5). The rotor
transform (3) uses theta_e - n_p theta so that rotor quantities are referred to the stator.
For a balanced sinusoidal set of peak value X_pk the magnitude is |x| = sqrt(3/2) X_pk (8).

Every function accepts Python scalars or numpy arrays (broadcast together). The ``*_nb``
functions are numba-compiled scalar versions of the same formulas for use inside njit code.
"""

from __future__ import annotations

import math

import numpy as np

from acdrive._jit import njit
from acdrive.errors import InputError

#: sqrt(2/3): leading coefficient of the power-invariant 3-c transformation (Bodson (1)).
K_3C = math.sqrt(2.0 / 3.0)
#: sqrt(3/2): ratio |complex variable| / peak line-neutral value in steady state (Bodson (8)).
K_PEAK = math.sqrt(1.5)
_SQRT3_2 = math.sqrt(3.0) / 2.0


# --- the formulas, written once; plain arithmetic valid for numpy arrays and in numba ---------


def _abc_to_complex(a, b, c, theta_e):
    """Bodson (1): sqrt(2/3) exp(-j theta_e) (a + alpha b + alpha^2 c)."""
    alpha_beta = (a - 0.5 * (b + c)) + 1j * (_SQRT3_2 * (b - c))
    return K_3C * alpha_beta * np.exp(-1j * theta_e)


def _complex_to_abc(x, theta_e):
    """Bodson (2): the zero-sum three-phase set whose 3-c transform is ``x``."""
    y = x * np.exp(1j * theta_e)
    re = y.real
    im = y.imag
    a = K_3C * re
    b = K_3C * (-0.5 * re + _SQRT3_2 * im)
    c = K_3C * (-0.5 * re - _SQRT3_2 * im)
    return a, b, c


abc_to_complex_nb = njit(cache=True)(_abc_to_complex)
abc_to_complex_nb.__doc__ = """Scalar numba version of :func:`abc_to_complex` (Bodson (1))."""

complex_to_abc_nb = njit(cache=True)(_complex_to_abc)
complex_to_abc_nb.__doc__ = """Scalar numba version of :func:`complex_to_abc` (Bodson (2));
returns the tuple (a, b, c)."""


@njit(cache=True)
def rotor_abc_to_complex_nb(x, y, z, theta_e, theta, n_p):
    """Scalar numba version of :func:`rotor_abc_to_complex` (Bodson (3))."""
    return abc_to_complex_nb(x, y, z, theta_e - n_p * theta)


@njit(cache=True)
def complex_to_rotor_abc_nb(v_r, theta_e, theta, n_p):
    """Scalar numba version of :func:`complex_to_rotor_abc` (Bodson (4)); returns (x, y, z)."""
    return complex_to_abc_nb(v_r, theta_e - n_p * theta)


# --- public numpy API ------------------------------------------------------------------------


def _as_real(field: str, value) -> np.ndarray:
    arr = np.asarray(value)
    if arr.dtype.kind not in "biuf":
        raise InputError(field, f"must be real numbers, got dtype {arr.dtype}")
    arr = arr.astype(float)
    if not np.all(np.isfinite(arr)):
        raise InputError(field, "must be finite (not NaN or infinite)")
    return arr


def _as_complex(field: str, value) -> np.ndarray:
    arr = np.asarray(value)
    if arr.dtype.kind not in "biufc":
        raise InputError(field, f"must be numbers, got dtype {arr.dtype}")
    arr = arr.astype(complex)
    if not np.all(np.isfinite(arr)):
        raise InputError(field, "must be finite (not NaN or infinite)")
    return arr


def _unwrap(arr):
    """Return a Python-style scalar for 0-d results, the array otherwise."""
    return arr[()] if isinstance(arr, np.ndarray) and arr.ndim == 0 else arr


def _check_pole_pairs(n_p) -> int:
    if isinstance(n_p, bool) or not isinstance(n_p, (int, np.integer, float, np.floating)):
        raise InputError("n_p", "must be a positive integer")
    if not math.isfinite(float(n_p)) or float(n_p) != int(n_p) or int(n_p) < 1:
        raise InputError("n_p", f"must be a positive integer, got {n_p}")
    return int(n_p)


def abc_to_complex(a, b, c, theta_e=0.0):
    """Stator 3-c transformation, Bodson (1).

    ``x = sqrt(2/3) exp(-j theta_e) (a + alpha b + alpha^2 c)`` with ``alpha = exp(j 2 pi/3)``.
    ``theta_e`` is an arbitrary frame angle [rad] (0: stationary frame). Arguments broadcast.
    A zero-sequence component (a + b + c != 0) does not appear in ``x``.
    """
    a, b, c = (_as_real(n, v) for n, v in (("a", a), ("b", b), ("c", c)))
    theta_e = _as_real("theta_e", theta_e)
    return _unwrap(_abc_to_complex(a, b, c, theta_e))


def complex_to_abc(x, theta_e=0.0):
    """Inverse stator 3-c transformation, Bodson (2); returns the tuple (a, b, c).

    The result is the unique three-phase set with a + b + c = 0 whose transform (1) is ``x``.
    """
    x = _as_complex("x", x)
    theta_e = _as_real("theta_e", theta_e)
    return tuple(_unwrap(p) for p in _complex_to_abc(x, theta_e))


def rotor_abc_to_complex(x, y, z, theta_e, theta, n_p):
    """Rotor 3-c transformation, Bodson (3): (1) with the angle theta_e - n_p theta.

    ``x, y, z``: rotor phase quantities (phases X, Y, Z); ``theta``: mechanical rotor angle
    [rad] between stator phase A and rotor phase X; ``n_p``: pole pairs. The result is referred
    to the frame of angle theta_e, the same as the stator variables.
    """
    n_p = _check_pole_pairs(n_p)
    theta = _as_real("theta", theta)
    theta_e = _as_real("theta_e", theta_e)
    return abc_to_complex(x, y, z, theta_e - n_p * theta)


def complex_to_rotor_abc(v_r, theta_e, theta, n_p):
    """Inverse rotor 3-c transformation, Bodson (4); returns the zero-sum tuple (x, y, z)."""
    n_p = _check_pole_pairs(n_p)
    theta = _as_real("theta", theta)
    theta_e = _as_real("theta_e", theta_e)
    return complex_to_abc(v_r, theta_e - n_p * theta)


def rotate(x, angle):
    """Return ``x exp(j angle)``: the vector turned counterclockwise by ``angle`` [rad].

    Changing the frame angle of (1) from theta_1 to theta_2 is ``rotate(x, theta_1 - theta_2)``.
    """
    x = _as_complex("x", x)
    angle = _as_real("angle", angle)
    return _unwrap(x * np.exp(1j * angle))


def complex_power(v, i):
    """Instantaneous complex power ``v i* = P + jQ``, Bodson (5).

    P is the total instantaneous active power sum_k v_k i_k absorbed by the three windings and
    Q = (1/sqrt 3) [(v_b - v_c) i_a + (v_c - v_a) i_b + (v_a - v_b) i_c] the instantaneous
    reactive power (positive for a lagging, inductive current). Valid for any frame angle, and
    for unbalanced sets as long as the currents sum to zero (Y or Delta connection).
    """
    return _unwrap(_as_complex("v", v) * np.conj(_as_complex("i", i)))


def peak_from_complex(x):
    """Peak line-neutral value of a balanced sinusoidal set from its complex variable, Bodson (8).

    ``X_pk = |x| / sqrt(3/2)``. For a non-sinusoidal set this is the instantaneous peak-value
    equivalent used in Bodson's Figs. 5-6.
    """
    return _unwrap(np.abs(_as_complex("x", x)) / K_PEAK)


def complex_from_peak(peak, phase=0.0):
    """Complex variable of a balanced set, Bodson (8): ``sqrt(3/2) X_pk exp(j phase)``.

    The set is ``a = X_pk cos(theta_e + phase)``, ``b`` and ``c`` the same delayed by 2 pi/3 and
    4 pi/3, transformed with the frame angle theta_e of (1). A current lagging the voltage by the
    power-factor angle phi (Bodson (6)) has ``phase = -phi``.
    """
    peak = _as_real("peak", peak)
    phase = _as_real("phase", phase)
    return _unwrap(K_PEAK * peak * np.exp(1j * phase))


#: How many units in the last place a magnitude may lie above its limit and still count as at
#: the limit, not beyond it. A command already scaled back to a limit (x limit / |x|) comes out
#: up to a few ulps above it after rounding; limiting it again must neither change it nor count
#: the sample as limited (a controller that limits its command to the converter's range would
#: otherwise make the converter report rounding as overmodulation).
LIMIT_ULPS = 4
#: The relative tolerance of every magnitude limit, LIMIT_ULPS machine epsilons
#: (``beyond_limit``).
LIMIT_RTOL = LIMIT_ULPS * float(np.finfo(np.float64).eps)


@njit(cache=True, error_model="numpy")
def beyond_limit(magnitude, limit):
    """Is ``magnitude`` beyond ``limit`` by more than ``LIMIT_RTOL`` of it (a few ulps)? The one
    test by which acdrive limits a space vector's magnitude and counts the sample as limited
    (converter saturation, overmodulation, a current controller's saturation)."""
    return magnitude > limit + LIMIT_RTOL * limit


@njit(cache=True, error_model="numpy")
def clip_magnitude(x, limit):
    """(x, False) if |x| is not beyond ``limit`` (``beyond_limit``: a few ulps above it still
    count as at it), else (x scaled back along its own direction to magnitude ``limit``, True):
    a converter's voltage limit or a current command's limit on a space vector."""
    magnitude = np.abs(x)
    if not beyond_limit(magnitude, limit):
        return x, False
    return x * (limit / magnitude), True
