"""Pre-run checks of the DFIM drive's control period T_s (``simulation.sample_time``).

The controller sees the drive only at the samples, so T_s bounds what it can do. Each check
below compares T_s with one time scale of the drive; a sampled loop that is unstable is refused
before the run (``InputError``, exit 2), a period that is merely long for a loop is a warning that
``summary.json`` carries (``control_period_warnings``, appended to its ``warnings``).

* **Supply period** (the supply-frequency estimator, ``control._bodson.SupplyFrequencyEstimator``):
  it reads the grid voltage's phase advance 2 pi f T_s over one sample, which it can only tell
  apart from 2 pi f T_s - 2 pi below pi: f T_s >= 1/2 (the Nyquist frequency) aliases and is
  refused; fewer than :data:`SUPPLY_SAMPLES_WARN` samples per supply period is warned.
* **Speed loop** (Bodson (25)-(27)): the PI on the encoder's backward-difference speed (filtered
  by ``speed_filter_tau``) driving the shaft J dw/dt = tau held over each sample, torque taken
  as commanded. :func:`speed_loop_radius` gives the spectral radius of that sampled loop; >= 1 is
  refused. Its design puts both poles at s = -a_D,VEL; a_D,VEL T_s above
  :data:`SPEED_BANDWIDTH_T_S_WARN` (a sample rate less than about 12 times the loop's bandwidth,
  the upper end of the usual 0.15-0.5 range of Astrom and Wittenmark) is warned.
* **Rotor current loop** (current command, Bodson (45)-(50)): after the decoupling (46) the
  PI (47) with gains (49) sees sigma L_r di/dt = v - R_T i, held over each sample;
  :func:`current_loop_radius` >= 1 is refused. The design is the first-order loop
  a_D,CUR / (s + a_D,CUR) (50); the sampled loop's pole 1 - a_D,CUR T_s (R_T = 0) turns negative
  (the current rings at half the sample rate) above a_D,CUR T_s = 1, which is warned.
* **PWM period**: the averaged converter applies each command for one whole sample; a converter
  switching at ``converter_switching_frequency`` f_sw with f_sw T_s < 1 cannot (it switches less
  than once per command), which is warned.

The reduced loops leave out what the linearised whole drive (``analysis._drive_stability``)
keeps (the flux dynamics, the torque window); they decide only what they can: a loop already
unstable in its reduced sampled form will not be stabilised by the rest.
"""

from __future__ import annotations

import math

import numpy as np

from acdrive.errors import InputError
from acdrive.sim._setup import IMPLAUSIBLE_FACTOR, DriveSetup, MotorSetup

#: fewer samples than this per supply period are warned (the grid voltage then turns by more
#: than 18 degrees within one held command)
SUPPLY_SAMPLES_WARN = 20
#: a_D,VEL T_s above which the sampled speed loop is warned about
SPEED_BANDWIDTH_T_S_WARN = 0.5
#: a_D,CUR T_s above which the sampled rotor current loop is warned about
CURRENT_BANDWIDTH_T_S_WARN = 1.0
#: the sample time of the built-in DFIM scenarios [s]: a refused loop with a longer T_s names it
USUAL_SAMPLE_TIME = 200e-6
#: the same for the cage IM drive (the paper's 50 kHz)
USUAL_IM_SAMPLE_TIME = 20e-6


def speed_loop_radius(K_P: float, K_I: float, J: float, T_s: float, filter_tau: float) -> float:
    """Spectral radius of the sampled speed loop of Bodson (25)-(26) (module docstring).

    State [w_k, w_{k-1}, e_k, w_f,k-1]: with the torque u_k held over the sample the encoder's
    backward difference at t_k is (w_{k-1} + w_k) / 2; the filter w_f,k = w_f,k-1 + c (that -
    w_f,k-1), c = T_s / (tau + T_s); u_k = -K_P w_f,k + K_I e_k; e_k+1 = e_k - T_s w_f,k (the
    reference is zero: stability does not depend on it); w_k+1 = w_k + T_s u_k / J. With
    K_I = 0 (a proportional speed loop) the integral state is left out."""
    c = T_s / (filter_tau + T_s)

    def step(x):
        w, w_prev, e, wf_prev = x
        wf = wf_prev + c * (0.5 * (w + w_prev) - wf_prev)
        u = -K_P * wf + K_I * e
        return np.array([w + T_s * u / J, w, e - T_s * wf, wf])

    A = np.column_stack([step(col) for col in np.eye(4)])
    if K_I == 0.0:  # a P loop: the integral state acts on nothing and is left out
        A = np.delete(np.delete(A, 2, axis=0), 2, axis=1)
    return float(np.max(np.abs(np.linalg.eigvals(A))))


