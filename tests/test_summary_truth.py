"""Summaries say what the data show: the oscillation measure on real samples only, limit
excursions with count, peak and first time, and a relay that never closes."""

import math

import numpy as np
import pytest

from acdrive.drives.dfim import run_scenario
from acdrive.drives.dfim._result import LOG_NAMES, N_LOG, RPM_PER_RAD_S, SQRT_3_2, DriveResult
from acdrive.scenarios import build_setup
from acdrive.sim._metrics import TrackingRule


def synthetic(t, w_ref, w, i_r_pk=None, tracking=None):
    signals = np.zeros((t.size, 1, N_LOG))
    signals[:, 0, LOG_NAMES.index("w_ref")] = w_ref
    signals[:, 0, LOG_NAMES.index("w")] = w
    if i_r_pk is not None:
        signals[:, 0, LOG_NAMES.index("i_r_mag")] = SQRT_3_2 * i_r_pk
    rules = None if tracking is None else (tracking,)
    return DriveResult("synthetic", t, signals, t[1] - t[0], np.zeros(1), tracking=rules)


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
    settling = TrackingRule(windows=tuple((j, j + 0.5) for j in (0.05, 0.60, 1.15, 1.70)))
    assert synthetic(t, w_ref, w, tracking=settling).speed_oscillation() == (0.0, None)


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


# --- one source for every figure: headline, summary.json, result.summary and batch rows -------

#: the figures a single run and a batch row both give, under the same names
SHARED_FIGURES = (
    "speed_rms_error_whole_run_rpm",
    "speed_max_abs_error_whole_run_rpm",
    "speed_max_abs_error_whole_run_at_s",
    "speed_rms_error_tracking_rpm",
    "speed_max_abs_error_tracking_rpm",
    "speed_max_abs_error_tracking_at_s",
    "speed_final_error_rpm",
    "peak_stator_current_a",
    "peak_rotor_current_a",
)
#: batch against single run: the batch runs the single run's compiled loop with reducer parts
#: appended, which read the plant and never write it; its speed-error part calls the very kernel
#: (``sim._metrics.speed_error_update``) the summary runs on the logged samples, in the same order
#: of operations. The plant states agree with the reducer-free loop to the last bit (fast-math
#: contraction may differ in the larger compiled loop, acdrive.batch), and a last-bit difference
#: grows at most by the drive's sensitivity over a fraction of a second, far below 1e-9 relative.
BATCH_REL = 1e-9
#: the speed errors are differences of speeds: a last-bit difference of the speed is relative to
#: the speed's scale (the reference), not to the error, which can be near zero
SPEED_ERRORS = {k for k in SHARED_FIGURES if "error" in k and not k.endswith("_at_s")}
#: a headline figure is printed with two decimals: it is within half a unit of the last digit
HEADLINE_ABS = 0.005 + 1e-9

_NUMBER = r"(-?\d+(?:\.\d+)?)"


def _headline_figures(out: str) -> dict:
    import re

    lines = [line.strip() for line in out.splitlines()]
    figures = {}
    for label, key in (("speed tracking", "tracking"), ("speed error, whole run", "whole_run")):
        line = next(v for v in lines if v.startswith(label))
        found = re.search(rf"{_NUMBER} rpm RMS, largest {_NUMBER} rpm at {_NUMBER} s", line)
        assert found, line
        rms, largest, at = map(float, found.groups())
        figures[f"speed_rms_error_{key}_rpm"] = rms
        figures[f"speed_max_abs_error_{key}_rpm"] = largest
        figures[f"speed_max_abs_error_{key}_at_s"] = at
    for label, key in (("peak rotor current", "peak_rotor_current_a"),
                       ("peak stator current", "peak_stator_current_a")):  # fmt: skip
        line = next(v for v in lines if v.startswith(label))
        figures[key] = float(re.search(rf"{_NUMBER} A", line).group(1))
    return figures


def _valid_scenario(step_time, ramp_s, target_rpm, load, bandwidth, mode, duration, log_every):
    """A one-motor DFIM scenario within the loader's rules: a reference that holds 0, then
    steps (ramp_s = 0) or ramps to ``target_rpm`` and holds."""
    t1, t2 = step_time, step_time + ramp_s
    return {
        "name": "prop",
        "simulation": {"duration": duration, "log_every": log_every},
        "motor": [
            {
                "speed_reference_rpm": [[0, 0], [t1, 0], [t2, target_rpm], [duration, target_rpm]],
                "load_torque": load,
                "controller": {"speed_bandwidth": bandwidth, "mode": mode},
            }
        ],
    }


