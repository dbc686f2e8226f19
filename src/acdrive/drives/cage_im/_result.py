"""The result of one cage-IM drive run (``IMDriveResult``): named signals with units, event
counts and flags, and the metrics of its summary (module docstring of ``drives.cage_im._drive``:
the windows and rules of each figure)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from acdrive._arguments import (
    COUNT0,
    NONNEGATIVE,
    TEXT,
    Array,
    Flag,
    Instance,
    Number,
    Table,
    Text,
    checked,
)
from acdrive._frames import K_PEAK as SQRT_3_2
from acdrive.drives.cage_im._physics import foc_voltage, modulation_signals
from acdrive.drives.cage_im._setup import (
    FIELD_FRAME,
    IMDriveSetup,
    divergence_hint,
    profile_changes,
)
from acdrive.errors import SimulationDiverged
from acdrive.plant._converter import max_voltage_magnitude
from acdrive.sim._result import Result
from acdrive.sim._timing import run_timing

#: the last fraction of a run over which steady values are averaged
STEADY_FRACTION = 0.1
#: the shortest steady window [s]
STEADY_MIN_S = 0.05


def _steady_mask(t: np.ndarray) -> np.ndarray:
    span = max(STEADY_FRACTION * (t[-1] - t[0]), STEADY_MIN_S)
    return t >= t[-1] - span


@checked(
    setup=Instance(IMDriveSetup), label=TEXT, t=Array(1, finite=False, empty=True),
    signals=Table(Array(1, complex=True, finite=False, empty=True), empty=True),
    units=Table(Text(empty=True), empty=True), events=Table(Number(0, integer=True), empty=True),
    flags=Table(Array(1, finite=False, empty=True), empty=True), wall_time=NONNEGATIVE,
    steps=COUNT0, compile_time=NONNEGATIVE, compiled_now=Flag(), tier=Text(empty=True),
    descriptions=Table(Text(empty=True), empty=True),
)
@dataclass(eq=False, repr=False)
class IMDriveResult(Result):
    """The cage-IM drive's view of a run (``sim._result.Result``): its signals by name
    (``signals[name]``: complex for space vectors, in acdrive's power-invariant scaling, Bodson
    (8)), their units, the named event totals and the per-sample event flags; ``summary`` holds
    the metrics of the module docstring. The drive is one part of the view, ``im``:
    ``result.im.i_s`` is ``result.signal("i_s")``."""

    setup: IMDriveSetup
    label: str
    t: np.ndarray
    signals: dict[str, np.ndarray]
    units: dict[str, str]
    events: dict[str, int]
    flags: dict[str, np.ndarray]
    wall_time: float = 0.0
    steps: int = 0
    #: the loop's compile or load before the run (``acdrive.sim._timing``), apart from wall_time
    compile_time: float = 0.0
    compiled_now: bool = False
    tier: str = ""
    #: one-line description of each signal (the logged port's declaration)
    descriptions: dict[str, str] = field(default_factory=dict)

    @classmethod
    def from_system(
        cls,
        setup: IMDriveSetup,
        raw,
        ports: dict,
        events: dict[str, int],
        flags: dict[str, np.ndarray],
        label: str | None = None,
    ) -> IMDriveResult:
        """The view of ``raw`` (the ``sim.SystemResult`` of ``setup``'s system) that logged
        ``ports`` (signal name -> port, ``IMDrive.log_ports``), with the drive's named event
        totals and per-sample flags (``IMDrive.event_counts`` and ``event_flags``); a logged
        signal that is not finite raises ``SimulationDiverged``."""
        s = setup
        signals, units, descriptions = {}, {}, {}
        for name, port in ports.items():
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
            events=events,
            flags=flags,
            wall_time=raw.wall_time,
            steps=raw.steps,
            compile_time=raw.compile_time,
            compiled_now=raw.compiled_now,
            tier=raw.tier,
            descriptions=descriptions,
        )

    @property
    def title(self) -> str:
        return f"{self.setup.name} [{self.label}]: result columns"

    @property
    def duration(self) -> float:
        return float(self.t[-1] + self.setup.sample_time) if self.t.size else 0.0

    @property
    def plot_signals(self) -> tuple[str, ...]:
        """The current against its reference, the speed against its reference (FOC modes) and
        the electrical torque."""
        speed = () if self.setup.mode == "current" else ("w_ref", "w")
        return ("i_ref", "i_s", *speed, "tau_e")

    def _declare(self) -> dict[str, tuple[str, str]]:
        return {
            f"im.{n}": (self.units.get(n, ""), self.descriptions.get(n, n)) for n in self.signals
        }

    def _values(self, key: str) -> np.ndarray:
        return self.signals[key.removeprefix("im.")]

    def _headline(self) -> list[str]:
        s, summary = self.setup, self.summary
        out = [f"[{self.label}] mode {s.mode}",
               f"current RMS error {summary['current_rms_error_a']:.3g} A"]  # fmt: skip
        if s.mode != "current":
            w = self.signal("w")
            out.append(f"speed {float(np.min(w)):.1f} to {float(np.max(w)):.1f} rad/s")
        return out

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
        from acdrive.drives.cage_im._recovery import im_speed_outcome, im_step_events
        from acdrive.drives.cage_im._tracking import im_tracking_rule
        from acdrive.sim._metrics import speed_tracking
        from acdrive.sim._step_response import step_response

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
        out["step_response"] = step_response(t, w, w_ref, im_step_events(self.setup))
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
        from acdrive.drives.cage_im._recovery import im_position_outcome

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

    def _compute_summary(self) -> dict:
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
        out.update(run_timing([self]))
        return out

    # -- export -----------------------------------------------------------------------------
    def table_columns(self, separator: str = ".") -> list:
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