def current_loop_radius(
    sigma_L_r: float, R_T: float, K_PC: float, K_IC: float, T_s: float
) -> float:
    """Spectral radius of the sampled rotor current loop (module docstring): sigma L_r di/dt =
    v - R_T i held over each sample (i_k+1 = phi i_k + gamma v_k, phi = exp(-R_T T_s / (sigma
    L_r))), v_k = -K_PC i_k + K_IC I_k, I_k+1 = I_k - T_s i_k (reference zero)."""
    rate = R_T / sigma_L_r
    phi = math.exp(-rate * T_s)
    gamma = (1.0 - phi) / R_T if rate * T_s > 1e-12 else T_s / sigma_L_r
    if K_IC == 0.0:  # (49) with R_T = 0: no integral action, the integrator acts on nothing
        return abs(phi - gamma * K_PC)
    A = np.array([[phi - gamma * K_PC, gamma * K_IC], [-T_s, 1.0]])
    return float(np.max(np.abs(np.linalg.eigvals(A))))


def _modes(setup: DriveSetup) -> set[str]:
    return set(setup.compare_modes) or {m.controller.mode for m in setup.motors}


def _at_fault(setup: DriveSetup, k: int, key: str) -> str:
    """The field a refused loop names: the sample time if it is longer than the built-ins'; for
    the speed loop a design inertia J_d = K_P^2 / (4 K_I) (27) more than IMPLAUSIBLE_FACTOR from
    the machine's J (the loop gain is a J_d / J); else the controller's bandwidth."""
    if setup.sample_time > USUAL_SAMPLE_TIME:
        return "simulation.sample_time"
    motor = setup.motors[k]
    g = motor.controller.gains
    if key == "speed_bandwidth" and g.K_I > 0.0:
        ratio = g.K_P**2 / (4.0 * g.K_I) / motor.machine.J
        if not 1.0 / IMPLAUSIBLE_FACTOR <= ratio <= IMPLAUSIBLE_FACTOR:
            return f"motor[{k}].controller.design_inertia"
    return f"motor[{k}].controller.{key}"


def _speed_bandwidth(motor: MotorSetup) -> float:
    """a_D,VEL of the gains (27): K_P = 2 a J, K_I = a^2 J give a = 2 K_I / K_P."""
    g = motor.controller.gains
    return 2.0 * g.K_I / g.K_P


def _current_radius(motor: MotorSetup, T_s: float) -> float:
    p = motor.controller.params or motor.machine
    K_PC, K_IC = motor.controller.current_gains(motor.machine)
    return current_loop_radius(p.sigma * p.L_r, motor.controller.R_T, K_PC, K_IC, T_s)


