"""Typed simulation results: logged signals, derived metrics, export to pandas / CSV / Parquet."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acdrive._arguments import (
    NONNEGATIVE,
    POSITIVE,
    TEXT,
    Array,
    Flag,
    Instance,
    Items,
    Text,
    checked,
)
from acdrive._frames import K_PEAK as SQRT_3_2  # Bodson (8)
from acdrive.columns import Column
from acdrive.control._dfim import EVENT_NAMES
from acdrive.sim._metrics import (
    OSCILLATION_BAND_HZ,
    RPM_PER_RAD_S,
    TrackingRule,
    limit_cycle,
    speed_oscillation,
    speed_tracking,
)
from acdrive.sim._result import Result
from acdrive.sim._timing import run_timing

#: the signals of a DFIM drive run, per motor and logged sample (``DriveResult.signals``)
LOG_NAMES = ("w", "w_ref", "tau_com", "tau_e", "v_s_mag", "v_r_mag", "i_s_mag", "i_r_mag", "i_rx",
             "i_ry", "flags", "i_r_com_mag", "q_s", "v_mismatch", "theta_adj", "m_adj", "phase",
             "mode", "relay_closed", "i_r_com_d", "i_r_com_q", "i_r_d", "i_r_q")  # fmt: skip
N_LOG = len(LOG_NAMES)

_PK = "peak phase value (space-vector magnitude / sqrt(3/2), Bodson (8))"
_SV = (
    "power-invariant space-vector component in the stator-voltage frame (divide by sqrt(3/2) "
    "for phase peak)"
)
#: the columns of the result files: (file name, signal of ``LOG_NAMES``, scale, unit, description).
#: Magnitudes are written as peak phase values (suffix ``_pk``, as summary.json and the figures),
#: components as power-invariant space vectors (suffix ``_sv``; ``acdrive.columns``).
FILE_COLUMNS = (
    ("w", "w", 1.0, "rad/s", "shaft speed (mechanical)"),
    ("w_ref", "w_ref", 1.0, "rad/s", "speed reference (mechanical)"),
    ("tau_com", "tau_com", 1.0, "N m", "torque command of the speed controller (25), limited"),
    ("tau_e", "tau_e", 1.0, "N m", "electromagnetic torque"),
    ("v_s_pk", "v_s_mag", 1.0 / SQRT_3_2, "V", f"stator terminal voltage, {_PK}"),
    ("v_r_pk", "v_r_mag", 1.0 / SQRT_3_2, "V", f"rotor voltage applied by the converter, {_PK}"),
    ("i_s_pk", "i_s_mag", 1.0 / SQRT_3_2, "A", f"stator current, {_PK}"),
    ("i_r_pk", "i_r_mag", 1.0 / SQRT_3_2, "A", f"rotor current, {_PK}"),
    ("i_rx", "i_rx", 1.0, "A", "rotor phase X current, instantaneous"),
    ("i_ry", "i_ry", 1.0, "A", "rotor phase Y current, instantaneous"),
    ("flags", "flags", 1.0, "",
     "event bits raised on this sample: " + ", ".join(
         f"{1 << b} {name}" for b, name in enumerate(EVENT_NAMES))),
    ("i_r_com_pk", "i_r_com_mag", 1.0 / SQRT_3_2, "A", f"rotor current command (43), {_PK}"),
    ("q_s", "q_s", 1.0, "var", "stator reactive power Im(v_s conj(i_s)) (Bodson (5))"),
    ("v_mismatch", "v_mismatch", 1.0, "",
     "|v_s - v_grid| / |v_grid|: stator voltage against the grid's (synchronisation)"),
    ("theta_adj", "theta_adj", 1.0, "rad", "synchroniser's angle adjustment theta_adj"),
    ("m_adj", "m_adj", 1.0, "", "synchroniser's magnitude adjustment m_adj"),
    ("relay_command", "phase", 1.0, "", "synchroniser's relay command: 1 close, 0 open"),
    ("mode", "mode", 1.0, "", "controller mode in use: 0 voltage command, 1 current command"),
    ("relay_closed", "relay_closed", 1.0, "", "stator relay: 1 closed, 0 open"),
    ("i_r_com_d_sv", "i_r_com_d", 1.0, "A", f"rotor current command (43), d: {_SV}"),
    ("i_r_com_q_sv", "i_r_com_q", 1.0, "A", f"rotor current command (43), q: {_SV}"),
    ("i_r_d_sv", "i_r_d", 1.0, "A", f"measured rotor current, d: {_SV}"),
    ("i_r_q_sv", "i_r_q", 1.0, "A", f"measured rotor current, q: {_SV}"),
)  # fmt: skip

_MAG = "power-invariant space-vector magnitude (Bodson (8): divide by sqrt(3/2) for phase peak)"
#: unit and description of each signal of ``LOG_NAMES`` (as simulated: magnitudes are
#: power-invariant space-vector magnitudes; ``FILE_COLUMNS`` scales them to phase peak)
SIGNALS = {log: (unit, text.replace(_PK, _MAG) if scale != 1.0 else text)
           for _, log, scale, unit, text in FILE_COLUMNS}  # fmt: skip


@checked(
    name=TEXT, t=Array(1, finite=False, empty=True), signals=Array(3, finite=False, empty=True),
    sample_time=POSITIVE, final_state=Array(finite=False, empty=True), wall_time=NONNEGATIVE,
    compile_time=NONNEGATIVE, compiled_now=Flag(), tier=Text(empty=True),
    tracking=Items(Instance(TrackingRule), optional=True),
)
@dataclass(eq=False, repr=False)
class DriveResult(Result):
    """The DFIM drive's view of a run (``sim._result.Result``): every motor's signals at every
    logged sample.

    ``signals[i, k, j]`` is signal ``LOG_NAMES[j]`` of motor k at time ``t[i]``: speeds in rad/s,
    torques in N m, voltage and current magnitudes as complex space-vector magnitudes (Bodson (8):
    divide by sqrt(3/2) for the peak phase value), rotor phase currents X and Y in A, and the
    event-flag bits of ``acdrive.control._dfim``. Each motor is one part of the view, named as
    its machine part in the system: ``dfim0``, ``dfim1``, ... (``result.dfim0.w``;
    ``result.dfim.w`` when there is one motor); ``signal(name, k)`` reads motor k and a bare
    name reads motor 0. The result files keep their layout (``FILE_COLUMNS``, ``_m1``, ``_m2``
    suffixes counting motors from 1).
    """

    name: str
    t: np.ndarray
    signals: np.ndarray
    sample_time: float
    final_state: np.ndarray
    wall_time: float = 0.0
    #: the loop's compile or load before the run (``acdrive.sim._timing``), apart from wall_time
    compile_time: float = 0.0
    compiled_now: bool = False
    tier: str = ""
    #: per motor, where the speed is expected to track (``drives.dfim._tracking.tracking_rule`` of the
    #: scenario); None (a result built by hand): every sample
    tracking: tuple[TrackingRule, ...] | None = None

    #: a bare signal name reads motor 0
    _default_part = 0
    plot_signals = ("w", "w_ref", "i_r_mag", "i_s_mag", "tau_com", "tau_e")

    @property
    def n_motors(self) -> int:
        return self.signals.shape[1]

    @property
    def title(self) -> str:
        return f"{self.name}: result columns"

    @property
    def duration(self) -> float:
        return float(self.t[-1] + self.sample_time) if self.t.size else 0.0

    def _declare(self) -> dict[str, tuple[str, str]]:
        return {f"dfim{k}.{name}": SIGNALS[name] for k in range(self.n_motors)
                for name in LOG_NAMES}  # fmt: skip

    def _values(self, key: str) -> np.ndarray:
        part, name = key.split(".", 1)
        return self.signals[:, int(part.removeprefix("dfim")), LOG_NAMES.index(name)]

    def speed_rpm(self, motor: int = 0) -> np.ndarray:
        return self.signal("w", motor) * RPM_PER_RAD_S

    def reference_rpm(self, motor: int = 0) -> np.ndarray:
        return self.signal("w_ref", motor) * RPM_PER_RAD_S

    def peak(self, name: str, motor: int = 0) -> np.ndarray:
        """Peak phase value of a space-vector magnitude signal (Bodson (8))."""
        return self.signal(name, motor) / SQRT_3_2

    def events(self, motor: int = 0) -> dict[str, int]:
        """Number of samples on which each event flag was raised."""
        flags = self.signal("flags", motor).astype(np.int64)
        return {
            name: int(np.count_nonzero(flags & (1 << bit))) for bit, name in enumerate(EVENT_NAMES)
        }

    def first_event_time(self, name: str, motor: int = 0) -> float | None:
        flags = self.signal("flags", motor).astype(np.int64)
        hits = np.flatnonzero(flags & (1 << EVENT_NAMES.index(name)))
        return float(self.t[hits[0]]) if hits.size else None

    def tracking_rule(self, motor: int = 0) -> TrackingRule:
        """Where motor ``motor``'s speed is expected to track (``sim._metrics.TrackingRule``):
        the scenario's rule when the result comes from a simulation, else every sample."""
        return self.tracking[motor] if self.tracking is not None else TrackingRule()

    def speed_tracking(self, motor: int = 0) -> tuple[dict, dict, np.ndarray]:
        """(speed-error figures, ``speed_tracking``, tracked mask) of motor ``motor``
        (``sim._metrics.speed_tracking``: the kernel the batch runs on line)."""
        rule = self.tracking_rule(motor)
        closed = self.signal("relay_closed", motor) if rule.relay else None
        return speed_tracking(self.t, self.signal("w", motor), self.signal("w_ref", motor),
                              closed, rule)  # fmt: skip

    def tracking_mask(self, motor: int = 0) -> np.ndarray:
        """Samples where the speed is expected to track (``tracking_rule``)."""
        return self.speed_tracking(motor)[2]

    def speed_oscillation(self, motor: int = 0, band_hz=OSCILLATION_BAND_HZ):
        """(band RMS [rpm], dominant frequency [Hz] or None) of the speed error over the longest
        stretch of tracked samples (``sim._metrics.speed_oscillation``; the frequency only where
        a limit cycle is shown)."""
        err = (self.signal("w_ref", motor) - self.signal("w", motor)) * RPM_PER_RAD_S
        return speed_oscillation(self.t, err, self.tracking_mask(motor), band_hz)

    def limit_excursions(self, motor: int, limits_pk: dict[str, float]) -> dict[str, dict]:
        """For each current signal (``i_r_mag``, ``i_s_mag``) and its peak-phase limit [A]: the
        number of logged samples above the limit, the largest peak and the first time above."""
        out = {}
        for name, limit in limits_pk.items():
            peak = self.peak(name, motor)
            above = np.flatnonzero(peak > limit)
            out[name] = {
                "limit_a": float(limit),
                "samples_above": int(above.size),
                "peak_a": float(np.max(peak)),
                "first_time_s": float(self.t[above[0]]) if above.size else None,
            }
        return out

    def _compute_summary(self) -> dict:
        """Headline metrics (motor 0 at top level, every motor under ``motors``), each computed
        once in ``acdrive.sim._metrics`` with its window in its name: ``_whole_run_`` (every
        logged sample) or ``_tracking_`` (``speed_tracking``: the rule, the excluded windows and
        the same figures); ``sim._metrics.limit_cycle`` over the longest tracked stretch:
        ``speed_oscillation_rms_rpm`` in OSCILLATION_BAND_HZ, the period correlation,
        ``speed_limit_cycle`` and ``speed_oscillation_hz`` (None unless a limit cycle is shown)."""
        per_motor = []
        for k in range(self.n_motors):
            figures, tracking, mask = self.speed_tracking(k)
            err = (self.signal("w_ref", k) - self.signal("w", k)) * RPM_PER_RAD_S
            per_motor.append(
                {
                    **figures,
                    "speed_tracking": tracking,
                    "peak_rotor_current_a": float(np.max(self.peak("i_r_mag", k))),
                    "peak_stator_current_a": float(np.max(self.peak("i_s_mag", k))),
                    "peak_rotor_voltage_v": float(np.max(self.peak("v_r_mag", k))),
                    "limit_events": self.events(k),
                    **limit_cycle(self.t, err, mask),
                }
            )
        return {
            "scenario": self.name,
            **per_motor[0],
            "motors": per_motor,
            "duration_s": float(self.t[-1] + self.sample_time),
            **run_timing([self]),
        }

    def table_columns(self, separator: str = ".") -> list[Column]:
        """The columns of the result files (``FILE_COLUMNS``; for several motors every signal
        once per motor, named ``<name>_m<k>`` for motor k = 1, 2, ...), with units and
        descriptions (the names hold no separator)."""
        out = [Column("t", self.t, "s", "time of the logged sample")]
        for k in range(self.n_motors):
            suffix = "" if self.n_motors == 1 else f"_m{k + 1}"
            who = "" if self.n_motors == 1 else f"motor {k + 1}: "
            for name, log_name, scale, unit, description in FILE_COLUMNS:
                values = self.signals[:, k, LOG_NAMES.index(log_name)]
                if name == "flags":
                    values = values.astype(np.int32)
                elif scale != 1.0:
                    values = values * scale
                out.append(Column(name + suffix, values, unit, who + description))
        return out

    def _headline(self) -> list[str]:
        """The speed range and the largest rotor current of the summary (phase peak)."""
        speed = self.speed_rpm(0)
        peak = max(m["peak_rotor_current_a"] for m in self.summary["motors"])
        return [
            f"speed {float(np.min(speed)):.0f} to {float(np.max(speed)):.0f} rpm",
            f"peak rotor current {peak:.3g} A (phase peak)",
        ]
