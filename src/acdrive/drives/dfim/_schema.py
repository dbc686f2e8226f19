"""DFIM scenario files (TOML): validation and translation into a ``DriveSetup``.

Every field is checked on load; a bad one raises ``InputError("<path.to.field>", "<rule>")``.
Schema (all tables optional except [[motor]]; units in the key names where not SI):

    drive = "dfim" (or no drive: the default), name, description, note (copied into
    summary.json), compare_modes (e.g. ["voltage", "current"]: one run per mode)
    [simulation]  duration, sample_time, substeps, log_every
    [supply]      voltage_pk | voltage_pk_profile = [[t, V], ...], frequency_hz |
                  frequency_hz_profile, resistance, inductance,
                  phase_a_scale | phase_a_scale_profile, and the same for phases b and c (each
                  phase EMF's magnitude as a fraction of voltage_pk, 0 to 1; any of them gives an
                  unbalanced source, ``plant.UnbalancedSource``, e.g. a collapsed phase)
    [[motor]]     machine (built-in name) or [motor.params] (R_s, R_r, L_s, L_r, M, n_p, J),
                  viscous_friction, coulomb_friction, load_torque | load_torque_profile,
                  speed_reference_rpm = [[t, rpm], ...], initial_speed_rpm,
                  dc_link_voltage | dc_link_voltage_profile (V; a profile is fed from a DC source
                  and limits the applied rotor voltage; the controller's limit and the converter
                  loss use its value at t = 0),
                  encoder_counts_per_rev, encoder_offset, converter_dead_time (s),
                  converter_switching_frequency (Hz), converter_device_drop (V)
                  current_sensor_fault_time (s; current measurements fail from then on),
                  relay_forced_close_time (s; the stator relay closes then whatever the
                  synchroniser says: a mis-operation; needs controller.sync.enabled)
    [motor.perturbation]  R_s, R_r, L_s, L_r, M, J: factors on the simulated machine and shaft
                  only [1]; the controller keeps the nominal machine as its estimates (R_s to M in
                  its laws, sigma L_r in (49)) and the nominal J in (27) (Amezquita-Brooks et al.
                  sec. VIII's perturbed-plant experiment, for the DFIM drive)
    [motor.design]  machine_file (a machine parameter file, e.g. written by ``acdrive identify``:
                  its [machine.params], L_m read as M) or [motor.design.params]: the machine the
                  controller is designed on (its estimates, (27) with its J, (49)); fields not
                  given keep the scenario's machine, which stays the simulated plant
    [motor.controller]  mode ("voltage" | "current"), lossless_law (R_s = 0 form (39)),
                  current_bandwidth, R_T,
                  reactive_power_kp, reactive_power_ki | reactive_power_bandwidth, speed_bandwidth, design_inertia (J used in (27),
                  default: the machine's J), K_F, reactive_power,
                  stator_current_limit_pk, rotor_current_limit_pk, theta_adj, m_adj,
                  speed_filter_tau, frequency_filter_tau, min_stator_voltage_pk,
                  computation_delay_samples (0 or 1: the command applied one sample later)
    [motor.controller.sync]  enabled, gain, tolerance_magnitude, tolerance_phase_deg, hold_time

Physical pre-checks, made before any simulation (each an ``InputError`` naming the field):

- converter: a dead time needs a switching frequency, must be shorter than the switching period
  (t_d f_sw < 1), and the fundamental loss ``ConverterLosses.fundamental_loss(V_dc)`` must be
  smaller than the largest voltage the converter applies, ``max_voltage_magnitude(V_dc)``; with a
  DC-link profile, the loss (at the nominal voltage, as simulated) against the lowest voltage of
  the profile;
- integration step: see :func:`choose_substeps`. An omitted ``simulation.substeps`` is raised
  from its default of 4 to what the plant's fastest mode needs, with a one-line
  ``acdrive.errors.Notice``; a step no allowed number of substeps can make stable is refused;
- ``simulation.log_every`` must not exceed the number of control steps of the run;
- the control period against the supply period, the speed and current loops
  (``drives.dfim._period.check_control_period``: an aliasing frequency estimator or an unstable sampled
  loop is refused; a long but workable period is a warning in summary.json).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import warnings

import numpy as np

from acdrive._toml import Section as _Section
from acdrive._toml import (
    design_machine,
    log_every_of,
    machine_from,
    perturbed_plant,
    simulation_span,
)
from acdrive.control._speed import SpeedPIGains, require_feedforward_fraction
from acdrive.drives.dfim._period import check_control_period
from acdrive.drives.dfim._result import N_LOG
from acdrive.drives.dfim._setup import (
    RK4_STEP_LIMIT,
    ConverterLosses,
    DFIMController,
    DriveSetup,
    MotorSetup,
    Supply,
    Synchroniser,
    check_setup,
    fastest_electrical_rate,
)
from acdrive.errors import (
    InputError,
    Notice,
    require_between,
    require_nonnegative,
    require_positive,
    require_safe_name,
)
from acdrive.machines._dfim import DFIMParams
from acdrive.machines._dfim_part import LOSS_CURRENT_SCALE
from acdrive.machines._record import electrical_fields
from acdrive.plant._converter import max_voltage_magnitude
from acdrive.plant._mechanics import W_COULOMB
from acdrive.plant._sensors import MAX_COUNTS_PER_REV
from acdrive.sim._compiled import LOG_BUDGET_BYTES, MAX_SUBSTEPS, MAX_WORK

__all__ = ["KIND", "build_dfim_setup", "choose_substeps", "fastest_mode"]

#: the scenario's ``drive`` value of this drive (the default when a scenario names none)
KIND = "dfim"
#: the built-in machine of a motor table without ``machine`` or ``[motor.params]``
DEFAULT_MACHINE = "bodson-dfim"
#: the fields of a motor's ``[motor.params]`` table
PARAMS_FIELDS = (*electrical_fields(DFIMParams), "J")

RAD_S_PER_RPM = math.pi / 30.0
#: largest supply frequency [Hz]: the machine model (constant lumped inductances and
#: resistances, no skin effect, iron loss or winding capacitance) is one of power-frequency
#: machines; grids are 50/60 Hz, aircraft grids 360-800 Hz, so 1 kHz bounds what it describes
MAX_SUPPLY_HZ = 1000.0
#: most motors on one supply: each adds its parts to the one compiled loop, whose first compile
#: grows faster than the number of motors (measured on a loaded 2-core machine: 51 s for 4
#: motors, 489 s for 8); Bodson's experiments use one or two, the built-ins up to three. Four
#: keeps a first run near a minute.
MAX_MOTORS = 4
#: the factors of ``[motor.perturbation]`` (on the simulated machine and shaft only)
PERTURBATION_FIELDS = ("R_s", "R_r", "L_s", "L_r", "M", "J")
#: a machine parameter file names the magnetising inductance L_m (``acdrive identify``)
DESIGN_ALIASES = {"M": "L_m"}
#: sample time [s] and substeps per sample when the scenario does not say
DEFAULT_SAMPLE_TIME = 200e-6
DEFAULT_SUBSTEPS = 4


def _machine(section: _Section, index: int) -> DFIMParams:
    machine = machine_from(section, DFIMParams, PARAMS_FIELDS, DEFAULT_MACHINE)
    B = section.number("viscous_friction", 0.0, require_nonnegative)
    tau_c = section.number("coulomb_friction", 0.0, require_nonnegative)
    return dataclasses.replace(machine, B=B, tau_c=tau_c)


def _phase_tolerance(field: str, value) -> float:
    """A phase tolerance [degrees]: > 0 and at most 180 (a phase error is at most 180 degrees)."""
    value = require_positive(field, value)
    if value > 180.0:
        raise InputError(field, f"must be at most 180 degrees, got {value:g}")
    return value


def _sync(section: _Section) -> Synchroniser:
    sync = Synchroniser(
        enabled=section.boolean("enabled", False),
        gain=section.number("gain", 40.0, require_positive),
        tolerance_magnitude=section.number("tolerance_magnitude", 0.02, require_positive),
        tolerance_phase=section.number("tolerance_phase_deg", 2.0, _phase_tolerance)
        * math.pi
        / 180,
        hold_time=section.number("hold_time", 0.02, require_nonnegative),
    )
    section.done()
    return sync


def _reactive_power_gains(section: _Section) -> tuple[float, float]:
    """Q-loop gains: given directly, or from a bandwidth a_Q assuming a unity plant from Q command
    to Q (Bodson III-B): an integrator K_I = a_Q gives the closed loop a_Q / (s + a_Q)."""
    if section.has("reactive_power_bandwidth"):
        if section.has("reactive_power_kp") or section.has("reactive_power_ki"):
            raise InputError(section.field("reactive_power_bandwidth"),
                             "give either the bandwidth or reactive_power_kp / _ki, not both")  # fmt: skip
        return 0.0, section.number("reactive_power_bandwidth", 0.0, require_positive)
    return (section.number("reactive_power_kp", 0.0, require_nonnegative),
            section.number("reactive_power_ki", 0.0, require_nonnegative))  # fmt: skip


def _controller(section: _Section, machine: DFIMParams) -> DFIMController:
    mode = section.text("mode", "voltage", choices=("voltage", "current"))
    bandwidth = section.number("speed_bandwidth", 314.0, require_positive)
    K_F = section.number("K_F", 2.0 / 3.0, require_feedforward_fraction)
    design_inertia = section.number("design_inertia", machine.J, require_positive)
    q_kp, q_ki = _reactive_power_gains(section)
    gains = dataclasses.replace(SpeedPIGains.design(design_inertia, bandwidth), K_F=K_F)
    controller = DFIMController(
        gains=gains,
        mode=mode,
        current_bandwidth=section.number("current_bandwidth", 3142.0, require_positive),
        R_T=section.number("R_T", 1.0, require_nonnegative),
        reactive_power=section.number("reactive_power", 0.0),
        reactive_power_kp=q_kp,
        reactive_power_ki=q_ki,
        stator_current_limit_pk=section.number("stator_current_limit_pk", 6.0, require_positive),
        rotor_current_limit_pk=section.number("rotor_current_limit_pk", 6.0, require_positive),
        theta_adj=section.number("theta_adj", 0.0),
        m_adj=section.number("m_adj", 1.0, require_positive),
        speed_filter_tau=section.number("speed_filter_tau", 0.0, require_nonnegative),
        frequency_filter_tau=section.number("frequency_filter_tau", 0.01, require_nonnegative),
        min_stator_voltage_pk=section.number("min_stator_voltage_pk", 1.0, require_positive),
        sync=_sync(_Section(section.get("sync", {}), section.field("sync"))),
        lossless_law=section.boolean("lossless_law", False),
        computation_delay_samples=section.integer(
            "computation_delay_samples", 0, minimum=0, maximum=1
        ),
    )
    section.done()
    _check_gains(section, controller, machine, bandwidth, design_inertia)
    return controller


def _check_gains(
    section: _Section, controller: DFIMController, machine: DFIMParams, bandwidth: float,
    design_inertia: float,
) -> None:  # fmt: skip
    """The gains the design equations give must be numbers: K_P = 2 a J and K_I = a^2 J (27),
    K_P,C = sigma L_r a_C and K_I,C = R_T a_C (49) overflow for extreme bandwidths, inductances
    or R_T; the field named is the input that made the gain overflow (of a product, the factor
    farther from 1 in decades)."""
    K_PC, K_IC = controller.current_gains(machine)
    motor = section.path.rsplit(".", 1)[0]
    inertia = (
        section.field("design_inertia") if section.has("design_inertia") else f"{motor}.params.J"
    )

    def larger(*fields):  # the factor of a product farther from 1: it made the product overflow
        return max(fields, key=lambda f: abs(math.log10(f[1])) if f[1] > 0.0 else 0.0)[0]

    speed = larger((section.field("speed_bandwidth"), bandwidth), (inertia, design_inertia))
    current = section.field("current_bandwidth")
    gains = [
        ("K_P (27)", controller.gains.K_P, speed),
        ("K_I (27)", controller.gains.K_I, speed),
        ("K_P,C (49)", K_PC, larger((current, controller.current_bandwidth),
                                    (f"{motor}.params.L_r", machine.L_r - machine.M**2 / machine.L_s))),
        ("K_I,C (49)", K_IC, larger((current, controller.current_bandwidth),
                                    (section.field("R_T"), controller.R_T))),
    ]  # fmt: skip
    for name, value, field in gains:
        if not math.isfinite(value):
            raise InputError(field, f"gives the gain {name} = {value}: the design overflows")


def _converter(
    section: _Section, k: int, v_dc: float, v_min: float | None = None
) -> ConverterLosses:
    """The rotor converter's losses, refused unless the DC link ``v_dc`` can supply them.

    A dead time acts only through the switching frequency (loss V_dc t_d f_sw), so it needs one,
    and it must be shorter than the switching period; the fundamental loss must stay below the
    largest voltage the converter applies, or no rotor voltage at all would remain. With a DC-link
    profile the loss is simulated at the nominal ``v_dc`` and the converter applies at most
    ``v_min`` / sqrt(2) at the profile's lowest point ``v_min``.
    """
    field = f"motor[{k}].converter_"
    losses = ConverterLosses(
        dead_time=section.number("converter_dead_time", 0.0, require_nonnegative),
        switching_frequency=section.number(
            "converter_switching_frequency", 0.0, require_nonnegative
        ),
        device_drop=section.number("converter_device_drop", 0.0, require_nonnegative),
    )
    t_d, f_sw, drop = losses.dead_time, losses.switching_frequency, losses.device_drop
    if t_d > 0.0 and f_sw == 0.0:
        raise InputError(
            field + "switching_frequency",
            f"must be given (> 0 Hz) with converter_dead_time = {t_d:g} s: the dead-time loss "
            "is dc_link_voltage x dead time x switching frequency",
        )
    if t_d * f_sw >= 1.0:
        raise InputError(
            field + "dead_time",
            f"must be shorter than the switching period 1 / converter_switching_frequency = "
            f"{1.0 / f_sw:.3g} s, got {t_d:g} s (dead time x switching frequency = "
            f"{t_d * f_sw:.3g} >= 1)",
        )
    loss = float(losses.fundamental_loss(v_dc))
    lowest = v_dc if v_min is None else v_min
    v_max = float(max_voltage_magnitude(lowest))
    if not loss < v_max:
        dead_part = v_dc * t_d * f_sw
        link = (
            f"dc_link_voltage {v_dc:g} V"
            if v_min is None
            else f"dc_link_voltage_profile from {v_dc:g} V, lowest {v_min:g} V"
        )
        raise InputError(
            field + ("dead_time" if dead_part > drop else "device_drop"),
            f"the converter's fundamental loss sqrt(3/2) (4/pi) (V_dc t_d f_sw + V_drop) = "
            f"{loss:.4g} V must be smaller than the largest voltage it applies, V_dc / sqrt(2) = "
            f"{v_max:.4g} V ({link}, converter_dead_time {t_d:g} s, "
            f"converter_switching_frequency {f_sw:g} Hz, converter_device_drop {drop:g} V): "
            "the DC link cannot supply it",
        )
    return losses


def _supply_frequency(field: str, value) -> float:
    """A supply frequency [Hz]: > 0 and at most :data:`MAX_SUPPLY_HZ`."""
    value = require_positive(field, value)
    if value > MAX_SUPPLY_HZ:
        raise InputError(
            field, f"must be at most {MAX_SUPPLY_HZ:g} Hz (the lumped machine model describes "
            f"power-frequency supplies), got {value:g} Hz"
        )  # fmt: skip
    return value


def _phase_scales(section: _Section):
    """(k_a, k_b, k_c) profiles of the phase EMF magnitudes, or None if the scenario gives none
    (a balanced source). Each scale is a fraction of voltage_pk between 0 (the phase's EMF
    collapsed) and 1 (healthy), so voltage_pk stays the largest phase EMF the checks assume."""
    keys = [f"phase_{x}_scale" for x in "abc"]
    if not any(section.has(key) or section.has(f"{key}_profile") for key in keys):
        return None

    def fraction(field, value):
        return require_between(field, value, 0.0, 1.0)

    return tuple(section.constant_or_profile(key, 1.0, rule=fraction) for key in keys)


def _forced_close(section: _Section, duration: float) -> float:
    """relay_forced_close_time: inf if not given, else a time in [0, duration)."""
    if not section.has("relay_forced_close_time"):
        return math.inf
    value = section.number("relay_forced_close_time", 0.0, require_nonnegative)
    if value >= duration:
        raise InputError(
            section.field("relay_forced_close_time"),
            f"must be shorter than simulation.duration ({duration:g} s), got {value:g} s",
        )
    return value


def _flux_rate(machine: DFIMParams, R_s: float, L_s: float, R_r: float, w_el: float) -> float:
    """Largest |eigenvalue| [1/s] of the flux equations of ``machines._dfim_part`` at a fixed electrical
    rotor speed ``w_el``: d psi_s/dt = -R_s i_s, d psi_r/dt = -R_r i_r + j w_el psi_r in the
    stationary frame (the rotor-side mode turns at w_el there)."""
    return _flux_rate_of(float(machine.M), float(machine.L_r), R_s, L_s, R_r, w_el)


@functools.lru_cache(maxsize=4096)  # a batch's variants mostly share their machines
def _flux_rate_of(M: float, L_r: float, R_s: float, L_s: float, R_r: float, w_el: float) -> float:
    with np.errstate(all="ignore"):
        L = np.array([[L_s, M], [M, L_r]])
        try:
            A = -np.diag([R_s, R_r]) @ np.linalg.inv(L) + np.diag([0.0, 1j * w_el])
        except np.linalg.LinAlgError:
            return math.inf
        if not np.all(np.isfinite(A)):
            return math.inf
        return float(np.max(np.abs(np.linalg.eigvals(A))))


def fastest_mode(setup: DriveSetup) -> tuple[float, str, str]:
    """(rate [1/s], field, what): the fastest mode the RK4 integrator meets, an upper estimate.

    Per motor, over the scenario's speed range (the speed references and the initial speed; the
    rotor flux turns at n_p w in the stationary frame, so the range raises the estimate above
    synchronous speed):

    - the flux transients: the exact eigenvalues of the linear flux equations at electrical rotor
      speeds from 0 to the largest |n_p w|; the shared supply impedance adds n R_g, n L_g to the
      stator for the common mode of n motors (the differential modes see none); a converter loss
      V_loss acts on small rotor currents as a resistance of up to V_loss / LOSS_CURRENT_SCALE
      (the slope of its smoothed sign function at zero current, met when a synchronising motor
      starts de-energised), added to R_r;
    - the rotating phasor states: the supply's 2 pi f and the rotor's n_p w;
    - friction: (B + tau_c / W_COULOMB) / J, the slope of the smoothed Coulomb friction.

    The result is never below ``fastest_electrical_rate`` (which gives the divergence hint), so a
    run that still diverges is never told to use fewer substeps than were chosen. Not estimated:
    the electromechanical mode of a tiny inertia (the divergence hint names J). ``field`` names
    the input behind the largest term; ``what`` describes it.
    """
    supply = setup.supply
    n = len(setup.motors)
    w_g = 2.0 * math.pi * float(np.max(supply.frequency_hz[1]))
    modes = [(w_g, "supply.frequency_hz", "the supply rotation 2 pi f")]
    for k, motor in enumerate(setup.motors):
        modes += _motor_modes(k, motor, n, supply)
    modes = [(math.inf if math.isnan(r) else r, f, w) for r, f, w in modes]
    rate, field, what = max(modes, key=lambda mode: mode[0])  # the first of equal ones
    floor = fastest_electrical_rate(setup)
    if floor > rate or math.isnan(floor):
        k = max(range(n), key=lambda i: _decay(setup.motors[i].machine))
        rate = math.inf if math.isnan(floor) else floor
        field = (
            "supply.frequency_hz" if w_g > _decay(setup.motors[k].machine) else f"motor[{k}].params"
        )
        what = "the electrical mode R / (sigma L) + 2 pi f"
    return rate, field, what


def _decay(m: DFIMParams) -> float:
    return max(m.R_s / (m.sigma * m.L_s), m.R_r / (m.sigma * m.L_r))


def _motor_modes(k: int, motor: MotorSetup, n: int, supply: Supply) -> list:
    """The (rate, field, what) terms of :func:`fastest_mode` for motor ``k`` of ``n``."""
    m, conv = motor.machine, motor.converter
    speeds = [abs(motor.initial_speed), *np.abs(motor.speed_reference[1])]
    w_el = m.n_p * max(speeds)
    grid = np.linspace(0.0, w_el, 5) if math.isfinite(w_el) else [math.inf]
    stators = [(m.R_s + n * supply.resistance, m.L_s + n * supply.inductance)]
    if n > 1:  # differential modes of several motors see no supply impedance
        stators.append((m.R_s, m.L_s))

    def flux(R_s, L_s, R_r):
        return max(_flux_rate(m, R_s, L_s, R_r, float(w)) for w in grid)

    at_speed = "initial_speed_rpm" if speeds[0] >= max(speeds) else "speed_reference_rpm"
    modes = [
        (flux(m.R_s, m.L_s, m.R_r), f"motor[{k}].params",
         f"the flux transient of motor[{k}] (up to {w_el:.4g} rad/s electrical)"),
        (max(flux(R_s, L_s, m.R_r) for R_s, L_s in stators), "supply.resistance",
         f"the flux transient of motor[{k}] through the supply impedance"),
        (w_el, f"motor[{k}].{at_speed}", f"the rotor rotation n_p w of motor[{k}]"),
    ]  # fmt: skip
    loss = float(conv.fundamental_loss(motor.dc_link_voltage))
    if loss > 0.0:
        R_loss = m.R_r + loss / LOSS_CURRENT_SCALE
        dead = motor.dc_link_voltage * conv.dead_time * conv.switching_frequency
        modes.append(
            (max(flux(R_s, L_s, R_loss) for R_s, L_s in stators),
             f"motor[{k}].converter_" + ("dead_time" if dead > conv.device_drop else "device_drop"),
             f"the converter loss of motor[{k}] ({loss:.3g} V) near zero rotor current")
        )  # fmt: skip
    friction = "viscous_friction" if m.B > m.tau_c / W_COULOMB else "coulomb_friction"
    modes.append(
        ((m.B + m.tau_c / W_COULOMB) / m.J, f"motor[{k}].{friction}",
         f"the friction slope of motor[{k}] over its inertia J")
    )  # fmt: skip
    return modes


def choose_substeps(setup: DriveSetup, given: bool) -> int:
    """Substeps per sample for ``setup``: refuse, raise or keep, against its fastest mode.

    RK4 with step h = sample_time / substeps is stable for h |lambda| up to about 2.8; the
    integration step must satisfy h x rate <= RK4_STEP_LIMIT (2.5, ``drives.dfim._setup``) for the rate of
    :func:`fastest_mode`, i.e. substeps >= need = ceil(sample_time x rate / RK4_STEP_LIMIT).

    Decision (the issue allows refusing, or choosing enough substeps and saying so):

    - need > MAX_SUBSTEPS: refused (InputError, exit 2) naming the field at fault: no allowed
      number of substeps integrates it, so the run could only diverge or take hours;
    - simulation.substeps omitted and need > the default 4: the run goes ahead with ``need``
      substeps and a one-line ``Notice`` says which value was chosen and why. That is what a drive
      engineer who lengthened the sample time expects: the plant is integrated correctly and only
      the wall time grows (whether the *controller* works at that sample time is another
      question, checked before this by ``drives.dfim._period.check_control_period``);
    - simulation.substeps given: kept as written, even below ``need``. An explicit value is a
      deliberate choice (reproducing a run, studying the integrator), and the estimate is an upper
      one (the converter-loss slope, for one, only applies near zero rotor current), so overriding
      it could change a run that is fine; if it does diverge, the exit-3 message names the
      substeps needed.
    """
    rate, field, what = fastest_mode(setup)
    substeps = setup.substeps
    ratio = setup.sample_time * rate / RK4_STEP_LIMIT
    if not ratio <= MAX_SUBSTEPS:
        usual = DEFAULT_SAMPLE_TIME * rate / RK4_STEP_LIMIT <= MAX_SUBSTEPS
        if setup.sample_time > DEFAULT_SAMPLE_TIME and usual:
            field = "simulation.sample_time"  # the default sample time would do: it is at fault
        h_max = RK4_STEP_LIMIT / rate if rate > 0 else math.inf
        raise InputError(
            field,
            f"{what} is about {rate:.3g} 1/s: RK4 needs an integration step of at most "
            f"{h_max:.3g} s, i.e. "
            + (f"{ratio:.3g}" if math.isfinite(ratio) else "unboundedly many")
            + f" substeps of simulation.sample_time = {setup.sample_time:g} s (limit "
            f"{MAX_SUBSTEPS}): shorten simulation.sample_time to at most "
            f"{MAX_SUBSTEPS * h_max:.3g} s"
            + ("" if field == "simulation.sample_time" else f" or check {field}"),
        )
    need = max(math.ceil(ratio), 1)
    if given or need <= substeps:
        return substeps
    warnings.warn(
        Notice(
            f"simulation.substeps = {need} chosen (default {substeps} too few): "
            f"{what} is about {rate:.3g} 1/s, and RK4 needs an integration step "
            f"simulation.sample_time / substeps of at most {RK4_STEP_LIMIT / rate:.3g} s"
        ),
        stacklevel=3,
    )
    return need


def _check_size(duration, sample_time, substeps, log_every, n_motors, n_runs) -> None:
    """Refuse a run whose log would not fit the memory budget or that would take hours."""
    # name the field most likely at fault: a sample time shorter than the default, else duration
    field = "simulation.sample_time" if sample_time < 200e-6 else "simulation.duration"
    steps = duration / sample_time
    what = (
        f"{duration:g} s at a sample time of {sample_time:g} s is "
        + (f"{steps:.3g}" if math.isfinite(steps) else "more than 1e308")
        + " control steps"
        + (f" x {n_motors} motors" if n_motors > 1 else "")
        + (f" x {n_runs} runs (compare_modes)" if n_runs > 1 else "")
    )
    rows = math.ceil(steps / log_every) if math.isfinite(steps) else math.inf
    log_bytes = float(rows) * N_LOG * n_motors * 8.0 * n_runs
    if log_bytes > LOG_BUDGET_BYTES:
        raise InputError(
            field,
            f"{what}; its log would need "
            + (
                f"about {log_bytes / 1024**3:.3g} GB"
                if math.isfinite(log_bytes)
                else "unbounded memory"
            )
            + " (limit "
            f"{LOG_BUDGET_BYTES / 1024**3:g} GB): shorten simulation.duration, lengthen "
            f"simulation.sample_time or raise simulation.log_every",
        )
    work = steps * substeps * n_motors * n_runs
    if work > MAX_WORK:
        raise InputError(
            field,
            f"{what} with {substeps} substeps: {work:.3g} integration steps (limit "
            f"{MAX_WORK:.0e}, about half an hour): shorten simulation.duration, lengthen "
            f"simulation.sample_time or use fewer simulation.substeps",
        )


def build_dfim_setup(data: dict) -> DriveSetup:
    """Validate a parsed DFIM scenario (``drive = "dfim"`` or no ``drive``) and build its
    ``DriveSetup``."""
    top = _Section(data, "")
    if top.text("drive", KIND) != KIND:
        raise InputError("drive", f'must be "{KIND}" for this loader')
    name = require_safe_name("name", top.get("name", "custom"))  # becomes an output folder
    top.text("description", "")
    note = top.text("note", "")
    compare = top.get("compare_modes", [])
    if not isinstance(compare, list) or any(m not in ("voltage", "current") for m in compare):
        raise InputError("compare_modes", 'must be a list of "voltage" / "current"')
    if len(set(compare)) < len(compare):
        raise InputError(
            "compare_modes", f"must name each mode once (a mode run twice gives the same run), "
            f"got {compare}"
        )  # fmt: skip
    sim = _Section(top.get("simulation", {}), "simulation")
    duration, sample_time = simulation_span(sim, 1.0, DEFAULT_SAMPLE_TIME)
    substeps_given = sim.has("substeps")
    substeps = sim.integer("substeps", DEFAULT_SUBSTEPS, maximum=MAX_SUBSTEPS)
    log_every = log_every_of(sim, duration, sample_time)
    sim.done()

    sup = _Section(top.get("supply", {}), "supply")
    supply = Supply(
        voltage_pk=sup.constant_or_profile("voltage_pk", 11.1, rule=require_nonnegative),
        frequency_hz=sup.constant_or_profile("frequency_hz", 60.0, rule=_supply_frequency),
        resistance=sup.number("resistance", 0.0, require_nonnegative),
        inductance=sup.number("inductance", 0.0, require_nonnegative),
        phase_scales=_phase_scales(sup),
    )
    sup.done()
    if supply.voltage_pk[1][0] <= 0.0:
        raise InputError("supply.voltage_pk", "must be > 0 at t = 0 (the drive starts connected)")

    motors_data = top.get("motor")
    if not isinstance(motors_data, list) or not motors_data:
        raise InputError("motor", "at least one [[motor]] table is required")
    if len(motors_data) > MAX_MOTORS:
        raise InputError(
            "motor", f"at most {MAX_MOTORS} [[motor]] tables on one supply (each one lengthens "
            f"the compilation of the simulation loop), got {len(motors_data)}"
        )  # fmt: skip
    motors = []
    for k, raw in enumerate(motors_data):
        sec = _Section(raw, f"motor[{k}]")
        nominal = _machine(sec, k)
        machine, _ = perturbed_plant(sec, nominal, PERTURBATION_FIELDS)
        if not sec.has("speed_reference_rpm"):
            raise InputError(sec.field("speed_reference_rpm"), "is required")
        dc_link = sec.constant_or_profile("dc_link_voltage", 30.0, rule=require_positive)
        dc_link_profile = dc_link if sec.has("dc_link_voltage_profile") else None
        dc_link_voltage = float(dc_link[1][0])  # nominal: the voltage the drive starts with
        design = nominal
        if sec.has("design"):  # the controller designed on estimates, the plant the truth
            dsec = _Section(sec.get("design"), sec.field("design"))
            design, _ = design_machine(dsec, nominal, PARAMS_FIELDS, DESIGN_ALIASES)
            dsec.done()
        controller = _controller(
            _Section(sec.get("controller", {}), sec.field("controller")), design
        )
        if machine is not design:  # the controller keeps its design machine as its estimates
            controller = dataclasses.replace(controller, params=design)
        motor = MotorSetup(
            machine=machine,
            controller=controller,
            speed_reference=sec.profile("speed_reference_rpm", RAD_S_PER_RPM),
            load_torque=sec.constant_or_profile("load_torque", 0.0),
            dc_link_voltage=dc_link_voltage,
            dc_link_profile=dc_link_profile,
            converter=_converter(
                sec, k, dc_link_voltage, None if dc_link_profile is None else float(min(dc_link[1]))
            ),
            encoder_counts_per_rev=float(
                sec.integer("encoder_counts_per_rev", 0, minimum=0, maximum=MAX_COUNTS_PER_REV)
            ),
            encoder_offset=sec.number("encoder_offset", 0.0),
            initial_speed=sec.number("initial_speed_rpm", 0.0) * RAD_S_PER_RPM,
            current_sensor_fault_time=sec.number(
                "current_sensor_fault_time", math.inf, require_nonnegative
            )
            if sec.has("current_sensor_fault_time")
            else math.inf,
            relay_forced_close_time=_forced_close(sec, duration),
        )
        if motor.relay_forced_close_time < math.inf and not motor.controller.sync.enabled:
            raise InputError(
                sec.field("relay_forced_close_time"),
                "needs controller.sync.enabled = true (without synchronisation the relay is "
                "closed from the start)",
            )
        sec.done()
        motors.append(motor)
    top.done()
    _check_size(duration, sample_time, substeps, log_every, len(motors), max(len(compare), 1))
    setup = DriveSetup(
        motors=tuple(motors),
        supply=supply,
        duration=duration,
        sample_time=sample_time,
        substeps=substeps,
        log_every=log_every,
        name=name,
        compare_modes=tuple(compare),
        note=note,
    )
    check_setup(setup)
    check_control_period(setup)
    chosen = choose_substeps(setup, substeps_given)
    if chosen != substeps:
        _check_size(duration, sample_time, chosen, log_every, len(motors), max(len(compare), 1))
        setup = dataclasses.replace(setup, substeps=chosen)
    return setup
