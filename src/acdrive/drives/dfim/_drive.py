"""The DFIM drive of a ``DriveSetup`` built from parts, and its run as a ``DriveResult``.

Per motor k (part names end in k): the machine ``dfim`` (Bodson (9)) on a ``shaft`` (26), its
stator ``relay`` to the shared ``bus``, the rotor ``converter`` (averaged, limited to V_dc/sqrt(2));
the sensors ``encoder`` and ``currents``; the estimators ``speed`` and ``frequency``; the speed
``reference``; the ``sync``hroniser (28) and the speed ``controller`` (section III). Shared: the
``grid`` source and the ``bus`` behind the supply's series R-L. The wiring follows Bodson's bench
(section IV-A): the controller reads the stator terminal and grid voltages, the stator and rotor
currents and the encoder, and commands the rotor converter and the stator relay.

Fault variants, each present only when the scenario asks for it (the other scenarios keep their
topology): a ``grid`` with per-phase EMF magnitudes (``UnbalancedSource``, e.g. a collapsed
phase); a DC link ``dc`` whose voltage follows a profile, feeding a ``DCFedConverter`` (the
controller's rotor-voltage limit and the converter loss stay at the nominal DC-link voltage); a
relay ``forced`` closed at a given time whatever the synchroniser commands (``ForcedRelay``); a
``delay`` of one sample between the controller's rotor-voltage command and the converter
(``ComputationDelay``: the controller computes during the period and its command takes effect at
the next sample instant).
"""

from __future__ import annotations

import numpy as np

from acdrive._arguments import POSITIVE, Function, Table, Text, checked
from acdrive.drives._registry import Setup
from acdrive._frames import K_PEAK as SQRT_3_2
from acdrive._frames import complex_to_abc
from acdrive.control import _bodson as bodson
from acdrive.control._delay import ComputationDelay
from acdrive.control._dfim import EVENT_NAMES, MODE_CURRENT, MODE_VOLTAGE
from acdrive.control._speed import SpeedReference
from acdrive.drives.dfim._result import LOG_NAMES, DriveResult
from acdrive.drives.dfim._tracking import tracking_rule
from acdrive.errors import SimulationDiverged
from acdrive.machines._dfim_part import DoublyFedMachine
from acdrive.plant._converter import AveragedConverter, DCFedConverter, max_voltage_magnitude
from acdrive.plant._mechanics import Shaft
from acdrive.plant._network import ForcedRelay, StatorRelay, SupplyBus
from acdrive.plant._sensors import CurrentSensors, Encoder
from acdrive.plant._sources import DCSource, ThreePhaseSource, UnbalancedSource
from acdrive.sim._compiled import CompiledSystem
from acdrive.sim._system import System

#: the converter's event and the parts whose events make up the flags column of a DriveResult
_EVENT_ALIASES = {"saturated": "converter_saturation"}


def _estimates(params) -> dict:
    return {"R_s": params.R_s, "R_r": params.R_r, "L_s": params.L_s, "L_r": params.L_r,
            "M": params.M, "n_p": params.n_p}  # fmt: skip


