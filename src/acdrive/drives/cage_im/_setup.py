"""The typed description of a cage induction motor drive run (``IMDriveSetup``, frozen
dataclasses validated on construction) and the profiles it is given in; the scenario loader
(``drives.cage_im._schema``) builds it, ``drives.cage_im._drive.IMDrive`` turns it into parts."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from acdrive._arguments import COUNT, NONNEGATIVE, POSITIVE, TEXT, Instance, Items, Text, checked
from acdrive._frames import K_PEAK as SQRT_3_2
from acdrive._toml import constant
from acdrive.control._foc import (
    CURRENT_LIMIT,
    J_ESTIMATE,
    MIN_FLUX,
    POSITION_GAIN,
    RATED_FLUX,
    RATED_SPEED,
    RATED_TORQUE,
    SPEED_P_BANDWIDTH,
    SpeedPI,
    speed_p_gain,
)
from acdrive.control._lti import builtin
from acdrive.control._speed import SpeedPIGains
from acdrive.core._profile import Profile
from acdrive.errors import InputError
from acdrive.machines._induction import DELORENZO_IM, IMParams
from acdrive.plant._inverter import carrier_samples
from acdrive.plant._mechanics import W_COULOMB

MODES = ("current", "speed-p", "speed-pi", "position")
INVERTER_MODELS = ("averaged", "switching")
WAVEFORMS = ("sine", "step")
#: the paper's unregulated DC link [V] and SVPWM carrier [Hz] (sec. VI)
PAPER_DC_LINK, PAPER_PWM_FREQUENCY = 310.0, 5000.0
#: the paper's dSPACE base sampling period [s] (50 kHz, sec. VI)
PAPER_SAMPLE_TIME = 2e-5
#: logged space vectors in the IFOC's field frame (d + j q); the others are stationary
FIELD_FRAME = ("i_dq_ref",)


def profile_at(profile: Profile, t) -> np.ndarray:
    """Value of a piecewise-linear profile at times ``t``, as ``core.table_at`` computes
    it in the loop (held outside its range; a repeated time is a vertical step, the later value
    from that time on)."""
    times, values = (np.asarray(a, dtype=float) for a in profile)
    t = np.asarray(t, dtype=float)
    if times.size == 1:
        return np.full(t.shape, values[0])
    hi = np.clip(np.searchsorted(times, t, side="right"), 1, times.size - 1)
    lo = hi - 1
    span = times[hi] - times[lo]
    with np.errstate(invalid="ignore", divide="ignore"):
        frac = np.where(span > 0.0, (t - times[lo]) / np.where(span > 0, span, 1.0), 1.0)
    out = values[lo] + (values[hi] - values[lo]) * np.clip(frac, 0.0, 1.0)
    out = np.where(t <= times[0], values[0], out)
    return np.where(t >= times[-1], values[-1], out)


def profile_changes(profile: Profile) -> list[float]:
    """Times > 0 at which a profile starts to change (a step or the start of a slope)."""
    times, values = (np.asarray(a, dtype=float) for a in profile)
    out = []
    for i in range(1, times.size):
        if values[i] != values[i - 1] and times[i - 1] > 0.0 and times[i - 1] not in out:
            out.append(float(times[i - 1]))
    return sorted(out)


@dataclass(frozen=True)
class Mechanics:
    """The shaft (``plant._mechanics``): inertia J [kg m^2], viscous friction B [N m s/rad],
    Coulomb friction tau_c [N m] (smoothed over W_COULOMB), the active load torque profile [N m]
    and the eddy-current brake coefficient profile k_b [N m s/rad] (torque k_b w); or a
    ``prescribed_speed`` profile [rad/s] (a locked rotor is 0): then the shaft is held there and
    J, friction, load and brake play no part."""

    J: float = J_ESTIMATE
    B: float = 0.0
    tau_c: float = 0.0
    load: Profile = field(default_factory=lambda: constant(0.0))
    brake: Profile = field(default_factory=lambda: constant(0.0))
    prescribed_speed: Profile | None = None

    @property
    def free(self) -> bool:
        return self.prescribed_speed is None

    def external_torque(self, t, w) -> np.ndarray:
        """The load as the paper's load cell measures it: active load plus brake, tau_L + k_b w."""
        return profile_at(self.load, t) + profile_at(self.brake, t) * w

    def friction_torque(self, w) -> np.ndarray:
        """B w + tau_c tanh(w / W_COULOMB), as ``plant._mechanics.load_torque`` computes it."""
        return self.B * w + self.tau_c * np.tanh(np.asarray(w) / W_COULOMB)


@dataclass(frozen=True)
class InverterSetup:
    """The inverter: ``model`` "averaged" (carrier-period average) or "switching" (two-level
    SVPWM), the DC-link voltage profile [V], the carrier frequency [Hz], dead time [s] and
    device drop [V] (switching model only)."""

    model: str = "averaged"
    dc_link: Profile = field(default_factory=lambda: constant(PAPER_DC_LINK))
    f_pwm: float = PAPER_PWM_FREQUENCY
    dead_time: float = 0.0
    device_drop: float = 0.0

    @property
    def dc_link_min(self) -> float:
        return float(np.min(self.dc_link[1]))


