"""Resolver read by a resolver-to-digital converter (RDC): the demodulated sine and cosine
envelopes with their errors, and the converter's type-II tracking loop giving angle and speed.

The excitation carrier is not simulated: the inputs of the loop are the envelopes after
synchronous demodulation (a converter samples them at the carrier's peak), each of unit nominal
amplitude. With the disc angle ``phi = theta + offset`` the resolver's angle is

    theta_r = phi + eccentricity sin(phi - eccentricity_angle)                              (R1)

(a rotor mounted off the stator's centre, or a runout, modulates the air gap once per
revolution: an angle error at the first harmonic of the mechanical angle, of amplitude
``eccentricity`` in radians), and the envelopes are

    S = (1 + imbalance) sin(theta_r) + offset_sin
    C = cos(theta_r + quadrature) + offset_cos                                              (R2)

(``imbalance`` the amplitude imbalance of the sine channel, ``quadrature`` the phase error of the
cosine channel against exact quadrature, the offsets in units of the nominal amplitude). A single
speed resolver is modelled: one electrical cycle per revolution.

Static angle errors of (R2), for small errors (derived from tan(theta_r + e) = S / C):
an imbalance ``a`` gives e = atan2((1 + a) sin th, cos th) - th = sum_k q^k sin(2 k th) / k with
q = a / (2 + a) (the series of log(1 - q exp(-2 j th)) taken apart), to first order
(a/2) sin 2 th: positive where the sine channel is the larger one; a quadrature error
``g`` gives e = (g/2)(1 - cos 2 th); an offset gives a first-harmonic error.

The tracking loop (the type-II loop of an RDC, F. M. Gardner, *Phaselock Techniques*, 3rd ed.,
Wiley 2005, ch. 2-3: a proportional-integral filter ahead of the integrator that is the
angle estimate) runs once per sample:

    e = S cos(theta_hat) - C sin(theta_hat)          (= sin(theta_r - theta_hat) without errors)
    I += K_i T_s e,   w_hat = I + K_p e,   theta_hat += T_s w_hat                           (R3)

Linearised (e ~ theta_r - theta_hat) the loop is theta_hat / theta_r = (K_p s + K_i) /
(s^2 + K_p s + K_i); matching s^2 + 2 zeta w_n s + w_n^2 gives the design

    K_p = 2 damping bandwidth,   K_i = bandwidth^2                                          (R4)

so ``bandwidth`` is the natural frequency w_n of the closed loop's poles and ``damping`` their
damping ratio. Two integrators in the loop make the error to a constant speed (an angle ramp)
zero in steady state. (R3) is the forward-Euler form of the continuous loop; its characteristic
polynomial z^2 - (2 - x - y) z + (1 - x), with x = 2 zeta w_n T_s and y = (w_n T_s)^2, has its
roots inside the unit circle iff x < 2 and 4 - 2 x - y > 0 (Jury), checked before each run; it
follows (R4)'s poles to O(w_n T_s)."""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from acdrive._jit import jit
from acdrive.core._parts import SampledPart
from acdrive.core._signals import Layout, real

PARAMS = Layout(
    real("pole_pairs", "", "pole pairs of the machine, for the electrical angle", "count"),
    real("offset", "rad", "mounting offset: resolver angle minus shaft angle", ""),
    real("imbalance", "", "amplitude imbalance a: the sine envelope is (1 + a) sin", ""),
    real("quadrature", "rad", "phase error of the cosine envelope against quadrature", ""),
    real("offset_sin", "", "offset of the sine envelope, per unit of its amplitude", ""),
    real("offset_cos", "", "offset of the cosine envelope, per unit of its amplitude", ""),
    real("eccentricity", "rad", "first-harmonic angle error amplitude (R1)", "nonnegative"),
    real("eccentricity_angle", "rad", "mechanical angle of the eccentricity (R1)", ""),
    real("bandwidth", "rad/s", "natural frequency w_n of the tracking loop's poles", "positive"),
    real("damping", "", "damping ratio of the tracking loop's poles", "positive"),
)
STATES = Layout(
    real("angle", "rad", "tracking loop's angle, in [0, 2 pi)"),
    real("integral", "rad/s", "tracking loop's integral term"),
)
INPUTS = Layout(real("theta", "rad", "shaft angle"))
OUTPUTS = Layout(
    real("theta", "rad", "angle of the tracking loop, in [0, 2 pi)"),
    real("theta_e", "rad", "electrical angle pole_pairs theta, in [0, 2 pi)"),
    real("w", "rad/s", "speed of the tracking loop"),
    real("error", "", "the loop's error signal e of (R3)"),
)
(_POLE_PAIRS, _OFFSET, _IMBALANCE, _QUADRATURE, _OFFSET_SIN, _OFFSET_COS, _ECCENTRICITY,
 _ECCENTRICITY_ANGLE, _BANDWIDTH, _DAMPING) = (PARAMS.slot(v.name) for v in PARAMS)  # fmt: skip
