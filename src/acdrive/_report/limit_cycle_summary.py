"""A drive run's summary as the Bodson report prints it when the run limit-cycles.

The whole-run numbers of a run that limit-cycles (``DriveResult.summary``) change in their last
digits from one platform to the next (``spread`` module docstring). ``shown_summary`` returns
the summary of such a run with those numbers replaced by ``Shown`` values, which print the
number rounded to the significance the limit cycle allows whatever format the report asks for:

- an RMS speed error: rounded to the spread of the mean square over sub-windows of the tracked
  samples, carried to the root (d sqrt(m) = dm / (2 sqrt(m)));
- a largest speed error or a peak current: rounded to the limit cycle's own size, the largest
  speed error over the tracked samples, or the current's deviation from its slow course
  (``cycle_amplitude``): where the largest value falls in the cycle is what moves;
- an event count: its order of magnitude only (``spread.order_of_magnitude``);

never coarser than the number's leading digit, with the rounding step printed beside it.

A run that does not limit-cycle keeps its summary unchanged.
"""

from __future__ import annotations

import math

import numpy as np

from acdrive._spread import (
    mean_and_spread,
    order_of_magnitude,
    round_to_spread,
)
from acdrive.drives.dfim._outcome import OSCILLATION_FINDING_RPM


class Shown(float):
    """A number that prints as ``text`` (its value rounded to what it is known to), whatever
    the format specification."""

    def __new__(cls, value: float, text: str):
        obj = super().__new__(cls, value)
        obj.text = text
        return obj

    def __format__(self, spec: str) -> str:
        return self.text

    def __repr__(self) -> str:
        return self.text

    __str__ = __repr__


def limit_cycles(outcome) -> bool:
    """Whether any motor of any run of ``outcome`` limit-cycles (speed-error RMS in the band
    above the summary's finding threshold)."""
    return any(
        r.speed_oscillation(k)[0] > OSCILLATION_FINDING_RPM
        for r in outcome.results.values()
        for k in range(r.n_motors)
    )


#: Length [s] of the moving average that separates a signal's limit cycle (tens of Hz) from its
#: slow course along the run (ramps, steps).
CYCLE_AVERAGE_S = 0.1


def cycle_amplitude(t, x, mask) -> float:
    """Standard deviation of ``x`` about its CYCLE_AVERAGE_S moving average over the samples
    in ``mask``: the size of the limit cycle in ``x``, by which its largest value moves."""
    dt = float(t[1] - t[0])
    n = max(1, round(CYCLE_AVERAGE_S / dt))
    slow = np.convolve(x, np.ones(n) / n, mode="same")
    return float(np.std((x - slow)[mask])) if np.any(mask) else 0.0


def _shown_motor(result, k: int, entry: dict) -> dict:
    err = result.reference_rpm(k) - result.speed_rpm(k)
    tracking = result.tracking_mask(k)
    square = err[tracking] ** 2
    ms, ms_spread = mean_and_spread(square)
    rms = float(np.sqrt(ms))
    amplitude = float(np.max(np.abs(err[tracking]))) if tracking.any() else 0.0
    out = dict(entry)
    for key, value in entry.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            continue
        if key == "speed_rms_error_tracking_rpm":
            spread = ms_spread / (2.0 * rms) if rms > 0 else 0.0
        elif key == "speed_rms_error_whole_run_rpm":
            ms_all, ms_all_spread = mean_and_spread(err**2)
            spread = ms_all_spread / (2.0 * math.sqrt(ms_all)) if ms_all > 0 else 0.0
        elif key.startswith("speed_max_abs_error"):
            spread = amplitude
        elif key.startswith("peak_") and key.endswith("_a"):
            name = "i_r_mag" if "rotor" in key else "i_s_mag"
            spread = cycle_amplitude(result.t, result.peak(name, k), tracking)
        else:
            continue
        out[key] = Shown(
            value, round_to_spread(value, spread, ".3f", leading_digit=True, show_step=True)
        )
    if "limit_events" in entry:
        out["limit_events"] = {
            name: Shown(count, order_of_magnitude(count)) if count else count
            for name, count in entry["limit_events"].items()
        }
    return out


def shown_summary(outcome) -> dict:
    """``outcome.summary`` with the whole-run numbers of a limit-cycling run rounded to what
    the limit cycle allows (module docstring); unchanged if no run limit-cycles. The top-level
    numbers are those of motor 1 of the outcome's main run."""
    summary = outcome.summary
    if not limit_cycles(outcome):
        return summary
    result = outcome.main
    shown = dict(summary)
    shown.update(_shown_motor(result, 0, {k: v for k, v in summary.items() if k != "motors"}))
    if "motors" in summary:
        shown["motors"] = [
            _shown_motor(result, k, motor) for k, motor in enumerate(summary["motors"])
        ]
    return shown
