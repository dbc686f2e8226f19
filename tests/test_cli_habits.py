"""Command-line habits: --version, a --help that imports no numerical library, negative option
values, the output folder in --out's help, the progress bar only on a terminal, the first-compile
notice, and a headline whose tracking windows come from the reference profile."""

import io
import json
import math
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import acdrive
from acdrive._progress import Progress
from acdrive.cli import build_parser, main

OWN_COMMANDS = ("run", "scenarios", "limits", "icad", "stability", "reproduce")
HEAVY = ("numba", "numpy", "scipy", "pandas", "matplotlib", "pyarrow", "tqdm")


def _python(code: str, env=None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        check=False, capture_output=True, text=True, env=env,
    )  # fmt: skip


def test_version(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.strip() == f"acdrive {acdrive.__version__}"


def test_help_of_every_command_imports_no_numerical_library():
    """--help (top level and each command) in a fresh interpreter: none of the heavy libraries
    is imported, so the answer is fast (the timing itself is not a test)."""
    commands = [[], *([c] for c in OWN_COMMANDS)]
    out = _python(f"""
        import sys
        from acdrive.cli import main
        for words in {commands!r}:
            try:
                main([*words, "--help"])
            except SystemExit as exc:
                assert exc.code == 0, (words, exc.code)
        print(sorted(m for m in {HEAVY!r} if m in sys.modules))
    """)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip().splitlines()[-1] == "[]"


def test_top_level_help_lists_every_command_without_importing_it(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    text = capsys.readouterr().out
    for name in OWN_COMMANDS:
        assert name in text


def test_the_lazy_table_says_what_each_command_says():
    """The one-line help of the command table is the help each command registers."""
    import argparse

    from acdrive.cli import COMMANDS

    parser = build_parser()  # every command's full parser
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    registered = {choice.dest: choice.help for choice in action._choices_actions}
    assert set(registered) <= set(COMMANDS) and set(OWN_COMMANDS) <= set(registered)
    for name, text in registered.items():
        assert COMMANDS[name] == text, name


def test_icad_help_constants_match_the_analysis():
    from acdrive._commands import icad as command
    from acdrive.analysis import _icad as analysis
    from acdrive.analysis._plants import MACHINES

    assert command.MACHINES == tuple(MACHINES)
    assert command.CONTROLLER_NAMES == tuple(analysis.CONTROLLER_NAMES)
    assert command.A_CUR_DEFAULT == analysis.A_CUR_DEFAULT


@pytest.mark.parametrize("value", ["-0.1", "-1e-3", "-2.5E+1", "-.5", "-inf"])
def test_negative_numbers_are_option_values(value):
    argv = ["stability", "--speed-rpm", "900", "--load-nm", value]
    args = build_parser(argv).parse_args(argv)
    assert args.load_nm == float(value)


def test_negative_load_runs_end_to_end(capsys):
    code = main(["stability", "--speed-rpm", "-900", "--load-nm", "-0.1", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["load_nm"] == -0.1 and out["speed_rpm"] == -900.0


def test_out_help_says_where_the_output_goes(capsys):
    with pytest.raises(SystemExit):
        main(["run", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "DIR/<scenario name>/" in text and "parquet" in text


def test_progress_bar_only_on_a_terminal(monkeypatch):
    class Terminal(io.StringIO):
        def isatty(self):
            return True

    plain = io.StringIO()
    monkeypatch.setattr(sys, "stderr", plain)
    with Progress(2, "job") as bar:
        bar.phase("step one")
        bar.advance(2)
    assert plain.getvalue() == ""
    terminal = Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    with Progress(2, "job") as bar:
        bar.phase("step one")
        bar.advance(2)
    assert "job" in terminal.getvalue() and "step one" in terminal.getvalue()


# --- the headline's tracking windows -------------------------------------------------------


def _ramp_and_stop():
    from acdrive.scenarios import load_scenario

    return load_scenario("bodson-ramp")  # 0 -> 2700 rpm ramp, abrupt stop at 11 s


def _result(setup, t, w, relay=None):
    from acdrive.drives.dfim._result import LOG_NAMES, N_LOG, DriveResult

    times, values = setup.motors[0].speed_reference
    signals = np.zeros((t.size, 1, N_LOG))
    signals[:, 0, LOG_NAMES.index("w_ref")] = np.interp(t, times, values, right=values[-1])
    # the profile's step at 11 s: np.interp takes the later value at the shared time
    signals[:, 0, LOG_NAMES.index("w")] = w
    signals[:, 0, LOG_NAMES.index("relay_closed")] = 1.0 if relay is None else relay
    return DriveResult(setup.name, t, signals, t[1] - t[0], np.zeros(1))


def test_tracking_windows_follow_the_reference_step_torque_limit_and_bandwidth():
    from acdrive._frames import K_PEAK
    from acdrive.drives.dfim._outcome import tracking_windows
    from acdrive.machines import machine_vector, torque_limits_case1
    from acdrive.sim._metrics import SETTLE_TIME_CONSTANTS, SLEW_MARGIN

    setup = _ramp_and_stop()
    m = setup.motors[0]
    t = np.arange(0.0, 14.0, 1e-3)
    times, values = m.speed_reference
    reference = np.interp(t, times, values)
    step = float(np.max(np.abs(np.diff(values))))
    # expected window: the stop's size slewed at the smaller torque limit, then 6 / a to settle
    limits = torque_limits_case1(machine_vector(m.machine), 2 * math.pi * 60.0,
                                 K_PEAK * 11.1, K_PEAK * 6.0, K_PEAK * 6.0)  # fmt: skip
    tau = min(abs(min(limits[:3])), abs(max(limits[3:5])))
    a = m.controller.gains.K_P / (2 * m.machine.J)
    end = 11.0 + SLEW_MARGIN * m.machine.J * step / tau + SETTLE_TIME_CONSTANTS / a
    w = reference.copy()
    w[t >= 11.0] = np.maximum(values[3] - 700.0 * (t[t >= 11.0] - 11.0), 0.0)  # the slew
    w[np.argmin(np.abs(t - 5.0))] += 0.002  # an error where tracking is expected
    after = np.flatnonzero(t >= end + 0.01)[0]
    w[after] += 0.001  # a smaller one just after the window
    tracking = tracking_windows(_result(setup, t, w), setup)
    assert len(tracking["windows_s"]) == 1
    assert tracking["windows_s"][0] == pytest.approx([11.0, end], rel=1e-12)
    rpm = 30.0 / math.pi
    assert tracking["max_abs_error_rpm"] == pytest.approx(0.002 * rpm, rel=1e-6)
    assert tracking["max_abs_error_at_s"] == pytest.approx(5.0, abs=1e-9)
    inside = (t >= 11.0) & (t < end)
    assert tracking["tracked_fraction"] == pytest.approx(1.0 - inside.mean())
    for number in (f"{tau:.3g} N m", f"{a:.0f} rad/s"):
        assert number in tracking["rule"]


def test_an_open_relay_is_not_tracking():
    from acdrive.drives.dfim._outcome import tracking_windows

    setup = _ramp_and_stop()
    t = np.arange(0.0, 2.0, 1e-3)
    relay = (t >= 1.0).astype(float)
    w = np.zeros_like(t)  # the reference ramps from 0.5 s; the open-stator shaft stays still
    result = _result(setup, t, w, relay)
    tracking = tracking_windows(result, setup)
    assert tracking["windows_s"][0][0] == pytest.approx(1.0)  # settling after the closing
    assert tracking["tracked_fraction"] < 0.5
    assert "relay closed" in tracking["rule"]


def test_headline_prints_the_summary_numbers(tmp_path, capsys):
    path = tmp_path / "step.toml"
    path.write_text(
        'name = "step"\n[simulation]\nduration = 0.4\n[[motor]]\n'
        "speed_reference_rpm = [[0, 0], [0.1, 0], [0.1, 300], [0.4, 300]]\n"
        "[motor.controller]\nspeed_bandwidth = 100.0\n"
    )
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--no-figures"]) == 0
    out = capsys.readouterr().out
    folder = tmp_path / "out" / "step"
    summary = json.loads((folder / "summary.json").read_text())
    tracking = summary["speed_tracking"]
    assert len(tracking["windows_s"]) == 1 and tracking["windows_s"][0][0] == pytest.approx(0.1)
    row = next(line for line in out.splitlines() if "speed tracking" in line)
    assert f"{tracking['rms_error_rpm']:.2f} rpm RMS" in row
    assert f"largest {tracking['max_abs_error_rpm']:.2f} rpm" in row
    assert summary["speed_max_abs_error_whole_run_rpm"] > tracking["max_abs_error_rpm"]
    assert f"{summary['speed_max_abs_error_whole_run_rpm']:.1f}" not in row
    assert out.splitlines()[-1].startswith(f"wrote {folder}/: data.parquet")
