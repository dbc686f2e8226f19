"""The cage induction motor drive of Amezquita-Brooks et al. (sections VI-VIII) built from parts.

Data flow (as the DFIM drive, ``drives.dfim._drive``): scenario (TOML, ``drives.cage_im._schema``) ->
``IMDriveSetup`` (frozen dataclasses) -> ``IMDrive`` (parts and wires) -> ``sim.System``
-> compiled loop -> ``IMDriveResult`` (named signals with units, events, ``summary()``) ->
``run_im_scenario`` (one run per compared current controller) -> ``drives.cage_im._outputs`` (data,
figures, summary.json).

**Parts** (names as in the logs and event counts):

* plant: ``dc`` (``plant.DCSource``, the paper's unregulated 310 V link, a profile), the
  inverter (``inverter``), the machine ``machine`` (``machines._cage_part``, (1)-(2); the
  *plant's* parameters, perturbed in the sec. VIII scenario) and the shaft ``shaft``
  (``plant.Shaft``: inertia, viscous and Coulomb friction, active load profile,
  eddy-current brake coefficient profile; or ``PrescribedSpeed`` for a locked rotor or a
  dynamometer-held speed);
* sensors: ``encoder`` (``plant.Encoder``) and ``speed`` (``control._bodson
  .SpeedEstimator``, backward difference of the encoder angle);
* control (Fig. 12): ``current`` (``control.StationaryCurrentController``: a built-in LTI
  controller by name on both stationary axes, discretised by ZOH or Tustin at the control
  sample time, limited to v_dc / sqrt(2) from the DC link with back-calculation anti-windup) and
  the reference generation of the mode:

  - ``current``: ``reference`` (``control.CurrentProgram``), a balanced sinusoidal
    current reference (the locked-rotor test, Fig. 11; Fig. 23) or a step on the alpha axis
    (Figs. 18, 20), tabulated at every control sample;
  - ``speed-p``: ``speed_reference`` -> ``speed_controller`` (``control.SaturatedSpeedP``,
    (21)) -> ``ifoc`` (``control.IndirectFOC``) -> ``current`` (Fig. 16);
  - ``speed-pi``: the same with ``control.SpeedPI`` (Fig. 13);
  - ``position``: ``position_controller`` (``control.PositionP``) -> ``SpeedPI`` -> IFOC
    (Fig. 14).

**Inverter models.** ``switching``: ``plant.Inverter``, the two-level SVPWM bridge with
exact switching instants, dead time and device drops; it latches the command once per carrier
period T_pwm = N T_s. ``averaged``: the same inverter's carrier-period average, i.e. the command
latched at the carrier period start (``CarrierLatch``, the PWM unit's shadow register) and held
for the whole period by ``plant.DCFedConverter`` within its linear range
|v| <= v_dc / sqrt(2). Feeding the averaged converter straight from the 50 kHz controller would
model a 50 kHz PWM, with a tenth of the real hold delay; with the latch, the mean of the switching
pattern over each carrier period is exactly the averaged model's voltage (the volt-second balance
of ``plant._inverter``), and the two models differ only by the ripple (``tests/test_im_drive.py``).
The latch is defined here rather than in ``plant/`` because this work may not edit that layer; it
belongs beside ``DCFedConverter``.

**Initial state.** In the FOC modes the drive starts magnetised by default
(``FOCSetup.magnetised``): the machine at its standstill steady state for the flux current
i_d = psi_ref(0) / L_m (estimate) along the field angle of the encoder's reading, the rotor flux
L_m i_s (plant), the flux model at psi_ref(0) and the current controller's state that outputs the
stator voltage R_s i_s with zero error (bumpless, ``bumpless_state``). Otherwise everything starts
at zero (a demagnetised machine; the IFOC reports ``unmagnetised`` while the flux builds up).

**Metrics** (``IMDriveResult.summary``; every figure from the logged data):

* current tracking: e = i_ref - i_s (space vectors, power-invariant, Bodson (8)); the RMS phase
  error sqrt(mean |e|^2 / 3) [A] (the three zero-sum phase errors have sum of squares |e|^2) over
  t >= ``metrics_from``, and the same of the reference (its RMS phase current);
* speed: the error against the reference (RMS and largest over the whole run and where tracking
  is expected, ``sim._metrics``, as the batch's rows), the mean error over the last
  ``STEADY_FRACTION`` of the run, the largest deviation after each load change, the steady torque balance
  tau_e - (tau_L + k_b w + B w + tau_c tanh(w / W_COULOMB)); ``speed_outcome``: each disturbance
  of the scenario (load, brake, DC link) judged for largest error, recovery, reversal and stall
  by the DFIM drive's rule (``sim._recovery``, in rpm);
* the saturated ramp of (21) (a speed step with ``speed-p``): the ideal response with perfect
  current control and no friction is the constant-torque ramp w_0 + (tau_max / J)(t - t_step)
  while k_p (w_ref - w) > tau_max, until t_sat = t_step + J (w_ref - w_0 - tau_max / k_p) /
  tau_max; ``speed_ramp_error_rad_s`` is the RMS of w - w_ideal over [t_step, t_sat] (Fig. 16(a)),
  ``ramp_slope_rad_s2`` the least-squares slope of w over the middle of that interval
  (from 10 % to 70 % of it);
* position: the final error, the overshoot and the largest deviation after a load change;
  ``position_outcome``: the position error's recovery after each disturbance (the speed is not
  judged there: ``sim._recovery.POSITION_SPEED_NOT_JUDGED``);
* peaks: stator current and voltage command in phase peak amperes and volts (a space vector's
  magnitude over sqrt(3/2)) against the linear SVPWM limit v_dc / sqrt(3), the electromagnetic
  torque; ``voltage_check`` (FOC modes): the field-oriented steady voltage ``foc_voltage`` at the
  top speed and flux reference against that limit (a DC link too low for the flux is reported
  here and in the warnings, not refused);
* several runs (``run_im_scenario``): ``current_rms_error_<label>_a``, and for the ramp
  ``speed_ramp_error_<label>`` [rad/s] and ``ramp_slope_<label>_rad_s2``;
* event counts (control samples): ``current_controller_saturation`` (the voltage command was
  limited to v_dc / sqrt(2)), ``overmodulation`` (the inverter limited a latched command),
  ``current_limit`` and ``unmagnetised`` (IFOC), ``torque_limit`` (speed controller),
  ``speed_limit`` (position controller).

A run whose state stops being finite raises ``SimulationDiverged`` with the time and a hint; a
logged signal that is not finite is an error too (never a silent NaN).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from acdrive._frames import K_PEAK as SQRT_3_2
from acdrive._frames import complex_to_abc
from acdrive.control._bodson import SpeedEstimator
from acdrive.control._current import (
    CurrentProgram,
    StationaryCurrentController,
)
from acdrive.control._foc import (
    CURRENT_LIMIT,
    J_ESTIMATE,
    MIN_FLUX,
    POSITION_GAIN,
    RATED_FLUX,
    RATED_SPEED,
    RATED_TORQUE,
    SPEED_P_BANDWIDTH,
    IndirectFOC,
    PositionP,
    SaturatedSpeedP,
    SpeedPI,
    speed_p_gain,
)
from acdrive.control._lti import builtin
from acdrive.control._speed import SpeedPIGains, SpeedReference
from acdrive.errors import InputError, SimulationDiverged
from acdrive.machines._cage_part import CageInductionMachine
from acdrive.machines._induction import DELORENZO_IM, IMParams, stator_current_ss
from acdrive.plant._converter import DCFedConverter, max_voltage_magnitude
from acdrive.plant._inverter import CarrierLatch, Inverter, carrier_samples
from acdrive.plant._mechanics import W_COULOMB, PrescribedSpeed, Shaft
from acdrive.plant._sensors import Encoder, encoder_angle
from acdrive.plant._sources import DCSource
from acdrive.scenarios._files import Profile, constant
from acdrive.sim._system import System

MODES = ("current", "speed-p", "speed-pi", "position")
INVERTER_MODELS = ("averaged", "switching")
WAVEFORMS = ("sine", "step")
#: the paper's unregulated DC link [V] and SVPWM carrier [Hz] (sec. VI)
PAPER_DC_LINK, PAPER_PWM_FREQUENCY = 310.0, 5000.0
#: the paper's dSPACE base sampling period [s] (50 kHz, sec. VI)
PAPER_SAMPLE_TIME = 2e-5
#: logged space vectors in the IFOC's field frame (d + j q); the others are stationary
FIELD_FRAME = ("i_dq_ref",)
#: the last fraction of a run over which steady values are averaged
STEADY_FRACTION = 0.1
#: the shortest steady window [s]
STEADY_MIN_S = 0.05


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


# --- setup ------------------------------------------------------------------------------------


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
    (``control._lti.BUILTIN``), its discretisation ("tustin" or "zoh"), an optional Tustin
    pre-warping frequency [rad/s] and the anti-windup gain (``control._current``)."""

    controller: str = "paper-20"
    method: str = "tustin"
    prewarp: float | None = None
    aw_gain: float = 1.0

    @property
    def lti(self):
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


