"""Scenario tables of the PM speed drive (``drive = "pm"``) -> ``PMDriveSetup``.

Every field is read through ``acdrive._toml.Section``: an unknown key, a wrong type or a
broken rule raises ``InputError("<table>.<key>", "<rule>")`` (one line, before any work). Schema
(defaults in brackets; units in the key names where not SI):

    drive = "pm", name, description
    [machine]     machine (a name of ``MACHINES``) or [machine.params] (R_s, L_d, L_q, psi_m,
                  n_p, J: ``machines.PMSGParams``, psi_m the peak flux per phase), not both;
                  J (rotor and load) [the machine's J], viscous_friction [0],
                  load_torque | load_torque_profile (N m) [0]
    [machine.perturbation]  R_s, L_d, L_q, psi_m, J: factors on the simulated machine and shaft
                  only [1] (the controllers keep the scenario's machine and J)
    [design]      machine_file (a machine parameter file: its [machine.params]) or
                  [design.params] (R_s, L_d, L_q, psi_m, n_p, J): the machine the controllers are
                  designed on (the current PI, the MTPA and field-weakening references, the
                  speed PI from its J); fields not given keep the scenario's, which stays the plant
    [converter]   model ("averaged" | "switching") ["averaged"], dc_link_voltage,
                  pwm_frequency_hz (switching only)
    [control]     current_limit_pk_a (phase peak), current_bandwidth_rad_s,
                  speed_bandwidth_rad_s, K_F [1], voltage_margin [0.9], tau_max [MTPA torque at
                  the current limit]
    [reference]   speed_rad_s | speed_rad_s_profile
    [sensors]     encoder_counts_per_rev [0: ideal], encoder_offset_rad [0]
    [simulation]  duration, sample_time, substeps [4], log_every [every sample up to 100,000]

A current-step scenario (``kind = "current-step"``: seed 001's PMSG current subsystem under
ICAD's controller, ``drives.pm._icad_step``) has instead:

    drive = "pm", kind = "current-step", name, description
    [machine]          machine or [machine.params], as above
    [operating_point]  electrical_frequency_hz (the constant electrical speed is 2 pi f)
    [control]          bandwidth_rad_s (a of ICAD's k = a (L_d s + R_s) / s)
    [reference]        d_step_pk_a (phase peak), step_time
    [comparison]       frequencies_rad_s (a list: where the coupling is compared with (10))
    [simulation]       duration, sample_time, substeps [2]

Built-in scenarios are the TOML files in ``scenarios/`` next to this module (``builtin_names``,
``builtin``).
"""

from __future__ import annotations

import math
from pathlib import Path

from acdrive._toml import Section, design_machine, parse_toml, perturbed_plant
from acdrive.drives.pm._icad_step import CurrentStepSetup
from acdrive.drives.pm._machines import BLY171D, IPMSM_2KW2
from acdrive.drives.pm._setup import CONVERTERS, PMDriveSetup
from acdrive.errors import InputError, require_nonnegative, require_positive
from acdrive.machines._pmsm import PMSG_2MW, PMSGParams
from acdrive.machines._record import electrical_fields
from acdrive.sim._log_plan import default_log_every
from acdrive.plant._sensors import check_counts_per_rev

DRIVE = "pm"
#: machines a scenario may name (``drives.pm._machines`` and seed 001's PMSG)
MACHINES = {"bly171d": BLY171D, "ipmsm-2.2kw": IPMSM_2KW2, "pmsg-2mw": PMSG_2MW}
MACHINE_FIELDS = (*electrical_fields(PMSGParams), "J")
#: the factors of ``[machine.perturbation]`` on the simulated machine (J: on the simulated shaft)
PERTURBATION_FIELDS = ("R_s", "L_d", "L_q", "psi_m")
SCENARIO_DIR = Path(__file__).with_name("scenarios")
#: the scenario kinds (top-level ``kind``): the speed drive and the current-step run
KINDS = ("speed", "current-step")


def _profile_points(section: Section, key: str, default):
    """A number or a list of [t, value] points from ``key`` or ``key_profile`` (not both)."""
    if section.has(key) and section.has(f"{key}_profile"):
        raise InputError(section.field(key), f"give either {key} or {key}_profile, not both")
    if section.has(f"{key}_profile"):
        times, values = section.profile(f"{key}_profile")
        return [[float(a), float(b)] for a, b in zip(times, values, strict=True)]
    if default is None and not section.has(key):
        raise InputError(section.field(key), f"is required (or {key}_profile)")
    return section.number(key, default)


