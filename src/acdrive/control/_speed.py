"""Speed PI with feedforward and conditional integration (Bodson (25)-(27)); a speed reference
profile as a sampled part."""

from __future__ import annotations

from dataclasses import dataclass

from acdrive._jit import jit
from acdrive.core._parts import SampledPart
from acdrive.core._signals import Layout, real, table
from acdrive.core._tables import table_at
from acdrive.errors import InputError, require_finite, require_positive


def require_feedforward_fraction(field: str, value) -> float:
    """``value`` as float if it is a valid K_F of the speed PI (Bodson (25)), else InputError.

    K_F is the fraction of the proportional action applied to the reference: from 0 (I-P
    control, no closed-loop zero) to 1 (a plain PI, zero at -a_D,VEL / 2 with the design (27),
    the most overshoot); in between it moves the zero -K_I / (K_F K_P) = -a_D,VEL / (2 K_F),
    which is what the paper uses it for. Above 1 the reference would be amplified beyond the
    proportional gain itself, more overshoot than a plain PI; below 0 it would push against it.
    """
    value = require_finite(field, value)
    if not 0.0 <= value <= 1.0:
        raise InputError(
            field, f"the feedforward fraction of Bodson (25) must be between 0 (I-P control) and "
            f"1 (a plain PI), got {value:g}"
        )  # fmt: skip
    return value


@dataclass(frozen=True)
class SpeedPIGains:
    """K_P, K_I, K_F of Bodson (25); K_F checked by :func:`require_feedforward_fraction`."""

    K_P: float
    K_I: float
    K_F: float

    def __post_init__(self):
        object.__setattr__(self, "K_F", require_feedforward_fraction("K_F", self.K_F))

    @classmethod
    def design(cls, J: float, bandwidth: float, K_F: float = 2.0 / 3.0) -> SpeedPIGains:
        """Both roots of J s^2 + K_P s + K_I (27) at s = -a_D,VEL: K_P = 2 a J, K_I = a^2 J.

        ``bandwidth`` is a_D,VEL in rad/s; K_F = 2/3 is the value Bodson recommends after (27)
        to avoid overshoot; with these gains it leaves a small one,
        e^-4 / 3 = 0.61 % (:meth:`step_overshoot`); none for K_F <= 1/2.
        """
        J = require_positive("J", J)
        a = require_positive("speed_bandwidth", bandwidth)
        return cls(K_P=2.0 * a * J, K_I=a * a * J, K_F=K_F)

    def step_overshoot(self, J: float) -> float:
        """Overshoot (fraction of the step) of the speed after a small reference step, with an
        ideal torque and the integrator never clamped: the continuous loop of Bodson (25)-(27),
        w / w_ref = (K_F K_P s + K_I) / (J s^2 + K_P s + K_I).

        For the double root of :meth:`design` (K_P = 2 a J, K_I = a^2 J) the step response is
        1 - e^-x (1 - c x) with x = a t and c = 2 K_F - 1, whose peak above 1 is
        c e^-(1 + c)/c at x = (1 + c)/c if c > 0, and which never exceeds 1 if c <= 0
        (K_F <= 1/2). K_F = 1 gives e^-2 = 13.5 %, K_F = 2/3 gives e^-4 / 3 = 0.61 %. Other
        gains are evaluated numerically from the same transfer function."""
        import math

        J = require_positive("J", J)
        a = self.K_P / (2.0 * J)
        if math.isclose(self.K_I, a * a * J, rel_tol=1e-12):
            c = 2.0 * self.K_F - 1.0
            return c * math.exp(-(1.0 + c) / c) if c > 0.0 else 0.0
        import numpy as np
        from scipy import signal

        num, den = [self.K_F * self.K_P, self.K_I], [J, self.K_P, self.K_I]
        poles = np.roots(den)
        t = np.linspace(0.0, 20.0 / float(np.min(np.abs(poles.real))), 200_001)
        _, y = signal.step((num, den), T=t)
        return max(float(np.max(y)) - 1.0, 0.0)


@jit
def speed_pi(K_P, K_I, K_F, e_int, w_ref, w, tau_lo, tau_hi, T_s):
    """One sample of (25): returns (tau_com, new e_int, limited).

    tau_com = K_F K_P w_ref - K_P w + K_I e_int, clipped to [tau_lo, tau_hi]; the integrator
    e_int advances (forward Euler) only while the unclipped command is inside the limits.
    """
    tau = K_F * K_P * w_ref - K_P * w + K_I * e_int
    if tau > tau_hi:
        return tau_hi, e_int, True
    if tau < tau_lo:
        return tau_lo, e_int, True
    return tau, e_int + T_s * (w_ref - w), False


REFERENCE_PARAMS = Layout(table("w", "rad/s", "speed reference profile"))
REFERENCE_OUTPUTS = Layout(real("w_ref", "rad/s", "speed reference"))
_REF_TABLE = REFERENCE_PARAMS.table_start


@jit
def speed_reference_step(t, T_s, u, p, s, y):
    y[0] = table_at(p, _REF_TABLE, t)
    return 0


class SpeedReference(SampledPart):
    """A speed reference read from a piecewise-linear profile at each sample."""

    SOURCE = "speed reference profile (control._speed, core._tables.table_at)"

    PARAMS, OUTPUTS = REFERENCE_PARAMS, REFERENCE_OUTPUTS
    step = speed_reference_step