# --- physics helpers ---------------------------------------------------------------------------


def modulation_signals(v: np.ndarray, v_dc: np.ndarray) -> np.ndarray:
    """Phase modulation signals 2 d_x - 1 (rows a, b, c) of centred SVPWM for the limited
    voltage vectors ``v`` on DC links ``v_dc``: the min-max zero sequence added to the phase
    values (Bodson (2)), over v_dc / 2, as ``plant._inverter`` sets its duty cycles."""
    x = np.array(complex_to_abc(np.asarray(v, dtype=complex)))
    offset = -0.5 * (x.max(axis=0) + x.min(axis=0))
    with np.errstate(invalid="ignore", divide="ignore"):
        m = np.where(v_dc > 0.0, 2.0 * (x + offset) / np.where(v_dc > 0, v_dc, 1.0), 0.0)
    return np.clip(m, -1.0, 1.0)


def foc_voltage(p: IMParams, psi: float, tau: float, w: float) -> complex:
    """Stator voltage v_dq [V, space vector] of the field-oriented steady state of the cage
    machine (1)-(2) with rotor flux ``psi`` on the d axis, torque ``tau`` at mechanical speed
    ``w``: i_d = psi / L_m, i_q = tau L_r / (n_p L_m psi), w_e = n_p w + R_r tau / (n_p psi^2)
    and, from the stator row of (1) in the frame turning at w_e,
    v = (R_s + L_m^2 R_r / L_r^2 + j w_e sigma L_s) i - (L_m / L_r)(R_r / L_r - j n_p w) psi."""
    i = complex(psi / p.L_m, tau * p.L_r / (p.n_p * p.L_m * psi))
    w_r = p.n_p * w
    w_e = w_r + p.R_r * tau / (p.n_p * psi * psi)
    R_eq = p.R_s + p.L_m**2 * p.R_r / p.L_r**2
    return (R_eq + 1j * w_e * p.sigma * p.L_s) * i - p.L_m / p.L_r * (
        p.R_r / p.L_r - 1j * w_r
    ) * psi


def bumpless_state(part: StationaryCurrentController, v: complex) -> dict:
    """Initial state of the current controller that outputs ``v`` with zero error and stays
    there (x = A_d x, C_d x = v: the integrators' direction); zero if it has no integrator."""
    d = part.discrete
    n = d.order
    if n == 0:
        return {}
    null = scipy.linalg.null_space(d.Ad - np.eye(n), rcond=1e-9)
    if null.shape[1] == 0:
        return part.state_for(np.zeros(n))
    target = np.array([v.real, v.imag])
    coef, *_ = np.linalg.lstsq(d.Cd @ null, target, rcond=None)
    x = null @ coef
    if np.linalg.norm(d.Cd @ x - target) > 1e-9 * max(1.0, abs(v)):
        x = np.zeros(n)
    return part.state_for(x)