@dataclass(frozen=True)
class CurrentControl:
    """The stationary-frame current controller: a built-in LTI controller by name
    (``control._lti.BUILTIN``, fixed published transfer functions) or "imc-pi", the PI designed
    from the design machine (``_current_design.imc_current_pi``: ``bandwidth`` [rad/s], its gains
    ``pi_gains`` = (K_P, K_I) computed by the scenario loader), its discretisation ("tustin" or
    "zoh"), an optional Tustin pre-warping frequency [rad/s] and the anti-windup gain
    (``control._current``); or "icad-proposed", ``proposal`` the ``analysis._design.Proposal``
    found on the design machine (``_current_design.icad_proposal``: its controller and ICAD
    check)."""

    controller: str = "paper-20"
    method: str = "tustin"
    prewarp: float | None = None
    aw_gain: float = 1.0
    bandwidth: float | None = None
    pi_gains: tuple[float, float] | None = None
    proposal: object | None = field(default=None, compare=False)

    @property
    def designed(self) -> bool:
        """True if the controller is designed from the machine's parameters (not a fixed one)."""
        return self.pi_gains is not None or self.proposal is not None

    @property
    def lti(self):
        if self.proposal is not None:
            return self.proposal.controller
        if self.pi_gains is not None:
            from acdrive.control._lti import LTI

            return LTI.pi(*self.pi_gains, name=self.controller)
        return builtin(self.controller)


@dataclass(frozen=True)
class CurrentReference:
    """Current reference of the ``current`` mode, in phase peak amperes (the paper's
    amplitude-invariant i_alpha, i_beta): "sine", a balanced set i_alpha = A cos(w (t - t_0) +
    phi), i_beta = A sin(...) from ``start`` on (zero before), or "step", i_alpha = A from
    ``start`` on (i_beta = 0). As a space vector (Bodson (8)) i = sqrt(3/2) A e^{j ...}."""

    waveform: str = "sine"
    amplitude_pk: float = 1.0
    frequency: float = 300.0
    phase: float = 0.0
    start: float = 0.0

    def vector(self, t) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        on = t >= self.start
        if self.waveform == "step":
            return np.where(on, SQRT_3_2 * self.amplitude_pk, 0.0) + 0j
        angle = self.frequency * (t - self.start) + self.phase
        return np.where(on, SQRT_3_2 * self.amplitude_pk * np.exp(1j * angle), 0.0)


@dataclass(frozen=True)
class FOCSetup:
    """Indirect FOC (``control.IndirectFOC``): rotor-flux reference profile [Wb], stator
    current limit [A, space-vector magnitude], the flux below which no torque current is given,
    the magnetised start, and the controller's estimates of R_r, L_r, L_m (None: the nominal
    machine's)."""

    psi_ref: Profile = field(default_factory=lambda: constant(RATED_FLUX))
    i_max: float = CURRENT_LIMIT
    psi_min: float = MIN_FLUX
    magnetised: bool = True
    estimates: IMParams | None = None


@dataclass(frozen=True)
class SpeedPSetup:
    """(21): gain k_p [N m s/rad] and torque limit tau_max [N m] (``control._foc`` defaults)."""

    k_p: float = speed_p_gain(J_ESTIMATE, SPEED_P_BANDWIDTH)
    tau_max: float = RATED_TORQUE


_PI_DEFAULT = SpeedPI.DEFAULTS


@dataclass(frozen=True)
class SpeedPISetup:
    """Speed PI (``control.SpeedPI``): K_P, K_I, K_F and tau_max (its defaults)."""

    K_P: float = _PI_DEFAULT["K_P"]
    K_I: float = _PI_DEFAULT["K_I"]
    K_F: float = _PI_DEFAULT["K_F"]
    tau_max: float = _PI_DEFAULT["tau_max"]

    @classmethod
    def design(cls, J: float, bandwidth: float, K_F: float = 1.0, tau_max: float = RATED_TORQUE):
        """Both roots of J s^2 + K_P s + K_I at -bandwidth (Bodson (27), ``SpeedPIGains``)."""
        g = SpeedPIGains.design(J, bandwidth, K_F)
        return cls(K_P=g.K_P, K_I=g.K_I, K_F=K_F, tau_max=tau_max)


@dataclass(frozen=True)
class PositionSetup:
    """P position loop (``control.PositionP``): K_theta [1/s], speed reference limit."""

    K_theta: float = POSITION_GAIN
    w_max: float = RATED_SPEED


@dataclass(frozen=True)
class SensorSetup:
    """Encoder resolution (0: ideal) and offset [rad]; speed estimate's low-pass [s]."""

    counts_per_rev: float = 0.0
    offset: float = 0.0
    speed_filter_tau: float = 0.0


