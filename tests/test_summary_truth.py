"""Summaries say what the data show: the oscillation measure on real samples only, limit
excursions with count, peak and first time, and a relay that never closes."""

import math

import numpy as np
import pytest

from acdrive.scenarios._loader import build_setup
from acdrive.sim._outcome import run_scenario
from acdrive.sim._result import LOG_NAMES, N_LOG, RPM_PER_RAD_S, SQRT_3_2, DriveResult


def synthetic(t, w_ref, w, i_r_pk=None):
    signals = np.zeros((t.size, 1, N_LOG))
    signals[:, 0, LOG_NAMES.index("w_ref")] = w_ref
    signals[:, 0, LOG_NAMES.index("w")] = w
    if i_r_pk is not None:
        signals[:, 0, LOG_NAMES.index("i_r_mag")] = SQRT_3_2 * i_r_pk
    return DriveResult("synthetic", t, signals, t[1] - t[0], np.zeros(1))


def test_oscillation_rms_and_frequency_of_a_known_limit_cycle():
    T = 2e-4
    t = np.arange(0, 2.0, T)
    amplitude_rpm, f = 7.0, 47.0
    w_ref = 100.0 + 50.0 * t  # a ramp: the trend is not an oscillation
    w = w_ref - amplitude_rpm / RPM_PER_RAD_S * np.sin(2 * math.pi * f * t)
    rms, hz = synthetic(t, w_ref, w).speed_oscillation()
    assert rms == pytest.approx(amplitude_rpm / math.sqrt(2), rel=0.02)
    assert hz == pytest.approx(f, abs=1.0)


def test_no_oscillation_reported_from_a_few_samples():
    T = 2e-4
    t = np.arange(0, 2.0, T)
    # the reference jumps every 0.55 s: tracking stretches of 0.05 s are too short to judge
    w_ref = 100.0 * np.floor((t + 0.5) / 0.55)  # jumps at 0.05, 0.60, 1.15, 1.70 s
    w = w_ref - 0.5 * np.sin(2 * math.pi * 10.0 * t)
    assert synthetic(t, w_ref, w).speed_oscillation() == (0.0, 0.0)


def test_tracking_error_with_no_oscillation_gives_near_zero():
    t = np.arange(0, 2.0, 2e-4)
    w_ref = 100.0 + 30.0 * t
    w = w_ref - 2.0 * (1 - np.exp(-t / 0.3))  # a slow lag, no limit cycle
    rms, _ = synthetic(t, w_ref, w).speed_oscillation()
    assert rms < 0.05


def test_limit_excursions_count_peak_and_first_time():
    t = np.arange(0, 1.0, 1e-3)
    i_r = np.where((t >= 0.25) & (t < 0.30), 7.0, 4.0)
    i_r[270] = 7.5
    result = synthetic(t, np.zeros_like(t), np.zeros_like(t), i_r_pk=i_r)
    e = result.limit_excursions(0, {"i_r_mag": 6.0})["i_r_mag"]
    assert e["samples_above"] == 50 and e["peak_a"] == pytest.approx(7.5)
    assert e["first_time_s"] == pytest.approx(0.25)
    assert result.limit_excursions(0, {"i_r_mag": 8.0})["i_r_mag"]["first_time_s"] is None


def test_a_relay_that_never_closes_is_reported():
    setup = build_setup(
        {
            "name": "never-closes",
            "simulation": {"duration": 0.3},
            "motor": [
                {
                    "speed_reference_rpm": [[0, 0], [0.3, 0]],
                    "controller": {"sync": {"enabled": True, "hold_time": 1.0}},
                }
            ],
        }
    )
    summary = run_scenario(setup).summary
    assert summary["synchronisation"]["relay_closed"] is False
    assert any("never closed the relay" in w for w in summary["warnings"])