def current_loop_radius(plant: IMParams, w_mech: float, discrete, n_carrier: int) -> float:
    """Spectral radius of the sampled current loop over one carrier period (linear, unsaturated):
    the plant (1) at electrical speed n_p w held by a zero-order hold over each control sample,
    the discretised controller ``discrete`` (2 x 2) running every sample, and its command latched
    at the first sample of each carrier period of ``n_carrier`` samples (``CarrierLatch``, the
    inverter). Below 1: the loop is stable at this speed."""
    A, B, C, _ = stator_current_ss(plant, plant.n_p * w_mech)
    T = discrete.T_s
    n, m = A.shape[0], B.shape[1]
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = A * T, B * T
    E = scipy.linalg.expm(M)
    Ap, Bp = E[:n, :n], E[:n, n:]
    Ac, Bc, Cc, Dc = discrete.Ad, discrete.Bd, discrete.Cd, discrete.Dd
    nc = Ac.shape[0]
    size = n + nc + 2
    xp, xc, h = slice(0, n), slice(n, n + nc), slice(n + nc, size)
    # e = -C x_p (zero reference)
    hold = np.zeros((size, size))  # samples 1 .. N-1 of the carrier period
    hold[xp, xp], hold[xp, h] = Ap, Bp
    hold[xc, xp], hold[xc, xc] = -Bc @ C, Ac
    hold[h, h] = np.eye(2)
    latch = np.zeros((size, size))  # sample 0: the command is taken
    v_row = np.hstack([-Dc @ C, Cc, np.zeros((2, 2))])  # v = C_c x_c + D_c e
    latch[xp, :] = np.hstack([Ap, np.zeros((n, nc + 2))]) + Bp @ v_row
    latch[xc, xp], latch[xc, xc] = -Bc @ C, Ac
    latch[h, :] = v_row
    period = np.linalg.matrix_power(hold, n_carrier - 1) @ latch
    return float(np.max(np.abs(np.linalg.eigvals(period))))


# --- the drive from parts ---------------------------------------------------------------------


def _reference_tables(ref: CurrentReference, duration: float, T_s: float) -> dict:
    """The tables of a ``CurrentProgram``: the reference at every control sample of the run
    (exact there), or the vertical step."""
    if ref.waveform == "step":
        a = SQRT_3_2 * ref.amplitude_pk
        return {"re": [[0.0, 0.0], [ref.start, 0.0], [ref.start, a]], "im": 0.0}
    n = round(duration / T_s) + 1
    t = np.arange(n) * T_s
    i = ref.vector(t)
    if ref.start > 0.0:  # the vertical step at the start, whatever the sample grid
        k = int(np.searchsorted(t, ref.start))
        t = np.insert(t, k, [ref.start, ref.start])
        first = ref.vector(np.array([ref.start]))[0]
        i = np.insert(i, k, [0.0, first])
    return {"re": (t, i.real), "im": (t, i.imag)}


