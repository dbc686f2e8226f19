"""The speed metrics of a run, each computed in one place, with the window it is taken over.

A single run (``DriveResult.summary``, ``IMDriveResult.summary``, summary.json, the headline of
``acdrive run``) and a batch (``acdrive.batch`` reducers, sweep tables) read the same figures:
the batch computes them inside its compiled loop with the kernels below, and a single run feeds
its logged samples to the same kernels after the run (``speed_errors``). Both take the samples
on the logging grid (every ``log_every``-th control sample), so the two agree to rounding.

Windows, named in the keys:

* ``_whole_run_``: every logged sample;
* ``_tracking_``: where the speed is expected to track its reference (``TrackingRule``): the
  stator relay closed (DFIM), and not within SLEW_MARGIN x J |dw| / tau + SETTLE_TIME_CONSTANTS /
  a_D,VEL of a reference change faster than tau / J (known from the scenario before the run) or
  of a relay closing (dw: the speed error at closing, found on line). The rule with its numbers
  is written beside the figures (``speed_tracking.rule``);
* ``_late_``: the last ``LATE_WINDOW_S`` of the run.

The limit-cycle band RMS (``limit_cycle``) is taken on the longest stretch of tracked samples;
its frequency is reported only where a limit cycle is shown: that RMS above
``OSCILLATION_FINDING_RPM`` over the stretch and over its end, and a persistent period
(``period_correlation``). Below it the
dominant bin of noise, or of a drift's share of the band, is no frequency of anything.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from acdrive._jit import jit, njit

RPM_PER_RAD_S = 30.0 / math.pi
#: band [Hz] in which a speed-error oscillation counts as a limit cycle, not a tracking lag
OSCILLATION_BAND_HZ = (20.0, 200.0)
#: speed-error RMS [rpm] in OSCILLATION_BAND_HZ above which a run states an oscillation
OSCILLATION_FINDING_RPM = 1.0
#: the end of the run in which an oscillation is also looked for [s]: five periods of the band's
#: lowest frequency, so a late or growing oscillation is not averaged away over a quiet start
LATE_WINDOW_S = 5.0 / OSCILLATION_BAND_HZ[0]
#: the drive may deliver less than its current-limit torque while slewing (converter voltage,
#: losses): a step's slewing window is this many times the time at the limit torque
SLEW_MARGIN = 2.0
#: time constants 1 / a_D,VEL of the speed loop after slewing: both roots of Bodson (27) sit at
#: -a_D,VEL, whose step error (1 + a t) e^{-a t} is below 2 % after 6 / a_D,VEL
SETTLE_TIME_CONSTANTS = 6.0

_inline = njit(cache=True, error_model="numpy", inline="always")


# --- the tracking window and the speed error over it -------------------------------------------


@dataclass(frozen=True)
class TrackingRule:
    """Where a motor's speed is expected to track its reference (module docstring).

    ``windows``: the excluded (start, end) [s] after each reference change faster than the drive
    can follow, from the scenario; ``slew_s_per_rad_s`` (SLEW_MARGIN J / tau) and ``settle_s``
    (SETTLE_TIME_CONSTANTS / a_D,VEL) size the window after a relay closing from the speed error
    then; ``relay`` True: samples with the stator relay open are not tracked; ``text``: the rule
    in words with its numbers."""

    windows: tuple[tuple[float, float], ...] = ()
    slew_s_per_rad_s: float = 0.0
    settle_s: float = 0.0
    relay: bool = False
    text: str = "every logged sample (no reference change is excluded)"

    def window_array(self) -> np.ndarray:
        return np.array([x for w in self.windows for x in w], dtype=float)


def reference_change_windows(times, values, J: float, tau: float, settle: float) -> tuple:
    """(start, end) [s] after each change of a speed reference profile (``times`` [s],
    ``values`` [rad/s]) faster than tau / J: a step, or a segment steeper than the torque limit
    ``tau`` [N m] accelerates the inertia ``J`` [kg m^2]; from the segment's start for
    SLEW_MARGIN J |dw| / tau + ``settle`` s."""
    times, values = np.asarray(times, dtype=float), np.asarray(values, dtype=float)
    out = []
    for i in range(1, times.size):
        dt, dw = times[i] - times[i - 1], abs(values[i] - values[i - 1])
        if dw > 0.0 and (dt <= 0.0 or dw / dt > tau / J):
            start = float(times[i - 1])
            out.append((start, start + (SLEW_MARGIN * J / tau) * dw + settle))
    return tuple(sorted(out))


def reference_tracking_rule(speed_reference, J: float, tau: float, a: float, relay: bool,
                            loop: str) -> TrackingRule:  # fmt: skip
    """The ``TrackingRule`` of a speed loop of bandwidth ``a`` [rad/s] (``loop`` names it in the
    text) driving the inertia ``J`` with at most ``tau``, following ``speed_reference`` (times
    [s], values [rad/s]); ``relay``: gated by a stator relay."""
    settle = SETTLE_TIME_CONSTANTS / a
    times, values = speed_reference
    text = (
        f"{'relay closed and ' if relay else ''}not within {SLEW_MARGIN:g} x J |dw| / tau + "
        f"{SETTLE_TIME_CONSTANTS:g} / a of a reference step{' or relay closing' * relay} (J = "
        f"{J:.3g} kg m^2, tau = {tau:.3g} N m, a = {loop} = {a:.0f} rad/s: {settle * 1e3:.1f} ms "
        "to settle)"
    )
    return TrackingRule(
        windows=reference_change_windows(times, values, J, tau, settle),
        slew_s_per_rad_s=SLEW_MARGIN * J / tau,
        settle_s=settle,
        relay=relay,
        text=text,
    )


#: the state of the speed-error kernel (``speed_error_update``), one float each
SPEED_ERROR_STATES = (
    ("started", "", "1 once the first sample is in"),
    ("closed_prev", "", "relay state at the previous sample"),
    ("until", "s", "end of the window after the latest relay closing"),
    ("n_all", "", "samples in the whole run"),
    ("sum_sq_all", "", "sum of e^2 over the whole run"),
    ("peak_all", "", "largest |e| over the whole run"),
    ("t_peak_all", "s", "its time"),
    ("n_tracked", "", "samples in the tracking window"),
    ("sum_sq_tracked", "", "sum of e^2 over the tracking window"),
    ("peak_tracked", "", "largest |e| over the tracking window"),
    ("t_peak_tracked", "s", "its time"),
    ("last", "", "e at the last sample"),
)
#: the initial ``until``: no relay closing yet (finite: the part's states are checked finite)
NO_CLOSING = -1e300
(_STARTED, _CLOSED, _UNTIL, _N_ALL, _SQ_ALL, _PK_ALL, _T_ALL, _N_TR, _SQ_TR, _PK_TR, _T_TR,
 _LAST) = range(len(SPEED_ERROR_STATES))  # fmt: skip


@_inline
def speed_error_update(t, e, closed, slew, settle, windows, s):
    """Take one logged sample into the speed-error state ``s``: ``e`` = w_ref - w [rad/s] at
    time ``t``, ``closed`` the relay (> 0.5 closed; 1 where there is none), ``slew`` and
    ``settle`` and the flat (start, end, ...) ``windows`` of a ``TrackingRule``. Returns True if
    the sample is in the tracking window."""
    if s[_STARTED] == 0.0:
        s[_STARTED] = 1.0
        s[_CLOSED] = closed
    elif closed > 0.5 and s[_CLOSED] <= 0.5:  # a relay closing: settle from here
        end = t + slew * abs(e) + settle
        s[_UNTIL] = max(s[_UNTIL], end)
    s[_CLOSED] = closed
    a = abs(e)
    s[_N_ALL] += 1.0
    s[_SQ_ALL] += e * e
    if s[_N_ALL] == 1.0 or a > s[_PK_ALL]:
        s[_PK_ALL] = a
        s[_T_ALL] = t
    s[_LAST] = e
    tracked = closed > 0.5 and t >= s[_UNTIL]
    if tracked:
        for j in range(windows.size // 2):
            if windows[2 * j] <= t < windows[2 * j + 1]:
                tracked = False
    if tracked:
        s[_N_TR] += 1.0
        s[_SQ_TR] += e * e
        if s[_N_TR] == 1.0 or a > s[_PK_TR]:
            s[_PK_TR] = a
            s[_T_TR] = t
    return tracked


@jit
def _speed_errors_offline(t, w, w_ref, closed, slew, settle, windows, s, mask, until):
    for i in range(t.size):
        mask[i] = speed_error_update(t[i], w_ref[i] - w[i], closed[i], slew, settle, windows, s)
        until[i] = s[_UNTIL]


def speed_error_state(t, w, w_ref, closed, rule: TrackingRule):
    """(state, tracked mask, window end after the latest relay closing per sample) of the logged
    samples: the final state ``speed_error_update`` (the kernel the batch runs on line) leaves
    after taking them in order, computed with array operations that round alike (the running
    sums are sequential, ``np.cumsum``; a peak is the first largest |e|), so that a summary
    needs no compiled code (``tests/test_metrics.py`` checks equality with the kernel)."""
    t = np.ascontiguousarray(t, dtype=float)
    e = np.ascontiguousarray(w_ref, dtype=float) - np.ascontiguousarray(w, dtype=float)
    if closed is None or not rule.relay:
        closed = np.ones(t.size)
    closed = np.ascontiguousarray(closed, dtype=float)
    s = np.zeros(len(SPEED_ERROR_STATES))
    s[_UNTIL] = NO_CLOSING
    if t.size == 0:
        return s, np.zeros(0, dtype=np.bool_), np.zeros(0)
    a = np.abs(e)
    shut = closed > 0.5
    closing = np.zeros(t.size, dtype=np.bool_)
    closing[1:] = shut[1:] & (closed[:-1] <= 0.5)
    ends = np.where(closing, t + rule.slew_s_per_rad_s * a + rule.settle_s, NO_CLOSING)
    until = np.maximum.accumulate(ends)
    mask = shut & (t >= until)
    windows = rule.window_array()
    for j in range(windows.size // 2):
        mask &= ~((windows[2 * j] <= t) & (t < windows[2 * j + 1]))
    squares = e * e
    k = int(np.argmax(a))
    s[_STARTED], s[_CLOSED], s[_UNTIL] = 1.0, closed[-1], until[-1]
    s[_N_ALL], s[_SQ_ALL], s[_PK_ALL], s[_T_ALL] = t.size, np.cumsum(squares)[-1], a[k], t[k]
    s[_LAST] = e[-1]
    tracked = np.flatnonzero(mask)
    if tracked.size:
        k = int(tracked[np.argmax(a[tracked])])
        s[_N_TR], s[_SQ_TR] = tracked.size, np.cumsum(squares[tracked])[-1]
        s[_PK_TR], s[_T_TR] = a[k], t[k]
    return s, mask, until


def speed_error_state_by_kernel(t, w, w_ref, closed, rule: TrackingRule):
    """``speed_error_state`` by the compiled kernel itself, sample by sample (the reference the
    array version is tested against)."""
    s = np.zeros(len(SPEED_ERROR_STATES))
    s[_UNTIL] = NO_CLOSING
    mask = np.zeros(t.size, dtype=np.bool_)
    until = np.zeros(t.size)
    if closed is None or not rule.relay:
        closed = np.ones(t.size)
    _speed_errors_offline(
        np.ascontiguousarray(t, dtype=float), np.ascontiguousarray(w, dtype=float),
        np.ascontiguousarray(w_ref, dtype=float), np.ascontiguousarray(closed, dtype=float),
        rule.slew_s_per_rad_s, rule.settle_s, rule.window_array(), s, mask, until,
    )  # fmt: skip
    return s, mask, until


def speed_error_figures(s, scale: float, unit: str) -> dict:
    """The named figures of a final speed-error state ``s`` (values x ``scale``, key suffix
    ``unit``: ``rpm`` or ``rad_s``): RMS and largest |error| with its time over the whole run
    and over the tracking window (None where the window holds no sample), the final error."""
    nan = None

    def rms(sq, n):
        return math.sqrt(sq / n) * scale if n else nan

    return {
        f"speed_rms_error_whole_run_{unit}": rms(s[_SQ_ALL], s[_N_ALL]),
        f"speed_max_abs_error_whole_run_{unit}": s[_PK_ALL] * scale if s[_N_ALL] else nan,
        "speed_max_abs_error_whole_run_at_s": s[_T_ALL] if s[_N_ALL] else nan,
        f"speed_rms_error_tracking_{unit}": rms(s[_SQ_TR], s[_N_TR]),
        f"speed_max_abs_error_tracking_{unit}": s[_PK_TR] * scale if s[_N_TR] else nan,
        "speed_max_abs_error_tracking_at_s": s[_T_TR] if s[_N_TR] else nan,
        f"speed_final_error_{unit}": s[_LAST] * scale if s[_N_ALL] else nan,
    }


def speed_tracking(t, w, w_ref, closed, rule: TrackingRule, scale=RPM_PER_RAD_S, unit="rpm"):
    """The speed-error figures of the logged samples (``speed_error_figures``) and
    ``speed_tracking``: the ``rule``, the excluded ``windows_s`` (reference changes and relay
    closings, clipped to the run), the ``tracked_fraction`` and, as there, the tracking RMS and
    largest |error| with its time. Returns (figures, speed_tracking, tracked mask)."""
    s, mask, until = speed_error_state(t, w, w_ref, closed, rule)
    figures = speed_error_figures(s, scale, unit)
    end = float(t[-1]) if t.size else 0.0
    windows = [[a, min(b, end)] for a, b in rule.windows if a <= end]
    rises = np.flatnonzero(np.diff(until) > 0) + 1
    windows += [[float(t[i]), min(float(until[i]), end)] for i in rises]
    windows.sort()
    text = rule.text
    if rule.relay and closed is not None:
        open_s = float(np.count_nonzero(np.asarray(closed) <= 0.5)) * (
            t[1] - t[0] if t.size > 1 else 0.0
        )
        if open_s > 0.0:
            text = f"{text}; {open_s:.3g} s with the relay open excluded"
    tracking = {
        "rule": "speed error where tracking is expected: " + text,
        "windows_s": windows,
        "tracked_fraction": float(np.mean(mask)) if mask.size else 0.0,
        f"rms_error_{unit}": figures[f"speed_rms_error_tracking_{unit}"],
        f"max_abs_error_{unit}": figures[f"speed_max_abs_error_tracking_{unit}"],
        "max_abs_error_at_s": figures["speed_max_abs_error_tracking_at_s"],
    }
    return figures, tracking, mask


# --- the limit-cycle band ----------------------------------------------------------------------


def longest_run(mask: np.ndarray) -> tuple[int, int]:
    """(start, stop) of the longest stretch of True in ``mask`` ((0, 0) if there is none)."""
    padded = np.concatenate([[False], np.asarray(mask, dtype=bool), [False]])
    edges = np.flatnonzero(np.diff(padded.astype(np.int8)))
    starts, stops = edges[0::2], edges[1::2]
    if starts.size == 0:
        return 0, 0
    k = int(np.argmax(stops - starts))
    return int(starts[k]), int(stops[k])


def band_spectrum(t, err, band_hz=OSCILLATION_BAND_HZ):
    """(RMS, frequencies, power) of ``err`` in ``band_hz``: its linear trend removed, a Hann
    window w against leakage from slow transients, then Parseval on its FFT: mean square in the
    band = 2 sum |X_k|^2 / (N sum w^2) over the band's bins. None if the stretch is shorter than
    five periods of the band's lowest frequency (too short to tell a limit cycle from a
    transient) or has fewer than 16 samples."""
    n = t.size
    dt = t[1] - t[0] if n > 1 else 0.0
    if n < 16 or n * dt < (5.0 / band_hz[0]) * (1.0 - 1e-9):  # (rounding of n dt)
        return None
    err = err - np.polyval(np.polyfit(t - t[0], err, 1), t - t[0])
    window = np.hanning(n)
    spectrum = np.fft.rfft(err * window)
    freq = np.fft.rfftfreq(n, dt)
    inside = (freq >= band_hz[0]) & (freq <= band_hz[1]) & (freq > 0) & (freq < 0.5 / dt)
    power = np.abs(spectrum[inside]) ** 2
    if power.size == 0:
        return None
    rms = float(np.sqrt(2.0 * power.sum() / (n * np.sum(window**2))))
    return rms, freq[inside], power


#: a limit cycle repeats its period: the band-limited error's normalised autocorrelation at its
#: first peak (one period) is at least this. A sinusoid of constant amplitude gives above 0.85
#: even at 20 Hz over the shortest stretch judged (0.25 s, five periods; Hann-windowed), band-
#: limited noise about 0.3, the band's share of a drifting or diverging speed well below 0.75.
PERIOD_CORRELATION_MIN = 0.75


def period_correlation(t, err, band_hz=OSCILLATION_BAND_HZ) -> tuple[float, float | None]:
    """(r, 1 / lag [Hz] or None): the normalised autocorrelation r of ``err`` restricted to
    ``band_hz`` (trend removed, Hann-windowed, out-of-band bins zeroed, zero-padded so the
    correlation is linear) at its highest peak after its first zero crossing within lags of one
    period of the band (1 / high to 1 / low); (0, None) if there is no such interior peak."""
    n = t.size
    if n < 16:
        return 0.0, None
    dt = t[1] - t[0]
    err = err - np.polyval(np.polyfit(t - t[0], err, 1), t - t[0])
    spectrum = np.fft.rfft(err * np.hanning(n), 2 * n)
    freq = np.fft.rfftfreq(2 * n, dt)
    spectrum[(freq < band_hz[0]) | (freq > band_hz[1])] = 0.0
    ac = np.fft.irfft(np.abs(spectrum) ** 2, 2 * n)[:n]
    if ac[0] <= 0.0:
        return 0.0, None
    ac = ac / ac[0]
    longest = min(int(1.0 / (band_hz[0] * dt)) + 1, n - 1)
    negative = np.flatnonzero(ac[: longest + 1] < 0.0)
    if negative.size == 0:
        return 0.0, None
    first = int(negative[0])
    k = first + int(np.argmax(ac[first : longest + 1]))
    if k in (first, longest):  # no interior peak: no period within the band
        return float(max(ac[k], 0.0)), None
    return float(ac[k]), 1.0 / (k * dt)


def limit_cycle(t, err_rpm, mask, band_hz=OSCILLATION_BAND_HZ) -> dict:
    """The limit-cycle figures of the speed error ``err_rpm`` over the longest stretch of
    consecutive ``mask`` samples: ``speed_oscillation_rms_rpm`` over the stretch
    (``band_spectrum``; 0 from a stretch too short to judge), ``speed_oscillation_end_rms_rpm``
    over its last LATE_WINDOW_S, ``speed_oscillation_period_correlation``: the smaller
    ``period_correlation`` r of the two. ``speed_limit_cycle``: shown where both RMS exceed
    OSCILLATION_FINDING_RPM and r is at least PERIOD_CORRELATION_MIN: an oscillation whose period
    repeats and that lasts to the end of the stretch, not a transient's, a drift's or a passing
    disturbance's share of the band. Then ``speed_oscillation_hz`` is the stretch's dominant
    frequency (else None)."""
    start, stop = longest_run(mask)
    t, err = np.asarray(t)[start:stop], np.asarray(err_rpm)[start:stop]
    found = band_spectrum(t, err, band_hz)
    tail = t >= t[-1] - LATE_WINDOW_S * (1 - 1e-9) if t.size else np.zeros(0, dtype=bool)
    end = band_spectrum(t[tail], err[tail], band_hz) if found is not None else None
    if found is None or end is None:
        rms = found[0] if found is not None else 0.0
        return {"speed_oscillation_rms_rpm": rms, "speed_oscillation_end_rms_rpm": None,
                "speed_oscillation_hz": None, "speed_oscillation_period_correlation": None,
                "speed_limit_cycle": False}  # fmt: skip
    rms, freq, power = found
    r = min(period_correlation(t, err, band_hz)[0], period_correlation(t[tail], err[tail])[0])
    shown = bool(
        rms > OSCILLATION_FINDING_RPM
        and end[0] > OSCILLATION_FINDING_RPM
        and r >= PERIOD_CORRELATION_MIN
    )
    return {
        "speed_oscillation_rms_rpm": rms,
        "speed_oscillation_end_rms_rpm": end[0],
        "speed_oscillation_hz": float(freq[np.argmax(power)]) if shown else None,
        "speed_oscillation_period_correlation": r,
        "speed_limit_cycle": shown,
    }


def speed_oscillation(t, err_rpm, mask, band_hz=OSCILLATION_BAND_HZ) -> tuple[float, float | None]:
    """(band RMS [rpm], dominant frequency [Hz] or None) of ``limit_cycle``: the frequency only
    where a limit cycle is shown."""
    c = limit_cycle(t, err_rpm, mask, band_hz)
    return c["speed_oscillation_rms_rpm"], c["speed_oscillation_hz"]
