"""Small-signal stability of the whole DFIM speed drive at an operating point (shaft speed, load).

The closed loop of Bodson's drive is linearised around its equilibrium: machine (9) with the
mechanics (26) (load torque, viscous friction, the true inertia J), the supply behind its optional
series R-L impedance (the test bench's transformer), the speed PI (25) with its integrator and
gains from (27), and the torque controller in either mode:

* ``voltage``: stator current command (22) and the rotor voltage of the steady-state law (20),
  evaluated with the measured speed and the measured stator voltage (Bodson III-A, Fig. 2);
* ``current``: rotor current command (43) from the same stator current command, and the rotor
  current loop (45)-(47) with its integrator and the gains (49) (Bodson III-E).

Both linearisations use the simulator's parts-built drive (``acdrive.drives.DFIMDrive``)
and its compiled loop; they are kept clearly apart:

``continuous``  the controller as the continuous-time law of the paper, evaluated with the
                functions the sampled controller uses (``machines._dfim``, ``control._speed.speed_pi``,
                ``control._bodson.rotor_current_loop`` with the ``SpeedController`` part's parameter
                and state arrays). The plant is the compiled system's own right-hand side
                (``derivatives``) with the converter's output held at the law's rotor voltage and
                the relay closed, evaluated in the frame that rotates with the supply (the
                stator-voltage frame when the supply has no impedance), with the flux linkages
                psi_s, psi_r as states. The Jacobian is taken by central differences around the
                equilibrium found by Newton (``acdrive.analysis._linearise``).
``sampled``     the sampled-data loop exactly as the compiled simulator runs it: one sample of the
                compiled loop (project, plant outputs, the sampled parts in wiring order: encoder,
                current sensors, speed and supply-frequency estimators, reference, synchroniser,
                speed controller; the converter's zero-order hold of the rotor voltage in rotor
                coordinates; the RK4 substeps of the plant), optionally with the command applied
                one sample later (computation delay, inserted between controller and converter).
                The result is the Jacobian of this one-sample map at its fixed point; its
                eigenvalues z are reported also as s = ln(z) / T_s for comparison with the
                continuous model.

Units: SI (speeds in rad/s unless the name ends in ``_rpm``); complex space vectors in the
power-invariant scaling of Bodson (1)-(8).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from acdrive._frames import K_PEAK as SQRT_3_2  # Bodson (8): space-vector magnitude per peak
from acdrive.analysis._linearise import (
    Coordinate,
    SampleMap,
    fixed_point,
    get_complex,
    jacobian,
    newton,
    set_complex,
    slot,
)
from acdrive.control._bodson import rotor_current_loop
from acdrive.control._speed import SpeedPIGains, speed_pi
from acdrive.drives.dfim._drive import DFIMDrive
from acdrive.drives.dfim._setup import (
    ConverterLosses,
    DFIMController,
    DriveSetup,
    MotorSetup,
    Supply,
    constant,
)
from acdrive.drives.dfim._setup import (
    speed_range as setup_speed_range,
)
from acdrive.errors import InputError, require_finite, require_nonnegative, require_positive
from acdrive.machines._dfim import (
    BODSON_DFIM,
    DFIMParams,
    machine_vector,
    rotor_current_for,
    rotor_voltage_for,
    stator_current_command,
    torque_window,
)
from acdrive.plant._converter import max_voltage_magnitude

RAD_S_PER_RPM = math.pi / 30.0
MODES = ("voltage", "current")
KINDS = ("continuous", "sampled")
SPEED_LOOPS = ("closed", "open", "frozen")
#: |z| below this is a structural zero of the sampled map (a state overwritten every sample)
Z_ZERO = 1e-9


@dataclass(frozen=True)
class DriveModel:
    """A parameter study's shorthand for a one-motor DFIM drive on Bodson's bench: it builds the
    ``DriveSetup`` the linearisation takes (:func:`drive_setup`); the linearisation itself reads
    only that setup (:class:`DriveView`). Varying one bench effect is then one field:

    machine: the true machine (its J and viscous friction B enter the mechanics (26));
    controller_params: the controller's estimates (default: the true values);
    speed_bandwidth: a_D,VEL of (27) [rad/s]; design_inertia: the J used in (27) (default:
    machine.J, so a larger true J than designed is machine.J > design_inertia); K_F: (25);
    current_bandwidth, R_T: a_D,CUR and R_T of (49); supply_*: peak line-neutral voltage,
    frequency and the series R-L impedance in front of the stator (the controller then sees the
    measured stator terminal voltage); speed_filter_tau: first-order filter on the measured speed;
    current_limit_pk: stator and rotor current limits (peak) for the torque window (30)-(37);
    speed_loop: "closed" (PI (25) active), "open" (torque command held at its equilibrium value,
    mechanics free) or "frozen" (torque command held and speed constant: electrical loop only);
    sample_time, substeps, delay_samples: the sampled model (the compiled loop's sample period, its
    RK4 substeps per period, 0 or 1 sample of computation delay);
    converter_loss: fundamental voltage [V, space-vector magnitude] the rotor converter loses
    against the rotor current (dead time, device drops), v_R,applied = v_R - V i_R/|i_R|: the
    simulator's first-harmonic converter model (``ConverterLosses``), given here by its result.
    """

    mode: str = "voltage"
    machine: DFIMParams = BODSON_DFIM
    controller_params: DFIMParams | None = None
    speed_bandwidth: float = 314.0
    design_inertia: float | None = None
    K_F: float = 2.0 / 3.0
    current_bandwidth: float = 3142.0
    R_T: float = 1.0
    supply_voltage_pk: float = 11.1
    supply_frequency_hz: float = 60.0
    supply_resistance: float = 0.0
    supply_inductance: float = 0.0
    speed_filter_tau: float = 0.0
    current_limit_pk: float = 6.0
    speed_loop: str = "closed"
    sample_time: float = 200e-6
    substeps: int = 4
    delay_samples: int = 0
    converter_loss: float = 0.0

    def __post_init__(self):
        if self.mode not in MODES:
            raise InputError("mode", f"must be one of {', '.join(MODES)}")
        if self.speed_loop not in SPEED_LOOPS:
            raise InputError("speed_loop", f"must be one of {', '.join(SPEED_LOOPS)}")
        for name in (
            "speed_bandwidth",
            "current_bandwidth",
            "R_T",
            "supply_voltage_pk",
            "supply_frequency_hz",
            "current_limit_pk",
            "sample_time",
        ):
            object.__setattr__(self, name, require_positive(name, getattr(self, name)))
        for name in (
            "K_F",
            "supply_resistance",
            "supply_inductance",
            "speed_filter_tau",
            "converter_loss",
        ):
            object.__setattr__(self, name, require_nonnegative(name, getattr(self, name)))
        if self.design_inertia is not None:
            object.__setattr__(
                self, "design_inertia", require_positive("design_inertia", self.design_inertia)
            )
        if self.delay_samples not in (0, 1):
            raise InputError("delay_samples", "must be 0 or 1")
        if (
            isinstance(self.substeps, bool)
            or not isinstance(self.substeps, int)
            or self.substeps < 1
        ):
            raise InputError("substeps", "must be an integer >= 1")

    # --- derived quantities ------------------------------------------------------------------
    @property
    def gains(self) -> SpeedPIGains:
        """K_P = 2 a J, K_I = a^2 J (27) with the design inertia, and K_F."""
        J = self.design_inertia or self.machine.J
        return dataclasses.replace(SpeedPIGains.design(J, self.speed_bandwidth), K_F=self.K_F)


@dataclass(frozen=True)
class OperatingPoint:
    """Shaft speed [rad/s] and load torque [N m] (the non-inertial load of (26), friction apart)."""

    speed: float
    load_torque: float = 0.0

    @property
    def speed_rpm(self) -> float:
        return self.speed / RAD_S_PER_RPM


class DriveView:
    """What the linearisation reads of a DFIM ``DriveSetup``, computed from it (never a copy of
    its fields): motor 0 of ``setup`` held at ``point`` (:func:`operating_setup`) and the speed
    loop's state (``"closed"``, ``"open"``, ``"frozen"``, as :class:`DriveModel`'s).

    ``setup`` is the drive the linearisation builds (``acdrive.drives.get("dfim").build``) and
    compiles; the properties below are read from its motor, controller and supply.
    """

    def __init__(self, setup: DriveSetup, point: OperatingPoint, speed_loop: str = "closed"):
        if speed_loop not in SPEED_LOOPS:
            raise InputError("speed_loop", f"must be one of {', '.join(SPEED_LOOPS)}")
        self.setup = operating_setup(setup, point)
        self.point, self.speed_loop = point, speed_loop
        self.motor = self.setup.motors[0]
        self.controller = self.motor.controller

    mode = property(lambda self: self.controller.mode)
    machine = property(lambda self: self.motor.machine)
    #: the controller's parameter estimates (None: the true machine's)
    controller_params = property(lambda self: self.controller.params)
    gains = property(lambda self: self.controller.gains)
    R_T = property(lambda self: self.controller.R_T)
    speed_filter_tau = property(lambda self: self.controller.speed_filter_tau)
    supply_resistance = property(lambda self: self.setup.supply.resistance)
    sample_time = property(lambda self: self.setup.sample_time)
    substeps = property(lambda self: self.setup.substeps)

    @property
    def current_gains(self) -> tuple[float, float]:
        """(K_P,C, K_I,C) of Bodson (49) from the controller's estimates."""
        return self.controller.current_gains(self.machine)

    @property
    def w_e(self) -> float:
        return 2.0 * math.pi * float(self.setup.supply.frequency_hz[1][0])

    @property
    def v_g(self) -> float:
        """Grid space-vector magnitude sqrt(3/2) V_pk (Bodson (8))."""
        return SQRT_3_2 * float(self.setup.supply.voltage_pk[1][0])

    @property
    def i_s_max(self) -> float:
        return SQRT_3_2 * self.controller.stator_current_limit_pk

    @property
    def i_r_max(self) -> float:
        return SQRT_3_2 * self.controller.rotor_current_limit_pk


