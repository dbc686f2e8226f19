"""Typed description of a DFIM drive simulation and its translation into the engine's arrays.

``DriveSetup`` holds validated physical data (machines, supply, loads, sensors, controllers,
references); ``simulate`` builds the arrays, sets the initial steady state and runs the compiled
loop, returning a ``DriveResult``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from acdrive.control import dfim as ctl
from acdrive.control.speed import SpeedPIGains
from acdrive.errors import InputError
from acdrive.machines.dfim import DFIMParams, machine_vector
from acdrive.plant.converter import max_voltage_magnitude
from acdrive.plant.dfim_bus import (
    OMEGA,
    PSI_R_IM,
    PSI_R_RE,
    PSI_S_IM,
    PSI_S_RE,
    STATES_PER_MOTOR,
    n_states,
)
from acdrive.plant.profiles import pad_profiles
from acdrive.sim import engine
from acdrive.sim.result import DriveResult

SQRT_3_2 = np.sqrt(1.5)
Profile = tuple[np.ndarray, np.ndarray]


def constant(value: float) -> Profile:
    return np.array([0.0]), np.array([float(value)])


@dataclass(frozen=True)
class Supply:
    """Three-phase stator supply: peak line-neutral voltage and frequency profiles, behind a
    series R-L impedance shared by every motor on it (Bodson's transformer)."""

    voltage_pk: Profile = field(default_factory=lambda: constant(11.1))
    frequency_hz: Profile = field(default_factory=lambda: constant(60.0))
    resistance: float = 0.0
    inductance: float = 0.0


@dataclass(frozen=True)
class DFIMController:
    """Voltage-command controller settings (Bodson III-A, III-B, III-D, IV-A)."""

    gains: SpeedPIGains
    reactive_power: float = 0.0
    stator_current_limit_pk: float = 6.0
    rotor_current_limit_pk: float = 6.0
    theta_adj: float = 0.0
    m_adj: float = 1.0
    speed_filter_tau: float = 0.0
    frequency_filter_tau: float = 0.01
    min_stator_voltage_pk: float = 1.0
    params: DFIMParams | None = None  # controller's parameter estimates (default: the true ones)


@dataclass(frozen=True)
class MotorSetup:
    """One DFIM with its load, sensors, converter, controller and speed reference."""

    machine: DFIMParams
    controller: DFIMController
    speed_reference: Profile  # rad/s (mechanical) vs s
    load_torque: Profile = field(default_factory=lambda: constant(0.0))
    dc_link_voltage: float = 30.0
    encoder_counts_per_rev: float = 0.0
    encoder_offset: float = 0.0
    initial_speed: float = 0.0


@dataclass(frozen=True)
class DriveSetup:
    """A complete simulation: motors on one supply, sample time and duration."""

    motors: tuple[MotorSetup, ...]
    supply: Supply = field(default_factory=Supply)
    duration: float = 1.0
    sample_time: float = 200e-6
    substeps: int = 4
    log_every: int = 1
    name: str = "custom"


def max_speed(motor: MotorSetup, supply: Supply) -> float:
    """Largest |shaft speed| [rad/s] the converter can hold at zero torque.

    The steady rotor voltage at i_s = 0 is (Z_R / Z_MS) v_s (Bodson (20)), about |slip| (L_r/M) v_s;
    the converter gives at most V_dc / sqrt(2), so |slip| <= V_dc / sqrt(2) / ((L_r/M) v_s).
    """
    m = motor.machine
    v_s = SQRT_3_2 * float(np.max(supply.voltage_pk[1]))
    f = float(np.max(supply.frequency_hz[1]))
    slip_max = max_voltage_magnitude(motor.dc_link_voltage) / (m.L_r / m.M * v_s)
    return 2.0 * np.pi * f / m.n_p * (1.0 + slip_max)


def _controller_arrays(motor: MotorSetup, supply: Supply, T_s: float) -> np.ndarray:
    c = motor.controller
    cp = np.zeros(ctl.N_CTRL_PARAMS)
    cp[ctl.CP_KP], cp[ctl.CP_KI], cp[ctl.CP_KF] = c.gains.K_P, c.gains.K_I, c.gains.K_F
    cp[ctl.CP_Q_REF] = c.reactive_power
    cp[ctl.CP_I_S_MAX] = SQRT_3_2 * c.stator_current_limit_pk
    cp[ctl.CP_I_R_MAX] = SQRT_3_2 * c.rotor_current_limit_pk
    cp[ctl.CP_THETA_ADJ], cp[ctl.CP_M_ADJ] = c.theta_adj, c.m_adj
    cp[ctl.CP_W_E_NOM] = 2.0 * np.pi * float(supply.frequency_hz[1][0])
    cp[ctl.CP_SPEED_TAU], cp[ctl.CP_FREQ_TAU] = c.speed_filter_tau, c.frequency_filter_tau
    cp[ctl.CP_V_MIN] = SQRT_3_2 * c.min_stator_voltage_pk
    cp[ctl.CP_T_S] = T_s
    return cp


def initial_state(setup: DriveSetup) -> tuple[np.ndarray, np.ndarray]:
    """Plant state and held rotor voltages for a zero-torque steady state at t = 0.

    With i_s = 0 the stator voltage is Z_MS i_r (19), so i_r = v_s / (j w_e M) and the rotor
    voltage is Z_R i_r; at t = 0 the supply angle is zero, so v_s is real in the stationary frame.
    """
    x = np.zeros(n_states(len(setup.motors)))
    v_r_rotor = np.zeros(len(setup.motors), dtype=complex)
    v_s = SQRT_3_2 * float(setup.supply.voltage_pk[1][0])
    w_e = 2.0 * np.pi * float(setup.supply.frequency_hz[1][0])
    for k, motor in enumerate(setup.motors):
        m, o = motor.machine, STATES_PER_MOTOR * k
        w_slip = w_e - m.n_p * motor.initial_speed
        i_r = v_s / (1j * w_e * m.M) if w_e > 0 else 0.0j
        psi_s, psi_r = m.M * i_r, m.L_r * i_r
        x[o + PSI_S_RE], x[o + PSI_S_IM] = psi_s.real, psi_s.imag
        x[o + PSI_R_RE], x[o + PSI_R_IM] = psi_r.real, psi_r.imag
        x[o + OMEGA] = motor.initial_speed
        v_r_rotor[k] = (m.R_r + 1j * w_slip * m.L_r) * i_r
    return x, v_r_rotor


def build_arrays(setup: DriveSetup) -> dict:
    """All engine inputs for one variant, as a dict of arrays named after ``engine.run_drive``."""
    motors = setup.motors
    n = len(motors)
    machines = np.array([machine_vector(m.machine) for m in motors])
    p_est = np.array([machine_vector(m.controller.params or m.machine) for m in motors])
    load_t, load_tau = pad_profiles([m.load_torque for m in motors])
    ref_t, ref_w = pad_profiles([m.speed_reference for m in motors])
    sensors = np.zeros((n, engine.N_SENSOR))
    cp = np.zeros((n, ctl.N_CTRL_PARAMS))
    cs = np.zeros((n, ctl.N_CTRL_STATES))
    x, v_r0 = initial_state(setup)
    for k, m in enumerate(motors):
        sensors[k, engine.SN_ENC_OFFSET] = m.encoder_offset
        sensors[k, engine.SN_ENC_CPR] = m.encoder_counts_per_rev
        sensors[k, engine.SN_V_R_MAX] = max_voltage_magnitude(m.dc_link_voltage)
        cp[k] = _controller_arrays(m, setup.supply, setup.sample_time)
        cs[k, ctl.CS_VR_RE], cs[k, ctl.CS_VR_IM] = v_r0[k].real, v_r0[k].imag
    s = setup.supply
    supply = tuple(np.ascontiguousarray(a, dtype=float) for a in (*s.voltage_pk, *s.frequency_hz))
    return dict(
        x=x,
        machines=machines,
        bus=np.array([s.resistance, s.inductance]),
        supply=supply,
        load_t=load_t,
        load_tau=load_tau,
        sensors=sensors,
        p_est=p_est,
        cp=cp,
        cs=cs,
        ref_t=ref_t,
        ref_w=ref_w,
        closed=np.ones(n, dtype=np.bool_),
    )


def n_steps(setup: DriveSetup) -> int:
    return int(round(setup.duration / setup.sample_time))


def simulate(setup: DriveSetup) -> DriveResult:
    """Run the compiled loop on ``setup`` and return its typed result.

    Raises RuntimeError if the state stops being finite (a simulation never returns NaN silently).
    """
    arrays = build_arrays(setup)
    steps = n_steps(setup)
    log = np.zeros(
        (steps // setup.log_every + (steps % setup.log_every > 0), len(setup.motors), engine.N_LOG)
    )
    start = time.perf_counter()
    done, status = engine.run_drive(
        **arrays,
        T_s=setup.sample_time,
        n_sub=setup.substeps,
        n_steps=steps,
        log_every=setup.log_every,
        log=log,
    )
    elapsed = time.perf_counter() - start
    if status != engine.STATUS_OK:
        raise RuntimeError(
            f"simulation '{setup.name}' diverged (non-finite state) at t = {done * setup.sample_time:.6f} s"
        )
    t = np.arange(log.shape[0]) * setup.sample_time * setup.log_every
    return DriveResult(
        name=setup.name,
        t=t,
        signals=log,
        sample_time=setup.sample_time,
        final_state=arrays["x"],
        wall_time=elapsed,
    )


def check_setup(setup: DriveSetup) -> None:
    """Cross-field rules that single fields cannot express (raises InputError)."""
    for k, motor in enumerate(setup.motors):
        limit = max_speed(motor, setup.supply)
        ref = motor.speed_reference[1]
        if np.max(np.abs(ref)) > limit:
            raise InputError(
                f"motor[{k}].speed_reference_rpm",
                f"must stay within +-{limit * 30 / np.pi:.0f} rpm (the converter's rotor-voltage limit)",
            )
    if setup.substeps < 1:
        raise InputError("simulation.substeps", "must be an integer >= 1")
