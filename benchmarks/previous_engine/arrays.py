"""Translation of a ``DriveSetup`` into the previous engine's hand-numbered arrays (frozen)."""

from __future__ import annotations

import time

import numpy as np

from acdrive._frames import K_PEAK as SQRT_3_2
from acdrive.drives import DriveResult
from acdrive.drives.dfim._setup import DriveSetup, MotorSetup, Supply, divergence_hint
from acdrive.errors import SimulationDiverged
from acdrive.plant._converter import max_voltage_magnitude

from . import controller as ctl
from . import engine
from .dfim_bus import (
    OMEGA,
    PSI_R_IM,
    PSI_R_RE,
    PSI_S_IM,
    PSI_S_RE,
    STATES_PER_MOTOR,
    n_states,
    project_phasors,
)
from .profiles import pad_profiles
from .vector import machine_vector


def _controller_arrays(motor: MotorSetup, supply: Supply, T_s: float) -> np.ndarray:
    c = motor.controller
    cp = np.zeros(ctl.N_CTRL_PARAMS)
    cp[ctl.CP_KP], cp[ctl.CP_KI], cp[ctl.CP_KF] = c.gains.K_P, c.gains.K_I, c.gains.K_F
    cp[ctl.CP_Q_REF] = c.reactive_power
    cp[ctl.CP_Q_KP], cp[ctl.CP_Q_KI] = c.reactive_power_kp, c.reactive_power_ki
    cp[ctl.CP_I_S_MAX] = SQRT_3_2 * c.stator_current_limit_pk
    cp[ctl.CP_I_R_MAX] = SQRT_3_2 * c.rotor_current_limit_pk
    cp[ctl.CP_THETA_ADJ], cp[ctl.CP_M_ADJ] = c.theta_adj, c.m_adj
    cp[ctl.CP_W_E_NOM] = 2.0 * np.pi * float(supply.frequency_hz[1][0])
    cp[ctl.CP_SPEED_TAU], cp[ctl.CP_FREQ_TAU] = c.speed_filter_tau, c.frequency_filter_tau
    cp[ctl.CP_V_MIN] = SQRT_3_2 * c.min_stator_voltage_pk
    cp[ctl.CP_T_S] = T_s
    cp[ctl.CP_MODE] = ctl.MODE_CURRENT if c.mode == "current" else ctl.MODE_VOLTAGE
    cp[ctl.CP_KPC], cp[ctl.CP_KIC] = c.current_gains(motor.machine)
    cp[ctl.CP_R_T] = c.R_T
    cp[ctl.CP_V_R_MAX] = max_voltage_magnitude(motor.dc_link_voltage)
    cp[ctl.CP_SYNC] = 1.0 if c.sync.enabled else 0.0
    cp[ctl.CP_SYNC_GAIN] = c.sync.gain
    cp[ctl.CP_SYNC_TOL_MAG], cp[ctl.CP_SYNC_TOL_PHASE] = (
        c.sync.tolerance_magnitude,
        c.sync.tolerance_phase,
    )
    cp[ctl.CP_SYNC_HOLD] = c.sync.hold_time
    cp[ctl.CP_LOSSLESS] = 1.0 if c.lossless_law else 0.0
    return cp


def initial_state(setup: DriveSetup) -> tuple[np.ndarray, np.ndarray]:
    """Plant state and held rotor voltages at t = 0.

    A connected motor starts in its zero-torque steady state: with i_s = 0 the stator voltage is
    Z_MS i_r (19), so i_r = v_s / (j w_e M) and the rotor voltage is Z_R i_r (at t = 0 the supply
    angle is zero, so v_s is real in the stationary frame). A motor that synchronises first starts
    de-energised, with its stator open and the converter at zero.
    """
    x = np.zeros(n_states(len(setup.motors)))
    v_r_rotor = np.zeros(len(setup.motors), dtype=complex)
    v_s = SQRT_3_2 * float(setup.supply.voltage_pk[1][0])
    w_e = 2.0 * np.pi * float(setup.supply.frequency_hz[1][0])
    for k, motor in enumerate(setup.motors):
        m, o = motor.machine, STATES_PER_MOTOR * k
        w_slip = w_e - m.n_p * motor.initial_speed
        energised = w_e > 0 and not motor.controller.sync.enabled
        i_r = v_s / (1j * w_e * m.M) if energised else 0.0j
        psi_s, psi_r = m.M * i_r, m.L_r * i_r
        x[o + PSI_S_RE], x[o + PSI_S_IM] = psi_s.real, psi_s.imag
        x[o + PSI_R_RE], x[o + PSI_R_IM] = psi_r.real, psi_r.imag
        x[o + OMEGA] = motor.initial_speed
        v_r_rotor[k] = (m.R_r + 1j * w_slip * m.L_r) * i_r
    project_phasors(x, np.array([machine_vector(mo.machine) for mo in setup.motors]))
    return x, v_r_rotor


def motor_data(motor: MotorSetup) -> np.ndarray:
    """The plant's per-motor vector: machine parameters, then the converter loss (dfim_bus)."""
    loss = motor.converter.fundamental_loss(motor.dc_link_voltage)
    return np.append(machine_vector(motor.machine), loss)


def build_arrays(setup: DriveSetup) -> dict:
    """All engine inputs for one variant, as a dict of arrays named after ``engine.run_drive``."""
    motors = setup.motors
    n = len(motors)
    machines = np.array([motor_data(m) for m in motors])
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
        sensors[k, engine.SN_CURRENT_FAULT_T] = m.current_sensor_fault_time
        cp[k] = _controller_arrays(m, setup.supply, setup.sample_time)
        cs[k, ctl.CS_VR_RE], cs[k, ctl.CS_VR_IM] = v_r0[k].real, v_r0[k].imag
    s = setup.supply
    supply = tuple(np.ascontiguousarray(a, dtype=float) for a in (*s.voltage_pk, *s.frequency_hz))
    return {
        "x": x,
        "machines": machines,
        "bus": np.array([s.resistance, s.inductance]),
        "supply": supply,
        "load_t": load_t,
        "load_tau": load_tau,
        "sensors": sensors,
        "p_est": p_est,
        "cp": cp,
        "cs": cs,
        "ref_t": ref_t,
        "ref_w": ref_w,
        "closed": np.array([not m.controller.sync.enabled for m in motors], dtype=np.bool_),
    }


def n_steps(setup: DriveSetup) -> int:
    return round(setup.duration / setup.sample_time)


def simulate_previous_engine(setup: DriveSetup) -> DriveResult:
    """Run the previous hand-wired engine (``sim.engine``) on ``setup``; kept only while
    ``benchmarks/compare_engines.py`` proves the parts-built drive equal to it.

    Raises ``SimulationDiverged`` (a RuntimeError) with the time and a hint of what to change if
    the state stops being finite (a simulation never returns NaN silently).
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
        raise SimulationDiverged(done * setup.sample_time, divergence_hint(setup), setup.name)
    t = np.arange(log.shape[0]) * setup.sample_time * setup.log_every
    return DriveResult(
        name=setup.name,
        t=t,
        signals=log,
        sample_time=setup.sample_time,
        final_state=arrays["x"],
        wall_time=elapsed,
    )