def _motor_parts(k: int, motor, setup) -> dict:
    """The parts of motor k, by role."""
    c, m = motor.controller, motor.machine
    est = _estimates(c.params or m)
    v_min = SQRT_3_2 * c.min_stator_voltage_pk
    kpc, kic = c.current_gains(m)
    w_nominal = 2.0 * np.pi * float(setup.supply.frequency_hz[1][0])
    parts = {
        "dfim": DoublyFedMachine.from_params(
            f"dfim{k}", m, V_loss=motor.converter.fundamental_loss(motor.dc_link_voltage)
        ),
        "shaft": Shaft(f"shaft{k}", J=m.J, B=m.B, tau_c=m.tau_c, load=motor.load_torque),
        "relay": StatorRelay(f"relay{k}"),
        "converter": (
            AveragedConverter(f"converter{k}", V_dc=motor.dc_link_voltage)
            if motor.dc_link_profile is None
            else DCFedConverter(f"converter{k}")
        ),
        "encoder": Encoder(
            f"encoder{k}", offset=motor.encoder_offset, counts_per_rev=motor.encoder_counts_per_rev
        ),
        "currents": CurrentSensors(
            f"currents{k}",
            fails=float(np.isfinite(motor.current_sensor_fault_time)),
            fault_time=(
                motor.current_sensor_fault_time
                if np.isfinite(motor.current_sensor_fault_time)
                else 0.0
            ),
        ),
        "speed": bodson.SpeedEstimator(f"speed{k}", tau=c.speed_filter_tau),
        "frequency": bodson.SupplyFrequencyEstimator(
            f"frequency{k}", w_nominal=w_nominal, tau=c.frequency_filter_tau, v_min=v_min
        ),
        "reference": SpeedReference(f"reference{k}", w=motor.speed_reference),
        "sync": bodson.Synchroniser(
            f"sync{k}",
            **est,
            enabled=float(c.sync.enabled),
            gain=c.sync.gain,
            tol_magnitude=c.sync.tolerance_magnitude,
            tol_phase=c.sync.tolerance_phase,
            hold=c.sync.hold_time,
            v_min=v_min,
            theta_adj=c.theta_adj,
            m_adj=c.m_adj,
        ),
        "controller": bodson.SpeedController(
            f"controller{k}",
            **est,
            K_P=c.gains.K_P,
            K_I=c.gains.K_I,
            K_F=c.gains.K_F,
            Q_ref=c.reactive_power,
            Q_kp=c.reactive_power_kp,
            Q_ki=c.reactive_power_ki,
            i_s_max=SQRT_3_2 * c.stator_current_limit_pk,
            i_r_max=SQRT_3_2 * c.rotor_current_limit_pk,
            v_min=v_min,
            mode=MODE_CURRENT if c.mode == "current" else MODE_VOLTAGE,
            K_PC=kpc,
            K_IC=kic,
            R_T=c.R_T,
            v_r_max=max_voltage_magnitude(motor.dc_link_voltage),
            lossless=float(c.lossless_law),
        ),
    }
    if motor.dc_link_profile is not None:
        parts["dc"] = DCSource(f"dc{k}", V=motor.dc_link_profile)
    if np.isfinite(motor.relay_forced_close_time):
        parts["forced"] = ForcedRelay(f"forced{k}", close_at=motor.relay_forced_close_time)
    if c.computation_delay_samples:
        parts["delay"] = ComputationDelay(f"delay{k}", unit="V", kind="complex")
    return parts


def _motor_wires(k: int, p: dict, grid, bus) -> list:
    dfim, shaft, relay, ctrl, sync = p["dfim"], p["shaft"], p["relay"], p["controller"], p["sync"]
    enc, cur, spd, freq = p["encoder"], p["currents"], p["speed"], p["frequency"]
    extra = []
    if "dc" in p:
        extra.append((p["dc"].out.v_dc, p["converter"].inp.v_dc))
    closed = sync.out.closed  # the relay follows the synchroniser, unless forced
    if "forced" in p:
        extra.append((sync.out.closed, p["forced"].inp.command))
        closed = p["forced"].out.closed
    command = ctrl.out.v_r  # what the converter applies: the command, or the delayed one
    if "delay" in p:
        extra.append((ctrl.out.v_r, p["delay"].inp.x))
        command = p["delay"].out.x
    return extra + [
        *bus.wires_from(k, dfim),
        (bus.out.v, dfim.inp.v_s), (bus.out.v, relay.inp.v_bus),
        (dfim.out.v_open, relay.inp.v_open),
        (closed, relay.inp.closed), (closed, dfim.inp.connected),
        (p["converter"].out.v, dfim.inp.v_r),
        (shaft.out.w, dfim.inp.w), (dfim.out.tau_e, shaft.inp.tau_e),
        (shaft.out.theta, enc.inp.theta),
        (dfim.out.i_s, cur.inp.i_s), (dfim.out.i_r_rotor, cur.inp.i_r),
        (enc.out.theta, spd.inp.theta), (grid.out.v, freq.inp.v_g),
        (relay.out.v, sync.inp.v_s), (grid.out.v, sync.inp.v_g), (spd.out.w, sync.inp.w),
        (freq.out.w_e, sync.inp.w_e), (enc.out.theta, sync.inp.theta),
        (relay.out.v, ctrl.inp.v_s), (cur.out.i_s, ctrl.inp.i_s), (cur.out.i_r, ctrl.inp.i_r),
        (cur.out.valid, ctrl.inp.currents_valid), (enc.out.theta, ctrl.inp.theta),
        (spd.out.w, ctrl.inp.w), (freq.out.w_e, ctrl.inp.w_e),
        (p["reference"].out.w_ref, ctrl.inp.w_ref), (closed, ctrl.inp.closed),
        (sync.out.v_r, ctrl.inp.v_r_sync), (sync.out.adj, ctrl.inp.adj),
        (sync.out.m_adj, ctrl.inp.m_adj),
        (command, p["converter"].inp.v_ref),
    ]  # fmt: skip


