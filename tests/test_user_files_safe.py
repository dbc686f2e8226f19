"""acdrive deletes or replaces only what it wrote (issue 19, item 1).

A folder or file that acdrive did not write (no marker, no stamp) is refused with one line naming
the option and the path, exit 2, before any work, at ``--out .`` and at a nested ``--out``, by
every command that writes files; ``--out ""`` is refused; output gets the user's umask; staging
folders of killed runs are cleaned up by the next run (only acdrive's, only of dead processes);
symbolic links follow one rule; a sweep folder is locked while a sweep runs in it.
"""

import json
import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest

from acdrive._output import (
    MARKER,
    OutputFile,
    OutputFolder,
    is_acdrive_file,
    is_acdrive_folder,
    png_metadata,
    remove_leftovers,
    write_marker,
)
from acdrive.errors import InputError

SHORT = """
name = "{name}"
[simulation]
duration = {duration}
[[motor]]
speed_reference_rpm = [[0, 0], [{duration}, 100]]
[motor.controller]
speed_bandwidth = 100.0
"""

SWEEP = """
name = "{name}"
base = "{base}"
[[vary]]
field = "motor[0].load_torque"
values = [0.0, 0.05]
"""


def _cli(*args, cwd=None, env=None):
    return subprocess.run(
        [sys.executable, "-m", "acdrive.cli", *map(str, args)],
        check=False,
        capture_output=True,
        text=True,
        cwd=cwd,
        env=env,
    )


def _tree(folder):
    """Every file below ``folder`` with its bytes and mode, to prove it untouched."""
    out = []
    for d, dirs, files in os.walk(folder):
        for f in files + dirs:
            path = os.path.join(d, f)
            data = Path(path).read_bytes() if os.path.isfile(path) else b""
            out.append((os.path.relpath(path, folder), data, os.lstat(path).st_mode))
    return sorted(out)


def _user_project(folder):
    """A user's code folder: what the audit saw deleted."""
    (folder / "src").mkdir(parents=True)
    (folder / "src" / "main.py").write_text("print('my code')\n")
    (folder / "src" / "notes.txt").write_text("my notes\n")


def _scenario(tmp_path, name, duration=0.2):
    path = tmp_path / f"{name}-scenario.toml"
    path.write_text(SHORT.format(name=name, duration=duration))
    return path


def _one_line(stderr, *needles):
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in stderr, stderr
    for needle in needles:
        assert needle in lines[0], stderr


# --- a user's folder named like the scenario -------------------------------------------------


@pytest.mark.parametrize("nested", [False, True], ids=["out-dot", "nested-out"])
def test_a_users_folder_named_like_the_scenario_is_refused_and_untouched(tmp_path, nested):
    work = tmp_path / "work"
    out = work / "a" / "b" if nested else work
    _user_project(out)
    scenario = _scenario(tmp_path, "src")
    before = _tree(tmp_path)
    result = _cli("run", scenario, "--out", "a/b" if nested else ".", "--no-figures", cwd=work)
    assert result.returncode == 2, result.stderr
    _one_line(result.stderr, "--out", "name", "src", "did not write")
    assert _tree(tmp_path) == before  # nothing created, nothing removed, no mode changed
    assert (out / "src" / "main.py").read_text() == "print('my code')\n"


def test_acdrives_own_output_is_still_replaced_whole(tmp_path):
    out = tmp_path / "out"
    scenario = _scenario(tmp_path, "short")
    assert _cli("run", scenario, "--out", out, "--no-figures").returncode == 0
    assert is_acdrive_folder(out / "short")
    (out / "short" / "stale.txt").write_text("from an older run")
    second = _cli("run", scenario, "--out", out, "--no-figures")
    assert second.returncode == 0, second.stderr
    assert not (out / "short" / "stale.txt").exists()
    assert json.loads((out / "short" / MARKER).read_text())["written_by"] == "acdrive"


def test_a_marker_that_is_not_acdrives_does_not_count(tmp_path):
    folder = tmp_path / "short"
    folder.mkdir()
    (folder / MARKER).write_text('{"written_by": "someone else"}')
    assert not is_acdrive_folder(folder)
    (folder / MARKER).write_text("not json")
    assert not is_acdrive_folder(folder)
    with pytest.raises(InputError, match="did not write"):
        OutputFolder(tmp_path, "short")


