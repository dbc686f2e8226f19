"""Typed description of a DFIM drive simulation.

``DriveSetup`` holds validated physical data (machines, supply, loads, sensors, controllers,
references); ``simulate`` runs it on the drive built from parts (``drives.dfim._drive``) and returns
a ``DriveResult``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from acdrive._arguments import COUNT, POSITIVE, TEXT, Instance, Items, Text, checked
from acdrive.drives._registry import Setup
from acdrive._frames import K_PEAK as SQRT_3_2  # Bodson (8): complex magnitude per peak value
from acdrive._toml import constant
from acdrive.control import _dfim as ctl
from acdrive.control._speed import SpeedPIGains
from acdrive.core._profile import Profile
from acdrive.drives.dfim._result import DriveResult
from acdrive.errors import InputError
from acdrive.machines._dfim import DFIMParams
from acdrive.plant._converter import max_voltage_magnitude


@dataclass(frozen=True)
class Supply:
    """Three-phase stator supply: peak line-neutral voltage and frequency profiles, behind a
    series R-L impedance shared by every motor on it (Bodson's transformer).

    ``phase_scales``: None for a balanced source, else the magnitude profiles (k_a, k_b, k_c) of
    the three phase EMFs as fractions of ``voltage_pk`` (``plant.UnbalancedSource``)."""

    voltage_pk: Profile = field(default_factory=lambda: constant(11.1))
    frequency_hz: Profile = field(default_factory=lambda: constant(60.0))
    resistance: float = 0.0
    inductance: float = 0.0
    phase_scales: tuple[Profile, Profile, Profile] | None = None


@dataclass(frozen=True)
class Synchroniser:
    """Grid synchronisation settings (Bodson (28), IV-A): the stator starts open when enabled."""

    enabled: bool = False
    gain: float = 40.0  # rate of the theta_adj / ln m_adj adjustments [1/s]
    tolerance_magnitude: float = 0.02  # |rho - 1| to close
    tolerance_phase: float = 0.035  # |phi| to close [rad] (2 degrees)
    hold_time: float = 0.02  # both tolerances met this long before closing [s]


@dataclass(frozen=True)
class DFIMController:
    """Controller settings (Bodson III-A to III-E, IV-A)."""

    gains: SpeedPIGains
    mode: str = "voltage"  # "voltage" or "current"
    current_bandwidth: float = 3142.0  # a_D,CUR [rad/s]
    R_T: float = 1.0  # [ohm], (47)
    reactive_power: float = 0.0
    reactive_power_kp: float = 0.0
    reactive_power_ki: float = 0.0
    stator_current_limit_pk: float = 6.0
    rotor_current_limit_pk: float = 6.0
    theta_adj: float = 0.0
    m_adj: float = 1.0
    speed_filter_tau: float = 0.0
    frequency_filter_tau: float = 0.01
    min_stator_voltage_pk: float = 1.0
    sync: Synchroniser = field(default_factory=Synchroniser)
    lossless_law: bool = False  # R_s = 0 law (39) with case-2 limits (40)-(42)
    params: DFIMParams | None = None  # controller's parameter estimates (default: the true ones)
    #: 0, or 1: the rotor-voltage command reaches the converter one sample later (the controller
    #: computes during the period; a ``ComputationDelay`` part between controller and converter)
    computation_delay_samples: int = 0

    def current_gains(self, machine: DFIMParams) -> tuple[float, float]:
        """(K_P,C, K_I,C) of (49) from the controller's parameter estimates."""
        p = self.params or machine
        return ctl.current_loop_gains(p.sigma, p.L_r, self.R_T, self.current_bandwidth)


@dataclass(frozen=True)
class ConverterLosses:
    """Non-ideal rotor converter: dead time t_d at switching frequency f_sw and a device voltage
    drop V_drop each cost a phase voltage Delta V = V_dc t_d f_sw + V_drop against the sign of the
    phase current; its fundamental is (4/pi) Delta V per phase, i.e. sqrt(3/2) (4/pi) Delta V as a
    space vector (Bodson (8)) opposing the rotor current. All zero (ideal) by default."""

    dead_time: float = 0.0
    switching_frequency: float = 0.0
    device_drop: float = 0.0

    def fundamental_loss(self, v_dc: float) -> float:
        delta_v = v_dc * self.dead_time * self.switching_frequency + self.device_drop
        return SQRT_3_2 * 4.0 / np.pi * delta_v


@dataclass(frozen=True)
class MotorSetup:
    """One DFIM with its load, sensors, converter, controller and speed reference.

    ``dc_link_voltage`` is the converter's nominal DC-link voltage (the controller's rotor-voltage
    limit and the converter loss are computed from it); ``dc_link_profile``, if given, is the DC
    link's voltage over time (``plant.DCSource``), which limits the applied rotor voltage,
    and starts at ``dc_link_voltage``. ``relay_forced_close_time``: the stator relay closes then
    whatever the synchroniser commands (a mis-operation; ``plant.ForcedRelay``)."""

    machine: DFIMParams
    controller: DFIMController
    speed_reference: Profile  # rad/s (mechanical) vs s
    load_torque: Profile = field(default_factory=lambda: constant(0.0))
    dc_link_voltage: float = 30.0
    converter: ConverterLosses = field(default_factory=lambda: ConverterLosses())
    encoder_counts_per_rev: float = 0.0
    encoder_offset: float = 0.0
    initial_speed: float = 0.0
    current_sensor_fault_time: float = np.inf  # current measurements fail from this time on
    dc_link_profile: Profile | None = None  # None: a constant dc_link_voltage
    relay_forced_close_time: float = np.inf  # inf: the relay follows the synchroniser

    @property
    def dc_link_min(self) -> float:
        """The lowest DC-link voltage of the run [V] (what the physical pre-checks use)."""
        if self.dc_link_profile is None:
            return self.dc_link_voltage
        return float(np.min(self.dc_link_profile[1]))


@checked(
    motors=Items(Instance(MotorSetup)), supply=Instance(Supply), duration=POSITIVE,
    sample_time=POSITIVE, substeps=COUNT, integrator=Text(("rk4", "rk6")), log_every=COUNT,
    name=TEXT, compare_modes=Items(Text(("voltage", "current")), empty=True), note=Text(empty=True),
)
@dataclass(frozen=True)
class DriveSetup:
    """A complete simulation: motors on one supply, sample time and duration."""

    motors: tuple[MotorSetup, ...]
    supply: Supply = field(default_factory=Supply)
    duration: float = 1.0
    sample_time: float = 200e-6
    substeps: int = 4
    integrator: str = "rk4"  # sim.INTEGRATORS
    log_every: int = 1
    name: str = "custom"
    compare_modes: tuple[str, ...] = ()  # run once per controller mode (Bodson Figs. 8-11)
    note: str = ""  # the scenario's own explanation, copied into the summary

    def with_mode(self, mode: str) -> DriveSetup:
        """The same drive with every controller in ``mode`` ("voltage" or "current")."""
        motors = tuple(
            dataclasses.replace(m, controller=dataclasses.replace(m.controller, mode=mode))
            for m in self.motors
        )
        return dataclasses.replace(self, motors=motors, compare_modes=())


def speed_range(motor: MotorSetup, supply: Supply) -> tuple[float, float]:
    """(lowest, highest) shaft speed [rad/s] the converter can hold at zero torque.

    The steady rotor voltage at i_s = 0 is (Z_R / Z_MS) v_s (Bodson (20)), about |slip| (L_r/M) v_s
    with slip s = (w_e - n_p w) / w_e; the converter gives at most V_dc / sqrt(2), so |s| <= s_max
    = V_dc / sqrt(2) / ((L_r/M) v_s), i.e. w_e (1 - s_max) / n_p <= w <= w_e (1 + s_max) / n_p:
    below zero speed the slip exceeds 1, so the negative bound is (w_e / n_p)(s_max - 1) in
    magnitude, not the positive one.

    The range is that of the nominal conditions: the supply voltage at t = 0, the DC link's nominal
    voltage, and the extremes of the supply frequency. A reference outside it could never be held;
    a fault that narrows the range for a while (a DC-link drop, a supply change) is simulated, and
    the converter's saturation is reported.
    """
    m = motor.machine
    v_s = SQRT_3_2 * float(supply.voltage_pk[1][0])
    f_low = float(np.min(supply.frequency_hz[1]))
    f_high = float(np.max(supply.frequency_hz[1]))
    slip_max = max_voltage_magnitude(motor.dc_link_voltage) / (m.L_r / m.M * v_s)
    return (
        2.0 * np.pi * f_low / m.n_p * (1.0 - slip_max),
        2.0 * np.pi * f_high / m.n_p * (1.0 + slip_max),
    )


def n_steps(setup: DriveSetup) -> int:
    return round(setup.duration / setup.sample_time)


#: RK4 is stable for h |lambda| below about 2.8 on the real axis; keep a margin
RK4_STEP_LIMIT = 2.5


def fastest_electrical_rate(setup: DriveSetup) -> float:
    """Rough magnitude [1/s] of the fastest electrical eigenvalue over the motors: the transient
    decay R / (sigma L) of stator or rotor plus the largest supply frequency (the rotation of the
    flux phasors in the stationary frame)."""
    w_e = 2.0 * np.pi * float(np.max(setup.supply.frequency_hz[1]))
    rates = []
    for motor in setup.motors:
        m = motor.machine
        rates.append(max(m.R_s / (m.sigma * m.L_s), m.R_r / (m.sigma * m.L_r)) + w_e)
    return max(rates)


def divergence_hint(setup: DriveSetup) -> str:
    """What to change in a scenario whose simulation diverged."""
    h = setup.sample_time / setup.substeps
    rate = fastest_electrical_rate(setup)
    if not np.isfinite(rate) or rate * setup.sample_time / RK4_STEP_LIMIT > 1e6:
        return (
            "the motor parameters give an electrical mode far too fast to integrate (R / (sigma L) "
            "of stator or rotor): check motor.params R_s, R_r, L_s, L_r and M"
        )
    if h * rate > RK4_STEP_LIMIT:
        need = int(np.ceil(setup.sample_time * rate / RK4_STEP_LIMIT))
        return (
            f"the integration step simulation.sample_time / simulation.substeps = {h:.3g} s is "
            f"too long for the machine's fastest electrical mode (about {rate:.0f} 1/s): raise "
            f"simulation.substeps to at least {need} or shorten simulation.sample_time"
        )
    j_min = min(m.machine.J for m in setup.motors)
    return (
        f"shorten simulation.sample_time (now {setup.sample_time:g} s) or raise "
        f"simulation.substeps (now {setup.substeps}); if that does not help, the drive itself "
        f"is unstable: check the motor inertia J (smallest {j_min:g} kg m^2; a tiny J makes the "
        f"shaft too fast for the sampled controller), controller.design_inertia and the "
        f"controller bandwidths"
    )


@checked(setup=Setup())  # any drive's: require_setup names the drive
def simulate(setup: DriveSetup) -> DriveResult:
    """Run ``setup`` on its parts-built system (``drives.dfim._drive``) and return its typed result.
    A DFIM setup only: another drive's setup is an ``InputError`` on ``setup`` pointing to
    ``acdrive.drives.run_scenario``, which runs any drive's.

    Raises ``SimulationDiverged`` (a RuntimeError) with the time and a hint of what to change if
    the state stops being finite (a simulation never returns NaN silently).
    """
    from acdrive.drives._registry import require_setup
    from acdrive.drives.dfim import _drive as dfim_drive

    require_setup(setup, (DriveSetup,), "acdrive.drives.simulate")
    return dfim_drive.simulate(setup, divergence_hint)


#: a supply voltage or load torque this many times beyond what the machine and its limits allow
#: is not a study of an overload (which runs, and the summary reports what happened) but a wrong
#: number or unit, refused naming that input
IMPLAUSIBLE_FACTOR = 10.0


def peak_torque_window(motor: MotorSetup, supply: Supply) -> tuple[float, float]:
    """(tau_lo, tau_hi) [N m]: the torque window of Bodson case 1 ((30), (32), (37)) at the
    nominal supply (voltage and frequency at t = 0) and the controller's current limits, the
    torques the drive can hold (tau_lo < 0 generating)."""
    from acdrive.machines._dfim import machine_vector, torque_window

    c = motor.controller
    v_s = SQRT_3_2 * float(supply.voltage_pk[1][0])
    w_e = 2.0 * np.pi * float(supply.frequency_hz[1][0])
    lo, hi, _ = torque_window(
        machine_vector(motor.machine), w_e, v_s,
        SQRT_3_2 * c.stator_current_limit_pk, SQRT_3_2 * c.rotor_current_limit_pk,
    )  # fmt: skip
    return float(lo), float(hi)


def _check_magnetising(k: int, motor: MotorSetup, supply: Supply) -> None:
    """The rotor must carry the magnetising current v_s / (w_e M) the supply needs at zero torque
    (Bodson (33)); far beyond both the rotor and the stator current limit the supply voltage is
    the input at fault, else the rotor current limit."""
    v_pk = float(np.max(supply.voltage_pk[1]))
    f_min = float(np.min(supply.frequency_hz[1]))
    magnetising_pk = v_pk / (2.0 * np.pi * f_min * motor.machine.M)
    limit = motor.controller.rotor_current_limit_pk
    if limit > magnetising_pk:
        return
    need = (
        f"the magnetising current the stator supply needs, supply.voltage_pk / (2 pi "
        f"supply.frequency_hz M) = {magnetising_pk:.4g} A peak (at {v_pk:g} V, {f_min:g} Hz)"
    )
    largest = max(limit, motor.controller.stator_current_limit_pk)
    if magnetising_pk > IMPLAUSIBLE_FACTOR * largest:  # both current limits far below it
        raise InputError(
            "supply.voltage_pk",
            f"{need} is more than {IMPLAUSIBLE_FACTOR:g} times motor[{k}]'s current limits "
            f"(rotor {limit:g} A, stator {motor.controller.stator_current_limit_pk:g} A): the "
            "supply voltage is far above what this machine can be magnetised from (Bodson (33))",
        )
    raise InputError(
        f"motor[{k}].controller.rotor_current_limit_pk", f"must exceed {need}",
    )  # fmt: skip


def _check_load(k: int, motor: MotorSetup, supply: Supply) -> None:
    """A load torque more than IMPLAUSIBLE_FACTOR times the largest torque of the drive's torque
    window (:func:`peak_torque_window`) is refused naming the load."""
    lo, hi = peak_torque_window(motor, supply)
    largest = max(hi, -lo)
    load = float(np.max(np.abs(motor.load_torque[1])))
    if largest > 0.0 and load > IMPLAUSIBLE_FACTOR * largest:
        raise InputError(
            f"motor[{k}].load_torque",
            f"|load torque| up to {load:g} N m is more than {IMPLAUSIBLE_FACTOR:g} times the "
            f"largest torque the drive can produce, {largest:.4g} N m (the torque window of "
            "Bodson (30), (32), (37) at the nominal supply and the controller's current "
            "limits): check its value and unit (N m)",
        )


def _check_dc_link(k: int, motor: MotorSetup, supply: Supply) -> None:
    """A speed reference out of the converter's range (:func:`speed_range`) because the DC link
    is far too low: the DC link the reference needs, sqrt(2) |s| (L_r / M) v_s at its largest
    slip s, is more than IMPLAUSIBLE_FACTOR times the one given; then the DC link is named."""
    m = motor.machine
    v_s = SQRT_3_2 * float(supply.voltage_pk[1][0])
    w_e = 2.0 * np.pi * float(supply.frequency_hz[1][0])
    slip = float(np.max(np.abs(w_e - m.n_p * motor.speed_reference[1]))) / w_e
    needed = float(np.sqrt(2.0)) * slip * m.L_r / m.M * v_s
    if needed > IMPLAUSIBLE_FACTOR * motor.dc_link_voltage:
        raise InputError(
            f"motor[{k}].dc_link_voltage",
            f"{motor.dc_link_voltage:g} V: the speed reference reaches a slip of {slip:.3g}, for "
            f"which the rotor converter needs a DC link of about sqrt(2) |s| (L_r / M) v_s = "
            f"{needed:.4g} V (Bodson (20) at zero torque), more than {IMPLAUSIBLE_FACTOR:g} "
            "times the one given",
        )


def check_setup(setup: DriveSetup) -> None:
    """Cross-field rules that single fields cannot express (raises InputError)."""
    for k, motor in enumerate(setup.motors):
        # the rotor must be able to carry the magnetising current v_s / (w_e M) at zero torque (33)
        _check_magnetising(k, motor, setup.supply)
        low, high = speed_range(motor, setup.supply)
        v_pk = float(setup.supply.voltage_pk[1][0])
        rule = (
            f"must stay within {low * 30 / np.pi:.0f} to {high * 30 / np.pi:.0f} rpm (the "
            "converter's rotor-voltage limit at the nominal supply and DC link: "
            f"dc_link_voltage {motor.dc_link_voltage:g} V against supply.voltage_pk {v_pk:g} V)"
        )
        ref = motor.speed_reference[1]
        if np.min(ref) < low or np.max(ref) > high:
            _check_dc_link(k, motor, setup.supply)
            raise InputError(f"motor[{k}].speed_reference_rpm", rule)
        # a motor connected at t = 0 starts in steady state at its initial speed; a synchronising
        # one starts with its stator open, and the summary reports a relay that cannot close
        if not motor.controller.sync.enabled and not low <= motor.initial_speed <= high:
            raise InputError(f"motor[{k}].initial_speed_rpm", rule)
        _check_load(k, motor, setup.supply)
    if setup.substeps < 1:
        raise InputError("simulation.substeps", "must be an integer >= 1")