class IMDrive:
    """The parts, wiring, initial state and logged signals of one ``IMDriveSetup`` run (its
    ``current_control.controller``; ``IMDriveSetup.runs`` splits a comparison)."""

    def __init__(self, setup: IMDriveSetup):
        self.setup = s = setup
        mech, inv, cc = s.mechanics, s.inverter, s.current_control
        p = {}
        p["dc"] = DCSource("dc", V=inv.dc_link)
        p["machine"] = CageInductionMachine.from_params("machine", s.plant)
        if mech.free:
            p["shaft"] = Shaft(
                "shaft", J=mech.J, B=mech.B, tau_c=mech.tau_c, load=mech.load, brake=mech.brake
            )
        else:
            p["shaft"] = PrescribedSpeed("shaft", w=mech.prescribed_speed)
        p["encoder"] = Encoder(
            "encoder", offset=s.sensors.offset, counts_per_rev=s.sensors.counts_per_rev
        )
        p["speed"] = SpeedEstimator("speed", tau=s.sensors.speed_filter_tau)
        p["current"] = StationaryCurrentController(
            "current",
            cc.lti,
            s.sample_time,
            cc.method,
            cc.prewarp,
            v_dc_input=True,
            aw_gain=cc.aw_gain,
        )
        if inv.model == "switching":
            p["inverter"] = Inverter(
                "inverter", f_pwm=inv.f_pwm, t_d=inv.dead_time, v_drop=inv.device_drop
            )
        else:
            p["latch"] = CarrierLatch("latch", f_pwm=inv.f_pwm)
            p["inverter"] = DCFedConverter("inverter")
        est = s.estimates
        if s.mode == "current":
            tables = _reference_tables(s.current_reference, s.duration, s.sample_time)
            p["reference"] = CurrentProgram("reference", **tables)
        else:
            p["ifoc"] = IndirectFOC.from_params(
                "ifoc", est, i_max=s.foc.i_max, psi_min=s.foc.psi_min, psi_ref=s.foc.psi_ref
            )
            if s.mode == "speed-p":
                p["speed_controller"] = SaturatedSpeedP(
                    "speed_controller", k_p=s.speed_p.k_p, tau_max=s.speed_p.tau_max
                )
            else:
                g = s.speed_pi
                p["speed_controller"] = SpeedPI(
                    "speed_controller", K_P=g.K_P, K_I=g.K_I, K_F=g.K_F, tau_max=g.tau_max
                )
            if s.mode == "position":
                p["position_controller"] = PositionP(
                    "position_controller",
                    K_theta=s.position.K_theta,
                    w_max=s.position.w_max,
                    theta_ref=s.position_reference,
                )
            else:
                p["speed_reference"] = SpeedReference("speed_reference", w=s.speed_reference)
        self.parts = p
        self.system = _build_system(s, p)

    # the reference the current controller follows, and the speed reference, by mode
    @property
    def current_reference_port(self):
        p = self.parts
        return p["reference"].out.i if "reference" in p else p["ifoc"].out.i_s_ref

    def log_ports(self) -> dict:
        """Signal name -> logged output port."""
        p = self.parts
        ports = {
            "i_s": p["machine"].out.i_s,
            "i_ref": self.current_reference_port,
            "psi_r": p["machine"].out.psi_r,
            "tau_e": p["machine"].out.tau_e,
            "w": p["shaft"].out.w,
            "theta": p["shaft"].out.theta,
            "w_meas": p["speed"].out.w,
            "v_ref": p["current"].out.v_ref,
            "v": p["inverter"].out.v,
            "v_dc": p["dc"].out.v_dc,
        }
        if "latch" in p:
            ports["v_pwm"] = p["latch"].out.v_ref
        else:
            ports["v_pwm"] = p["inverter"].out.v_lim
            ports["m_a"] = p["inverter"].out.m_a
        if "ifoc" in p:
            ports.update(
                tau_ref=p["speed_controller"].out.tau_ref,
                psi_est=p["ifoc"].out.psi_est,
                i_dq_ref=p["ifoc"].out.i_dq_ref,
                theta_f=p["ifoc"].out.theta_f,
                tau_est=p["ifoc"].out.tau_est,
            )
        if "speed_reference" in p:
            ports["w_ref"] = p["speed_reference"].out.w_ref
        if "position_controller" in p:
            ports["w_ref"] = p["position_controller"].out.w_ref
            ports["theta_ref"] = p["position_controller"].out.theta_ref
        return ports

    def initial(self) -> tuple[dict, dict]:
        """(initial states, held outputs) at t = 0 (module docstring, "Initial state")."""
        s, p = self.setup, self.parts
        initial, held = {}, {}
        if s.mode == "current" or not s.foc.magnetised:
            return initial, held
        psi0 = float(profile_at(s.foc.psi_ref, 0.0))
        est, plant = s.estimates, s.plant
        i_d = min(psi0 / est.L_m, s.foc.i_max)
        theta0 = encoder_angle(0.0, s.sensors.offset, s.sensors.counts_per_rev)
        direction = complex(math.cos(est.n_p * theta0), math.sin(est.n_p * theta0))
        i_s = i_d * direction
        psi_r = plant.L_m * i_s
        v = plant.R_s * i_s  # standstill steady state: di/dt = 0, dpsi/dt = 0
        initial["machine"] = {"i_s": i_s, "psi_r": psi_r}
        initial["ifoc"] = {"psi_est": psi0}
        initial["current"] = bumpless_state(p["current"], v)
        if "latch" in p:
            initial["latch"] = {"v": v}
            held["latch"] = {"v_ref": v}
            held["inverter"] = {"v": v}
        return initial, held

    def compile(self):
        return self.system.compile()

    def run(self, compiled=None) -> IMDriveResult:
        s = self.setup
        compiled = compiled or self.compile()
        initial, held = self.initial()
        ports = self.log_ports()
        try:
            raw = compiled.run(
                s.duration,
                s.sample_time,
                substeps=s.substeps,
                initial=initial,
                held=held,
                log=list(ports.values()),
                log_every=s.log_every,
            )
        except SimulationDiverged as exc:
            raise SimulationDiverged(exc.time, divergence_hint(s), s.name) from None
        return IMDriveResult.from_system(self, raw)

    def event_counts(self, raw) -> dict[str, int]:
        """Named event totals (samples) of a ``SystemResult`` (module docstring)."""
        e = raw.events
        out = {
            "current_controller_saturation": e["current"]["saturated"],
            "overmodulation": e["inverter"].get("overmodulation", e["inverter"].get("saturated")),
        }
        if "ifoc" in e:
            out["current_limit"] = e["ifoc"]["current_limit"]
            out["unmagnetised"] = e["ifoc"]["unmagnetised"]
            out["torque_limit"] = e["speed_controller"]["torque_limit"]
        if "position_controller" in e:
            out["speed_limit"] = e["position_controller"]["speed_limit"]
        return out

    def event_flags(self, raw) -> dict[str, np.ndarray]:
        """Per logged sample: was the current controller's command limited, did the inverter
        limit its latched command."""
        names = self.system.event_names()
        index = {part: i for i, (part, _) in enumerate(names)}
        log = raw.event_log
        return {
            "saturated": (log[:, index["current"]] & 1).astype(bool),
            "overmodulation": (log[:, index["inverter"]] & 1).astype(bool),
        }


def _build_system(s: IMDriveSetup, p: dict) -> System:
    machine, shaft, current, inverter, dc = (
        p["machine"],
        p["shaft"],
        p["current"],
        p["inverter"],
        p["dc"],
    )
    wires = [
        (shaft.out.w, machine.inp.w),
        (shaft.out.theta, p["encoder"].inp.theta),
        (p["encoder"].out.theta, p["speed"].inp.theta),
        (machine.out.i_s, current.inp.i_meas),
        (dc.out.v_dc, current.inp.v_dc),
        (dc.out.v_dc, inverter.inp.v_dc),
        (inverter.out.v, machine.inp.v_s),
    ]
    if s.mechanics.free:
        wires.append((machine.out.tau_e, shaft.inp.tau_e))
    if "latch" in p:
        wires += [
            (current.out.v_ref, p["latch"].inp.v_ref),
            (p["latch"].out.v_ref, inverter.inp.v_ref),
        ]
    else:
        wires += [(current.out.v_ref, inverter.inp.v_ref), (machine.out.i_s, inverter.inp.i_s)]
    if "reference" in p:
        wires.append((p["reference"].out.i, current.inp.i_ref))
    else:
        ifoc, sc = p["ifoc"], p["speed_controller"]
        wires += [
            (p["speed"].out.w, sc.inp.w),
            (sc.out.tau_ref, ifoc.inp.tau_ref),
            (p["encoder"].out.theta, ifoc.inp.theta),
            (ifoc.out.i_s_ref, current.inp.i_ref),
        ]
        if "position_controller" in p:
            pos = p["position_controller"]
            wires += [(p["encoder"].out.theta, pos.inp.theta), (pos.out.w_ref, sc.inp.w_ref)]
        else:
            wires.append((p["speed_reference"].out.w_ref, sc.inp.w_ref))
    return System(list(p.values()), wires, method=s.integrator)


