"""Scenario files (TOML): loading, validation, and translation into a ``DriveSetup``.

Every field is checked on load; a bad one raises ``InputError("<path.to.field>", "<rule>")``.
Schema (all tables optional except [[motor]]; units in the key names where not SI):

    name, description, note (copied into summary.json), compare_modes (e.g. ["voltage", "current"]: one run per mode)
    [simulation]  duration, sample_time, substeps, log_every
    [supply]      voltage_pk | voltage_pk_profile = [[t, V], ...], frequency_hz |
                  frequency_hz_profile, resistance, inductance
    [[motor]]     machine (built-in name) or [motor.params] (R_s, R_r, L_s, L_r, M, n_p, J),
                  viscous_friction, coulomb_friction, load_torque | load_torque_profile,
                  speed_reference_rpm = [[t, rpm], ...], initial_speed_rpm, dc_link_voltage,
                  encoder_counts_per_rev, encoder_offset, converter_dead_time (s),
                  converter_switching_frequency (Hz), converter_device_drop (V)
                  current_sensor_fault_time (s; current measurements fail from then on)
    [motor.controller]  mode ("voltage" | "current"), lossless_law (R_s = 0 form (39)),
                  current_bandwidth, R_T,
                  reactive_power_kp, reactive_power_ki | reactive_power_bandwidth, speed_bandwidth, design_inertia (J used in (27),
                  default: the machine's J), K_F, reactive_power,
                  stator_current_limit_pk, rotor_current_limit_pk, theta_adj, m_adj,
                  speed_filter_tau, frequency_filter_tau, min_stator_voltage_pk
    [motor.controller.sync]  enabled, gain, tolerance_magnitude, tolerance_phase_deg, hold_time
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import tomllib
from importlib import resources
from pathlib import Path

import numpy as np

from acdrive.control.speed import SpeedPIGains
from acdrive.errors import (
    InputError,
    require_finite,
    require_nonnegative,
    require_positive,
    require_safe_name,
)
from acdrive.machines.dfim import BODSON_DFIM, DFIMParams
from acdrive.sim.engine import N_LOG
from acdrive.sim.setup import (
    ConverterLosses,
    DFIMController,
    DriveSetup,
    MotorSetup,
    Supply,
    Synchroniser,
    check_setup,
    constant,
)
from acdrive.sim.system import LOG_BUDGET_BYTES, MAX_SUBSTEPS, MAX_WORK

MACHINES = {"bodson-dfim": BODSON_DFIM}
RAD_S_PER_RPM = math.pi / 30.0



def builtin_names() -> list[str]:
    folder = resources.files("acdrive.scenarios") / "builtin"
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))


def builtin_text(name: str) -> str:
    return (resources.files("acdrive.scenarios") / "builtin" / f"{name}.toml").read_text()


def read_scenario(source: str | Path) -> dict:
    """Parse a scenario: a built-in name or a path to a TOML file."""
    source = str(source)
    if source in builtin_names():
        text, origin = builtin_text(source), source
    else:
        path = Path(source)
        if not path.is_file():
            raise InputError(
                "scenario",
                f"'{source}' is neither a built-in scenario ({', '.join(builtin_names())}) nor a file",
            )
        try:
            text, origin = path.read_text(encoding="utf-8"), str(path)
        except UnicodeDecodeError:
            raise InputError("scenario", f"{path} is not a UTF-8 text file") from None
        except OSError as exc:
            raise InputError("scenario", f"cannot read {path} ({exc.strerror})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError("scenario", f"{origin} is not valid TOML ({exc})") from None


def load_scenario(source: str | Path) -> DriveSetup:
    """Read, validate and build a scenario into a ``DriveSetup``."""
    return build_setup(read_scenario(source))


class _Section:
    """A TOML table being validated: tracks the keys read so unknown keys can be reported."""

    def __init__(self, data, path: str):
        if not isinstance(data, dict):
            raise InputError(path, "must be a table")
        self.data, self.path, self.used = data, path, set()

    def field(self, key: str) -> str:
        return f"{self.path}.{key}" if self.path else key

    def get(self, key, default=None):
        self.used.add(key)
        return self.data.get(key, default)

    def has(self, key) -> bool:
        return key in self.data

    def number(self, key, default, rule=require_finite):
        value = self.get(key, default)
        return rule(self.field(key), value)

    def integer(self, key, default, minimum=1, maximum=None):
        value = self.get(key, default)
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            raise InputError(self.field(key), f"must be an integer >= {minimum}")
        if maximum is not None and value > maximum:
            raise InputError(self.field(key), f"must be an integer <= {maximum}, got {value}")
        return value

    def boolean(self, key, default):
        value = self.get(key, default)
        if not isinstance(value, bool):
            raise InputError(self.field(key), "must be true or false")
        return value

    def text(self, key, default=None, choices=None):
        value = self.get(key, default)
        if not isinstance(value, str):
            raise InputError(self.field(key), "must be a string")
        if choices is not None and value not in choices:
            raise InputError(self.field(key), f"must be one of {', '.join(choices)}")
        return value

    def profile(self, key, scale=1.0, rule=require_finite):
        """A list of [t, value] pairs with non-decreasing t >= 0, as (times, values) arrays."""
        value = self.get(key)
        name = self.field(key)
        if not isinstance(value, list) or not value:
            raise InputError(name, "must be a non-empty list of [time_s, value] pairs")
        times, values = [], []
        for i, pair in enumerate(value):
            if not isinstance(pair, list) or len(pair) != 2:
                raise InputError(f"{name}[{i}]", "must be a [time_s, value] pair")
            times.append(require_nonnegative(f"{name}[{i}][0]", pair[0]))
            values.append(rule(f"{name}[{i}][1]", pair[1]) * scale)
        if any(b < a for a, b in itertools.pairwise(times)):
            raise InputError(name, "times must be non-decreasing")
        return np.array(times), np.array(values)

    def constant_or_profile(self, key, default, scale=1.0, rule=require_finite):
        if self.has(key) and self.has(f"{key}_profile"):
            raise InputError(self.field(key), f"give either {key} or {key}_profile, not both")
        if self.has(f"{key}_profile"):
            return self.profile(f"{key}_profile", scale, rule)
        return constant(self.number(key, default, rule) * scale)

    def done(self):
        unknown = sorted(set(self.data) - self.used)
        if unknown:
            raise InputError(self.field(unknown[0]), "unknown key")


def _machine(section: _Section, index: int) -> DFIMParams:
    if section.has("machine") and section.has("params"):
        raise InputError(section.field("machine"), "give either machine or [params], not both")
    if section.has("params"):
        params = _Section(section.get("params"), section.field("params"))
        fields = ("R_s", "R_r", "L_s", "L_r", "M", "n_p", "J")
        values = {k: params.get(k) for k in fields}
        params.done()
        missing = [k for k, v in values.items() if v is None]
        if missing:
            raise InputError(params.field(missing[0]), "is required")
        try:
            machine = DFIMParams(**values)
        except InputError as exc:
            raise InputError(params.field(exc.field), exc.rule) from None
    else:
        name = section.text("machine", "bodson-dfim", choices=tuple(MACHINES))
        machine = MACHINES[name]
    B = section.number("viscous_friction", 0.0, require_nonnegative)
    tau_c = section.number("coulomb_friction", 0.0, require_nonnegative)
    return dataclasses.replace(machine, B=B, tau_c=tau_c)


def _sync(section: _Section) -> Synchroniser:
    sync = Synchroniser(
        enabled=section.boolean("enabled", False),
        gain=section.number("gain", 40.0, require_positive),
        tolerance_magnitude=section.number("tolerance_magnitude", 0.02, require_positive),
        tolerance_phase=section.number("tolerance_phase_deg", 2.0, require_positive)
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
    K_F = section.number("K_F", 2.0 / 3.0, require_nonnegative)
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
    )
    section.done()
    return controller


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


def build_setup(data: dict) -> DriveSetup:
    """Validate a parsed scenario and build its ``DriveSetup``."""
    top = _Section(data, "")
    name = require_safe_name("name", top.get("name", "custom"))  # becomes an output folder
    top.text("description", "")
    note = top.text("note", "")
    compare = top.get("compare_modes", [])
    if not isinstance(compare, list) or any(m not in ("voltage", "current") for m in compare):
        raise InputError("compare_modes", 'must be a list of "voltage" / "current"')
    sim = _Section(top.get("simulation", {}), "simulation")
    duration = sim.number("duration", 1.0, require_positive)
    sample_time = sim.number("sample_time", 200e-6, require_positive)
    if sample_time > duration:
        raise InputError("simulation.sample_time", "must not exceed simulation.duration")
    substeps = sim.integer("substeps", 4, maximum=MAX_SUBSTEPS)
    steps = duration / sample_time  # control steps (a float: may be astronomically large)
    log_every = sim.integer("log_every", 1)
    if math.isfinite(steps) and log_every > round(steps):
        raise InputError(
            "simulation.log_every",
            f"must not exceed the number of control steps of the run "
            f"({round(steps)} = simulation.duration / simulation.sample_time)",
        )
    sim.done()

    sup = _Section(top.get("supply", {}), "supply")
    supply = Supply(
        voltage_pk=sup.constant_or_profile("voltage_pk", 11.1, rule=require_nonnegative),
        frequency_hz=sup.constant_or_profile("frequency_hz", 60.0, rule=require_positive),
        resistance=sup.number("resistance", 0.0, require_nonnegative),
        inductance=sup.number("inductance", 0.0, require_nonnegative),
    )
    sup.done()
    if supply.voltage_pk[1][0] <= 0.0:
        raise InputError("supply.voltage_pk", "must be > 0 at t = 0 (the drive starts connected)")

    motors_data = top.get("motor")
    if not isinstance(motors_data, list) or not motors_data:
        raise InputError("motor", "at least one [[motor]] table is required")
    motors = []
    for k, raw in enumerate(motors_data):
        sec = _Section(raw, f"motor[{k}]")
        machine = _machine(sec, k)
        if not sec.has("speed_reference_rpm"):
            raise InputError(sec.field("speed_reference_rpm"), "is required")
        motor = MotorSetup(
            machine=machine,
            controller=_controller(
                _Section(sec.get("controller", {}), sec.field("controller")), machine
            ),
            speed_reference=sec.profile("speed_reference_rpm", RAD_S_PER_RPM),
            load_torque=sec.constant_or_profile("load_torque", 0.0),
            dc_link_voltage=sec.number("dc_link_voltage", 30.0, require_positive),
            converter=ConverterLosses(
                dead_time=sec.number("converter_dead_time", 0.0, require_nonnegative),
                switching_frequency=sec.number(
                    "converter_switching_frequency", 0.0, require_nonnegative
                ),
                device_drop=sec.number("converter_device_drop", 0.0, require_nonnegative),
            ),
            encoder_counts_per_rev=float(sec.integer("encoder_counts_per_rev", 0, minimum=0)),
            encoder_offset=sec.number("encoder_offset", 0.0),
            initial_speed=sec.number("initial_speed_rpm", 0.0) * RAD_S_PER_RPM,
            current_sensor_fault_time=sec.number(
                "current_sensor_fault_time", math.inf, require_nonnegative
            )
            if sec.has("current_sensor_fault_time")
            else math.inf,
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
    return setup
