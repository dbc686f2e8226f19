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

What the linearisation reads of the setup is ``drives.dfim._linearisation._view``, the loops themselves are in
``drives.dfim._linearisation._loops``, the studies over many linearisations (maps, tolerated bandwidth, bench
candidates) in ``drives.dfim._linearisation._studies``, the ``StateSpace`` of a result in
``drives.dfim._linearisation._control``.

Units: SI (speeds in rad/s unless the name ends in ``_rpm``); complex space vectors in the
power-invariant scaling of Bodson (1)-(8).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from acdrive._arguments import (
    COUNT,
    FRACTION,
    NONNEGATIVE,
    POSITIVE,
    Either,
    Instance,
    Number,
    Text,
    checked,
    optional,
)
from acdrive._frames import K_PEAK as SQRT_3_2  # Bodson (8): space-vector magnitude per peak
from acdrive.analysis._linearise import (
    fixed_point,
    jacobian,
)
from acdrive.control._speed import SpeedPIGains
from acdrive.drives.dfim._drive import DFIMDrive
from acdrive.drives.dfim._linearisation import _control as _drive_control
from acdrive.drives.dfim._linearisation._loops import _continuous_equilibrium, _Sampled
from acdrive.drives.dfim._linearisation._view import (
    RAD_S_PER_RPM,
    SPEED_LOOPS,
    DriveView,
    OperatingPoint,
)
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
    torque_window,
)
from acdrive.plant._converter import max_voltage_magnitude

MODES = ("voltage", "current")
KINDS = ("continuous", "sampled")
#: |z| below this is a structural zero of the sampled map (a state overwritten every sample)
Z_ZERO = 1e-9


@checked(
    mode=Text(MODES), machine=Instance(DFIMParams),
    controller_params=Instance(DFIMParams, optional=True), speed_bandwidth=POSITIVE,
    design_inertia=optional(POSITIVE), K_F=FRACTION, current_bandwidth=POSITIVE, R_T=POSITIVE,
    supply_voltage_pk=POSITIVE, supply_frequency_hz=POSITIVE, supply_resistance=NONNEGATIVE,
    supply_inductance=NONNEGATIVE, speed_filter_tau=NONNEGATIVE, current_limit_pk=POSITIVE,
    speed_loop=Text(SPEED_LOOPS), sample_time=POSITIVE, substeps=COUNT,
    delay_samples=Number(0, 1, integer=True), converter_loss=NONNEGATIVE,
)
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
        (``drives.dfim._linearisation._control``)."""
        return _drive_control.to_control(self)

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


def _rotor_voltage_limit(drive: DFIMDrive) -> float:
    """The largest rotor voltage magnitude the drive's converter applies (V_dc / sqrt(2))."""
    return max_voltage_magnitude(drive.motors[0]["converter"].values["V_dc"])


# ---------------------------------------------------------------------------------------------
# public entry points
# ---------------------------------------------------------------------------------------------


@checked(
    setup=Either(Instance(DriveSetup), Instance(DriveModel)),
    point=Instance(OperatingPoint, optional=True), kind=Text(KINDS),
    speed_loop=Text(SPEED_LOOPS, optional=True),
)
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
