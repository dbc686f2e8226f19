"""Typed simulation results: logged signals, derived metrics, export to pandas / CSV / Parquet."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from acdrive.control.dfim import EVENT_NAMES
from acdrive.frames import K_PEAK as SQRT_3_2  # Bodson (8)
from acdrive.sim.engine import LOG_NAMES

RPM_PER_RAD_S = 30.0 / np.pi


@dataclass
class DriveResult:
    """Signals of every motor at every logged sample.

    ``signals[i, k, j]`` is signal ``LOG_NAMES[j]`` of motor k at time ``t[i]``: speeds in rad/s,
    torques in N m, voltage and current magnitudes as complex space-vector magnitudes (Bodson (8):
    divide by sqrt(3/2) for the peak phase value), rotor phase currents X and Y in A, and the
    event-flag bits of ``acdrive.control.dfim``.
    """

    name: str
    t: np.ndarray
    signals: np.ndarray
    sample_time: float
    final_state: np.ndarray
    wall_time: float = 0.0

    @property
    def n_motors(self) -> int:
        return self.signals.shape[1]

    def signal(self, name: str, motor: int = 0) -> np.ndarray:
        return self.signals[:, motor, LOG_NAMES.index(name)]

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

    def tracking_mask(
        self, motor: int = 0, settle_s: float = 0.5, jump_rpm: float = 10.0
    ) -> np.ndarray:
        """Samples where the speed is expected to track: not within ``settle_s`` after a reference
        jump (a change larger than ``jump_rpm`` in one sample, such as the abrupt stop of Fig. 4)."""
        ref = self.reference_rpm(motor)
        jumps = np.flatnonzero(np.abs(np.diff(ref)) > jump_rpm) + 1
        mask = np.ones(ref.size, dtype=bool)
        for j in jumps:
            mask[(self.t >= self.t[j]) & (self.t < self.t[j] + settle_s)] = False
        return mask

    def speed_oscillation(self, motor: int = 0, band_hz=(20.0, 200.0)) -> tuple[float, float]:
        """(RMS [rpm], dominant frequency [Hz]) of the speed error in ``band_hz`` over the tracking
        samples (Parseval on the FFT of the masked error): a limit cycle shows up here, a slow
        tracking lag does not."""
        mask = self.tracking_mask(motor)
        if mask.sum() < 16:
            return 0.0, 0.0
        err = np.where(mask, self.reference_rpm(motor) - self.speed_rpm(motor), 0.0)
        spectrum = np.fft.rfft(err - err[mask].mean() * mask)
        freq = np.fft.rfftfreq(err.size, self.t[1] - self.t[0])
        inside = (freq >= band_hz[0]) & (freq <= band_hz[1])
        power = np.abs(spectrum[inside]) ** 2
        rms = float(np.sqrt(2.0 * power.sum() / (err.size * mask.sum())))
        return rms, float(freq[inside][np.argmax(power)]) if power.size else 0.0

    def summary(self) -> dict:
        """Headline metrics (motor 0 at top level, every motor under ``motors``).

        speed_rms_error_rpm is taken over ``tracking_mask`` samples (reference steps excluded for
        0.5 s); speed_max_abs_error_rpm over the whole run."""
        """Headline metrics (motor 0 at top level, every motor under ``motors``)."""
        per_motor = []
        oscillation = [self.speed_oscillation(k) for k in range(self.n_motors)]
        for k in range(self.n_motors):
            err = self.reference_rpm(k) - self.speed_rpm(k)
            tracking = self.tracking_mask(k)
            per_motor.append(
                {
                    "speed_rms_error_rpm": float(np.sqrt(np.mean(err[tracking] ** 2))),
                    "speed_max_abs_error_rpm": float(np.max(np.abs(err))),
                    "peak_rotor_current_a": float(np.max(self.peak("i_r_mag", k))),
                    "peak_stator_current_a": float(np.max(self.peak("i_s_mag", k))),
                    "peak_rotor_voltage_v": float(np.max(self.peak("v_r_mag", k))),
                    "limit_events": self.events(k),
                    "speed_oscillation_rms_rpm": oscillation[k][0],
                    "speed_oscillation_hz": oscillation[k][1],
                }
            )
        return {
            "scenario": self.name,
            **per_motor[0],
            "motors": per_motor,
            "duration_s": float(self.t[-1] + self.sample_time),
            "wall_time_s": self.wall_time,
        }

    def to_dataframe(self):
        """A pandas DataFrame with column ``t`` and one column per signal (``name`` for a single
        motor, ``name_k`` for motor k of several)."""
        import pandas as pd

        columns = {"t": self.t}
        for k in range(self.n_motors):
            suffix = "" if self.n_motors == 1 else f"_{k}"
            for j, name in enumerate(LOG_NAMES):
                columns[name + suffix] = self.signals[:, k, j]
        return pd.DataFrame(columns)

    def save(self, folder: Path, formats=("csv", "parquet")) -> list[Path]:
        folder = Path(folder)
        frame = self.to_dataframe()
        written = []
        if "csv" in formats:
            frame.to_csv(folder / "data.csv", index=False)
            written.append(folder / "data.csv")
        if "parquet" in formats:
            frame.to_parquet(folder / "data.parquet", index=False)
            written.append(folder / "data.parquet")
        return written