def operating_setup(setup: DriveSetup, point: OperatingPoint) -> DriveSetup:
    """Motor 0 of ``setup`` alone on its supply, held at ``point``, as the linearisation sees it:
    speed reference and initial speed at the operating speed, the load constant, the supply
    constant at its values at t = 0 (balanced), the stator connected (no synchronisation), an
    ideal encoder resolution (a quantiser has no derivative), no sensor fault, a constant DC
    link, no forced relay. The encoder offset stays unless the setup synchronises: the
    synchroniser then has identified it (Bodson IV-A) and the connected drive runs as without. Everything else (machine, controller, estimates,
    converter, computation delay, sample time, substeps, integrator) is the setup's."""
    motor = setup.motors[0]
    supply = setup.supply
    controller = dataclasses.replace(
        motor.controller, sync=dataclasses.replace(motor.controller.sync, enabled=False)
    )
    motor = dataclasses.replace(
        motor, controller=controller, speed_reference=constant(point.speed),
        load_torque=constant(point.load_torque), initial_speed=point.speed,
        encoder_counts_per_rev=0.0, current_sensor_fault_time=math.inf, dc_link_profile=None,
        encoder_offset=0.0 if motor.controller.sync.enabled else motor.encoder_offset,
        relay_forced_close_time=math.inf,
    )  # fmt: skip
    supply = dataclasses.replace(
        supply, voltage_pk=constant(float(supply.voltage_pk[1][0])),
        frequency_hz=constant(float(supply.frequency_hz[1][0])), phase_scales=None,
    )  # fmt: skip
    return dataclasses.replace(setup, motors=(motor,), supply=supply, duration=1.0,
                               name="stability", compare_modes=(), log_every=1)  # fmt: skip


def view_of(study, point: OperatingPoint, speed_loop: str | None = None) -> DriveView:
    """The :class:`DriveView` of ``study`` (a DFIM ``DriveSetup``, or a :class:`DriveModel`, which
    builds its setup with :func:`drive_setup`) at ``point``; ``speed_loop`` defaults to the
    model's (closed for a setup)."""
    if isinstance(study, DriveView):
        return study
    if isinstance(study, DriveModel):
        return DriveView(drive_setup(study, point), point, speed_loop or study.speed_loop)
    if isinstance(study, DriveSetup):
        return DriveView(study, point, speed_loop or "closed")
    raise InputError(
        "setup", "must be a DFIM DriveSetup (acdrive.drives.DriveSetup) or a DriveModel"
    )


@dataclass(frozen=True)
class StabilityResult:
    """Eigenvalues of the linearised closed loop at one operating point.

    eigenvalues: s-plane values [rad/s] (for ``sampled``: ln(z) / T_s of the non-zero z);
    z_eigenvalues: the eigenvalues of the one-sample map (``sampled`` only, else empty);
    max_real_part: largest real part of ``eigenvalues`` [1/s]; stable: all strictly in the open
    left half plane (continuous) or inside the unit circle (sampled);
    torque_command: tau_COM at the equilibrium; within_limits: tau_COM inside the on-line torque
    window (30)-(37), rotor current inside its limit and rotor voltage inside the converter's
    range (otherwise the real controller would be clipping and the linearisation does not
    describe it); state: the equilibrium state vector; state_names: its entries.
    """

    model: object  # the DriveSetup or DriveModel linearised
    point: OperatingPoint
    kind: str
    eigenvalues: np.ndarray
    z_eigenvalues: np.ndarray
    max_real_part: float
    stable: bool
    torque_command: float
    within_limits: bool
    state: np.ndarray = field(repr=False)
    state_names: tuple[str, ...] = field(repr=False)
    jacobian: np.ndarray = field(repr=False)
    view: DriveView | None = field(default=None, repr=False)  # what was linearised

    def to_control(self):
        """The linearised closed drive as a python-control ``StateSpace`` (continuous, or
        discrete with dt = T_s for ``sampled``): inputs ``w_ref`` [rad/s] and ``tau_L`` [N m],
        outputs ``w`` [rad/s] and the currents ``i_s``, ``i_r`` [A] (``_re``/``_im``, supply
        frame), states ``state_names`` (``.`` written ``_``, as python-control requires); its poles are ``eigenvalues`` (``z_eigenvalues``)
        (``analysis._drive_control``)."""
        from acdrive.analysis._drive_control import to_control

        return to_control(self)

    @property
    def dominant(self) -> complex:
        """The eigenvalue with the largest real part (s-plane), upper half plane if a pair."""
        re = self.eigenvalues.real
        top = self.eigenvalues[np.isclose(re, re.max(), rtol=1e-9, atol=1e-9)]
        return complex(top[np.argmax(top.imag)])


