"""The cage induction motor drive of Amezquita-Brooks et al. (sections VI-VIII) built from parts.

Data flow (as the DFIM drive, ``drives.dfim._drive``): scenario (TOML, ``drives.cage_im._schema``) ->
``IMDriveSetup`` (frozen dataclasses) -> ``IMDrive`` (parts and wires) -> ``sim.System``
-> compiled loop -> ``IMDriveResult`` (named signals with units, events, ``summary``) ->
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
  by the DFIM drive's rule (``sim._recovery``, in rpm); ``step_response``: rise time,
  overshoot, settling time and steady-state error after each speed-reference change, dip and
  recovery after each load or brake step (``sim._step_response``, in rad/s);
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

import math

import numpy as np

from acdrive._arguments import checked
from acdrive.drives._registry import Setup
from acdrive._frames import K_PEAK as SQRT_3_2
from acdrive.control._bodson import SpeedEstimator
from acdrive.control._current import (
    CurrentProgram,
    StationaryCurrentController,
)
from acdrive.control._foc import (
    IndirectFOC,
    PositionP,
    SaturatedSpeedP,
    SpeedPI,
)
from acdrive.control._speed import SpeedReference
from acdrive.core._profile import Profile
from acdrive.drives.cage_im._physics import bumpless_state
from acdrive.drives.cage_im._result import IMDriveResult
from acdrive.drives.cage_im._setup import (
    CurrentReference,
    IMDriveSetup,
    divergence_hint,
    profile_at,
)
from acdrive.errors import SimulationDiverged
from acdrive.machines._cage_part import CageInductionMachine
from acdrive.plant._converter import DCFedConverter
from acdrive.plant._inverter import CarrierLatch, Inverter
from acdrive.plant._mechanics import PrescribedSpeed, Shaft
from acdrive.plant._sensors import Encoder, encoder_angle
from acdrive.plant._sources import DCSource
from acdrive.sim._system import System

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
    return {"re": Profile(t, i.real), "im": Profile(t, i.imag)}


@checked(setup=Setup())  # any drive's: require_setup names the drive
class IMDrive:
    """The parts, wiring, initial state and logged signals of one ``IMDriveSetup`` run (its
    ``current_control.controller``; ``IMDriveSetup.runs`` splits a comparison)."""

    def __init__(self, setup: IMDriveSetup):
        from acdrive.drives._registry import require_setup

        self.setup = s = require_setup(setup, (IMDriveSetup,), "acdrive.drives.IMDrive")
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
        events, flags = self.event_counts(raw), self.event_flags(raw)
        return IMDriveResult.from_system(s, raw, ports, events, flags)

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
