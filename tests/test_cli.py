"""The acdrive command: main job, listing, limits, and one-line errors with exit code 2."""

import json
import subprocess
import sys

import pytest

from acdrive.cli import main


def run_cli(*args):
    return subprocess.run(
        [sys.executable, "-m", "acdrive.cli", *args], check=False, capture_output=True, text=True
    )


def test_limits_json_gives_paper_example():
    out = run_cli("limits", "--json")
    assert out.returncode == 0
    limits = json.loads(out.stdout)
    assert round(limits["tau_max_1"], 3) == 0.371
    assert round(limits["tau_max_2"], 3) == 0.341
    assert round(limits["tau_max_3"], 3) == 0.274
    assert limits["tau_lim"] == min(limits["tau_max_1"], limits["tau_max_2"], limits["tau_max_3"])


def test_scenarios_lists_default(capsys):
    assert main(["scenarios"]) == 0
    assert "bodson-ramp" in capsys.readouterr().out


def test_run_writes_outputs(tmp_path):
    scenario = tmp_path / "short.toml"
    scenario.write_text("""
name = "short"
[simulation]
duration = 0.3
[[motor]]
speed_reference_rpm = [[0, 0], [0.3, 100]]
[motor.controller]
speed_bandwidth = 100.0
""")
    out = run_cli("run", str(scenario), "--out", str(tmp_path / "out"))
    assert out.returncode == 0, out.stderr
    folder = tmp_path / "out" / "short"
    summary = json.loads((folder / "summary.json").read_text())
    for key in (
        "speed_rms_error_tracking_rpm",
        "speed_max_abs_error_whole_run_rpm",
        "peak_rotor_current_a",
        "peak_stator_current_a",
        "limit_events",
    ):
        assert key in summary
    assert (folder / "data.parquet").exists() and (folder / "fig4_speed.png").exists()
    import pandas as pd

    frame = pd.read_parquet(folder / "data.parquet")
    assert len(frame) == 1500 and {"t", "w", "i_r_pk", "i_r_d_sv"} <= set(frame.columns)


BAD = {
    "unknown key": (
        '[[motor]]\nspeed_reference_rpm = [[0, 0]]\ncolour = "red"\n',
        "motor[0].colour: unknown key",
    ),
    "negative resistance": (
        "[[motor]]\nspeed_reference_rpm = [[0, 0]]\n[motor.params]\nR_s = -1\nR_r = 1\nL_s = 0.01\nL_r = 0.01\nM = 0.009\nn_p = 2\nJ = 0.001\n",
        "motor[0].params.R_s: must be > 0",
    ),
    "wrong type": (
        '[simulation]\nduration = "long"\n[[motor]]\nspeed_reference_rpm = [[0, 0]]\n',
        "simulation.duration: must be a number",
    ),
    "nan": (
        "[supply]\nvoltage_pk = nan\n[[motor]]\nspeed_reference_rpm = [[0, 0]]\n",
        "supply.voltage_pk: must be finite",
    ),
    "out of range": (
        "[[motor]]\nspeed_reference_rpm = [[0, 0], [1, 9000]]\n",
        "motor[0].speed_reference_rpm: must stay within",
    ),
    "bad bandwidth": (
        "[[motor]]\nspeed_reference_rpm = [[0, 0]]\n[motor.controller]\nspeed_bandwidth = -5\n",
        "motor[0].controller.speed_bandwidth: must be > 0",
    ),
    "no motor": ('name = "x"\n', "motor: at least one"),
    "bad toml": ("[[motor]\n", "not valid TOML"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_scenarios_fail_with_one_line(tmp_path, case):
    text, message = BAD[case]
    path = tmp_path / "bad.toml"
    path.write_text(text)
    out = run_cli("run", str(path), "--out", str(tmp_path / "out"))
    assert out.returncode == 2
    assert out.stderr.count("\n") == 1 and message in out.stderr
    assert "Traceback" not in out.stderr
    assert not (tmp_path / "out").exists()  # no half-written output folder


@pytest.mark.parametrize(
    "args",
    [
        ["run", "no-such-scenario"],
        ["limits", "--voltage-pk", "-3"],
        ["limits", "--frequency", "abc"],
        ["frobnicate"],
    ],
)
def test_bad_arguments_fail_with_one_line(args):
    out = run_cli(*args)
    assert out.returncode == 2
    assert out.stderr.count("\n") == 1 and "Traceback" not in out.stderr