# ---------------------------------------------------------------------------------------------
# validation of an operating point
# ---------------------------------------------------------------------------------------------


def speed_range(study) -> tuple[float, float]:
    """(lowest, highest) speed [rad/s] the drive can hold (converter rotor-voltage limit,
    ``drives.dfim._setup.speed_range``)."""
    view = view_of(study, OperatingPoint(0.0))
    return setup_speed_range(view.motor, view.setup.supply)


def check_point(model, point: OperatingPoint) -> None:
    """Raise InputError unless ``point`` is finite, inside the speed range, with a load torque
    (plus friction) inside the torque window of the controller (30)-(37); ``model``: a
    ``DriveSetup``, a :class:`DriveModel` or their :class:`DriveView`."""
    w = require_finite("speed", point.speed)
    model = view_of(model, OperatingPoint(w, require_finite("load_torque", point.load_torque)))
    tau_l = require_finite("load_torque", point.load_torque)
    low, high = speed_range(model)
    if not low <= w <= high:
        raise InputError(
            "speed",
            f"must stay within {low / RAD_S_PER_RPM:.0f} to {high / RAD_S_PER_RPM:.0f} rpm",
        )
    lo, hi = _torque_window(model, model.v_g)
    need = tau_l + model.machine.B * w
    if not lo < need < hi:
        raise InputError(
            "load_torque",
            f"load plus friction {need:.3f} N m is outside the torque window [{lo:.3f}, {hi:.3f}] N m",
        )


def _torque_window(model: DriveView, v_s: float) -> tuple[float, float]:
    p_est = machine_vector(model.controller_params or model.machine)
    lo, hi, _ = torque_window(p_est, model.w_e, v_s, model.i_s_max, model.i_r_max)
    return lo, hi


# ---------------------------------------------------------------------------------------------
# the simulator's drive at an operating point
# ---------------------------------------------------------------------------------------------


def _supply(model: DriveModel) -> Supply:
    return Supply(
        voltage_pk=constant(model.supply_voltage_pk),
        frequency_hz=constant(model.supply_frequency_hz),
        resistance=model.supply_resistance,
        inductance=model.supply_inductance,
    )


def _motor_setup(model: DriveModel, point: OperatingPoint) -> MotorSetup:
    return MotorSetup(
        machine=model.machine,
        controller=DFIMController(
            gains=model.gains,
            mode=model.mode,
            current_bandwidth=model.current_bandwidth,
            R_T=model.R_T,
            stator_current_limit_pk=model.current_limit_pk,
            rotor_current_limit_pk=model.current_limit_pk,
            speed_filter_tau=model.speed_filter_tau,
            params=model.controller_params,
            computation_delay_samples=model.delay_samples,
        ),
        speed_reference=constant(point.speed),
        load_torque=constant(point.load_torque),
        initial_speed=point.speed,
        converter=converter_losses(model.converter_loss),
    )


def converter_losses(fundamental_loss: float) -> ConverterLosses:
    """The simulator's converter model with a given fundamental loss [V]: a device drop only
    (``ConverterLosses.fundamental_loss`` is sqrt(3/2) (4/pi) times the per-phase loss)."""
    per_phase = fundamental_loss / (SQRT_3_2 * 4.0 / math.pi)
    return ConverterLosses(device_drop=per_phase)


def drive_setup(model: DriveModel, point: OperatingPoint, duration: float = 1.0) -> DriveSetup:
    """The simulator's ``DriveSetup`` for ``model`` held at ``point``: speed reference and
    initial speed at the operating speed, constant load torque."""
    return DriveSetup(
        motors=(_motor_setup(model, point),),
        supply=_supply(model),
        duration=duration,
        sample_time=model.sample_time,
        substeps=model.substeps,
        name="stability",
    )


def _drive(model: DriveView) -> DFIMDrive:
    """The DFIM drive's own build of the view's setup (one motor: parts ``dfim0``, ``shaft0``,
    ..., ``controller0``, and ``grid``, ``bus``), through the registry."""
    from acdrive.drives import get

    return get("dfim").build(model.setup)


def _rotor_voltage_limit(drive: DFIMDrive) -> float:
    """The largest rotor voltage magnitude the drive's converter applies (V_dc / sqrt(2))."""
    return max_voltage_magnitude(drive.motors[0]["converter"].values["V_dc"])


class _Plant:
    """The compiled plant right-hand side of the drive (``derivatives`` of the generated loop),
    with the converter's output held at a given rotor voltage and the relay closed.

    The supply angle theta_g and the rotor angle are zero at the instant of evaluation: the
    stationary frame is then the frame that rotates with the supply (v_g real), rotor coordinates
    coincide with it, and the supply-frame derivatives are the stationary ones minus j w_e x.
    """

    def __init__(self, model: DriveView):
        self.drive = drive = _drive(model)
        system, parts = drive.system, drive.motors[0]
        self.parts, self.module = parts, drive.compile().module
        self.P, self.PO = system.pack_params()
        self.X, _ = system.pack_initial()  # angles zero, phasors e^{j 0}
        self.Y = system.pack_held({parts["sync"].name: {"closed": 1.0}})
        self.U = np.zeros(system.sizes["u"])
        self.dX = np.empty_like(self.X)
        dfim, shaft = parts["dfim"], parts["shaft"]
        self.i_psi_s = slot(system, dfim, "x", "psi_s")
        self.i_psi_r = slot(system, dfim, "x", "psi_r")
        self.i_w = slot(system, shaft, "x", "w")
        self.i_v_r = slot(system, parts["converter"], "y", "v")
        self.i_v_s = slot(system, parts["relay"], "y", "v")  # what the controller measures
        self.i_i_s = slot(system, dfim, "y", "i_s")
        self.i_i_r = slot(system, dfim, "y", "i_r")
        self.w_e = model.w_e

    def load(self, psi_s: complex, psi_r: complex, w: float) -> None:
        """Set the fluxes and the speed (angles stay zero) and evaluate the plant outputs."""
        X = self.X
        set_complex(X, self.i_psi_s, psi_s)
        set_complex(X, self.i_psi_r, psi_r)
        X[self.i_w] = w
        self.module.project(X, self.P, self.PO)
        self.module.plant_outputs(0.0, X, self.P, self.PO, self.Y, self.U)

    def evaluate(self, v_r: complex):
        """(d psi_s/dt, d psi_r/dt, dw/dt) in the supply frame and the stator terminal voltage,
        for the state last given to ``load`` and the rotor voltage ``v_r`` (supply frame)."""
        X, dX = self.X, self.dX
        set_complex(self.Y, self.i_v_r, v_r)
        self.module.derivatives(0.0, X, self.P, self.PO, self.Y, self.U, dX)
        psi_s, psi_r = get_complex(X, self.i_psi_s), get_complex(X, self.i_psi_r)
        dpsi_s = get_complex(dX, self.i_psi_s) - 1j * self.w_e * psi_s
        dpsi_r = get_complex(dX, self.i_psi_r) - 1j * self.w_e * psi_r
        return dpsi_s, dpsi_r, dX[self.i_w], get_complex(self.Y, self.i_v_s)

    def terminal_voltage(self, v_r: complex) -> complex:
        return self.evaluate(v_r)[3]

    def currents(self) -> tuple[complex, complex]:
        """(i_s, i_r) of the loaded state: the machine part's outputs (flux-current relation (9))."""
        return get_complex(self.Y, self.i_i_s), get_complex(self.Y, self.i_i_r)


