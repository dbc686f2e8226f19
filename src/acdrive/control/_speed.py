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

        ``bandwidth`` is a_D,VEL in rad/s; K_F = 2/3 is the paper's no-overshoot choice.
        """
        J = require_positive("J", J)
        a = require_positive("speed_bandwidth", bandwidth)
        return cls(K_P=2.0 * a * J, K_I=a * a * J, K_F=K_F)


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

    PARAMS, OUTPUTS = REFERENCE_PARAMS, REFERENCE_OUTPUTS
    step = speed_reference_step