def divergence_hint(setup: IMDriveSetup) -> str:
    return (
        f"shorten simulation.sample_time (now {setup.sample_time:g} s) or raise "
        f"simulation.substeps (now {setup.substeps}); if that does not help, check the machine "
        "parameters, the inertia J and the controller gains"
    )


# --- results ---------------------------------------------------------------------------------


def _steady_mask(t: np.ndarray) -> np.ndarray:
    span = max(STEADY_FRACTION * (t[-1] - t[0]), STEADY_MIN_S)
    return t >= t[-1] - span


@dataclass
class IMDriveResult:
    """Logged signals of one run by name (``signals[name]``: complex for space vectors, in
    acdrive's power-invariant scaling, Bodson (8)), their units, the named event totals and the
    per-sample event flags; ``summary()`` computes the metrics of the module docstring."""

    setup: IMDriveSetup
    label: str
    t: np.ndarray
    signals: dict[str, np.ndarray]
    units: dict[str, str]
    events: dict[str, int]
    flags: dict[str, np.ndarray]
    wall_time: float = 0.0
    steps: int = 0
    #: one-line description of each signal (the logged port's declaration)
    descriptions: dict[str, str] = field(default_factory=dict)

    @classmethod
    def from_system(cls, drive: IMDrive, raw, label: str | None = None) -> IMDriveResult:
        s = drive.setup
        signals, units, descriptions = {}, {}, {}
        for name, port in drive.log_ports().items():
            signals[name] = raw.signal(port)
            units[name] = port.var.unit
            descriptions[name] = f"{port.var.doc} ({port.path})"
        if "m_a" not in signals:  # averaged model: the modulation signal of the latched command
            signals["m_a"] = modulation_signals(signals["v_pwm"], signals["v_dc"])[0]
            units["m_a"] = ""
            descriptions["m_a"] = "phase-a modulation signal of the latched voltage command"
        w = signals["w"]
        signals["tau_load"] = s.mechanics.external_torque(raw.t, w)
        signals["tau_friction"] = s.mechanics.friction_torque(w)
        units["tau_load"] = units["tau_friction"] = "N m"
        descriptions["tau_load"] = "load torque on the shaft (active load and brake)"
        descriptions["tau_friction"] = "friction torque on the shaft"
        for name, values in signals.items():
            bad = ~np.isfinite(values)
            if bad.any():
                first = float(raw.t[np.argmax(bad)])
                raise SimulationDiverged(
                    first, f"logged signal {name} is not finite; " + divergence_hint(s), s.name
                )
        return cls(
            setup=s,
            label=label or s.current_control.controller,
            t=raw.t,
            signals=signals,
            units=units,
            events=drive.event_counts(raw),
            flags=drive.event_flags(raw),
            wall_time=raw.wall_time,
            steps=raw.steps,
            descriptions=descriptions,
        )

    def signal(self, name: str) -> np.ndarray:
        try:
            return self.signals[name]
        except KeyError:
            raise KeyError(f"{name} was not logged (logged: {', '.join(self.signals)})") from None

    def __repr__(self) -> str:
        """One line for a notebook or a log: what ran and its headline numbers (computed)."""
        s = self.setup
        duration = float(self.t[-1] + s.sample_time) if self.t.size else 0.0
        head = (
            f"<IMDriveResult {s.name!r} [{self.label}]: mode {s.mode}, {duration:g} s in "
            f"{self.t.size} samples; current RMS error {self.current_rms_error():.3g} A"
        )
        if s.mode != "current":
            w = self.signal("w")
            head += f", speed {float(np.min(w)):.1f} to {float(np.max(w)):.1f} rad/s"
        return head + ">"

    def plot(self, axes=None):
        """Phase-a current against its reference (phase peak), the speed against its reference
        (FOC modes) and the electrical torque against time; returns the matplotlib Figure."""
        import matplotlib.pyplot as plt

        rows = 2 if self.setup.mode == "current" else 3
        if axes is None:
            fig, axes = plt.subplots(rows, 1, sharex=True, figsize=(8, 2.2 * rows + 0.6))
        else:
            fig = axes[0].figure
        ax = iter(axes)
        a = next(ax)
        a.plot(self.t, self.phase_peak("i_ref").real, "k--", lw=0.8, label="reference")
        a.plot(self.t, self.phase_peak("i_s").real, lw=0.7, label="i_alpha")
        a.set_ylabel("current [A, phase peak]")
        a.legend(loc="best")
        a.set_title(f"{self.setup.name} [{self.label}]")
        if rows == 3:
            a = next(ax)
            a.plot(self.t, self.signal("w_ref"), "k--", lw=0.8, label="reference")
            a.plot(self.t, self.signal("w"), lw=0.8, label="speed")
            a.set_ylabel("speed [rad/s]")
            a.legend(loc="best")
        a = next(ax)
        a.plot(self.t, self.signal("tau_e"), lw=0.7)
        a.set_ylabel("torque [N m]")
        a.set_xlabel("time [s]")
        fig.tight_layout()
        return fig

    def phase_peak(self, name: str) -> np.ndarray:
        """A space vector in the paper's amplitude-invariant alpha, beta scaling (peak phase
        amperes or volts): the power-invariant vector over sqrt(3/2) (Bodson (8))."""
        return self.signal(name) / SQRT_3_2

    # -- metrics ----------------------------------------------------------------------------
    def metrics_mask(self) -> np.ndarray:
        return self.t >= self.setup.metrics_from

    def current_rms_error(self, mask=None) -> float:
        """RMS phase current error sqrt(mean |i_ref - i_s|^2 / 3) [A] over ``mask`` (default:
        t >= metrics_from)."""
        mask = self.metrics_mask() if mask is None else mask
        e = self.signal("i_ref")[mask] - self.signal("i_s")[mask]
        return float(np.sqrt(np.mean(np.abs(e) ** 2) / 3.0)) if e.size else math.nan

    def current_rms_reference(self, mask=None) -> float:
        mask = self.metrics_mask() if mask is None else mask
        i = self.signal("i_ref")[mask]
        return float(np.sqrt(np.mean(np.abs(i) ** 2) / 3.0)) if i.size else math.nan

    def load_changes(self) -> list[float]:
        m = self.setup.mechanics
        if not m.free:
            return []
        times = sorted(set(profile_changes(m.load)) | set(profile_changes(m.brake)))
        return [t for t in times if t < self.t[-1]]

    def speed_metrics(self) -> dict:
        """The speed figures of the module docstring; the speed error over the whole run and
        where tracking is expected (``sim._metrics.speed_tracking`` under
        ``im_tracking_rule``: the batch's figures of the same names) with ``speed_tracking``."""
        from acdrive.drives.cage_im._tracking import im_tracking_rule
        from acdrive.sim._metrics import speed_tracking
        from acdrive.sim._recovery import im_speed_outcome

        t, w, w_ref = self.t, self.signal("w"), self.signal("w_ref")
        steady = _steady_mask(t)
        err = w_ref - w
        figures, tracking, mask = speed_tracking(
            t, w, w_ref, None, im_tracking_rule(self.setup), scale=1.0, unit="rad_s"
        )
        out = {
            "speed_final_rad_s": float(np.mean(w[steady])),
            "speed_reference_final_rad_s": float(np.mean(w_ref[steady])),
            "speed_steady_error_rad_s": float(np.mean(err[steady])),
            **figures,
            "speed_tracking": tracking,
        }
        final_ref = float(w_ref[-1])
        if final_ref != 0.0:
            out["speed_overshoot_rad_s"] = float(np.max(np.sign(final_ref) * (w - final_ref)))
        out["load_changes"] = [self._deviation(tc, w) for tc in self.load_changes()]
        out["speed_outcome"] = im_speed_outcome(self, mask)
        tau_e, tau_l, tau_f = (
            self.signal(n)[steady] for n in ("tau_e", "tau_load", "tau_friction")
        )
        out["torque_balance"] = {
            "tau_e_n_m": float(np.mean(tau_e)),
            "load_n_m": float(np.mean(tau_l)),
            "friction_n_m": float(np.mean(tau_f)),
            "residual_n_m": float(np.mean(tau_e - tau_l - tau_f)),
        }
        return out

    def _deviation(self, t_change: float, x: np.ndarray, name: str = "speed") -> dict:
        """Largest deviation of ``x`` after a load change at ``t_change``, relative to its mean
        over the 50 ms before the change (or up to the next change)."""
        t = self.t
        later = [c for c in self.load_changes() if c > t_change]
        end = later[0] if later else t[-1] + 1.0
        before = (t >= t_change - 0.05) & (t < t_change)
        after = (t >= t_change) & (t < end)
        if not before.any() or not after.any():
            return {"time_s": t_change}
        base = float(np.mean(x[before]))
        dev = x[after] - base
        k = int(np.argmax(np.abs(dev)))
        unit = "rad" if name == "position" else "rad_s"
        return {
            "time_s": t_change,
            f"{name}_before_{unit}": base,
            f"max_deviation_{unit}": float(dev[k]),
            "at_s": float(t[after][k]),
        }

    def ramp_metrics(self) -> dict | None:
        """The saturated ramp of (21) after a speed step (module docstring), or None when the
        speed reference is not a single step from the initial speed or the step never saturates."""
        s = self.setup
        if s.mode != "speed-p":
            return None
        times, values = s.speed_reference
        changes = [i for i in range(1, len(values)) if values[i] != values[i - 1]]
        if len(changes) != 1 or times[changes[0]] != times[changes[0] - 1]:
            return None
        t_step, w_target = float(times[changes[0]]), float(values[changes[0]])
        t, w = self.t, self.signal("w")
        k_p, tau_max, J = s.speed_p.k_p, s.speed_p.tau_max, s.mechanics.J
        w0 = float(w[np.searchsorted(t, t_step)]) if t_step <= t[-1] else float(w[-1])
        sign = 1.0 if w_target >= w0 else -1.0
        span = abs(w_target - w0) - tau_max / k_p
        if span <= 0.0:
            return None
        t_sat = t_step + J * span / tau_max
        ideal = ideal_ramp(t, t_step, w0, w_target, k_p, tau_max, J)
        window = (t >= t_step) & (t <= min(t_sat, t[-1]))
        middle = (t >= t_step + 0.1 * (t_sat - t_step)) & (t <= t_step + 0.7 * (t_sat - t_step))
        slope = float(np.polyfit(t[middle], w[middle], 1)[0]) if middle.sum() > 2 else math.nan
        w_mid = w0 + sign * 0.4 * abs(w_target - w0)
        friction = float(s.mechanics.friction_torque(np.array([w_mid]))[0])
        return {
            "t_step_s": t_step,
            "t_saturated_end_s": t_sat,
            "ideal_slope_rad_s2": sign * tau_max / J,
            "ideal_slope_with_friction_rad_s2": sign * (tau_max - sign * friction) / J,
            "ramp_slope_rad_s2": slope,
            "speed_ramp_error_rad_s": float(np.sqrt(np.mean((w[window] - ideal[window]) ** 2))),
        }

    def position_metrics(self) -> dict:
        from acdrive.sim._recovery import im_position_outcome

        t, theta = self.t, self.signal("theta") + self.setup.sensors.offset
        ref = self.signal("theta_ref")
        steady = _steady_mask(t)
        final_ref = float(ref[-1])
        changes = self.load_changes()
        before = t < (changes[0] if changes else t[-1] + 1.0)
        out = {
            "position_final_rad": float(np.mean(theta[steady])),
            "position_reference_final_rad": final_ref,
            "position_final_error_rad": float(np.mean(ref[steady] - theta[steady])),
            "position_overshoot_rad": float(
                np.max(np.sign(final_ref or 1.0) * (theta[before] - ref[before]))
            ),
            "load_changes": [self._deviation(tc, theta, "position") for tc in self.load_changes()],
            "position_outcome": im_position_outcome(self),
        }
        return out

    def voltage_check(self) -> dict | None:
        """Can the DC link hold the flux reference at the top speed? The field-oriented steady
        voltage (``foc_voltage``, plant parameters) at the largest speed reference and flux
        reference, with no torque and with the torque limit, against the linear SVPWM limit of
        the lowest DC-link voltage (FOC modes only); in phase peak volts, as the other voltages
        of the summary (a space-vector magnitude over sqrt(3/2), Bodson (8))."""
        s = self.setup
        if s.mode == "current":
            return None
        w = s.top_speed() if s.mode != "position" else float(np.max(np.abs(self.signal("w"))))
        psi = float(np.max(s.foc.psi_ref[1]))
        tau = s.speed_p.tau_max if s.mode == "speed-p" else s.speed_pi.tau_max
        limit = float(max_voltage_magnitude(s.inverter.dc_link_min))
        return {
            "speed_rad_s": w,
            "flux_wb": psi,
            "needed_no_load_v": abs(foc_voltage(s.plant, psi, 0.0, w)) / SQRT_3_2,
            "needed_at_torque_limit_v": abs(foc_voltage(s.plant, psi, tau, w)) / SQRT_3_2,
            "limit_v": limit / SQRT_3_2,
        }

    def summary(self) -> dict:
        """The metrics of the module docstring for this run (units in the key names)."""
        s = self.setup
        i_s = np.abs(self.signal("i_s"))
        v_ref = np.abs(self.signal("v_ref"))
        out = {
            "controller": s.current_control.controller,
            "current_rms_error_a": self.current_rms_error(),
            "current_rms_reference_a": self.current_rms_reference(),
            "metrics_from_s": s.metrics_from,
            "peak_stator_current_a": float(np.max(i_s) / SQRT_3_2),
            "peak_voltage_command_v": float(np.max(v_ref) / SQRT_3_2),
            "voltage_limit_v": float(max_voltage_magnitude(s.inverter.dc_link_min) / SQRT_3_2),
            "peak_torque_n_m": float(np.max(np.abs(self.signal("tau_e")))),
            "events": dict(self.events),
        }
        ref_rms = out["current_rms_reference_a"]
        out["current_rms_error_relative"] = (
            out["current_rms_error_a"] / ref_rms if ref_rms > 0 else math.nan
        )
        if s.mode in ("speed-p", "speed-pi"):
            out.update(self.speed_metrics())
        if s.mode == "position":
            out.update(self.position_metrics())
        ramp = self.ramp_metrics()
        if ramp is not None:
            out["ramp"] = ramp
        check = self.voltage_check()
        if check is not None:
            out["voltage_check"] = check
        out["duration_s"] = float(self.t[-1] + s.sample_time * s.log_every)
        out["wall_time_s"] = self.wall_time
        return out

    # -- export -----------------------------------------------------------------------------
    def columns(self) -> list:
        """The columns of the result files (``acdrive.columns.Column``: name, values, unit,
        description). A space vector gives ``<name>_alpha_sv`` and ``<name>_beta_sv``, or
        ``<name>_d_sv`` and ``<name>_q_sv`` in the IFOC's field frame (``FIELD_FRAME``): the
        components of the power-invariant space vector as simulated (Bodson (8); divide by
        sqrt(3/2) for the phase-peak scaling of the figures and summary.json)."""
        from acdrive.columns import Column

        out = [Column("t", self.t, "s", "time of the logged sample")]
        for name, values in self.signals.items():
            unit, text = self.units[name], self.descriptions.get(name, name)
            if np.iscomplexobj(values):
                re, im = ("d", "q") if name in FIELD_FRAME else ("alpha", "beta")
                scaling = (
                    "power-invariant space-vector component (divide by sqrt(3/2) for phase peak)"
                )
                out.append(Column(f"{name}_{re}_sv", values.real, unit, f"{text}, {re}: {scaling}"))
                out.append(Column(f"{name}_{im}_sv", values.imag, unit, f"{text}, {im}: {scaling}"))
            else:
                out.append(Column(name, values, unit, text))
        for flag, what in (
            ("saturated", "the current controller's voltage command was limited"),
            ("overmodulation", "the inverter limited its latched command"),
        ):
            out.append(Column(flag, self.flags[flag].astype(np.int8), "", f"1 where {what}"))
        return out

    def to_dataframe(self):
        """A pandas DataFrame of :meth:`columns`; units in ``frame.attrs["units"]``,
        descriptions in ``frame.attrs["descriptions"]``."""
        import pandas as pd

        cols = self.columns()
        frame = pd.DataFrame({c.name: c.values for c in cols})
        frame.attrs["units"] = {c.name: c.unit for c in cols}
        frame.attrs["descriptions"] = {c.name: c.description for c in cols}
        return frame

    def save(self, folder, fmt: str = "parquet") -> list:
        """Write the data as ``fmt`` (``acdrive.columns.FORMATS``: parquet, csv or mat) and
        ``columns.md`` into ``folder`` (created if needed); return the paths written."""
        from pathlib import Path

        from acdrive.columns import write_table

        title = f"{self.setup.name} [{self.label}]: result columns"
        return write_table(Path(folder), self.columns(), fmt, title)