def fluxes(params: DFIMParams, i_s: complex, i_r: complex) -> tuple[complex, complex]:
    """psi_s = L_s i_s + M i_r, psi_r = M i_s + L_r i_r (Bodson (9))."""
    return params.L_s * i_s + params.M * i_r, params.M * i_s + params.L_r * i_r


# ---------------------------------------------------------------------------------------------
# continuous-time controller laws (Bodson (20)+(22); (22)+(43)+(45)-(47))
# ---------------------------------------------------------------------------------------------


def _voltage_law(p, w_e, w_hat, v_s_mag, tau_com):
    """Rotor voltage (20) for the stator current command (22) with Q = 0 (stator-voltage frame);
    ``p``: the controller's parameter array (its machine estimates)."""
    i_s_com, _ = stator_current_command(p, w_e, v_s_mag, tau_com, 0.0)
    return rotor_voltage_for(p, w_e, w_hat, v_s_mag, i_s_com)


def _current_law(p, s, i_int, w_e, w_hat, v_s_mag, tau_com, i_s, i_r, z):
    """Rotor current loop (46)-(47) around the command (43), continuous time; returns
    (v_r, d z / dt) in the stator-voltage frame, z being the integral of the current error.

    The sampled controller's own ``rotor_current_loop`` (control._bodson) is evaluated on the
    ``SpeedController``'s parameter array ``p`` without voltage limit (prepared so by the caller)
    and its state array ``s`` (the integral at ``s[i_int]``), with a unit step: one forward-Euler
    step of length 1 then returns the integrand, d z / dt = (z after the step) - z.
    """
    i_s_com, _ = stator_current_command(p, w_e, v_s_mag, tau_com, 0.0)
    i_r_com = rotor_current_for(p, w_e, v_s_mag, i_s_com)
    set_complex(s, i_int, z)
    v_r, _ = rotor_current_loop(p, s, 1.0, w_e, w_hat, v_s_mag, i_s, i_r, i_r_com)
    return v_r, get_complex(s, i_int) - z


# ---------------------------------------------------------------------------------------------
# continuous-time closed loop
# ---------------------------------------------------------------------------------------------


class _Continuous:
    """Right-hand side of the continuous closed loop in the supply frame.

    State: Re/Im psi_s, Re/Im psi_r, [w], [e_I], [w_f], [Re/Im z]: speed unless frozen, speed-PI
    integrator if the speed loop is closed, speed-filter state if speed_filter_tau > 0, rotor
    current-loop integrator in current mode.
    """

    def __init__(self, model: DriveView):
        self.model, self.point = model, model.point
        self.plant = _Plant(model)
        ctrl = self.plant.parts["controller"]
        # the SpeedController part's arrays: parameters (machine estimates, gains) and a state
        # for the current loop's integral; no voltage limit in the continuous law (see
        # _current_law)
        self.p = ctrl.p
        self.p_unlimited = ctrl.p.copy()
        self.p_unlimited[ctrl.PARAMS.slot("v_r_max")] = np.inf
        self.s = ctrl.initial_state()
        self.i_int = ctrl.STATES.slot("ir_int")
        self.K_P, self.K_I, self.K_F = (ctrl.values[n] for n in ("K_P", "K_I", "K_F"))
        names = ["psi_s.re", "psi_s.im", "psi_r.re", "psi_r.im"]
        if model.speed_loop != "frozen":
            names.append("w")
        if model.speed_loop == "closed":
            names.append("e_I")
        if model.speed_filter_tau > 0.0:
            names.append("w_f")
        if model.mode == "current":
            names += ["z.re", "z.im"]
        self.names = tuple(names)
        self.tau_hold = 0.0
        self.w_ref = model.point.speed  # the speed reference (an input of ``to_control``)

    def unpack(self, x):
        s = dict(zip(self.names, x))
        w = s.get("w", self.point.speed)
        return (
            complex(s["psi_s.re"], s["psi_s.im"]),
            complex(s["psi_r.re"], s["psi_r.im"]),
            w,
            s.get("e_I", 0.0),
            s.get("w_f", w),
            complex(s.get("z.re", 0.0), s.get("z.im", 0.0)),
        )

    def torque_command(self, x) -> float:
        """The speed PI (25) without limits (the controller's own ``speed_pi``)."""
        _, _, _, e_I, w_f, _ = self.unpack(x)
        if self.model.speed_loop != "closed":
            return self.tau_hold
        return speed_pi(self.K_P, self.K_I, self.K_F, e_I, self.w_ref, w_f, -np.inf,
                        np.inf, 1.0)[0]  # fmt: skip

    def rhs(self, x) -> np.ndarray:
        m, plant = self.model, self.plant
        psi_s, psi_r, w, _, w_f, z = self.unpack(x)
        tau = self.torque_command(x)
        plant.load(psi_s, psi_r, w)
        i_s, i_r = plant.currents()
        # the controller uses the measured stator terminal voltage, which depends on the rotor
        # voltage through the supply inductance: solve this algebraic loop by fixed-point iteration
        v_s = m.v_g - m.supply_resistance * i_s
        for _ in range(200):
            v_r, dz = self._law(v_s, w_f, tau, i_s, i_r, z)
            v_new = plant.terminal_voltage(v_r)
            change = abs(v_new - v_s)
            v_s = v_new
            if change <= 1e-15 * m.v_g:
                break
        else:
            raise RuntimeError("the measured stator voltage does not converge (supply inductance)")
        v_r, dz = self._law(v_s, w_f, tau, i_s, i_r, z)
        dpsi_s, dpsi_r, dw, _ = plant.evaluate(v_r)
        self.last_dw = dw  # the torque balance (26), also when the speed is frozen
        self.last_v_s, self.last_v_r = v_s, v_r
        out = {
            "psi_s.re": dpsi_s.real,
            "psi_s.im": dpsi_s.imag,
            "psi_r.re": dpsi_r.real,
            "psi_r.im": dpsi_r.imag,
            "w": dw,
            "e_I": self.w_ref - w_f,
            "w_f": (w - w_f) / m.speed_filter_tau if m.speed_filter_tau > 0 else 0.0,
            "z.re": dz.real,
            "z.im": dz.imag,
        }
        return np.array([out[n] for n in self.names])

    def _law(self, v_s, w_hat, tau, i_s, i_r, z):
        """Rotor voltage in the supply frame: the law in the measured stator-voltage frame."""
        m = self.model
        v_mag = abs(v_s)
        to_supply = v_s / v_mag
        if m.mode == "voltage":
            return _voltage_law(self.p, m.w_e, w_hat, v_mag, tau) * to_supply, 0j
        v_r, dz = _current_law(self.p_unlimited, self.s, self.i_int, m.w_e, w_hat, v_mag, tau,
                               i_s / to_supply, i_r / to_supply, z)  # fmt: skip
        return v_r * to_supply, dz

    def guess(self) -> np.ndarray:
        """Equilibrium of the drive with exact controller parameters and no supply impedance."""
        m, pt = self.model, self.point
        p = machine_vector(m.machine)
        tau = pt.load_torque + m.machine.B * pt.speed
        self.tau_hold = tau
        i_s, _ = stator_current_command(p, m.w_e, m.v_g, tau, 0.0)
        i_r = rotor_current_for(p, m.w_e, m.v_g, i_s)
        psi_s, psi_r = fluxes(m.machine, i_s, i_r)
        g = m.gains
        e_I = (tau - g.K_F * g.K_P * pt.speed + g.K_P * pt.speed) / g.K_I
        z = m.R_T * i_r / m.current_gains[1]
        values = {
            "psi_s.re": psi_s.real,
            "psi_s.im": psi_s.imag,
            "psi_r.re": psi_r.real,
            "psi_r.im": psi_r.imag,
            "w": pt.speed,
            "e_I": e_I,
            "w_f": pt.speed,
            "z.re": z.real,
            "z.im": z.imag,
        }
        return np.array([values[n] for n in self.names])

    def scales(self) -> np.ndarray:
        m = self.model
        psi = m.v_g / m.w_e
        scale = {"w": 100.0, "e_I": 0.1, "w_f": 100.0}
        return np.array([scale.get(n, psi if n.startswith("psi") else 0.01) for n in self.names])