def _toml(data: dict) -> str:
    sim, motor = data["simulation"], data["motor"][0]
    c = motor["controller"]
    return (
        f'name = "{data["name"]}"\n[simulation]\nduration = {sim["duration"]!r}\n'
        f"log_every = {sim['log_every']}\n[[motor]]\n"
        f"speed_reference_rpm = {motor['speed_reference_rpm']!r}\n"
        f"load_torque = {motor['load_torque']!r}\n[motor.controller]\n"
        f'speed_bandwidth = {c["speed_bandwidth"]!r}\nmode = "{c["mode"]}"\n'
    )


def _figures_agree(step_time, ramp_s, target_rpm, load, bandwidth, mode, duration, log_every):
    import contextlib
    import io
    import json
    import tempfile
    from pathlib import Path

    from acdrive.batch import simulate_batch
    from acdrive.cli import main
    from acdrive.drives.dfim import simulate

    data = _valid_scenario(step_time, ramp_s, target_rpm, load, bandwidth, mode, duration,
                           log_every)  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "prop.toml"
        path.write_text(_toml(data))
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            assert main(["run", str(path), "--out", str(Path(tmp) / "out"), "--no-figures"]) == 0
        written = json.loads((Path(tmp) / "out" / "prop" / "summary.json").read_text())
    result = simulate(build_setup(data))
    direct = result.summary
    row = simulate_batch(data, [{}]).rows[0]
    assert row["status"] == "ok"
    headline = _headline_figures(out.getvalue())
    for key in SHARED_FIGURES:
        # summary.json is result.summary written out (same simulation, same function)
        assert written[key] == direct[key], key
        assert written["motors"][0][key] == direct[key], key
        scale = max(abs(target_rpm), 1.0) if key in SPEED_ERRORS else 1e-3
        assert row[key] == pytest.approx(direct[key], rel=BATCH_REL, abs=BATCH_REL * scale), key
        if key in headline:
            assert abs(headline[key] - direct[key]) <= HEADLINE_ABS, (key, headline[key])
    tracking = written["speed_tracking"]
    assert tracking["rms_error_rpm"] == written["speed_rms_error_tracking_rpm"]
    assert tracking["max_abs_error_rpm"] == written["speed_max_abs_error_tracking_rpm"]
    # and the figures are those of the data: the whole-run ones recomputed here from the log
    err = (result.signal("w_ref") - result.signal("w")) * RPM_PER_RAD_S
    assert direct["speed_max_abs_error_whole_run_rpm"] == pytest.approx(np.max(np.abs(err)))
    assert direct["speed_rms_error_whole_run_rpm"] == pytest.approx(np.sqrt(np.mean(err**2)))
    mask = result.tracking_mask()
    assert direct["speed_rms_error_tracking_rpm"] == pytest.approx(np.sqrt(np.mean(err[mask] ** 2)))


def test_every_output_gives_the_same_figures_for_random_valid_scenarios():
    """Random valid scenarios through `acdrive run` (headline and summary.json),
    ``DriveResult.summary`` and ``simulate_batch``: the same figures everywhere (tolerances:
    BATCH_REL, HEADLINE_ABS). Small runs, five examples, derandomised: under a minute once the
    two loops are compiled."""
    from hypothesis import given, settings
    from hypothesis import strategies as st

    @settings(max_examples=5, deadline=None, derandomize=True)
    @given(
        step_time=st.floats(0.02, 0.1),
        ramp_s=st.sampled_from([0.0, 0.05, 0.12]),
        target_rpm=st.floats(-600.0, 900.0).filter(lambda x: abs(x) > 1.0),
        load=st.floats(0.0, 0.1),
        bandwidth=st.floats(60.0, 314.0),
        mode=st.sampled_from(["voltage", "current"]),
        duration=st.floats(0.25, 0.4),
        log_every=st.sampled_from([1, 3]),
    )
    def check(**kwargs):
        _figures_agree(**kwargs)

    check()
