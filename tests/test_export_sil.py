"""Software in the loop (issue 22, item 2): the exported C controller of each DFIM chain, compiled
with gcc and run in acdrive's loop in place of the compiled sampled parts, reproduces acdrive's
own run within 1e-12 of each logged signal's peak over the whole (shortened) run, with the same
event counts. Each case runs in a child process with ACDRIVE_STRICT_MATH=1 (numba then does no
fast-math, so the double C build compiled with -ffp-contract=off can agree to rounding), and
checks that the run exercised what the case is about (a ramp that moves the shaft, the fallback
from current command, the relay closing)."""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys

import pytest

from acdrive.export._scenario import DOUBLE_TOLERANCE, FLOAT_MARGIN, float_bound
from acdrive.scenarios._files import builtin_text

pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc is not installed")


def _sil(scenario: str, *extra: str) -> dict:
    env = dict(os.environ, ACDRIVE_STRICT_MATH="1")
    code = "import sys; from acdrive.cli import main; raise SystemExit(main(sys.argv[1:]))"
    done = subprocess.run(
        [sys.executable, "-c", code, "export", "sil", scenario, "--json", *extra],
        check=False, capture_output=True, text=True, env=env, timeout=1200,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def _scenario(tmp_path, name: str, replace: dict[str, str]) -> str:
    """A built-in scenario with some lines replaced (each key must occur once)."""
    text = builtin_text(name)
    for old, new in replace.items():
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return str(path)


def _check_equal(report: dict) -> None:
    assert report["strict_math"] is True
    assert report["real"] == "double"
    worst = report["worst_ratio"]
    assert worst <= DOUBLE_TOLERANCE, f"{report['worst_signal']}: {worst:.3e} of its peak"
    assert report["events_equal"], (report["events_acdrive"], report["events_c"])


def test_voltage_mode_ramp(tmp_path):
    """bodson-ramp (voltage command (20)) with its ramp compressed into 0.3 s."""
    path = _scenario(tmp_path, "bodson-ramp", {
        "duration = 14.0": "duration = 0.3",
        "speed_reference_rpm = [[0.0, 0.0], [0.5, 0.0], [9.5, 2700.0], [11.0, 2700.0], "
        "[11.0, 0.0], [14.0, 0.0]]": "speed_reference_rpm = [[0.0, 0.0], [0.02, 0.0], "
        "[0.3, 1500.0]]",
    })  # fmt: skip
    report = _sil(path)
    _check_equal(report)
    signals = report["signals"]
    assert signals["shaft0.w"]["peak"] > 50.0  # the shaft moved (rad/s)
    assert signals["controller0.mode"]["peak"] == 0.0  # voltage command throughout
    assert signals["controller0.tau_com"]["peak"] > 0.0


def test_current_mode_and_sensor_fallback(tmp_path):
    """bodson-sensor-fault (current command (43)-(49)) with the measurement lost at 0.15 s."""
    path = _scenario(tmp_path, "bodson-sensor-fault", {
        "duration = 4.0": "duration = 0.3",
        "current_sensor_fault_time = 1.5": "current_sensor_fault_time = 0.15",
    })  # fmt: skip
    report = _sil(path)
    _check_equal(report)
    events = report["events_c"]
    assert events["currents0"]["lost"] > 0
    assert events["controller0"]["sensor_fallback"] > 0
    assert report["signals"]["controller0.mode"]["peak"] == 1.0  # current command before it


def test_synchronisation():
    """bodson-sync: the synchroniser (28) builds the stator voltage and closes the relay."""
    report = _sil("bodson-sync", "--duration", "0.5")
    _check_equal(report)
    assert report["events_c"]["sync0"]["relay_closed"] == 1


def test_ifoc_with_controller_20():
    """im-foc-speed: IFOC, speed PI and the ICAD controller (20) through the speed step."""
    report = _sil("im-foc-speed", "--duration", "0.1")
    _check_equal(report)
    signals = report["signals"]
    assert signals["speed.w"]["peak"] > 50.0  # the step at 0.05 s moved the shaft (rad/s)
    assert report["events_c"]["speed_controller"]["torque_limit"] > 0


def test_ifoc_with_pi_and_saturated_p(tmp_path):
    """im-icad-vs-pi's PI run: IFOC, the saturated P speed loop (21), the stationary PI."""
    path = _scenario(tmp_path, "im-icad-vs-pi", {
        'compare_controllers = { icad = "paper-20", pi = "paper-pi" }\n': "",
        "[inverter]": '[current_control]\ncontroller = "paper-pi"\n\n[inverter]',
    })  # fmt: skip
    report = _sil(path, "--duration", "0.1")
    _check_equal(report)
    assert report["signals"]["speed.w"]["peak"] > 10.0  # ramping at the torque limit
    assert report["events_c"]["speed_controller"]["torque_limit"] > 0


def test_pm_field_oriented_control():
    """pm-bly171d-svpwm: speed PI within the available torque, MTPA / field-weakening reference,
    rotor-frame current PIs, on the switching SVPWM inverter."""
    report = _sil("pm-bly171d-svpwm", "--duration", "0.1")
    _check_equal(report)
    assert report["signals"]["speed.w"]["peak"] > 100.0  # the step to 300 rad/s moved the rotor
    assert report["events_c"]["speed_pi"]["torque_limit"] > 0


def test_forced_relay_close():
    """fault-forced-close: the relay closed by force at 10 ms during synchronisation."""
    report = _sil("fault-forced-close", "--duration", "0.1")
    _check_equal(report)
    assert report["events_c"]["forced0"]["forced"] > 0


def _scenario_file(tmp_path, duration: str = "0.1", fault: str = "0.05") -> str:
    return _scenario(tmp_path, "bodson-sensor-fault", {
        "duration = 4.0": f"duration = {duration}",
        "current_sensor_fault_time = 1.5": f"current_sensor_fault_time = {fault}",
    })  # fmt: skip


def test_float_build_runs_in_the_loop(tmp_path):
    """The float build (-DACDRIVE_FLOAT) runs the current-command chain in the loop to the end:
    it really computes in float (it differs from acdrive's double run), every signal stays
    finite, and its worst deviation is within the derived bound: FLOAT_MARGIN times the worst
    deviation of the double build with its inputs rounded to float32 (``float_bound``), which
    is itself of float's size (above the unit roundoff 2^-24, far below 1)."""
    report = _sil(_scenario_file(tmp_path), "--real", "float")
    assert report["real"] == "float"
    ratios = [row["ratio"] for row in report["signals"].values()]
    assert all(math.isfinite(r) for r in ratios)
    assert report["worst_ratio"] > 0.0
    rounding = report["input_rounding_ratio"]
    assert 2.0**-24 < rounding < 1e-2
    assert report["float_bound"] == FLOAT_MARGIN * rounding
    assert report["within_float_bound"] is True
    assert report["bounded_worst_ratio"] <= report["float_bound"]


def test_float_bound_is_the_margin_times_the_input_rounding():
    assert float_bound(1e-5) == FLOAT_MARGIN * 1e-5
    assert float_bound(0.0) == FLOAT_MARGIN * 2.0**-24  # never below float's resolution


def test_float_build_beyond_its_bound_is_one_line(tmp_path, capsys, monkeypatch):
    """A float build whose deviation exceeds its bound: one line naming the bound, exit 2 (the
    margin is shrunk here so that the real float build of a short run exceeds it)."""
    from acdrive.cli import main
    from acdrive.export import _scenario

    monkeypatch.setattr(_scenario, "FLOAT_MARGIN", 1e-3)
    path = _scenario_file(tmp_path)
    assert main(["export", "sil", path, "--real", "float"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "float build" in err[0] and "beyond the float bound" in err[0]


def test_two_motors_two_chains():
    """bodson-two-motors: one chain per motor, both C steps in the loop on the shared bus."""
    report = _sil("bodson-two-motors", "--duration", "0.2")
    _check_equal(report)
    assert report["chains"] == ["bodson_two_motors0", "bodson_two_motors1"]


def test_no_limit_stand_ins_are_left_out_of_a_float_comparison():
    """Where acdrive and the double build hold 1e300 for "no limit" (the PM drive's flux limit
    at standstill), the float build holds float32(1e38): such samples are left out, a sample
    where only one side is "no limit" is the difference it is."""
    from types import SimpleNamespace

    import numpy as np

    from acdrive.export._sil import deviation
    from acdrive.sim._ccode._prelude import FLOAT_NO_LIMIT, PRELUDE

    assert f"ACD_R({FLOAT_NO_LIMIT!r})" in PRELUDE
    held = float(np.float32(FLOAT_NO_LIMIT))
    reference = SimpleNamespace(columns=["psi"], data=np.array([[1e300], [2.0], [4.0]]))
    in_float = SimpleNamespace(columns=["psi"], data=np.array([[held], [2.5], [4.0]]))
    assert deviation(reference, in_float, held) == {"psi": (0.5, 4.0)}
    assert deviation(reference, in_float)["psi"][1] == 1e300  # without: the stand-in is the peak
    finite = SimpleNamespace(columns=["psi"], data=np.array([[3.0], [2.0], [4.0]]))
    assert deviation(reference, finite, held)["psi"][0] == 1e300 - 3.0


def test_pm_float_build_within_its_bound():
    """The PM drive's float build from standstill (flux limit "no limit" there) through the
    speed step: within its derived bound, the flux limit compared where it is finite."""
    report = _sil("pm-bly171d-svpwm", "--duration", "0.1", "--real", "float")
    assert report["within_float_bound"] is True
    assert report["bounded_worst_ratio"] <= report["float_bound"]
    assert report["signals"]["torque_reference.psi_max"]["ratio"] < 1e-4
    assert report["signals"]["speed.w"]["peak"] > 100.0