# ---------------------------------------------------------------------------------------------
# sampled-data closed loop: one sample of the compiled drive
# ---------------------------------------------------------------------------------------------


class _Sampled(SampleMap):
    """One sample of the compiled drive as a map of the state at the sample instant.

    The frame is re-referenced at every sample (supply angle theta_g and rotor angle zero at
    t_k), so the map is autonomous. Its state z holds the system's own quantities (named
    ``<part>.<quantity>``, ``.re``/``.im`` for complex ones), at t_k in that frame:

    * ``dfim0.psi_s``, ``dfim0.psi_r``: the machine's flux linkages, stationary frame rotated by
      -theta_g (plant state); ``shaft0.w``: the shaft speed (plant state);
    * ``speed0.theta_prev``: the encoder reading the speed estimator keeps from the previous
      sample, relative to the present shaft angle (minus the angle travelled over the last
      period: its backward difference); ``controller0.e_int``: the speed-PI integral (25);
      ``speed0.w``: the speed estimate (the filter state);
    * ``converter0.v``: the rotor voltage the converter held over the last period (its output, in
      rotor coordinates rotated by n_p theta - theta_g): the plant outputs the sensors read at t_k
      depend on it through the supply impedance;
    * in current mode, ``controller0.ir_int``: the rotor current-loop integral (47);
    * with one sample of computation delay, ``delay0.stored``: the controller's command of the
      previous sample, waiting in the drive's ``ComputationDelay`` part between controller and
      converter (rotor coordinates, likewise rotated).

    The discrete states outside z are those the loop sets on its first sample and then keeps
    (started flags, the synchroniser's closed relay and adjustments, the controller's mode and
    handover flag, the supply-frequency estimate at its nominal start): the template ``S0``,
    ``Y0`` is one sample of the compiled loop from the drive's own initial state. Besides, the
    supply-frequency estimator's previous grid voltage is v_g(t_k) e^{-j w_e T_s} in the frame of
    t_k, so that its estimate is w_e at every sample (the grid alone drives that estimator: its
    mode does not couple into the loop, and z leaves it out).
    """

    def __init__(self, model: DriveView, drive: DFIMDrive | None = None):
        if model.speed_loop != "closed":
            raise InputError("speed_loop", "the sampled-data model needs the closed speed loop")
        point = model.point
        drive = drive or _drive(model)
        super().__init__(drive.compile(), model.sample_time, model.substeps)
        self.model, self.point, self.drive = model, point, drive
        self.parts = parts = drive.motors[0]
        dfim, shaft, speed, conv, ctrl = (
            parts[k] for k in ("dfim", "shaft", "speed", "converter", "controller")
        )
        # the map state, by role (class docstring)
        self.c = c = {
            "psi_s": self.coordinate(dfim, "x", "psi_s", "stationary"),
            "psi_r": self.coordinate(dfim, "x", "psi_r", "stationary"),
            "w": self.coordinate(shaft, "x", "w"),
            "theta_prev": self.coordinate(speed, "s", "theta_prev", "shaft angle"),
            "e_int": self.coordinate(ctrl, "s", "e_int"),
            "w_est": self.coordinate(speed, "s", "w"),
            "v_held": self.coordinate(conv, "y", "v", "rotor"),
            "ir_int": self.coordinate(ctrl, "s", "ir_int"),
        }
        roles = list(c)[:-1] + (["ir_int"] if model.mode == "current" else [])
        if "delay" in parts:  # the drive's ComputationDelay part (model.delay_samples = 1)
            c["delay"] = self.coordinate(parts["delay"], "s", "stored", "rotor")
            roles.append("delay")
        self.coordinates = tuple(c[r] for r in roles)
        self.n_p = dfim.values["n_p"]
        self.i_theta_g = self.slot(drive.grid, "x", "theta_g")
        self.i_theta = self.slot(dfim, "x", "theta")  # the angle of rotor coordinates
        self.i_shaft_theta = self.slot(shaft, "x", "theta")  # what the encoder reads
        self.i_tau = self.slot(ctrl, "s", "tau_com")
        self.i_v_g_prev = self.slot(parts["frequency"], "s", "v_prev")
        # the loop's own start-up: one sample from the drive's initial state
        initial, held = drive.initial()
        self.X[:], self.S[:] = self.system.pack_initial(initial)
        self.Y[:] = self.system.pack_held(held)
        self.run_sample()
        self.S0, self.Y0 = self.S.copy(), self.Y.copy()
        self.X0, _ = self.system.pack_initial()  # angles zero, phasors e^{j 0}
        # the first sample stored v_g(0), the grid voltage at theta_g = 0
        v_g_prev = get_complex(self.S0, self.i_v_g_prev) * np.exp(-1j * model.w_e * self.T)
        set_complex(self.S0, self.i_v_g_prev, v_g_prev)
        self.torque_command = 0.0

    def read(self) -> np.ndarray:
        """The map state at t_k + T_s, re-referenced to the frame of that instant."""
        X = self.X
        theta_g = X[self.i_theta_g]
        self.back = np.exp(-1j * theta_g)  # stationary frame at t_k -> frame of the next sample
        self.rotor = np.exp(1j * (self.n_p * X[self.i_theta] - theta_g))  # rotor coordinates
        self.torque_command = self.S[self.i_tau]
        return super().read()

    def rereference(self, c: Coordinate, value):
        if c.frame == "stationary":
            return value * self.back
        if c.frame == "rotor":
            return value * self.rotor
        if c.frame == "shaft angle":
            return value - self.X[self.i_shaft_theta]
        return value

    def held_voltage(self, z: np.ndarray) -> complex:
        """The converter's output (rotor voltage held over the last period) in map state ``z``."""
        return self.value(z, self.c["v_held"].name)

    def guess(self, cont_state: np.ndarray, cont: _Continuous) -> np.ndarray:
        """The continuous equilibrium, with the rotor voltage of the law (20)."""
        psi_s, psi_r, w, e_I, _, integral = cont.unpack(cont_state)
        m = self.model
        tau = cont.torque_command(cont_state)
        v_r = _voltage_law(cont.p, m.w_e, w, m.v_g, tau)
        values = {"psi_s": psi_s, "psi_r": psi_r, "w": w, "theta_prev": -w * self.T,
                  "e_int": e_I, "w_est": w, "v_held": v_r, "ir_int": integral,
                  "delay": v_r}  # fmt: skip
        return self.vector({self.c[role].name: v for role, v in values.items() if role in self.c})

    def scales(self) -> np.ndarray:
        m = self.model
        psi = m.v_g / m.w_e
        scale = {"psi_s": psi * (1 + 1j), "psi_r": psi * (1 + 1j), "w": 100.0,
                 "theta_prev": 100.0 * self.T, "e_int": 0.1, "w_est": 100.0,
                 "v_held": 10.0 + 10j, "ir_int": 0.01 + 0.01j, "delay": 10.0 + 10j}  # fmt: skip
        return self.vector({self.c[role].name: v for role, v in scale.items() if role in self.c})