def _machine(section: Section) -> PMSGParams:
    if section.has("machine") and section.has("params"):
        raise InputError(section.field("machine"), "give either machine or [machine.params]")
    if section.has("params"):
        params = Section(section.get("params"), section.field("params"))
        values = {k: params.get(k) for k in MACHINE_FIELDS}
        params.done()
        missing = [k for k in MACHINE_FIELDS[:5] if values[k] is None]
        if missing:
            raise InputError(params.field(missing[0]), "is required")
        try:
            return PMSGParams(**values)
        except InputError as exc:
            raise InputError(params.field(exc.field), exc.rule) from None
    return MACHINES[section.text("machine", None, choices=sorted(MACHINES))]


def load(data: dict) -> PMDriveSetup | CurrentStepSetup:
    """The validated setup of a scenario table (module docstring)."""
    top = Section(data, "")
    if top.text("drive", DRIVE) != DRIVE:
        raise InputError("drive", f'must be "{DRIVE}" for this loader')
    if top.text("kind", "speed", choices=KINDS) == "current-step":
        return _current_step(top)
    name = top.text("name", "pm-speed")
    top.text("description", "")
    mech = Section(top.get("machine", {}), "machine")
    machine = _machine(mech)
    J = mech.number("J", None, require_positive) if mech.has("J") else machine.J
    B = mech.number("viscous_friction", 0.0, require_nonnegative)
    load_torque = _profile_points(mech, "load_torque", 0.0)
    plant, factors = perturbed_plant(mech, machine, PERTURBATION_FIELDS, apart=("J",))
    mech.done()
    estimates, design_J = (machine if factors else None), None
    if top.has("design"):  # the controllers designed on estimates, the plant the truth
        dsec = Section(top.get("design"), "design")
        estimates, taken = design_machine(dsec, machine, MACHINE_FIELDS)
        dsec.done()
        if "J" in taken:
            design_J = estimates.J
    if factors.get("J", 1.0) != 1.0:
        design_J = J if design_J is None else design_J
        J = J * factors["J"]
    conv = Section(top.get("converter", {}), "converter")
    model = conv.text("model", "averaged", choices=CONVERTERS)
    V_dc = conv.number("dc_link_voltage", None, require_positive)
    if model == "switching":
        f_pwm = conv.number("pwm_frequency_hz", None, require_positive)
    elif conv.has("pwm_frequency_hz"):
        raise InputError(conv.field("pwm_frequency_hz"), 'applies to model = "switching" only')
    else:
        f_pwm = None
    conv.done()
    ctl = Section(top.get("control", {}), "control")
    control = {
        "i_max_peak": ctl.number("current_limit_pk_a", None, require_positive),
        "current_bandwidth": ctl.number("current_bandwidth_rad_s", None, require_positive),
        "speed_bandwidth": ctl.number("speed_bandwidth_rad_s", None, require_positive),
        "K_F": ctl.number("K_F", 1.0),
        "voltage_margin": ctl.number("voltage_margin", 0.9),
        "tau_max": ctl.number("tau_max", None, require_positive) if ctl.has("tau_max") else None,
    }
    ctl.done()
    ref = Section(top.get("reference", {}), "reference")
    speed = _profile_points(ref, "speed_rad_s", None)
    ref.done()
    sen = Section(top.get("sensors", {}), "sensors")
    counts = sen.number("encoder_counts_per_rev", 0.0, check_counts_per_rev)
    offset = sen.number("encoder_offset_rad", 0.0)
    sen.done()
    sim = Section(top.get("simulation", {}), "simulation")
    run = {
        "duration": sim.number("duration", None, require_positive),
        "sample_time": sim.number("sample_time", None, require_positive),
        "substeps": sim.integer("substeps", 4),
        "log_every": sim.integer("log_every", 1) if sim.has("log_every") else None,
    }
    if run["log_every"] is None:  # every sample up to 100,000, else every k-th (_log_plan)
        steps = run["duration"] / run["sample_time"]
        run["log_every"] = default_log_every(round(steps)) if math.isfinite(steps) else 1
    sim.done()
    top.done()
    try:
        return PMDriveSetup(
            machine=plant, estimates=estimates, design_J=design_J, V_dc=V_dc,
            speed_reference=speed, name=name, J=J, B=B,
            load=load_torque, converter=model, f_pwm=f_pwm, encoder_counts=counts,
            encoder_offset=offset, **control, **run,
        )  # fmt: skip
    except InputError as exc:
        fields = dict(_SETUP_FIELDS)
        if top.has("design"):  # the controller's machine is the design table's
            design = top.get("design")
            where = "design.machine_file" if "machine_file" in design else "design.params.L_q"
            fields["estimates.L_q"] = where
        raise InputError(fields.get(exc.field, exc.field), exc.rule) from None


