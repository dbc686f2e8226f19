"""Design formulas of the permanent-magnet synchronous motor drive: torque, maximum torque per
ampere (MTPA), field weakening at the voltage limit, and controller gains.

**Scaling.** Everything here is in acdrive's power-invariant space-vector scaling, the scaling of
the machine part (``machines._pmsm_part``): a balanced set of phase peak X has |x| = sqrt(3/2) X,
and the magnet's flux linkage enters as psi_f = sqrt(3/2) psi_m with psi_m the peak flux linkage
per phase (the ``psi_m`` parameter of the part and of ``PMSGParams``). In this scaling the torque
has no 3/2:

    tau = n_p (psi_f i_q + (L_d - L_q) i_d i_q)                                        (T)

which is the textbook amplitude-invariant form tau = (3/2) n_p (psi_m i_q' + (L_d - L_q) i_d'
i_q') with peak-scaled currents i' = i / sqrt(3/2) (Ugalde-Loo et al. (8)). Currents and fluxes
scale alike, so the MTPA and field-weakening formulas below read the same in both scalings, as
long as psi_f and the currents are taken in the same one.

**MTPA** (the current angle that gives the most torque per ampere; L_q >= L_d). With
i_d = -|i| sin(beta), i_q = |i| cos(beta), the torque (T) is n_p (psi_f |i| cos(beta) + (L_q - L_d)
|i|^2 sin(beta) cos(beta)), and d tau / d beta = n_p (-psi_f |i| sin(beta) + (L_q - L_d) |i|^2
cos(2 beta)) = 0 with |i| sin(beta) = -i_d and |i|^2 cos(2 beta) = |i|^2 - 2 i_d^2 gives
2 (L_q - L_d) i_d^2 - psi_f i_d - (L_q - L_d) |i|^2 = 0, whose root with i_d <= 0 is

    i_d = (psi_f - sqrt(psi_f^2 + 8 (L_q - L_d)^2 |i|^2)) / (4 (L_q - L_d))           (MTPA)
        = -2 (L_q - L_d) |i|^2 / (psi_f + sqrt(psi_f^2 + 8 (L_q - L_d)^2 |i|^2)),

the second form being the same number without the 0/0 of a surface machine (L_q = L_d: i_d = 0).
The MTPA torque grows monotonically with |i|, so a torque is turned into a current by bisection on
|i| (``mtpa_current``).

**Voltage limit.** In steady state v_dq = R_s i_dq + j w_e psi_dq with psi_dq = (L_d i_d + psi_f)
+ j L_q i_q, so |v| <= R_s |i| + |w_e| |psi_dq|. With the current limited to i_max and the flux to

    |psi_dq| <= psi_max = (m V_max - R_s i_max) / |w_e|                               (V)

the steady-state voltage stays within m V_max, where V_max = V_dc / sqrt(2) is the linear range
of space-vector modulation in this scaling (phase peak V_dc / sqrt(3), ``plant._converter``) and
m < 1 the voltage margin left to the current controllers for transients. (V) is the voltage
ellipse (w_e L_d i_d + w_e psi_f)^2 + (w_e L_q i_q)^2 <= (m V_max - R_s i_max)^2.

**Field weakening** (``operating_point``). The flux on the limit ellipse is written by its angle
phi, psi_d = psi_max cos(phi), psi_q = psi_max sin(phi), i.e. i_d = (psi_d - psi_f) / L_d,
i_q = psi_q / L_q, and the torque along it is

    tau(phi) = n_p psi_max sin(phi) (a + b cos(phi)),  a = psi_f / L_d,  b = psi_max (1/L_q - 1/L_d)

which rises from 0 at phi = 0 to its maximum (maximum torque per volt, MTPV) where
a cos(phi) + b cos(2 phi) = 0, i.e. cos(phi_mtpv) = 2 b / (a + sqrt(a^2 + 8 b^2)). The reference
is the point of that rising branch with the commanded torque (bisection on phi); if it needs more
current than i_max, the reference moves along the ellipse to its intersection with the current
circle |i| = i_max (bisection again: past the smallest-current point of the ellipse, |i| grows
with phi). Below ``voltage_bound_speed`` the MTPA point of full current already lies inside the
ellipse and is taken as it is; (V) is conservative, so that speed lies a little below the
machine's ``base_speed``, where the exact steady-state voltage of that point reaches m V_max.

**Gains.** Current PI per axis by the internal model: with the cross terms and the back-EMF fed
forward, each axis is L di/dt = v - R_s i, and K_P = alpha L, K_I = alpha R_s puts the PI's zero on
the plant pole, leaving the loop alpha / (s + alpha) (bandwidth alpha). Speed PI from J and a
bandwidth: ``control._speed.SpeedPIGains.design`` (Bodson (27)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from acdrive._frames import K_PEAK
from acdrive._jit import jit, python_from_python
from acdrive.errors import InputError, require_positive

#: bisection steps: the interval shrinks by 2^-60, below a double's resolution of any start value
BISECTION_STEPS = 60


@python_from_python
@jit
def magnet_flux(psi_m):
    """psi_f = sqrt(3/2) psi_m: the magnet flux linkage as a power-invariant space vector, from the
    peak flux linkage per phase (as ``machines._pmsm_part.magnet_flux``)."""
    return K_PEAK * psi_m


@jit
def torque(n_p, psi_f, L_d, L_q, i_d, i_q):
    """(T): tau = n_p (psi_f i_q + (L_d - L_q) i_d i_q), power-invariant (module docstring)."""
    return n_p * (psi_f * i_q + (L_d - L_q) * i_d * i_q)


@jit
def mtpa_d_current(psi_f, L_d, L_q, i_s):
    """(MTPA): the d current of the MTPA point of current magnitude ``i_s`` >= 0 (L_q >= L_d)."""
    dL = L_q - L_d
    return -2.0 * dL * i_s * i_s / (psi_f + np.sqrt(psi_f * psi_f + 8.0 * dL * dL * i_s * i_s))


@python_from_python
@jit
def mtpa_point(psi_f, L_d, L_q, i_s):
    """(i_d, i_q >= 0) of the MTPA point of current magnitude ``i_s``."""
    i_d = mtpa_d_current(psi_f, L_d, L_q, i_s)
    return i_d, np.sqrt(max(i_s * i_s - i_d * i_d, 0.0))


@python_from_python
@jit
def mtpa_torque(n_p, psi_f, L_d, L_q, i_s):
    """Torque of the MTPA point of current magnitude ``i_s``."""
    i_d, i_q = mtpa_point(psi_f, L_d, L_q, i_s)
    return torque(n_p, psi_f, L_d, L_q, i_d, i_q)


@jit
def mtpa_current(n_p, psi_f, L_d, L_q, tau, i_max):
    """Current magnitude of the MTPA point giving torque ``tau`` >= 0 (bisection on [0, i_max];
    i_max if even that is not enough)."""
    if mtpa_torque(n_p, psi_f, L_d, L_q, i_max) <= tau:
        return i_max
    lo, hi = 0.0, i_max
    for _ in range(BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        if mtpa_torque(n_p, psi_f, L_d, L_q, mid) < tau:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@python_from_python
@jit
def flux_magnitude(psi_f, L_d, L_q, i_d, i_q):
    """|psi_dq| = |(L_d i_d + psi_f) + j L_q i_q|."""
    return np.sqrt((L_d * i_d + psi_f) ** 2 + (L_q * i_q) ** 2)


@jit
def flux_limit(R_s, v_max, margin, i_max, w_e):
    """(V): psi_max = (margin v_max - R_s i_max) / |w_e| (inf at standstill)."""
    if w_e == 0.0:
        return np.inf
    return (margin * v_max - R_s * i_max) / abs(w_e)


@jit
def _on_ellipse(psi_f, L_d, L_q, psi_max, phi):
    """(i_d, i_q) of the flux psi_max e^{j phi} (module docstring, field weakening)."""
    return (psi_max * np.cos(phi) - psi_f) / L_d, psi_max * np.sin(phi) / L_q


@jit
def mtpv_angle(psi_f, L_d, L_q, psi_max):
    """phi of the maximum torque on the flux ellipse |psi_dq| = psi_max."""
    a = psi_f / L_d
    b = psi_max * (1.0 / L_q - 1.0 / L_d)
    c = 2.0 * b / (a + np.sqrt(a * a + 8.0 * b * b))
    return np.arccos(min(max(c, -1.0), 1.0))


@jit
def _min_current_angle(psi_f, L_d, L_q, psi_max):
    """phi of the smallest current on the flux ellipse (L_q >= L_d): d|i|^2/dphi has the sign of
    psi_f / L_d^2 + psi_max cos(phi) (1/L_q^2 - 1/L_d^2)."""
    k = 1.0 / (L_q * L_q) - 1.0 / (L_d * L_d)
    if k == 0.0:
        return 0.0
    c = -psi_f / (L_d * L_d * psi_max * k)
    return np.arccos(min(max(c, -1.0), 1.0))


#: flags of ``operating_point``
CURRENT_LIMITED, VOLTAGE_LIMITED, BEYOND_REACH = 1, 2, 4


@jit
def operating_point(n_p, psi_f, L_d, L_q, tau, i_max, psi_max):
    """Current reference (i_d, i_q) for torque ``tau`` with |i| <= i_max and |psi_dq| <= psi_max
    (module docstring: MTPA, then field weakening), and flags: ``CURRENT_LIMITED`` (the torque
    was reduced to what i_max gives), ``VOLTAGE_LIMITED`` (the point lies on the voltage limit),
    ``BEYOND_REACH`` (even the smallest current on the voltage limit exceeds i_max: the speed is
    beyond what the drive can hold; the smallest-current point is returned).

    A negative torque gives the mirror point (i_d, -i_q)."""
    sign = 1.0 if tau >= 0.0 else -1.0
    T = abs(tau)
    flags = 0
    i_s = mtpa_current(n_p, psi_f, L_d, L_q, T, i_max)
    i_d, i_q = mtpa_point(psi_f, L_d, L_q, i_s)
    if torque(n_p, psi_f, L_d, L_q, i_d, i_q) < T * (1.0 - 1e-12):
        flags |= CURRENT_LIMITED
        T = torque(n_p, psi_f, L_d, L_q, i_d, i_q)
    if flux_magnitude(psi_f, L_d, L_q, i_d, i_q) <= psi_max:
        return i_d, sign * i_q, flags
    flags |= VOLTAGE_LIMITED
    phi_top = mtpv_angle(psi_f, L_d, L_q, psi_max)
    if n_p * psi_max * np.sin(phi_top) * (psi_f / L_d + psi_max * (1.0 / L_q - 1.0 / L_d)
                                          * np.cos(phi_top)) > T:  # fmt: skip
        lo, hi = 0.0, phi_top  # the rising branch: torque increases with phi
        for _ in range(BISECTION_STEPS):
            mid = 0.5 * (lo + hi)
            a, b = _on_ellipse(psi_f, L_d, L_q, psi_max, mid)
            if torque(n_p, psi_f, L_d, L_q, a, b) < T:
                lo = mid
            else:
                hi = mid
        phi = 0.5 * (lo + hi)
    else:
        phi = phi_top
    i_d, i_q = _on_ellipse(psi_f, L_d, L_q, psi_max, phi)
    if i_d * i_d + i_q * i_q <= i_max * i_max:
        return i_d, sign * i_q, flags
    flags |= CURRENT_LIMITED
    phi_low = min(_min_current_angle(psi_f, L_d, L_q, psi_max), phi)
    a, b = _on_ellipse(psi_f, L_d, L_q, psi_max, phi_low)
    if a * a + b * b > i_max * i_max:
        return a, sign * b, flags | BEYOND_REACH
    lo, hi = phi_low, phi  # |i| grows with phi here
    for _ in range(BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        a, b = _on_ellipse(psi_f, L_d, L_q, psi_max, mid)
        if a * a + b * b < i_max * i_max:
            lo = mid
        else:
            hi = mid
    i_d, i_q = _on_ellipse(psi_f, L_d, L_q, psi_max, lo)
    return i_d, sign * i_q, flags


@jit
def available_torque(n_p, psi_f, L_d, L_q, i_max, psi_max):
    """The largest torque within |i| <= i_max and |psi_dq| <= psi_max (0 beyond reach)."""
    i_d, i_q, flags = operating_point(n_p, psi_f, L_d, L_q, np.inf, i_max, psi_max)
    if flags & BEYOND_REACH:
        return 0.0
    return torque(n_p, psi_f, L_d, L_q, i_d, i_q)


def voltage_bound_speed(R_s, L_d, L_q, psi_f, n_p, i_max, v_max, margin) -> float:
    """Mechanical speed [rad/s] up to which the drive's voltage bound (V) admits the MTPA point of
    full current i_max: |w_e| = (margin v_max - R_s i_max) / |psi_dq(MTPA at i_max)|, / n_p.
    Above it the references (``operating_point``) leave MTPA at full current. (V) bounds
    |R_s i + j w_e psi| by R_s |i| + |w_e| |psi|, so this speed lies below the machine's
    ``base_speed`` (equal only when i_dq and j psi_dq are parallel)."""
    i_d, i_q = mtpa_point(psi_f, L_d, L_q, i_max)
    return (margin * v_max - R_s * i_max) / float(flux_magnitude(psi_f, L_d, L_q, i_d, i_q)) / n_p


def base_speed(R_s, L_d, L_q, psi_f, n_p, i_max, v_max, margin) -> float:
    """The machine's base speed [rad/s, mechanical]: the speed at which the steady-state voltage
    v_dq = R_s i_dq + j w_e psi_dq (module docstring, "Voltage limit") of the MTPA point of full
    current i_max reaches margin v_max. With a = R_s i_dq and b = j psi_dq,
    |a + w_e b|^2 = (margin v_max)^2 is the quadratic |b|^2 w_e^2 + 2 Re(a conj b) w_e + |a|^2 -
    (margin v_max)^2 = 0 in w_e, whose positive root, / n_p, is returned. Requires
    R_s i_max < margin v_max (else no speed is reachable at full current)."""
    limit = margin * v_max
    if not R_s * i_max < limit:
        raise InputError(
            "i_max",
            f"the resistive drop R_s i_max = {R_s * i_max:g} V (i_max = {i_max:g} A) must be below "
            f"margin v_max = {limit:g} V for a base speed to exist",
        )
    i_d, i_q = mtpa_point(psi_f, L_d, L_q, i_max)
    a = R_s * complex(i_d, i_q)
    b = 1j * complex(L_d * i_d + psi_f, L_q * i_q)
    bb = abs(b) ** 2
    half_linear = (a * b.conjugate()).real
    w_e = (-half_linear + math.sqrt(half_linear**2 - bb * (abs(a) ** 2 - limit**2))) / bb
    return w_e / n_p


@dataclass(frozen=True)
class CurrentPIGains:
    """Per-axis current PI of the rotor-frame controller, internal-model design: K_P = alpha L,
    K_I = alpha R_s per axis (module docstring, "Gains")."""

    K_P_d: float
    K_P_q: float
    K_I_d: float
    K_I_q: float

    @classmethod
    def design(cls, R_s: float, L_d: float, L_q: float, bandwidth: float) -> CurrentPIGains:
        """K_P = alpha L_d / L_q, K_I = alpha R_s: closed loop alpha / (s + alpha) per axis."""
        a = require_positive("current_bandwidth", bandwidth)
        for name, value in (("R_s", R_s), ("L_d", L_d), ("L_q", L_q)):
            require_positive(name, value)
        return cls(K_P_d=a * L_d, K_P_q=a * L_q, K_I_d=a * R_s, K_I_q=a * R_s)


def require_salient_or_round(field: str, L_d: float, L_q: float) -> None:
    """MTPA and field weakening here assume L_q >= L_d (surface or interior magnets)."""
    if L_q < L_d:
        raise InputError(
            field, f"L_q must be >= L_d (surface or interior magnets), got L_d = {L_d:g} H, "
            f"L_q = {L_q:g} H"
        )  # fmt: skip


def mtpa_angle(psi_f: float, L_d: float, L_q: float, i_s: float) -> float:
    """The MTPA current angle beta [rad] from the q axis toward negative d (0 for L_d = L_q)."""
    i_d, i_q = mtpa_point(psi_f, L_d, L_q, i_s)
    return math.atan2(-i_d, i_q)