# ---------------------------------------------------------------------------------------------
# public entry points
# ---------------------------------------------------------------------------------------------


def _continuous_equilibrium(model: DriveView):
    cont = _Continuous(model)
    x0 = cont.guess()
    if model.speed_loop == "closed":
        x = newton(cont.rhs, x0, cont.scales())
        return cont, x
    # held torque command: solve for it (with the electrical states) so that the torque balances
    # the load (26), the speed staying at the operating point
    free = [i for i, n in enumerate(cont.names) if n != "w"]

    def residual(v):
        x = x0.copy()
        x[free] = v[:-1]
        cont.tau_hold = v[-1]
        return np.append(cont.rhs(x)[free], cont.last_dw)

    v = newton(residual, np.append(x0[free], cont.tau_hold), np.append(cont.scales()[free], 0.1))
    x = x0.copy()
    x[free] = v[:-1]
    cont.tau_hold = v[-1]
    return cont, x


def linearize(
    setup, point: OperatingPoint | None = None, kind: str = "continuous",
    speed_loop: str | None = None,
) -> StabilityResult:  # fmt: skip
    """Linearise the closed loop of ``setup`` at ``point`` and return its eigenvalues.

    ``setup``: a DFIM ``DriveSetup`` (``acdrive.drives.DriveSetup``; its motor 0 on its supply,
    :func:`operating_setup`) or a :class:`DriveModel` (which builds one); ``point``: the
    operating point (default: the setup's final speed reference and load torque);
    ``kind``: "continuous" (continuous-time law, Jacobian of the right-hand side) or "sampled"
    (the simulator's sampled-data loop, Jacobian of the one-sample map; closed speed loop);
    ``speed_loop``: "closed" (default for a setup; a model's own otherwise), "open", "frozen".
    """
    if kind not in KINDS:
        raise InputError("kind", f"must be one of {', '.join(KINDS)}")
    if point is None:
        if not isinstance(setup, DriveSetup):
            raise InputError("point", "is needed with a DriveModel")
        m = setup.motors[0]
        point = OperatingPoint(float(m.speed_reference[1][-1]), float(m.load_torque[1][-1]))
    study, model = setup, view_of(setup, point, speed_loop)
    check_point(model, point)
    try:
        cont, x = _continuous_equilibrium(model)
    except (RuntimeError, np.linalg.LinAlgError):
        raise InputError(
            "load_torque", "no equilibrium: the drive cannot hold this load at this speed"
        ) from None
    tau = cont.torque_command(x)
    cont.rhs(x)
    v_s = abs(cont.last_v_s)  # the measured stator voltage the torque window is computed from
    v_r = abs(cont.last_v_r)
    i_r = abs(cont.plant.currents()[1])
    if kind == "continuous":
        A = jacobian(cont.rhs, x, cont.scales())
        s = np.linalg.eigvals(A)
        z_eig, state, names, jac = np.array([], dtype=complex), x, cont.names, A
        stable = bool(np.all(s.real < 0.0))
    else:
        smp = _Sampled(model, cont.plant.drive)
        try:
            z0, F = fixed_point(smp, smp.guess(x, cont), smp.scales())
        except (RuntimeError, np.linalg.LinAlgError):
            raise InputError(
                "load_torque", "no sampled-data equilibrium inside the controller's limits"
            ) from None
        smp(z0)
        tau = smp.torque_command
        z_eig = np.linalg.eigvals(F)
        nonzero = z_eig[np.abs(z_eig) > Z_ZERO]
        s = np.log(nonzero.astype(complex)) / model.sample_time
        state, names, jac = z0, smp.names, F
        stable = bool(np.all(np.abs(z_eig) < 1.0))
        v_r = abs(smp.held_voltage(z0))
    lo, hi = _torque_window(model, v_s)
    v_max = _rotor_voltage_limit(cont.plant.drive)
    # the linearisation describes the unclipped controller: torque inside the window (30)-(37),
    # rotor current inside its limit (43), converter inside its voltage range
    inside = lo < tau < hi and v_r < v_max and i_r <= model.i_r_max * (1.0 + 1e-9)
    s = s[np.lexsort((-s.imag, -s.real))]
    return StabilityResult(
        model=study,
        point=point,
        kind=kind,
        eigenvalues=s,
        z_eigenvalues=z_eig,
        max_real_part=float(np.max(s.real)),
        stable=stable,
        torque_command=float(tau),
        within_limits=bool(inside),
        state=state,
        state_names=names,
        jacobian=jac,
        view=model,
    )


# ---------------------------------------------------------------------------------------------
# maps over operating points and the tolerated velocity bandwidth
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class StabilityMap:
    """max_real_part[i, j] and stable[i, j] at speeds_rpm[i], loads_nm[j] for one model.

    feasible[i, j] is False where the drive has no equilibrium inside its limits (max_real_part
    is then NaN and stable False); ``all_stable`` looks at the feasible points only.
    """

    model: object  # the DriveSetup or DriveModel
    kind: str
    speeds_rpm: np.ndarray
    loads_nm: np.ndarray
    max_real_part: np.ndarray
    stable: np.ndarray
    feasible: np.ndarray

    @property
    def all_stable(self) -> bool:
        return bool(np.all(self.stable[self.feasible]))


def default_grid(model, n_speed: int = 13, n_load: int = 7, fraction: float = 0.9):
    """Speeds 0..2,700 rpm (the paper's experiments) and loads across ``fraction`` of the torque
    window (30)-(37) of the controller at the nominal supply."""
    view = view_of(model, OperatingPoint(0.0))
    lo, hi = _torque_window(view, view.v_g)
    speeds = np.linspace(0.0, 2700.0, n_speed)
    loads = np.linspace(fraction * lo, fraction * hi, n_load)
    return speeds, loads