def _frequencies(section: Section, key: str) -> tuple[float, ...]:
    value = section.get(key)
    if not isinstance(value, list) or not value:
        raise InputError(section.field(key), "must be a non-empty list of frequencies [rad/s]")
    return tuple(require_positive(section.field(key), v) for v in value)


def _current_step(top: Section) -> CurrentStepSetup:
    """The ``kind = "current-step"`` tables (module docstring) -> ``CurrentStepSetup``."""
    name = top.text("name", "pm-current-step")
    top.text("description", "")
    mech = Section(top.get("machine", {}), "machine")
    machine = _machine(mech)
    mech.done()
    op = Section(top.get("operating_point", {}), "operating_point")
    f_e = op.number("electrical_frequency_hz", None, require_positive)
    op.done()
    ctl = Section(top.get("control", {}), "control")
    bandwidth = ctl.number("bandwidth_rad_s", None, require_positive)
    ctl.done()
    ref = Section(top.get("reference", {}), "reference")
    step = ref.number("d_step_pk_a", None, require_positive)
    step_time = ref.number("step_time", None, require_nonnegative)
    ref.done()
    cmp_ = Section(top.get("comparison", {}), "comparison")
    frequencies = _frequencies(cmp_, "frequencies_rad_s")
    cmp_.done()
    sim = Section(top.get("simulation", {}), "simulation")
    duration = sim.number("duration", None, require_positive)
    sample_time = sim.number("sample_time", None, require_positive)
    substeps = sim.integer("substeps", 2)
    sim.done()
    top.done()
    fields = {
        "electrical_speed": "operating_point.electrical_frequency_hz",
        "bandwidth": "control.bandwidth_rad_s",
        "step": "reference.d_step_pk_a",
        "step_time": "reference.step_time",
        "frequencies": "comparison.frequencies_rad_s",
        "duration": "simulation.duration",
        "sample_time": "simulation.sample_time",
        "substeps": "simulation.substeps",
    }
    try:
        return CurrentStepSetup(
            machine=machine, electrical_speed=2.0 * math.pi * f_e, bandwidth=bandwidth,
            step=step, step_time=step_time, frequencies=frequencies, duration=duration,
            sample_time=sample_time, substeps=substeps, name=name,
        )  # fmt: skip
    except InputError as exc:
        raise InputError(fields.get(exc.field, exc.field), exc.rule) from None


#: setup field -> scenario field, for rules checked by ``PMDriveSetup`` itself
_SETUP_FIELDS = {
    "J": "machine.J",
    "design_J": "design.params.J",
    "B": "machine.viscous_friction",
    "load": "machine.load_torque_profile",
    "V_dc": "converter.dc_link_voltage",
    "f_pwm": "converter.pwm_frequency_hz",
    "i_max_peak": "control.current_limit_pk_a",
    "current_bandwidth": "control.current_bandwidth_rad_s",
    "speed_bandwidth": "control.speed_bandwidth_rad_s",
    "K_F": "control.K_F",
    "voltage_margin": "control.voltage_margin",
    "tau_max": "control.tau_max",
    "speed_reference": "reference.speed_rad_s_profile",
    "encoder_counts": "sensors.encoder_counts_per_rev",
    "duration": "simulation.duration",
    "sample_time": "simulation.sample_time",
    "substeps": "simulation.substeps",
    "log_every": "simulation.log_every",
    "estimates.L_q": "machine.params.L_q",
}


def builtin_names() -> list[str]:
    """Names of the built-in PM scenarios (the TOML files in ``scenarios/``)."""
    return sorted(p.stem for p in SCENARIO_DIR.glob("*.toml"))


def builtin(name: str) -> PMDriveSetup | CurrentStepSetup:
    """The setup of built-in scenario ``name``."""
    if name not in builtin_names():
        raise InputError("scenario", f"must be one of {', '.join(builtin_names())}")
    path = SCENARIO_DIR / f"{name}.toml"
    return load(parse_toml(path.read_text(encoding="utf-8"), str(path), "scenario"))