@pytest.mark.parametrize(
    "argv",
    [
        ["run", "--out", ""],
        ["run", "--out", "  "],
        ["reproduce", "icad", "--out", ""],
        ["stability", "--map", "--out", ""],
        ["icad", "pmsg-2mw", "--sweep", "--out", ""],
    ],
    ids=["run", "run-blank", "reproduce", "stability-map", "icad-sweep"],
)
def test_empty_out_is_refused(tmp_path, argv):
    (tmp_path / "keep.txt").write_text("user data")
    before = _tree(tmp_path)
    result = _cli(*argv, cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    _one_line(result.stderr, "--out", "empty")
    assert _tree(tmp_path) == before


def test_empty_out_is_refused_by_sweep(tmp_path):
    (tmp_path / "sweep.toml").write_text(SWEEP.format(name="s", base="bodson-step"))
    result = _cli("sweep", tmp_path / "sweep.toml", "--out", "", cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    _one_line(result.stderr, "--out", "empty")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sweep.toml"]


# --- permissions -----------------------------------------------------------------------------


@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002])
def test_output_gets_the_users_umask(tmp_path, umask):
    def with_umask():
        os.umask(umask)

    scenario = _scenario(tmp_path, "short")
    out = tmp_path / "out"
    proc = subprocess.run(
        [sys.executable, "-m", "acdrive.cli", "run", str(scenario), "--out", str(out),
         "--no-figures"],
        capture_output=True, text=True, preexec_fn=with_umask, check=False,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    folder_mode = stat.S_IMODE((out / "short").stat().st_mode)
    assert folder_mode == 0o777 & ~umask
    for path in (out / "short").iterdir():
        assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~umask, path


# --- leftovers of killed runs ----------------------------------------------------------------


def _dead_pid():
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def _leftover(root, name, pid, host=None):
    import socket

    folder = root / name
    folder.mkdir()
    info = {"written_by": "acdrive", "version": "0", "pid": pid,
            "host": host or socket.gethostname()}  # fmt: skip
    (folder / MARKER).write_text(json.dumps(info))
    (folder / "data.parquet").write_text("half written")
    return folder


def test_leftovers_of_dead_runs_are_removed_and_nothing_else(tmp_path):
    dead = _dead_pid()
    gone = _leftover(tmp_path, ".short.partial-abc", dead)
    live = _leftover(tmp_path, ".short.partial-live", os.getpid())  # a run in progress
    remote = _leftover(tmp_path, ".short.partial-far", dead, host="another-host")
    user = tmp_path / ".mine.partial-x"  # looks like staging, but no marker: the user's
    user.mkdir()
    (user / "keep.txt").write_text("user data")
    removed = remove_leftovers(tmp_path)
    assert removed == [gone]
    assert not gone.exists() and live.exists() and remote.exists()
    assert (user / "keep.txt").read_text() == "user data"


def test_an_interrupted_swap_gets_its_old_output_back(tmp_path):
    backup = _leftover(tmp_path, ".short.old-abc", _dead_pid())
    (backup / "short").mkdir()
    write_marker(backup / "short")
    (backup / "short" / "summary.json").write_text("{}")
    remove_leftovers(tmp_path)
    assert not backup.exists()
    assert (tmp_path / "short" / "summary.json").read_text() == "{}"


def test_the_next_run_removes_the_staging_folder_of_a_sigkilled_run(tmp_path):
    out = tmp_path / "out"
    (out).mkdir()
    (out / "keep.txt").write_text("user data")
    slow = _scenario(tmp_path, "short", duration=60.0)
    proc = subprocess.Popen(
        [sys.executable, "-m", "acdrive.cli", "run", str(slow), "--out", str(out)],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    deadline = time.monotonic() + 120
    while not any(p.name.startswith(".short.partial-") for p in out.iterdir()):
        assert time.monotonic() < deadline and proc.poll() is None, "no staging folder appeared"
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=60)
    assert any(p.name.startswith(".short.partial-") for p in out.iterdir())  # the leftover
    result = _cli("run", _scenario(tmp_path, "short"), "--out", out, "--no-figures")
    assert result.returncode == 0, result.stderr
    assert sorted(p.name for p in out.iterdir()) == ["keep.txt", "short"]


# --- symbolic links: one rule ----------------------------------------------------------------


@pytest.mark.slow
def test_out_may_be_a_link_to_a_folder_for_run_and_sweep(tmp_path):
    real = tmp_path / "real"
    real.mkdir()
    link = tmp_path / "link"
    link.symlink_to(real, target_is_directory=True)
    run = _cli("run", _scenario(tmp_path, "short"), "--out", link, "--no-figures")
    assert run.returncode == 0, run.stderr
    assert is_acdrive_folder(real / "short")
    sweep_file = tmp_path / "sweep.toml"
    sweep_file.write_text(SWEEP.format(name="s", base=_scenario(tmp_path, "base")))
    sweep = _cli("sweep", sweep_file, "--out", link)
    assert sweep.returncode == 0, sweep.stderr
    assert is_acdrive_folder(real / "s")


def test_the_folder_acdrive_replaces_is_never_a_link(tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "keep.txt").write_text("user data")
    out = tmp_path / "out"
    out.mkdir()
    for name in ("short", "s"):
        (out / name).symlink_to(elsewhere, target_is_directory=True)
    run = _cli("run", _scenario(tmp_path, "short"), "--out", out)
    assert run.returncode == 2
    _one_line(run.stderr, "--out", "short")
    sweep_file = tmp_path / "sweep.toml"
    sweep_file.write_text(SWEEP.format(name="s", base=_scenario(tmp_path, "base")))
    sweep = _cli("sweep", sweep_file, "--out", out)
    assert sweep.returncode == 2
    _one_line(sweep.stderr, "--out", "link")
    assert sorted(p.name for p in elsewhere.iterdir()) == ["keep.txt"]


# --- sweep folders ---------------------------------------------------------------------------


def test_a_sweep_refuses_a_users_folder_of_its_name(tmp_path):
    _user_project(tmp_path / "out")
    sweep_file = tmp_path / "sweep.toml"
    sweep_file.write_text(SWEEP.format(name="src", base="bodson-step"))
    before = _tree(tmp_path / "out")
    result = _cli("sweep", sweep_file, "--out", tmp_path / "out")
    assert result.returncode == 2
    _one_line(result.stderr, "--out", "did not write")
    assert _tree(tmp_path / "out") == before


def test_a_second_sweep_on_a_locked_folder_is_refused_and_touches_nothing(tmp_path):
    from acdrive.sweep import load_sweep, run_sweep
    from acdrive.sweep._engine import _Lock

    sweep_file = tmp_path / "sweep.toml"
    sweep_file.write_text(SWEEP.format(name="s", base=_scenario(tmp_path, "base")))
    spec = load_sweep(sweep_file)
    folder = tmp_path / "out" / "s"
    folder.mkdir(parents=True)
    write_marker(folder)
    (folder / "table").mkdir()
    (folder / "table" / ".chunk-000000.parquet.99.tmp").write_text("first sweep's chunk")
    with _Lock(folder):  # the first sweep, still running
        before = _tree(folder)
        with pytest.raises(InputError, match="in use by another sweep"):
            run_sweep(spec, tmp_path / "out", progress=False, report=False)
        assert _tree(folder) == before
    run_sweep(spec, tmp_path / "out", progress=False, report=False)  # the lock is free again
    assert not (folder / "table" / ".chunk-000000.parquet.99.tmp").exists()


def test_sweep_report_refuses_a_folder_acdrive_did_not_write(tmp_path):
    import pandas as pd

    from acdrive.sweep import load_sweep, write_report

    sweep_file = tmp_path / "sweep.toml"
    sweep_file.write_text(SWEEP.format(name="s", base="bodson-step"))
    (tmp_path / "mine").mkdir()
    with pytest.raises(InputError, match="did not write"):
        write_report(load_sweep(sweep_file), tmp_path / "mine", pd.DataFrame())
    assert list((tmp_path / "mine").iterdir()) == []


# --- single files: stability --map and reproduce ---------------------------------------------


def test_a_users_file_of_the_figures_name_is_refused(tmp_path):
    (tmp_path / "stability-map-continuous-a314.png").write_bytes(b"\x89PNG\r\n\x1a\nmine")
    before = _tree(tmp_path)
    result = _cli("stability", "--map", "--out", tmp_path)
    assert result.returncode == 2, result.stderr
    _one_line(result.stderr, "--out", "stability-map-continuous-a314.png", "did not write")
    assert _tree(tmp_path) == before


def test_output_file_replaces_only_acdrives_own_figure(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def draw(path, marked):
        fig, ax = plt.subplots()
        ax.plot([0, 1])
        fig.savefig(path, metadata=png_metadata("test") if marked else None)
        plt.close(fig)

    (tmp_path / "keep.txt").write_text("user data")
    with OutputFile(tmp_path, "fig.png") as output:
        draw(output.path, marked=True)
        target = output.publish()
    assert is_acdrive_file(target)
    with OutputFile(tmp_path, "fig.png") as output:  # acdrive's own: replaced
        draw(output.path, marked=True)
        output.publish()
    draw(tmp_path / "user.png", marked=False)
    assert not is_acdrive_file(tmp_path / "user.png")
    with pytest.raises(InputError, match="did not write"):
        OutputFile(tmp_path, "user.png")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig.png", "keep.txt", "user.png"]


def test_reproduce_refuses_a_users_report_of_its_name(tmp_path):
    (tmp_path / "icad.md").write_text("# my own notes on ICAD\n")
    before = _tree(tmp_path)
    start = time.monotonic()
    result = _cli("reproduce", "icad", "--out", tmp_path)
    assert result.returncode == 2, result.stderr
    _one_line(result.stderr, "--out", "icad.md", "did not write")
    assert time.monotonic() - start < 20  # refused before the report was computed
    assert _tree(tmp_path) == before


def test_the_committed_reports_are_recognised_as_acdrives(tmp_path):
    reports = Path(__file__).resolve().parents[1] / "docs" / "reproduction"
    for stem in ("bodson", "icad", "im-current-control"):
        assert is_acdrive_file(reports / f"{stem}.md"), stem
        assert is_acdrive_folder(reports / stem), stem