def stability_map(model, speeds_rpm, loads_nm, kind: str = "continuous") -> StabilityMap:
    """Linearise ``model`` (a DFIM ``DriveSetup`` or a :class:`DriveModel`) at every
    (speed, load) of the grid."""
    speeds_rpm = np.asarray(speeds_rpm, dtype=float)
    loads_nm = np.asarray(loads_nm, dtype=float)
    mrp = np.empty((speeds_rpm.size, loads_nm.size))
    stable = np.zeros(mrp.shape, dtype=bool)
    feasible = np.ones(mrp.shape, dtype=bool)
    for i, n in enumerate(speeds_rpm):
        for j, tl in enumerate(loads_nm):
            try:
                r = linearize(model, OperatingPoint(n * RAD_S_PER_RPM, tl), kind)
            except InputError as exc:
                if exc.field != "load_torque":
                    raise
                mrp[i, j], feasible[i, j] = np.nan, False
                continue
            feasible[i, j] = r.within_limits
            mrp[i, j], stable[i, j] = r.max_real_part, r.stable
    return StabilityMap(model, kind, speeds_rpm, loads_nm, mrp, stable, feasible)


def with_speed_bandwidth(study, bandwidth: float):
    """``study`` (a :class:`DriveModel` or a DFIM ``DriveSetup``) with the speed PI of motor 0
    designed for a_D,VEL = ``bandwidth`` by (27) with the same design inertia and K_F (of a
    setup: J = K_P^2 / (4 K_I), the inertia its gains were designed with)."""
    if isinstance(study, DriveModel):
        return dataclasses.replace(study, speed_bandwidth=bandwidth)
    motor = study.motors[0]
    g = motor.controller.gains
    gains = dataclasses.replace(SpeedPIGains.design(g.K_P**2 / (4.0 * g.K_I), bandwidth), K_F=g.K_F)
    controller = dataclasses.replace(motor.controller, gains=gains)
    motor = dataclasses.replace(motor, controller=controller)
    return dataclasses.replace(study, motors=(motor, *study.motors[1:]))


def max_stable_bandwidth(
    mode="voltage",
    speeds_rpm=None,
    loads_nm=None,
    *,
    kind: str = "continuous",
    lower: float = 5.0,
    upper: float = 3000.0,
    tol: float = 1.0,
    ratio: float = 1.25,
    **model_fields,
) -> float:
    """Largest a_D,VEL [rad/s] such that every grid point is stable for every bandwidth from
    ``lower`` up to it: the bandwidth is raised geometrically (factor ``ratio``) until a grid
    point becomes unstable, then the boundary is bisected to ``tol``. (Stability need not be
    monotonic in a_D,VEL: the voltage-command drive regains stability at no load in a window of
    higher bandwidths; this function reports the first loss.) Returns ``upper`` if no loss is
    found, 0.0 if the grid is unstable at ``lower``.

    ``mode``: "voltage" or "current" (a :class:`DriveModel` of that mode and ``model_fields``),
    or a DFIM ``DriveSetup`` whose speed PI is redesigned (:func:`with_speed_bandwidth`).
    """
    base = mode if isinstance(mode, DriveSetup) else DriveModel(mode=mode, **model_fields)
    if speeds_rpm is None or loads_nm is None:
        speeds_rpm, loads_nm = default_grid(base)

    def ok(a):
        return stability_map(with_speed_bandwidth(base, a), speeds_rpm, loads_nm, kind).all_stable

    if not ok(lower):
        return 0.0
    a = lower
    while a < upper:
        nxt = min(a * ratio, upper)
        if not ok(nxt):
            return _boundary(ok, a, nxt, tol, stable_below=True)
        a = nxt
    return upper


def _boundary(ok, lower: float, upper: float, tol: float, stable_below: bool) -> float:
    """Bisection for the value where ``ok`` (stable) changes, assuming it changes once.

    stable_below: stable at ``lower`` and unstable beyond the boundary (returns the largest
    stable value; 0.0 if unstable at ``lower``, ``upper`` if stable there); otherwise unstable
    at ``lower`` and stable beyond (returns the smallest stable value; ``lower`` if stable there,
    inf if unstable even at ``upper``).
    """
    if stable_below:
        if not ok(lower):
            return 0.0
        if ok(upper):
            return upper
    else:
        if ok(lower):
            return lower
        if not ok(upper):
            return math.inf
    lo, hi = lower, upper  # invariant: ok(lo) == stable_below != ok(hi)
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if ok(mid) == stable_below else (lo, mid)
    return lo if stable_below else hi


def _first_stable(ok, lower: float, upper: float, step: float, tol: float) -> float:
    """Smallest value in [lower, upper] where ``ok`` holds: scan by ``step``, then bisect the
    last step to ``tol`` (inf if ``ok`` never holds on the scan)."""
    if ok(lower):
        return lower
    v = lower
    while v < upper:
        nxt = min(v + step, upper)
        if ok(nxt):
            return _boundary(ok, v, nxt, tol, stable_below=False)
        v = nxt
    return math.inf


# ---------------------------------------------------------------------------------------------
# why the test bench did not oscillate: candidate effects, each in the linear model
# ---------------------------------------------------------------------------------------------


#: fundamental converter loss [V] of the paper scenarios' bench converter (1 us dead time at
#: 10 kHz on 30 V, 0.7 V device drop: sqrt(3/2) (4/pi) (0.3 + 0.7) V)
BENCH_LOSS = ConverterLosses(
    dead_time=1e-6, switching_frequency=10e3, device_drop=0.7
).fundamental_loss(30.0)


@dataclass(frozen=True)
class Candidate:
    """One effect the paper's bench may have had, as a DriveModel (and linearisation kind)."""

    name: str
    model: DriveModel
    kind: str = "continuous"


@dataclass(frozen=True)
class CandidateResult:
    """max_real_part at 900 rpm / 0 N m, worst over speeds 0..2700 rpm at zero load, and worst
    over the speed x load grid (feasible points); stable_*: the corresponding verdicts."""

    candidate: Candidate
    max_real_part_900: float
    worst_zero_load: float
    worst_grid: float
    stable_zero_load: bool
    stable_grid: bool