@checked(
    mode=Text(MODES), machine=Instance(IMParams), plant=Instance(IMParams),
    mechanics=Instance(Mechanics), inverter=Instance(InverterSetup),
    current_control=Instance(CurrentControl),
    current_reference=Instance(CurrentReference, optional=True),
    speed_reference=Instance(Profile, optional=True),
    position_reference=Instance(Profile, optional=True), foc=Instance(FOCSetup),
    speed_p=Instance(SpeedPSetup), speed_pi=Instance(SpeedPISetup),
    position=Instance(PositionSetup), sensors=Instance(SensorSetup), duration=POSITIVE,
    sample_time=POSITIVE, substeps=COUNT, integrator=Text(("rk4", "rk6")), log_every=COUNT,
    name=TEXT, description=Text(empty=True), note=Text(empty=True),
    compare_controllers=Items(Items(TEXT), empty=True), metrics_from=NONNEGATIVE,
)
@dataclass(frozen=True)
class IMDriveSetup:
    """A complete cage-IM drive simulation.

    ``machine`` is the nominal machine the controllers are designed for (the IFOC's default
    estimates); ``plant`` the simulated one (equal, or perturbed as in sec. VIII).
    ``compare_controllers`` lists (label, built-in controller) pairs: one run each, the rest of
    the setup unchanged (as the DFIM's ``compare_modes``); empty: one run with
    ``current_control.controller``. ``metrics_from`` [s]: start of the current-error window.
    """

    mode: str = "current"
    machine: IMParams = DELORENZO_IM
    plant: IMParams = DELORENZO_IM
    mechanics: Mechanics = field(default_factory=Mechanics)
    inverter: InverterSetup = field(default_factory=InverterSetup)
    current_control: CurrentControl = field(default_factory=CurrentControl)
    current_reference: CurrentReference | None = None
    speed_reference: Profile | None = None
    position_reference: Profile | None = None
    foc: FOCSetup = field(default_factory=FOCSetup)
    speed_p: SpeedPSetup = field(default_factory=SpeedPSetup)
    speed_pi: SpeedPISetup = field(default_factory=SpeedPISetup)
    position: PositionSetup = field(default_factory=PositionSetup)
    sensors: SensorSetup = field(default_factory=SensorSetup)
    duration: float = 0.2
    sample_time: float = PAPER_SAMPLE_TIME
    substeps: int = 4
    integrator: str = "rk4"
    log_every: int = 1
    name: str = "custom"
    description: str = ""
    note: str = ""
    compare_controllers: tuple[tuple[str, str], ...] = ()
    metrics_from: float = 0.0

    def __post_init__(self):
        if self.mode not in MODES:
            raise InputError("mode", f"must be one of {', '.join(MODES)}, got {self.mode!r}")
        needs = {
            "current": "current_reference",
            "speed-p": "speed_reference",
            "speed-pi": "speed_reference",
            "position": "position_reference",
        }[self.mode]
        if getattr(self, needs) is None:
            raise InputError(needs, f"is required in mode {self.mode}")
        if self.mode != "current" and not self.mechanics.free:
            raise InputError("mechanics.prescribed_speed", f"mode {self.mode} needs a free shaft")
        if self.inverter.model not in INVERTER_MODELS:
            raise InputError("inverter.model", f"must be one of {', '.join(INVERTER_MODELS)}")

    @property
    def carrier_samples(self) -> int:
        """N = T_pwm / T_s, control samples per carrier period."""
        return int(carrier_samples(self.inverter.f_pwm, self.sample_time))

    @property
    def estimates(self) -> IMParams:
        return self.foc.estimates or self.machine

    def runs(self) -> list[tuple[str, IMDriveSetup]]:
        """(label, setup) of every run: one per compared controller, else one."""
        if not self.compare_controllers:
            return [(self.current_control.controller, self)]
        return [
            (
                label,
                dataclasses.replace(
                    self,
                    current_control=dataclasses.replace(self.current_control, controller=name),
                    compare_controllers=(),
                ),
            )
            for label, name in self.compare_controllers
        ]

    def top_speed(self) -> float:
        """Largest |mechanical speed| [rad/s] the run is expected to reach: the prescribed speed,
        the speed reference, the position loop's speed limit, or, with currents imposed on a free
        shaft, the reference frequency over n_p (a motor runs up towards it)."""
        if self.mechanics.prescribed_speed is not None:
            return float(np.max(np.abs(self.mechanics.prescribed_speed[1])))
        if self.mode in ("speed-p", "speed-pi"):
            return float(np.max(np.abs(self.speed_reference[1])))
        if self.mode == "position":
            return float(self.position.w_max)
        ref = self.current_reference
        return abs(ref.frequency) / self.plant.n_p if ref.waveform == "sine" else 0.0


def divergence_hint(setup: IMDriveSetup) -> str:
    return (
        f"shorten simulation.sample_time (now {setup.sample_time:g} s) or raise "
        f"simulation.substeps (now {setup.substeps}); if that does not help, check the machine "
        "parameters, the inertia J and the controller gains"
    )