def ideal_ramp(t, t_step, w0, w_target, k_p, tau_max, J) -> np.ndarray:
    """Speed of (21) with a perfect torque and no friction after a step of the reference from
    w0 to w_target at t_step: the constant-torque ramp at tau_max / J while
    k_p |w_target - w| > tau_max, then the first-order approach w_target - (tau_max / k_p)
    e^{-(k_p / J)(t - t_sat)} (Fig. 16(a)'s ideal line)."""
    t = np.asarray(t, dtype=float)
    sign = 1.0 if w_target >= w0 else -1.0
    span = abs(w_target - w0) - tau_max / k_p
    out = np.full(t.shape, float(w0))
    if span <= 0.0:
        after = t >= t_step
        out[after] = w_target - (w_target - w0) * np.exp(-(k_p / J) * (t[after] - t_step))
        return out
    t_sat = t_step + J * span / tau_max
    ramp = (t >= t_step) & (t < t_sat)
    out[ramp] = w0 + sign * tau_max / J * (t[ramp] - t_step)
    tail = t >= t_sat
    out[tail] = w_target - sign * tau_max / k_p * np.exp(-(k_p / J) * (t[tail] - t_sat))
    return out


# --- scenarios: one or several runs -----------------------------------------------------------


@dataclass
class IMOutcome:
    """The runs of one scenario (label -> result) and its summary (summary.json)."""

    setup: IMDriveSetup
    results: dict[str, IMDriveResult]
    summary: dict = field(default_factory=dict)

    @property
    def main(self) -> IMDriveResult:
        return next(iter(self.results.values()))