def bench_candidates(bandwidth: float = 314.0) -> list[Candidate]:
    """The effects named in issue 3 and a few more, at velocity bandwidth ``bandwidth``, voltage
    command. Parameter errors are in the controller's estimates unless the name says "true"."""
    m0 = BODSON_DFIM
    base = DriveModel(speed_bandwidth=bandwidth, design_inertia=m0.J)
    replace = dataclasses.replace

    def est(**changes):
        return dataclasses.replace(base, controller_params=dataclasses.replace(m0, **changes))

    def true(**changes):
        return dataclasses.replace(
            base, machine=dataclasses.replace(m0, **changes), controller_params=m0
        )

    c = [
        Candidate("paper model (continuous-time law)", base),
        Candidate("sampled 5 kHz, ZOH, encoder difference", base, "sampled"),
        Candidate("sampled + one-sample computation delay", replace(base, delay_samples=1), "sampled"),
        Candidate("speed filter 1 ms", replace(base, speed_filter_tau=1e-3)),
        Candidate("speed filter 5 ms", replace(base, speed_filter_tau=5e-3)),
        Candidate("transformer R 0.3 ohm", replace(base, supply_resistance=0.3)),
        Candidate("transformer L 0.5 mH", replace(base, supply_inductance=0.5e-3)),
        Candidate(
            "transformer R 0.3 ohm + L 0.5 mH",
            replace(base, supply_resistance=0.3, supply_inductance=0.5e-3),
        ),
        Candidate("controller R_s x 0.7", est(R_s=0.7 * m0.R_s)),
        Candidate("controller R_s x 1.3", est(R_s=1.3 * m0.R_s)),
        Candidate("controller R_r x 0.7", est(R_r=0.7 * m0.R_r)),
        Candidate("controller R_r x 1.3", est(R_r=1.3 * m0.R_r)),
        Candidate("controller L_s, L_r, M x 0.9", est(L_s=0.9 * m0.L_s, L_r=0.9 * m0.L_r, M=0.9 * m0.M)),
        Candidate("controller M x 0.95", est(M=0.95 * m0.M)),
        Candidate("DC machine viscous B = 1e-4 (0.028 N m at 283 rad/s)", true(B=1e-4)),
        Candidate("true J = 2 x design", true(J=2 * m0.J)),
        Candidate("true J = 3 x design", true(J=3 * m0.J)),
        Candidate("true R_s x 2 (hot winding, cables)", true(R_s=2 * m0.R_s)),
        Candidate("true R_r + 0.25 ohm (converter, brushes, cables)", true(R_r=m0.R_r + 0.25)),
        Candidate("true R_r + 0.5 ohm (converter, brushes, cables)", true(R_r=m0.R_r + 0.5)),
        Candidate("converter voltage loss 1 V (dead time, device drops)", replace(base, converter_loss=1.0)),
        Candidate("converter voltage loss 2 V (dead time, device drops)", replace(base, converter_loss=2.0)),
        Candidate("scenario bench converter 1.56 V, sampled", replace(base, converter_loss=BENCH_LOSS), "sampled"),
        Candidate("scenario bench converter 1.56 V, sampled + delay", replace(base, converter_loss=BENCH_LOSS, delay_samples=1), "sampled"),
    ]  # fmt: skip
    return c


def evaluate_candidate(candidate: Candidate, n_speed: int = 7, n_load: int = 5) -> CandidateResult:
    """Linearise ``candidate`` at 900 rpm / 0 N m, along the zero-load line and over the grid."""
    m, kind = candidate.model, candidate.kind
    speeds, loads = default_grid(m, n_speed, n_load)
    zero = stability_map(m, speeds, [0.0], kind)
    grid = stability_map(m, speeds, loads, kind)
    at_900 = linearize(m, OperatingPoint(900 * RAD_S_PER_RPM, 0.0), kind)
    return CandidateResult(
        candidate=candidate,
        max_real_part_900=at_900.max_real_part,
        worst_zero_load=_worst(zero),
        worst_grid=_worst(grid),
        stable_zero_load=zero.all_stable,
        stable_grid=grid.all_stable,
    )


def _worst(m: StabilityMap) -> float:
    return float(np.max(np.where(m.feasible, m.max_real_part, -np.inf)))


@dataclass(frozen=True)
class Threshold:
    """Smallest value of a bench quantity that makes the voltage-command drive stable at the
    given bandwidth: along the zero-load line and over the whole speed x load grid (inf: not
    reached within the searched range, or the drive loses its equilibrium first, e.g. a viscous
    load that needs more torque than the limits allow)."""

    name: str
    unit: str
    zero_load: float
    grid: float


def stabilising_thresholds(
    bandwidth: float = 314.0,
    n_speed: int = 7,
    n_load: int = 5,
    kind: str = "continuous",
    **model_fields,
) -> list[Threshold]:
    """How large the true inertia, an extra rotor-circuit resistance unknown to the controller,
    a viscous load or a converter voltage loss must be for the drive to be stable at
    ``bandwidth``: the smallest such value (scan, then bisection).

    "zero load": speeds 0..2,700 rpm without load; "grid": the same speeds with loads across 90 %
    of the torque window, judged at the points where the drive keeps an equilibrium inside its
    limits (for the viscous load and the converter loss, which themselves cost torque or rotor
    voltage, a point they push outside the limits counts as a failure). ``model_fields`` go to the DriveModel (e.g. delay_samples=1);
    """
    m0 = BODSON_DFIM
    base = DriveModel(
        speed_bandwidth=bandwidth, design_inertia=m0.J, controller_params=m0, **model_fields
    )
    speeds, _ = default_grid(base, n_speed, n_load)

    def true(**changes):
        return dataclasses.replace(base, machine=dataclasses.replace(m0, **changes))

    makers = (  # name, unit, model for value v, scan range and step, tolerance, strict
        ("true J / design J", "-", lambda v: true(J=v * m0.J), 1.0, 10.0, 0.25, 0.01, False),
        ("extra rotor resistance", "ohm", lambda v: true(R_r=m0.R_r + v), 0.0, 3.0, 0.1, 0.005, False),
        ("viscous friction B", "N m s/rad", lambda v: true(B=v), 0.0, 0.02, 5e-4, 1e-5, True),
        ("converter voltage loss", "V", lambda v: dataclasses.replace(base, converter_loss=v), 0.0, 6.0, 0.25, 0.01, True),
    )  # fmt: skip
    out = []
    for name, unit, make, lo, hi, step, tol, strict in makers:
        verdicts = []
        for grid in ("zero", "full"):

            def ok(v, grid=grid, make=make, strict=strict):
                model = make(v)
                _, loads = default_grid(model, n_speed, n_load)
                m = stability_map(model, speeds, [0.0] if grid == "zero" else loads, kind)
                # the friction is itself a load: a point it pushes outside the limits fails
                return bool(np.all(m.stable)) if strict else m.all_stable

            verdicts.append(_first_stable(ok, lo, hi, step, tol))
        out.append(Threshold(name, unit, *verdicts))
    return out


# ---------------------------------------------------------------------------------------------
# nonlinear cross-check: the compiled drive started at the sampled equilibrium
# ---------------------------------------------------------------------------------------------


def simulate_from_equilibrium(result: StabilityResult, perturbation: np.ndarray, n_samples: int):
    """Run the compiled drive (``CompiledSystem.run``) ``n_samples`` samples from the sampled
    equilibrium of ``result`` plus ``perturbation`` (a map-state vector); returns (t, shaft speed
    w at every sample).

    ``result`` must come from ``linearize(..., kind="sampled")``; with a computation delay the
    drive runs with its ``ComputationDelay`` part, as the linearisation did.
    """
    if result.kind != "sampled":
        raise InputError("result", "needs a sampled-data result (kind='sampled')")
    smp = _Sampled(result.view)
    smp.load(result.state + perturbation)
    initial, held = smp.initial_and_held()
    w = smp.parts["shaft"].out.w
    run = smp.compiled.run(n_samples * smp.T, smp.T, substeps=smp.substeps, initial=initial,
                           held=held, log=[w])  # fmt: skip
    return run.t, run.signal(w)
