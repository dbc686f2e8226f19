"""How much of a run is logged, chosen before the run: every ``log_every``-th control sample, and
what that log takes in memory.

A run logs every sample while it has at most ``DEFAULT_LOG_ROWS`` of them; a longer run logs
every k-th sample, k the smallest integer that keeps at most ``DEFAULT_LOG_ROWS`` (the default).
A scenario's ``simulation.log_every`` or ``acdrive run --log-every`` chooses k instead. The
logged rows of a run with ``log_every`` k are its samples 0, k, 2k, ... as the run with k = 1
logs them, bit for bit (the loop records a row when ``sample % k == 0``).

The log of one run is two arrays the loop writes: the selected outputs (float64, one column per
real value, two per complex port) and the event bits (int64, one column per sampled part or
modulator), each with one row per logged sample; ``LogPlan.bytes`` is their size.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: logged samples a run keeps by default: all of a run with at most this many samples, else
#: every k-th (k the smallest that keeps at most this many)
DEFAULT_LOG_ROWS = 100_000

#: bytes per logged value (float64 outputs, int64 event bits)
VALUE_BYTES = 8


def default_log_every(n_steps: int) -> int:
    """The default ``log_every`` of a run of ``n_steps`` control samples: 1 up to
    ``DEFAULT_LOG_ROWS`` samples, else the smallest k with ceil(n_steps / k) <= DEFAULT_LOG_ROWS."""
    return max(1, -(-int(n_steps) // DEFAULT_LOG_ROWS))


def logged_rows(n_steps: int, log_every: int) -> int:
    """Rows of the log of a run of ``n_steps`` samples logged every ``log_every`` (samples 0, k,
    2k, ... below n_steps)."""
    return -(-int(n_steps) // int(log_every))


@dataclass(frozen=True)
class LogPlan:
    """The log of one run: every ``log_every``-th of ``n_steps`` samples, ``columns`` output
    values and ``event_columns`` event words per row; ``chosen_by`` names who chose
    ``log_every`` (``"default"``, ``"simulation.log_every"`` or ``"--log-every"``)."""

    n_steps: int
    log_every: int
    columns: int
    event_columns: int
    chosen_by: str = "default"

    @property
    def rows(self) -> int:
        return logged_rows(self.n_steps, self.log_every)

    @property
    def bytes(self) -> int:
        """Bytes of the two log arrays of the run (outputs and event bits)."""
        return self.rows * (self.columns + self.event_columns) * VALUE_BYTES

    def describe(self) -> str:
        """One phrase for the line announcing the run."""
        every = "every sample" if self.log_every == 1 else f"every {self.log_every}th sample"
        return (
            f"logging {every} ({self.chosen_by}): {self.rows:,} samples x "
            f"{self.columns + self.event_columns} values, {self.bytes / 1e6:.3g} MB"
        )

    def summary(self) -> dict:
        """summary.json's ``log``: the choice, its rule and the memory of the log."""
        return {
            "log_every": self.log_every,
            "chosen_by": self.chosen_by,
            "default_rule": f"every sample up to {DEFAULT_LOG_ROWS:,} samples, else every k-th "
            f"sample with k the smallest that keeps at most {DEFAULT_LOG_ROWS:,}",
            "samples": self.n_steps,
            "logged_samples": self.rows,
            "values_per_sample": self.columns + self.event_columns,
            "log_bytes": self.bytes,
        }


def run_steps(duration: float, sample_time: float) -> int:
    """Control samples of a run (as the engine counts them)."""
    return max(1, round(duration / sample_time)) if math.isfinite(duration / sample_time) else 1
