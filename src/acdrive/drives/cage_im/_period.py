"""Pre-run checks of the cage induction motor drive's control period T_s.

Its sampled current loop, with the inverter's carrier latch, is checked exactly by the scenario
loader (``drives.cage_im._schema`` with the compiled loop's carrier-period map of
``drives.cage_im._current_loop``: refused when unstable), and the
sample time must divide the PWM period; the speed loop is checked here like the DFIM's
(``drives._period.speed_loop_radius``), and both loops' a T_s are warned above the same limits.
"""

from __future__ import annotations

import math

import numpy as np

from acdrive.drives._period import (
    CURRENT_BANDWIDTH_T_S_WARN,
    SPEED_BANDWIDTH_T_S_WARN,
    speed_loop_radius,
)
from acdrive.errors import InputError

#: the sample time of the built-in cage-IM scenarios [s] (the paper's 50 kHz): a refused loop
#: with a longer T_s names it
USUAL_IM_SAMPLE_TIME = 20e-6


def _im_speed_gains(setup) -> tuple[float, float, str] | None:
    """(K_P, K_I, field) of the IM drive's speed loop, None without one (current mode)."""
    if setup.mode == "speed-p":
        return setup.speed_p.k_p, 0.0, "speed_controller.k_p"
    if setup.mode in ("speed-pi", "position"):
        return setup.speed_pi.K_P, setup.speed_pi.K_I, "speed_controller.K_P"
    return None


def _im_speed_bandwidth(K_P: float, K_I: float, J: float) -> float:
    """The speed loop's design root: a = 2 K_I / K_P of J s^2 + K_P s + K_I with both roots at
    -a (``SpeedPISetup.design``), or K_P / J for a proportional loop."""
    return 2.0 * K_I / K_P if K_I > 0.0 and K_P > 0.0 else K_P / J


def check_im_control_period(setup) -> None:
    """Refuse an IM drive whose sampled speed loop (as :func:`speed_loop_radius`, the torque
    taken as commanded through the fast current loop) is unstable."""
    gains = _im_speed_gains(setup)
    if gains is None:
        return
    K_P, K_I, key = gains
    T_s, J = setup.sample_time, setup.mechanics.J
    rho = speed_loop_radius(K_P, K_I, J, T_s, setup.sensors.speed_filter_tau)
    if rho >= 1.0:
        a = _im_speed_bandwidth(K_P, K_I, J)
        raise InputError(
            key if setup.sample_time <= USUAL_IM_SAMPLE_TIME else "simulation.sample_time",
            f"the sampled speed loop (K_P = {K_P:.4g}, K_I = {K_I:.4g}, J = {J:.4g} kg m^2: "
            f"a = {a:.4g} rad/s, a T_s = {a * T_s:.3g} at T_s = {T_s:g} s) is unstable "
            f"(spectral radius {rho:.4g} >= 1): shorten simulation.sample_time or lower the "
            "speed controller's gains",
        )


def im_current_bandwidth(setup) -> float:
    """The -3 dB bandwidth [rad/s] of the IM drive's current loop as designed: the continuous
    controller on the nominal machine's stator-current plant (Amezquita-Brooks (1)-(4)) at
    standstill, channel alpha, |T(j w)| = |L / (1 + L)| first below 1/sqrt(2) on a logarithmic
    grid of 1 to 1e7 rad/s (inf if never)."""
    from acdrive.machines._induction import stator_current_ss

    A, B, C, D = stator_current_ss(setup.machine, 0.0)
    w = np.geomspace(1.0, 1e7, 1401)
    k = setup.current_control.lti.freqresp(w)
    eye = np.eye(A.shape[0])
    g = np.array([(C @ np.linalg.solve(1j * x * eye - A, B) + D)[0, 0] for x in w])
    loop = g * k
    below = np.abs(loop / (1.0 + loop)) < 1.0 / math.sqrt(2.0)
    return float(w[np.argmax(below)]) if below.any() else math.inf


def im_control_period_warnings(setup) -> list[str]:
    """The IM drive's control-period warnings: a speed loop with a T_s above
    :data:`SPEED_BANDWIDTH_T_S_WARN`, a current loop with a_C T_s above
    :data:`CURRENT_BANDWIDTH_T_S_WARN` (a_C: :func:`im_current_bandwidth`). The PWM period needs
    none: the sample time must divide it, and the current loop with the inverter's latch is
    checked exactly before the run (``drives.cage_im._schema``)."""
    out = []
    T_s = setup.sample_time
    a_cur = im_current_bandwidth(setup)
    if a_cur * T_s > CURRENT_BANDWIDTH_T_S_WARN:
        out.append(
            f"control period: the current loop ({setup.current_control.controller}) has "
            f"a_C T_s = {a_cur * T_s:.3g} (-3 dB bandwidth a_C = {a_cur:.4g} rad/s as designed, "
            f"T_s = {T_s:g} s), above {CURRENT_BANDWIDTH_T_S_WARN:g}: the sampled loop no "
            "longer behaves as designed"
        )
    gains = _im_speed_gains(setup)
    if gains is None:
        return out
    K_P, K_I, _ = gains
    J = setup.mechanics.J
    a = _im_speed_bandwidth(K_P, K_I, J)
    if a * T_s > SPEED_BANDWIDTH_T_S_WARN:
        rho = speed_loop_radius(K_P, K_I, J, T_s, setup.sensors.speed_filter_tau)
        out.append(
            f"control period: the speed loop has a T_s = {a * T_s:.3g} (a = {a:.4g} rad/s, "
            f"T_s = {T_s:g} s), above {SPEED_BANDWIDTH_T_S_WARN:g}: the sampled loop departs "
            f"from its design (spectral radius {rho:.3g})"
        )
    return out