@checked(setup=Setup())  # any drive's: require_setup names the drive
class DFIMDrive:
    """The parts, wiring, initial state and logged signals of one ``DriveSetup``."""

    def __init__(self, setup):
        from acdrive.drives._registry import get, require_setup

        self.setup = require_setup(setup, get("dfim").setup_types, "acdrive.drives.DFIMDrive")
        s = setup.supply
        if s.phase_scales is None:
            self.grid = ThreePhaseSource("grid", V_pk=s.voltage_pk, f=s.frequency_hz)
        else:
            k_a, k_b, k_c = s.phase_scales
            self.grid = UnbalancedSource(
                "grid", V_pk=s.voltage_pk, f=s.frequency_hz, k_a=k_a, k_b=k_b, k_c=k_c
            )
        n = len(setup.motors)
        self.bus = SupplyBus("bus", n_machines=n, R=s.resistance, L=s.inductance)
        self.motors = [_motor_parts(k, m, setup) for k, m in enumerate(setup.motors)]
        parts = [self.grid, self.bus] + [p for motor in self.motors for p in motor.values()]
        wires = [
            (self.grid.out.v, self.bus.inp.v_g),
            *(
                w
                for k, p in enumerate(self.motors)
                for w in _motor_wires(k, p, self.grid, self.bus)
            ),
        ]
        self.system = System(parts, wires, method=setup.integrator)

    def initial(self) -> tuple[dict, dict]:
        """(initial states, held outputs) at t = 0.

        A connected motor starts in its zero-torque steady state: with i_s = 0 the stator
        voltage is Z_MS i_r (Bodson (19)), so i_r = v_s / (j w_e M) and the held rotor voltage is
        Z_R i_r = (R_r + j w_slip L_r) i_r (at t = 0 the supply angle is zero, so v_s is real).
        A motor that synchronises first starts de-energised, its stator open, the converter at
        zero. The steady state is that of the balanced supply at t = 0: per-phase scales other
        than 1 at t = 0 (``UnbalancedSource``) start with a transient.
        """
        setup = self.setup
        v_s = SQRT_3_2 * float(setup.supply.voltage_pk[1][0])
        w_e = 2.0 * np.pi * float(setup.supply.frequency_hz[1][0])
        initial, held = {}, {}
        for motor, parts in zip(setup.motors, self.motors, strict=True):
            m = motor.machine
            energised = w_e > 0 and not motor.controller.sync.enabled
            i_r = v_s / (1j * w_e * m.M) if energised else 0.0j
            v_r = (m.R_r + 1j * (w_e - m.n_p * motor.initial_speed) * m.L_r) * i_r
            initial[parts["dfim"].name] = {"psi_s": m.M * i_r, "psi_r": m.L_r * i_r}
            initial[parts["shaft"].name] = {"w": motor.initial_speed}
            initial[parts["sync"].name] = {"v_r": v_r}
            initial[parts["controller"].name] = {"v_r": v_r}
            held[parts["converter"].name] = {"v": v_r}
            if "delay" in parts:  # the steady command waits in the delay line
                initial[parts["delay"].name] = {"stored": v_r}
                held[parts["delay"].name] = {"x": v_r}
        return initial, held

    def log_ports(self) -> list:
        ports = [self.grid.out.v]
        for p in self.motors:
            ports += [
                p["shaft"].out.w, p["reference"].out.w_ref, p["controller"].out.tau_com,
                p["dfim"].out.tau_e, p["relay"].out.v, p["converter"].out.v, p["dfim"].out.i_s,
                p["dfim"].out.i_r_rotor, p["controller"].out.i_r_com, p["controller"].out.i_r_f,
                p["sync"].out.theta_adj, p["sync"].out.m_adj, p["sync"].out.closed,
                p["controller"].out.mode, p["relay"].out.closed,
            ]  # fmt: skip
            if "dc" in p:
                ports.append(p["dc"].out.v_dc)
        return ports

    def compile(self) -> CompiledSystem:
        return self.system.compile()

    def run(self, compiled: CompiledSystem | None = None):
        """The ``SystemResult`` of the whole setup (all logged ports, every event)."""
        setup = self.setup
        compiled = compiled or self.compile()
        initial, held = self.initial()
        return compiled.run(
            setup.duration, setup.sample_time, substeps=setup.substeps, initial=initial,
            held=held, log=self.log_ports(), log_every=setup.log_every,
        )  # fmt: skip

    def flags(self, result, k: int) -> np.ndarray:
        """The event bits of motor k per logged sample, in ``EVENT_NAMES`` order."""
        flags = np.zeros(result.t.size, dtype=np.int64)
        names = {p.name for p in self.motors[k].values()}
        for i, (part, events) in enumerate(self.system.event_names()):
            if part not in names:
                continue
            for bit, name in enumerate(events):
                name = _EVENT_ALIASES.get(name, name)
                if name in EVENT_NAMES:
                    raised = (result.event_log[:, i] >> bit) & 1
                    flags |= raised << EVENT_NAMES.index(name)
        return flags

    def drive_result(self, result) -> DriveResult:
        """The signals of ``result`` in the layout of ``DriveResult`` (``LOG_NAMES``)."""
        rows, n = result.t.size, len(self.motors)
        signals = np.zeros((rows, n, len(LOG_NAMES)))
        v_g = result.signal(self.grid.out.v)
        for k, p in enumerate(self.motors):
            sig = result.signal
            v_s, i_s = sig(p["relay"].out.v), sig(p["dfim"].out.i_s)
            i_rr = sig(p["dfim"].out.i_r_rotor)
            i_r_com, i_r_f = sig(p["controller"].out.i_r_com), sig(p["controller"].out.i_r_f)
            i_x, i_y, _ = complex_to_abc(i_rr)
            columns = {
                "w": sig(p["shaft"].out.w),
                "w_ref": sig(p["reference"].out.w_ref),
                "tau_com": sig(p["controller"].out.tau_com),
                "tau_e": sig(p["dfim"].out.tau_e),
                "v_s_mag": np.abs(v_s),
                "v_r_mag": np.abs(sig(p["converter"].out.v)),
                "i_s_mag": np.abs(i_s),
                "i_r_mag": np.abs(i_rr),
                "i_rx": i_x,
                "i_ry": i_y,
                "flags": self.flags(result, k),
                "i_r_com_mag": np.abs(i_r_com),
                "q_s": (v_s * np.conj(i_s)).imag,  # Bodson (5)
                "v_mismatch": np.abs(v_s - v_g) / np.maximum(np.abs(v_g), 1e-12),
                "theta_adj": sig(p["sync"].out.theta_adj),
                "m_adj": sig(p["sync"].out.m_adj),
                "phase": sig(p["sync"].out.closed),
                "mode": sig(p["controller"].out.mode),
                "relay_closed": sig(p["relay"].out.closed),
                "i_r_com_d": i_r_com.real,
                "i_r_com_q": i_r_com.imag,
                "i_r_d": i_r_f.real,
                "i_r_q": i_r_f.imag,
            }
            for j, name in enumerate(LOG_NAMES):
                signals[:, k, j] = columns[name]
        return DriveResult(
            name=self.setup.name,
            t=result.t,
            signals=signals,
            sample_time=self.setup.sample_time,
            final_state=result.final_state,
            wall_time=result.wall_time,
            compile_time=result.compile_time,
            compiled_now=result.compiled_now,
            tier=result.tier,
            tracking=tuple(tracking_rule(self.setup, k) for k in range(n)),
        )


