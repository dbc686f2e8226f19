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
  ``drives._period.current_loop_radius`` >= 1 is refused. The design is the first-order loop
  a_D,CUR / (s + a_D,CUR) (50); the sampled loop's pole 1 - a_D,CUR T_s (R_T = 0) turns negative
  (the current rings at half the sample rate) above a_D,CUR T_s = 1, which is warned.
* **PWM period**: the averaged converter applies each command for one whole sample; a converter
  switching at ``converter_switching_frequency`` f_sw with f_sw T_s < 1 cannot (it switches less
  than once per command), which is warned.

The reduced loops leave out what the linearised whole drive (``drives.dfim._linearisation._stability``)
keeps (the flux dynamics, the torque window); they decide only what they can: a loop already
unstable in its reduced sampled form will not be stabilised by the rest.
"""

from __future__ import annotations

import numpy as np

from acdrive.drives._period import (
    CURRENT_BANDWIDTH_T_S_WARN,
    SPEED_BANDWIDTH_T_S_WARN,
    current_loop_radius,
    speed_loop_radius,
)
from acdrive.drives.dfim._setup import IMPLAUSIBLE_FACTOR, DriveSetup, MotorSetup
from acdrive.errors import InputError

#: fewer samples than this per supply period are warned (the grid voltage then turns by more
#: than 18 degrees within one held command)
SUPPLY_SAMPLES_WARN = 20
#: the sample time of the built-in DFIM scenarios [s]: a refused loop with a longer T_s names it
USUAL_SAMPLE_TIME = 200e-6


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
