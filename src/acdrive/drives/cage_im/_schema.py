"""Scenario files of cage induction motor drives (``drive = "cage-im"``) -> ``IMDriveSetup``.

``scenarios.load_scenario`` hands a file that says ``drive = "cage-im"`` to
:func:`build_im_setup`. Every field is checked on load with ``acdrive._toml.Section``;
a bad one raises ``InputError("<path.to.field>", "<rule>")``, which the command prints as one line
(exit code 2) before any simulation or output. Schema (all tables optional except [reference];
units in the key names where not SI; defaults in brackets):

    drive = "cage-im", name, description, note (copied into summary.json),
    compare_controllers = { <label> = "<built-in controller>", ... }   one run per controller,
                  the label names its results (e.g. { icad = "paper-20", pi = "paper-pi" })
    [simulation]  duration [0.2], sample_time [2e-5: the paper's 50 kHz], substeps [4] (steps
                  of the integrator per held segment), integrator ("rk4" | "rk6": classical
                  fourth-order or Butcher's sixth-order Runge-Kutta, ``sim.INTEGRATORS``)
                  ["rk4"], log_every [every sample up to 100,000], metrics_from (s; start of the current-error window) [0]
    [machine]     machine ["delorenzo-im"; a built-in cage IM] or [machine.params]
                  (R_s, R_r, L_s, L_r, L_m, n_p): the nominal machine the controllers are
                  designed for; J [foc.J_ESTIMATE], viscous_friction, coulomb_friction [0],
                  load_torque | load_torque_profile (N m, active) [0],
                  brake | brake_profile (N m s/rad, eddy-current brake, torque k_b w) [0],
                  prescribed_speed_rad_s | prescribed_speed_rad_s_profile (the shaft held at
                  this speed; 0 = locked rotor; omit for a free shaft)
    [machine.perturbation]  R_s, R_r, L_s, L_r, L_m, J: factors on the simulated plant only [1]
                  (the controllers, the IFOC's estimates and the speed PI's design keep the
                  nominal machine)
    [design]      machine_file (a machine parameter file, e.g. written by ``acdrive identify``:
                  its [machine.params]) or [design.params]: the machine the controllers are
                  designed on (the IFOC's default estimates, the current-loop checks' controller
                  side); fields not given keep the scenario's machine, which stays the plant
    [inverter]    model ("averaged" | "switching") ["averaged"], dc_link_voltage |
                  dc_link_voltage_profile [310], pwm_frequency_hz [5000], dead_time_s and
                  device_drop_v (switching model only) [0]
    [current_control]  controller (``control._lti.BUILTIN``: fixed published transfer
                  functions; or "imc-pi": the PI designed on the design machine,
                  ``_current_design``, with bandwidth_rad_s; or "icad-proposed": the PI or PI x lag
                  ``analysis.propose_controller`` finds on the design machine's ICAD plant, with
                  [current_control.specs] the fields of ``analysis._design.Specifications``
                  [``PAPER_SPECS``]) ["paper-20"], discretisation
                  ("tustin" | "zoh") ["tustin"], prewarp_rad_s (Tustin only), anti_windup_gain [1]
    [reference]   mode ("current" | "speed-p" | "speed-pi" | "position"), and by mode:
                  current: waveform ("sine" | "step") ["sine"], amplitude_pk_a [1],
                  frequency_rad_s [300] (sine), phase_rad [0] (sine), start_s [0];
                  speed-p, speed-pi: speed_rad_s | speed_rad_s_profile;
                  position: position_rad | position_rad_profile (encoder angle)
    [foc]         (FOC modes) flux_reference_wb | flux_reference_wb_profile [foc.RATED_FLUX],
                  current_limit_pk_a (phase peak) [foc.CURRENT_LIMIT / sqrt(3/2)],
                  min_flux_wb [foc.MIN_FLUX], magnetised (start magnetised) [true]
    [foc.estimates]  R_r, L_r, L_m: the IFOC's parameter estimates [the nominal machine's]
    [speed_controller]  speed-p: k_p, tau_max [control._foc defaults]; speed-pi and position:
                  K_P, K_I (or bandwidth_rad_s: both roots of J s^2 + K_P s + K_I there), K_F,
                  tau_max [control.SpeedPI defaults]
    [position_controller]  (position) K_theta, w_max [control.PositionP defaults]
    [sensors]     encoder_counts_per_rev [0: ideal], encoder_offset_rad [0], speed_filter_tau_s [0]

Rules checked before the run, each naming its field:

- ``simulation.sample_time``: at most the PWM period 1 / ``inverter.pwm_frequency_hz`` and an
  integer fraction of it (the controller samples N times per carrier period; the inverter
  latches one command per period);
- ``inverter.dead_time_s``: shorter than half the switching period (each leg switches twice per
  carrier period, and every edge is delayed by the dead time), and only with the switching model;
- the controller's discretisation at the sample time (``control.discretise``: an unstable
  discretisation, a pre-warping frequency beyond the Nyquist frequency) and its anti-windup;
- the sampled current loop (``drives.cage_im._current_loop.current_loop_radius``: the compiled
  loop's own carrier-period map, plant (1) of the simulated machine, the discretised controller,
  the command latched for the carrier period) must be stable at every speed of the run, else ``simulation.sample_time`` (if the loop
  is unstable without the latch) or ``inverter.pwm_frequency_hz`` (the latch's delay) is refused;
- the sampled speed loop (``drives.cage_im._period.check_im_control_period``), as for the DFIM drive;
- the size of the run (log memory, integration steps), as for the DFIM drive.

A DC link too low for the flux reference at the requested speed is *not* refused: the drive then
runs in voltage saturation, which the results and summary.json report (events and
``voltage_check``).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from acdrive._frames import K_PEAK as SQRT_3_2
from acdrive._toml import Section as _Section
from acdrive._toml import (
    design_machine,
    log_every_of,
    machine_from,
    perturbed_plant,
    simulation_span,
)
from acdrive.control._current import StationaryCurrentController
from acdrive.control._foc import PositionP, SaturatedSpeedP, SpeedPI
from acdrive.control._lti import BUILTIN
from acdrive.control._speed import require_feedforward_fraction
from acdrive.drives.cage_im._current_design import (
    DESIGNED,
    PROPOSED,
    icad_proposal,
    imc_current_pi,
    specifications,
)
from acdrive.drives.cage_im._current_loop import current_loop_radius
from acdrive.drives.cage_im._period import check_im_control_period
from acdrive.drives.cage_im._setup import (
    INVERTER_MODELS,
    MODES,
    PAPER_DC_LINK,
    PAPER_PWM_FREQUENCY,
    PAPER_SAMPLE_TIME,
    WAVEFORMS,
    CurrentControl,
    CurrentReference,
    FOCSetup,
    IMDriveSetup,
    InverterSetup,
    Mechanics,
    PositionSetup,
    SensorSetup,
    SpeedPISetup,
    SpeedPSetup,
)
from acdrive.errors import (
    InputError,
    require_nonnegative,
    require_positive,
    require_safe_name,
)
from acdrive.machines._induction import IMParams
from acdrive.machines._record import electrical_fields
from acdrive.plant._sensors import MAX_COUNTS_PER_REV
from acdrive.sim._compiled import LOG_BUDGET_BYTES, MAX_SUBSTEPS, MAX_WORK
from acdrive.sim._integrators import INTEGRATORS

DRIVE = "cage-im"
#: the built-in machine of a machine table without ``name`` or ``[machine.params]``
DEFAULT_MACHINE = "delorenzo-im"
#: the fields of the ``[machine.params]`` table
PARAMS_FIELDS = electrical_fields(IMParams)
#: the factors of ``[machine.perturbation]``: the electrical parameters on the simulated machine,
#: J on the simulated shaft (the speed PI's bandwidth design keeps the nominal J)
PERTURBATION_FIELDS = ("R_s", "R_r", "L_s", "L_r", "L_m", "J")
#: relative tolerance of "the sample time divides the carrier period" (as plant._inverter)
_N_TOLERANCE = 1e-9
#: speeds (fractions of the run's top speed) at which the sampled current loop is checked
_CHECK_SPEEDS = np.linspace(0.0, 1.0, 5)


def _require_nothing(section: _Section, mode: str, why: str) -> None:
    """A table the mode does not use must not be given (its values would be ignored)."""
    if section.data:
        raise InputError(section.path, f"is not used in mode {mode} ({why}); remove it")


def _machine(sec: _Section) -> tuple[IMParams, IMParams, float]:
    """(nominal machine, simulated plant, factor on the plant's J)."""
    nominal = machine_from(
        sec, IMParams, PARAMS_FIELDS, DEFAULT_MACHINE,
        params_label="[machine.params]",
    )  # fmt: skip
    plant, factors = perturbed_plant(sec, nominal, PERTURBATION_FIELDS[:-1], ("J",))
    return nominal, plant, factors.get("J", 1.0)


def _mechanics(sec: _Section, machine: IMParams) -> Mechanics:
    default_j = machine.J if machine.J is not None else Mechanics().J
    brake = sec.constant_or_profile("brake", 0.0, rule=require_nonnegative)
    mech = Mechanics(
        J=sec.number("J", default_j, require_positive),
        B=sec.number("viscous_friction", 0.0, require_nonnegative),
        tau_c=sec.number("coulomb_friction", 0.0, require_nonnegative),
        load=sec.constant_or_profile("load_torque", 0.0),
        brake=brake,
        prescribed_speed=(
            sec.constant_or_profile("prescribed_speed_rad_s", 0.0)
            if sec.has("prescribed_speed_rad_s") or sec.has("prescribed_speed_rad_s_profile")
            else None
        ),
    )
    return mech


def _inverter(sec: _Section, sample_time: float) -> InverterSetup:
    model = sec.text("model", "averaged", choices=INVERTER_MODELS)
    dc = sec.constant_or_profile("dc_link_voltage", PAPER_DC_LINK, rule=require_positive)
    f_pwm = sec.number("pwm_frequency_hz", PAPER_PWM_FREQUENCY, require_positive)
    dead = sec.number("dead_time_s", 0.0, require_nonnegative)
    drop = sec.number("device_drop_v", 0.0, require_nonnegative)
    sec.done()
    period = 1.0 / f_pwm
    if sample_time > period * (1.0 + _N_TOLERANCE):
        raise InputError(
            "simulation.sample_time",
            f"must not be longer than the PWM period 1 / inverter.pwm_frequency_hz = {period:g} s "
            f"(the inverter applies one command per carrier period), got {sample_time:g} s",
        )
    ratio = period / sample_time
    n = round(ratio)
    if abs(ratio - n) > _N_TOLERANCE * ratio:
        raise InputError(
            "simulation.sample_time",
            f"must be the PWM period 1 / inverter.pwm_frequency_hz = {period:g} s divided by an "
            f"integer (the controller samples N times per carrier period), got {sample_time:g} s "
            f"(ratio {ratio:.6g})",
        )
    if dead >= 0.5 * period:
        raise InputError(
            "inverter.dead_time_s",
            f"must be shorter than half the switching period 1 / (2 pwm_frequency_hz) = "
            f"{0.5 * period:g} s (each leg switches twice per carrier period and every edge is "
            f"delayed by the dead time), got {dead:g} s",
        )
    if model == "averaged" and (dead > 0.0 or drop > 0.0):
        raise InputError(
            "inverter.dead_time_s" if dead > 0.0 else "inverter.device_drop_v",
            'applies to model = "switching" only (the averaged model is the ideal inverter\'s '
            "carrier-period average)",
        )
    return InverterSetup(model=model, dc_link=dc, f_pwm=f_pwm, dead_time=dead, device_drop=drop)


def _current_control(
    sec: _Section, machine: IMParams, field_name: str = "controller"
) -> CurrentControl:
    name = sec.text(field_name, "paper-20", choices=(*BUILTIN, DESIGNED, PROPOSED))
    method = sec.text("discretisation", "tustin", choices=("tustin", "zoh"))
    prewarp = (
        sec.number("prewarp_rad_s", None, require_positive) if sec.has("prewarp_rad_s") else None
    )
    gain = sec.number("anti_windup_gain", 1.0, require_nonnegative)
    bandwidth = gains = proposal = None
    if sec.has("specs") and name != PROPOSED:
        raise InputError(sec.field("specs"), f'applies to controller = "{PROPOSED}" only')
    if name == PROPOSED:
        table = sec.get("specs", {})
        if not isinstance(table, dict):
            raise InputError(sec.field("specs"), "must be a table of ICAD specifications")
        specs = specifications(table, sec.field("specs"))
        proposal = icad_proposal(machine, specs)  # on the design machine (estimates or nominal)
    if name == DESIGNED:
        if not sec.has("bandwidth_rad_s"):
            raise InputError(
                sec.field("bandwidth_rad_s"), f'is required with controller = "{DESIGNED}"'
            )
        bandwidth = sec.number("bandwidth_rad_s", None, require_positive)
        gains = imc_current_pi(machine, bandwidth)  # on the design machine (estimates or nominal)
    elif sec.has("bandwidth_rad_s"):
        raise InputError(sec.field("bandwidth_rad_s"), f'applies to controller = "{DESIGNED}" only '
                         "(a built-in controller is a fixed transfer function; the ICAD "
                         "proposal's bandwidth is specs.bandwidth_rad_s)")  # fmt: skip
    sec.done()
    return CurrentControl(controller=name, method=method, prewarp=prewarp, aw_gain=gain,
                          bandwidth=bandwidth, pi_gains=gains, proposal=proposal)  # fmt: skip


def _current_reference(sec: _Section) -> CurrentReference:
    waveform = sec.text("waveform", "sine", choices=WAVEFORMS)
    ref = CurrentReference(
        waveform=waveform,
        amplitude_pk=sec.number("amplitude_pk_a", 1.0),
        frequency=sec.number("frequency_rad_s", 300.0) if waveform == "sine" else 0.0,
        phase=sec.number("phase_rad", 0.0) if waveform == "sine" else 0.0,
        start=sec.number("start_s", 0.0, require_nonnegative),
    )
    if waveform == "step":
        for key in ("frequency_rad_s", "phase_rad"):
            if sec.has(key):
                raise InputError(sec.field(key), 'applies to waveform = "sine" only')
    return ref


def _foc(sec: _Section, machine: IMParams) -> FOCSetup:
    psi = sec.constant_or_profile(
        "flux_reference_wb", FOCSetup().psi_ref[1][0], rule=require_positive
    )
    i_max = sec.number("current_limit_pk_a", FOCSetup().i_max / SQRT_3_2, require_positive)
    psi_min = sec.number("min_flux_wb", FOCSetup().psi_min, require_nonnegative)
    magnetised = sec.boolean("magnetised", True)
    estimates = None
    if sec.has("estimates"):
        est = _Section(sec.get("estimates"), sec.field("estimates"))
        values = {
            k: est.number(k, getattr(machine, k), require_positive) for k in ("R_r", "L_r", "L_m")
        }
        est.done()
        try:
            estimates = dataclasses.replace(machine, **values)
        except InputError as exc:
            raise InputError(est.field(exc.field), exc.rule) from None
        if estimates.L_m > estimates.L_r:
            raise InputError(est.field("L_m"), "must not exceed L_r (L_r = L_m + rotor leakage)")
    sec.done()
    return FOCSetup(
        psi_ref=psi,
        i_max=i_max * SQRT_3_2,
        psi_min=psi_min,
        magnetised=magnetised,
        estimates=estimates,
    )


def _speed_p(sec: _Section) -> SpeedPSetup:
    d = SaturatedSpeedP.DEFAULTS
    out = SpeedPSetup(
        k_p=sec.number("k_p", d["k_p"], require_positive),
        tau_max=sec.number("tau_max", d["tau_max"], require_positive),
    )
    sec.done()
    return out


def _speed_pi(sec: _Section, J: float) -> SpeedPISetup:
    d = SpeedPI.DEFAULTS
    tau_max = sec.number("tau_max", d["tau_max"], require_positive)
    K_F = sec.number("K_F", d["K_F"], require_feedforward_fraction)
    if sec.has("bandwidth_rad_s"):
        for key in ("K_P", "K_I"):
            if sec.has(key):
                raise InputError(
                    sec.field("bandwidth_rad_s"),
                    f"give either bandwidth_rad_s or K_P / K_I, not both ({key})",
                )
        out = SpeedPISetup.design(
            J, sec.number("bandwidth_rad_s", 1.0, require_positive), K_F, tau_max
        )
    else:
        out = SpeedPISetup(
            K_P=sec.number("K_P", d["K_P"], require_nonnegative),
            K_I=sec.number("K_I", d["K_I"], require_nonnegative),
            K_F=K_F,
            tau_max=tau_max,
        )
    sec.done()
    return out


def _position(sec: _Section) -> PositionSetup:
    d = PositionP.DEFAULTS
    out = PositionSetup(
        K_theta=sec.number("K_theta", d["K_theta"], require_positive),
        w_max=sec.number("w_max", d["w_max"], require_positive),
    )
    sec.done()
    return out


def _compare(top: _Section) -> tuple[tuple[str, str], ...]:
    value = top.get("compare_controllers", {})
    if not isinstance(value, dict):
        raise InputError("compare_controllers", 'must be a table { label = "built-in controller" }')
    out = []
    for label, name in value.items():
        require_safe_name(f"compare_controllers.{label}", label)
        if not isinstance(name, str) or name not in BUILTIN:
            raise InputError(
                f"compare_controllers.{label}", f"must be one of {', '.join(BUILTIN)}, got {name!r}"
            )
        out.append((label, name))
    return tuple(out)


def _check_controller(setup: IMDriveSetup) -> None:
    """Discretisation, anti-windup and the sampled current loop of every run (module docstring)."""
    field_of = {
        "T_s": "simulation.sample_time",
        "prewarp": "current_control.prewarp_rad_s",
        "aw_gain": "current_control.anti_windup_gain",
        "method": "current_control.discretisation",
    }
    n = setup.carrier_samples
    top = setup.top_speed()
    for label, run in setup.runs():
        cc = run.current_control
        which = f"controller {cc.controller}" + (
            f" (run {label})" if setup.compare_controllers else ""
        )
        try:
            part = StationaryCurrentController(
                "current",
                cc.lti,
                run.sample_time,
                cc.method,
                cc.prewarp,
                v_dc_input=True,
                aw_gain=cc.aw_gain,
            )
        except InputError as exc:
            key = exc.field.split(".", 1)[-1]
            raise InputError(
                field_of.get(key, "current_control.controller"), f"{which}: {exc.rule}"
            ) from None
        for fraction in _CHECK_SPEEDS:
            w = float(fraction * top)
            rho = current_loop_radius(run.plant, w, part, n, setup.substeps)
            if rho < 1.0:
                continue
            alone = current_loop_radius(run.plant, w, part, 1, setup.substeps)
            hold = f"{n} samples (the {1.0 / run.inverter.f_pwm:g} s carrier period)"
            if alone >= 1.0:
                raise InputError(
                    "simulation.sample_time",
                    f"the sampled current loop with {which}, {cc.method} at {run.sample_time:g} s, "
                    f"is unstable at a shaft speed of {w:.4g} rad/s even without the PWM hold "
                    f"(spectral radius {alone:.6g} >= 1): shorten the sample time",
                )
            raise InputError(
                "inverter.pwm_frequency_hz",
                f"the sampled current loop with {which}, {cc.method} at {run.sample_time:g} s, "
                f"is unstable at a shaft speed of {w:.4g} rad/s when the inverter holds each "
                f"command for {hold} (spectral radius {rho:.6g} >= 1; {alone:.6g} without the "
                "hold): raise the PWM frequency",
            )


def _check_size(setup: IMDriveSetup) -> None:
    steps = setup.duration / setup.sample_time
    runs = max(len(setup.compare_controllers), 1)
    rows = math.ceil(steps / setup.log_every)
    log_bytes = rows * 40 * 8.0 * runs  # at most about 40 logged columns
    field = "simulation.duration"
    if log_bytes > LOG_BUDGET_BYTES:
        raise InputError(
            field,
            f"{setup.duration:g} s at {setup.sample_time:g} s is {steps:.3g} samples x {runs} "
            f"runs; the log would need about {log_bytes / 1024**3:.3g} GB (limit "
            f"{LOG_BUDGET_BYTES / 1024**3:g} GB): shorten it or raise simulation.log_every",
        )
    work = steps * setup.substeps * runs
    if work > MAX_WORK:
        raise InputError(
            field,
            f"{steps:.3g} samples x {setup.substeps} substeps x {runs} runs = {work:.3g} "
            f"integration steps (limit {MAX_WORK:.0e}): shorten simulation.duration",
        )


def build_im_setup(data: dict) -> IMDriveSetup:
    """Validate a parsed ``drive = "cage-im"`` scenario and build its ``IMDriveSetup``."""
    top = _Section(data, "")
    if top.text("drive") != DRIVE:
        raise InputError("drive", f'must be "{DRIVE}" for this loader')
    name = require_safe_name("name", top.get("name", "custom"))
    description = top.text("description", "")
    note = top.text("note", "")
    compare = _compare(top)

    sim = _Section(top.get("simulation", {}), "simulation")
    duration, sample_time = simulation_span(sim, 0.2, PAPER_SAMPLE_TIME)
    substeps = sim.integer("substeps", 4, maximum=MAX_SUBSTEPS)
    integrator = sim.text("integrator", "rk4", choices=tuple(INTEGRATORS))
    log_every = log_every_of(sim, duration, sample_time)
    metrics_from = sim.number("metrics_from", 0.0, require_nonnegative)
    if metrics_from >= duration:
        raise InputError(
            "simulation.metrics_from", f"must be before the end of the run ({duration:g} s)"
        )
    sim.done()

    msec = _Section(top.get("machine", {}), "machine")
    nominal, plant, J_factor = _machine(msec)
    if top.has("design"):  # the controllers designed on estimates, the plant the truth
        dsec = _Section(top.get("design"), "design")
        nominal, _ = design_machine(dsec, nominal, PARAMS_FIELDS)
        dsec.done()
    mechanics = _mechanics(msec, nominal)
    design_J = mechanics.J  # the speed PI's design inertia; the shaft's is perturbed
    if J_factor != 1.0:
        mechanics = dataclasses.replace(mechanics, J=design_J * J_factor)
    msec.done()
    inverter = _inverter(_Section(top.get("inverter", {}), "inverter"), sample_time)
    ccsec = _Section(top.get("current_control", {}), "current_control")
    if compare and ccsec.has("controller"):
        raise InputError(
            "current_control.controller", "give either it or compare_controllers, not both"
        )
    current_control = _current_control(ccsec, nominal)
    if compare:
        current_control = dataclasses.replace(current_control, controller=compare[0][1])

    if not top.has("reference"):
        raise InputError("reference", f"is required (its mode: {', '.join(MODES)})")
    ref = _Section(top.get("reference"), "reference")
    if not ref.has("mode"):
        raise InputError("reference.mode", f"is required ({', '.join(MODES)})")
    mode = ref.text("mode", choices=MODES)
    foc_sec = _Section(top.get("foc", {}), "foc")
    speed_sec = _Section(top.get("speed_controller", {}), "speed_controller")
    pos_sec = _Section(top.get("position_controller", {}), "position_controller")
    current_reference = speed_reference = position_reference = None
    foc, speed_p, speed_pi, position = FOCSetup(), SpeedPSetup(), SpeedPISetup(), PositionSetup()
    if mode == "current":
        current_reference = _current_reference(ref)
        _require_nothing(foc_sec, mode, "the current references are given")
        _require_nothing(speed_sec, mode, "no speed loop")
        _require_nothing(pos_sec, mode, "no position loop")
    else:
        if not mechanics.free:
            raise InputError(
                "machine.prescribed_speed_rad_s", f"mode {mode} controls the shaft: it must be free"
            )
        foc = _foc(foc_sec, nominal)
        if mode == "position":
            if not (ref.has("position_rad") or ref.has("position_rad_profile")):
                raise InputError("reference.position_rad_profile", "is required in mode position")
            position_reference = ref.constant_or_profile("position_rad", 0.0)
            position = _position(pos_sec)
        else:
            if not (ref.has("speed_rad_s") or ref.has("speed_rad_s_profile")):
                raise InputError("reference.speed_rad_s_profile", f"is required in mode {mode}")
            speed_reference = ref.constant_or_profile("speed_rad_s", 0.0)
            _require_nothing(pos_sec, mode, "no position loop")
        if mode == "speed-p":
            speed_p = _speed_p(speed_sec)
        else:
            speed_pi = _speed_pi(speed_sec, design_J)
    ref.done()

    sens = _Section(top.get("sensors", {}), "sensors")
    sensors = SensorSetup(
        counts_per_rev=float(
            sens.integer("encoder_counts_per_rev", 0, minimum=0, maximum=MAX_COUNTS_PER_REV)
        ),
        offset=sens.number("encoder_offset_rad", 0.0),
        speed_filter_tau=sens.number("speed_filter_tau_s", 0.0, require_nonnegative),
    )
    sens.done()
    top.done()
    setup = IMDriveSetup(
        mode=mode,
        machine=nominal,
        plant=plant,
        mechanics=mechanics,
        inverter=inverter,
        current_control=current_control,
        current_reference=current_reference,
        speed_reference=speed_reference,
        position_reference=position_reference,
        foc=foc,
        speed_p=speed_p,
        speed_pi=speed_pi,
        position=position,
        sensors=sensors,
        duration=duration,
        sample_time=sample_time,
        substeps=substeps,
        integrator=integrator,
        log_every=log_every,
        name=name,
        description=description,
        note=note,
        compare_controllers=compare,
        metrics_from=metrics_from,
    )
    _check_size(setup)
    _check_controller(setup)
    check_im_control_period(setup)
    return setup