def simulate(setup, divergence_hint=None) -> DriveResult:
    """Run ``setup`` on its parts-built system; ``SimulationDiverged`` names the time and, if
    ``divergence_hint(setup)`` is given, what to change."""
    drive = DFIMDrive(setup)
    try:
        result = drive.run()
    except SimulationDiverged as exc:
        if divergence_hint is None:
            raise
        raise SimulationDiverged(exc.time, divergence_hint(setup), setup.name) from None
    return drive.drive_result(result)


@checked(
    setup=Setup(),  # any drive's: require_setup names the drive
    method=Text(("RK4", "RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")),
    python_steps=Table(Function(), empty=True, optional=True), rtol=POSITIVE, atol=POSITIVE,
)
def simulate_slow(setup, method: str = "RK4", python_steps: dict | None = None,
                  rtol: float = 1e-10, atol: float = 1e-12) -> DriveResult:  # fmt: skip
    """Run ``setup`` on the slow path (``sim._reference``): the same compiled pieces stepped from
    Python, integrated by the loop's own RK4 (``method="RK4"``) or by ``solve_ivp`` (e.g.
    "Radau"); ``python_steps[part name]`` replaces a sampled part (e.g. ``"controller0"``) by a
    Python function with the signature of its compiled step."""
    from acdrive.drives._registry import get, require_setup
    from acdrive.sim._reference import simulate_reference

    require_setup(setup, get("dfim").setup_types, "acdrive.drives.simulate_slow")
    drive = DFIMDrive(setup)
    initial, held = drive.initial()
    result = simulate_reference(
        drive.compile(), setup.duration, setup.sample_time, initial=initial, held=held,
        log=drive.log_ports(), method=method, rtol=rtol, atol=atol, substeps=setup.substeps,
        python_steps=python_steps,
    )  # fmt: skip
    return drive.drive_result(result)