_ANGLE, _INTEGRAL = STATES.slot("angle"), STATES.slot("integral")
_THETA_IN = INPUTS.slot("theta")
_THETA, _THETA_E, _W, _ERROR = (OUTPUTS.slot(n) for n in ("theta", "theta_e", "w", "error"))
TWO_PI = 2.0 * np.pi


@jit
def wrap_angle(x):
    """``x`` modulo 2 pi, in [0, 2 pi)."""
    return x - TWO_PI * np.floor(x / TWO_PI)


@jit
def resolver_step(t, T_s, u, p, s, y):
    """The envelopes (R1)-(R2) at this sample and one step of the tracking loop (R3)-(R4)."""
    phi = u[_THETA_IN] + p[_OFFSET]
    theta_r = phi + p[_ECCENTRICITY] * np.sin(phi - p[_ECCENTRICITY_ANGLE])
    sine = (1.0 + p[_IMBALANCE]) * np.sin(theta_r) + p[_OFFSET_SIN]
    cosine = np.cos(theta_r + p[_QUADRATURE]) + p[_OFFSET_COS]
    angle = s[_ANGLE]
    error = sine * np.cos(angle) - cosine * np.sin(angle)
    w_n = p[_BANDWIDTH]
    s[_INTEGRAL] += w_n * w_n * T_s * error
    w = s[_INTEGRAL] + 2.0 * p[_DAMPING] * w_n * error
    y[_THETA] = angle
    y[_THETA_E] = wrap_angle(p[_POLE_PAIRS] * angle)
    y[_W] = w
    y[_ERROR] = error
    s[_ANGLE] = wrap_angle(angle + T_s * w)
    return 0


class Resolver(SampledPart):
    """Resolver envelopes with amplitude imbalance, quadrature error, offsets and eccentricity,
    read by an RDC's type-II tracking loop designed from its ``bandwidth`` and ``damping``;
    outputs the wrapped angle, electrical angle and speed."""

    SOURCE = ("resolver envelopes and the RDC's type-II tracking loop, Gardner, Phaselock "
              "Techniques, ch. 2-3 (plant._resolver.resolver_step)")  # fmt: skip

    PARAMS, STATES, INPUTS, OUTPUTS = PARAMS, STATES, INPUTS, OUTPUTS
    DEFAULTS: ClassVar[dict] = {"pole_pairs": 1.0, "offset": 0.0, "imbalance": 0.0,
                                "quadrature": 0.0, "offset_sin": 0.0, "offset_cos": 0.0,
                                "eccentricity": 0.0, "eccentricity_angle": 0.0,
                                "damping": 1.0 / np.sqrt(2.0)}  # fmt: skip
    step = resolver_step

    def check(self) -> None:
        from acdrive.errors import InputError

        imbalance = self.values["imbalance"]
        if not imbalance > -1.0:
            raise InputError(f"{self.name}.imbalance", "must be > -1 (the sine envelope's "
                             f"amplitude 1 + a positive), got {imbalance:g}")  # fmt: skip

    def check_run(self, sample_time: float) -> None:
        """The sampled loop (R3) is stable (Jury, see the module's docstring)."""
        from acdrive.errors import InputError

        w_n, zeta = self.values["bandwidth"], self.values["damping"]
        x, y = 2.0 * zeta * w_n * sample_time, (w_n * sample_time) ** 2
        if not (x < 2.0 and 4.0 - 2.0 * x - y > 0.0):
            raise InputError(f"{self.name}.bandwidth", f"{w_n:g} rad/s with damping {zeta:g} "
                             f"makes the sampled tracking loop unstable at a sample time of "
                             f"{sample_time:g} s (needs 2 zeta w_n T_s < 2 and "
                             f"4 - 4 zeta w_n T_s - (w_n T_s)^2 > 0)")  # fmt: skip