#: metrics compared between runs at the top level of summary.json, with a label inserted before
#: the unit suffix (``current_rms_error_a`` -> ``current_rms_error_<label>_a``)
COMPARED = {
    "current_rms_error_a": ("current_rms_error", "_a"),
    "peak_stator_current_a": ("peak_stator_current", "_a"),
}


def run_im_scenario(setup: IMDriveSetup) -> IMOutcome:
    """Simulate every run of ``setup`` (compiled systems are shared between runs of the same
    topology) and summarise: the first run's metrics at the top level, every run's under
    ``runs``, and, with several runs, the compared metrics per label."""
    results = {}
    for label, run_setup in setup.runs():
        drive = IMDrive(run_setup)
        result = drive.run()
        result.label = label
        results[label] = result
    summaries = {label: r.summary() for label, r in results.items()}
    first = next(iter(summaries.values()))
    summary = {
        "scenario": setup.name,
        "description": setup.description,
        "drive": "cage-im",
        "mode": setup.mode,
        "controller": first["controller"],
        "inverter": {
            "model": setup.inverter.model,
            "pwm_frequency_hz": setup.inverter.f_pwm,
            "carrier_samples": setup.carrier_samples,
            "dead_time_s": setup.inverter.dead_time,
            "device_drop_v": setup.inverter.device_drop,
        },
        "sample_time_s": setup.sample_time,
        "discretisation": setup.current_control.method,
        **first,
    }
    if len(results) > 1:
        for key, (stem, unit) in COMPARED.items():
            for label, s in summaries.items():
                summary[f"{stem}_{label}{unit}"] = s[key]
        for label, s in summaries.items():
            if "ramp" in s:
                summary[f"speed_ramp_error_{label}"] = s["ramp"]["speed_ramp_error_rad_s"]
                summary[f"ramp_slope_{label}_rad_s2"] = s["ramp"]["ramp_slope_rad_s2"]
    summary["runs"] = summaries
    summary["warnings"] = warnings_of(setup, results, summaries) + im_control_period_warnings(setup)
    if not summary["warnings"]:
        del summary["warnings"]
    if setup.note:
        summary["note"] = setup.note
    return IMOutcome(setup=setup, results=results, summary=summary)


