"""Output safety: names are one path component, nothing outside --out is touched, old output is
replaced whole or not at all, and interruptions leave no partial or hidden folder."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

SHORT = """
name = "{name}"
[simulation]
duration = {duration}
log_every = {log_every}
[[motor]]
speed_reference_rpm = [[0, 0], [{duration}, 100]]
[motor.controller]
speed_bandwidth = 100.0
"""


def _cli(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "acdrive.cli", *args],
        check=False,
        capture_output=True,
        text=True,
        cwd=cwd,
    )


def _tree(folder):
    """Every path below ``folder`` with its size, to prove a folder unchanged."""
    return sorted(
        (os.path.relpath(os.path.join(d, f), folder), os.path.getsize(os.path.join(d, f)))
        for d, _, files in os.walk(folder)
        for f in files
    )


def _scenario(tmp_path, name, duration=0.2, log_every=1):
    path = tmp_path / "scenario.toml"
    path.write_text(SHORT.format(name=name, duration=duration, log_every=log_every))
    return path


@pytest.mark.parametrize("name", [".", "", "..", "/tmp", "../escape", "a/b", ".hidden", "x" * 101])
def test_unsafe_names_are_refused_and_nothing_is_touched(tmp_path, name):
    work = tmp_path / "work"
    out = work / "out"
    out.mkdir(parents=True)
    (out / "keep.txt").write_text("user data")
    (work / "also-keep.txt").write_text("user data")
    scenario = _scenario(tmp_path, name)
    before = _tree(tmp_path)
    result = _cli("run", str(scenario), "--out", str(out), cwd=work)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("acdrive: error: name:"), result.stderr
    assert _tree(tmp_path) == before


def test_out_that_is_a_file_is_refused_before_simulating(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("user data")
    scenario = _scenario(tmp_path, "short")
    for out in (blocker, blocker / "below"):
        result = _cli("run", str(scenario), "--out", str(out))
        assert result.returncode == 2, result.stderr
        assert result.stderr.count("\n") == 1 and "--out" in result.stderr
        assert "Traceback" not in result.stderr
    assert blocker.read_text() == "user data"


def test_existing_file_with_the_scenario_name_is_not_replaced(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "short").write_text("user data")
    result = _cli("run", str(_scenario(tmp_path, "short")), "--out", str(out))
    assert result.returncode == 2 and "--out" in result.stderr
    assert (out / "short").read_text() == "user data"
    assert sorted(p.name for p in out.iterdir()) == ["short"]


@pytest.mark.slow
def test_rerun_replaces_the_old_output_whole(tmp_path):
    out = tmp_path / "out"
    scenario = _scenario(tmp_path, "short")
    first = _cli("run", str(scenario), "--out", str(out), "--no-figures")
    assert first.returncode == 0, first.stderr
    (out / "short" / "stale.txt").write_text("from an older run")
    (out / "neighbour.txt").write_text("user data")
    second = _cli("run", str(scenario), "--out", str(out), "--no-figures")
    assert second.returncode == 0, second.stderr
    assert not (out / "short" / "stale.txt").exists()
    assert json.loads((out / "short" / "summary.json").read_text())["limit_events"] is not None
    assert sorted(p.name for p in out.iterdir()) == ["neighbour.txt", "short"]  # nothing hidden


def test_binary_and_utf16_scenarios_are_one_line_errors(tmp_path):
    for content in ("name = 'x'\n".encode("utf-16"), bytes(range(256))):
        path = tmp_path / "bad.toml"
        path.write_bytes(content)
        result = _cli("run", str(path), "--out", str(tmp_path / "out"))
        assert result.returncode == 2 and result.stderr.count("\n") == 1, result.stderr
        assert "scenario" in result.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
@pytest.mark.parametrize("signum, code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_interrupted_run_keeps_the_old_output_and_leaves_nothing_hidden(tmp_path, signum, code):
    out = tmp_path / "out"
    quick = _scenario(tmp_path, "short", duration=0.2)
    assert _cli("run", str(quick), "--out", str(out), "--no-figures").returncode == 0
    old = _tree(out)
    # long enough to be interrupted while it simulates (60 s of it take under a second on the
    # native loop: the signal would come while the process exits), logged every 1000 samples
    slow = _scenario(tmp_path, "short", duration=3000.0, log_every=1000)
    proc = subprocess.Popen(
        [sys.executable, "-m", "acdrive.cli", "run", str(slow), "--out", str(out)],
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    while not any(p.name.startswith(".short.partial-") for p in out.iterdir()):
        assert time.monotonic() < deadline and proc.poll() is None, "no staging folder appeared"
        time.sleep(0.05)
    time.sleep(0.5)
    proc.send_signal(signum)
    _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == code
    assert stderr.count("\n") == 1 and "Traceback" not in stderr
    assert _tree(out) == old
    assert sorted(p.name for p in out.iterdir()) == ["short"]