def check_control_period(setup: DriveSetup) -> None:
    """Refuse a control period at which a sampled loop of the drive cannot work (module
    docstring): the supply frequency aliases, or the speed or current loop is unstable."""
    T_s = setup.sample_time
    f_max = float(np.max(setup.supply.frequency_hz[1]))
    if f_max * T_s >= 0.5:
        raise InputError(
            "simulation.sample_time",
            f"{T_s:g} s samples the {f_max:g} Hz supply {1.0 / (f_max * T_s):.3g} times per "
            "period; the supply-frequency estimator reads the phase advance 2 pi f T_s per sample "
            f"and aliases at f T_s >= 0.5 (here {f_max * T_s:.3g}): the sample time must be "
            f"shorter than 1 / (2 f) = {0.5 / f_max:.3g} s",
        )
    for k, motor in enumerate(setup.motors):
        g, a = motor.controller.gains, _speed_bandwidth(motor)
        rho = speed_loop_radius(
            g.K_P, g.K_I, motor.machine.J, T_s, motor.controller.speed_filter_tau
        )
        if rho >= 1.0:
            raise InputError(
                _at_fault(setup, k, "speed_bandwidth"),
                f"the sampled speed loop of motor[{k}] (Bodson (25)-(27), a_D,VEL = {a:.4g} "
                f"rad/s at T_s = {T_s:g} s: a_D,VEL T_s = {a * T_s:.3g}) is unstable (spectral "
                f"radius {rho:.4g} >= 1): shorten simulation.sample_time or lower "
                "controller.speed_bandwidth",
            )
        if "current" in _modes(setup):
            rho = _current_radius(motor, T_s)
            a_cur = motor.controller.current_bandwidth
            if rho >= 1.0:
                raise InputError(
                    _at_fault(setup, k, "current_bandwidth"),
                    f"the sampled rotor current loop of motor[{k}] (Bodson (45)-(50), a_D,CUR = "
                    f"{a_cur:.4g} rad/s at T_s = {T_s:g} s: a_D,CUR T_s = {a_cur * T_s:.3g}) is "
                    f"unstable (spectral radius {rho:.4g} >= 1): shorten simulation.sample_time "
                    "or lower controller.current_bandwidth",
                )


def control_period_warnings(setup: DriveSetup) -> list[str]:
    """One line per check of the module docstring that the control period passes only with a
    warning: the number, the limit and the rule."""
    T_s = setup.sample_time
    out = []
    f_max = float(np.max(setup.supply.frequency_hz[1]))
    if f_max * T_s > 1.0 / SUPPLY_SAMPLES_WARN:
        out.append(
            f"control period: {1.0 / (f_max * T_s):.3g} samples per period of the {f_max:g} Hz "
            f"supply (fewer than {SUPPLY_SAMPLES_WARN}: the grid voltage turns "
            f"{360.0 * f_max * T_s:.3g} degrees per held command, and the frequency estimator "
            "aliases at 2 samples per period)"
        )
    for k, motor in enumerate(setup.motors):
        g, a = motor.controller.gains, _speed_bandwidth(motor)
        if a * T_s > SPEED_BANDWIDTH_T_S_WARN:
            rho = speed_loop_radius(
                g.K_P, g.K_I, motor.machine.J, T_s, motor.controller.speed_filter_tau
            )
            out.append(
                f"control period: motor {k + 1}'s speed loop has a_D,VEL T_s = {a * T_s:.3g} "
                f"(a_D,VEL = {a:.4g} rad/s, T_s = {T_s:g} s), above "
                f"{SPEED_BANDWIDTH_T_S_WARN:g}: the sampled loop departs from its design (27) "
                f"(spectral radius {rho:.3g})"
            )
        a_cur = motor.controller.current_bandwidth
        if "current" in _modes(setup) and a_cur * T_s > CURRENT_BANDWIDTH_T_S_WARN:
            out.append(
                f"control period: motor {k + 1}'s rotor current loop has a_D,CUR T_s = "
                f"{a_cur * T_s:.3g} (a_D,CUR = {a_cur:.4g} rad/s, T_s = {T_s:g} s), above "
                f"{CURRENT_BANDWIDTH_T_S_WARN:g}: its sampled pole is negative, the current rings "
                f"at half the sample rate (spectral radius {_current_radius(motor, T_s):.3g})"
            )
        f_sw = motor.converter.switching_frequency
        if f_sw > 0.0 and f_sw * T_s < 1.0:
            out.append(
                f"control period: motor {k + 1}'s converter switches at {f_sw:g} Hz, a PWM period "
                f"1 / f_sw = {1.0 / f_sw:.3g} s longer than T_s = {T_s:g} s: the averaged "
                "converter applies every command for a whole sample, which a converter "
                "switching less than once per sample cannot"
            )
    return out


# --- the cage induction motor drive (``sim._im_drive``) ------------------------------------------
# Its sampled current loop, with the inverter's carrier latch, is checked exactly by
# ``scenarios._im_loader`` (``sim._im_drive.current_loop_radius``: refused when unstable), and
# the sample time must divide the PWM period; the speed loop is checked here like the DFIM's,
# and both loops' a T_s are warned above the DFIM's limits.


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
    checked exactly before the run (``scenarios._im_loader``)."""
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