def _span(result: IMDriveResult, flag: str) -> str:
    """When a per-sample event flag was raised, from the logged samples."""
    hits = np.flatnonzero(result.flags[flag])
    if hits.size == 0:
        return "between logged samples"
    return f"logged between {result.t[hits[0]]:.4g} s and {result.t[hits[-1]]:.4g} s"


def im_control_period_warnings(setup: IMDriveSetup) -> list[str]:
    """``drives.cage_im._period.im_control_period_warnings`` (imported when called)."""
    from acdrive.drives.cage_im._period import im_control_period_warnings as warnings

    return warnings(setup)


def warnings_of(setup: IMDriveSetup, results: dict, summaries: dict) -> list[str]:
    """What a reader must know about the runs, from their numbers: voltage saturation (with the
    DC link's shortfall where the flux reference at the speed reached needs more than it gives),
    overmodulation and current limiting, each with when it happened."""
    out = []
    n = max(1, round(setup.duration / setup.sample_time))
    for label, s in summaries.items():
        ev, result = s["events"], results[label]
        for key in ("speed_outcome", "position_outcome"):  # loss of control, no recovery
            out += s.get(key, {}).pop("warnings", [])
        if ev["current_controller_saturation"]:
            check = s.get("voltage_check")
            why = ""
            if check and check["needed_at_torque_limit_v"] > check["limit_v"]:
                why = (
                    f"; holding {check['flux_wb']:.3g} Wb at {check['speed_rad_s']:.0f} rad/s "
                    f"needs {check['needed_no_load_v']:.0f} V (no load) to "
                    f"{check['needed_at_torque_limit_v']:.0f} V (torque limit) of the "
                    f"{check['limit_v']:.0f} V the DC link gives (phase peak)"
                )
            out.append(
                f"{label}: the current controller's voltage command was limited to "
                f"v_dc/sqrt(2) on {ev['current_controller_saturation']} of {n} samples "
                f"({ev['current_controller_saturation'] / n:.1%}), {_span(result, 'saturated')}"
                + why
            )
        if ev.get("overmodulation"):
            out.append(
                f"{label}: the inverter limited its latched command (overmodulation) on "
                f"{ev['overmodulation']} samples, {_span(result, 'overmodulation')}"
            )
        if ev.get("current_limit"):
            out.append(
                f"{label}: the IFOC limited the stator current reference to "
                f"{setup.foc.i_max:g} A (space vector) on {ev['current_limit']} samples"
            )
    return out
