"""Staged output of `acdrive icad --sweep` and `acdrive reproduce`: --out is checked before any
computation, old output is replaced whole or not at all, an interruption (SIGTERM, SIGINT) leaves
the complete old output and no hidden folder, and nothing beside the output is touched.

`reproduce` takes about half a minute for real, so its staging is tested through the command with
the report writer replaced by a small fake (a driver script run as a subprocess); its --out checks
run against the real writer, which they stop before it starts.
"""

import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

#: the cheapest sweep (one speed, no contour cross-checks): a few seconds
SWEEP = ["icad", "pmsg-2mw", "--sweep", "--speeds", "0", "100", "1", "--no-verify", "--json"]
#: about a minute of analysis before any figure is written: long enough to be interrupted
SLOW_SWEEP = ["icad", "ugalde-im-300w", "--sweep", "--speeds", "0", "375", "100"]
FIGURES = {
    "nyquist_gamma.png",
    "nyquist_gamma_h.png",
    "bode_channels.png",
    "bode_kg.png",
    "pole_map.png",
    "coupling.png",
}


def _cli(*args, cwd=None):
    return subprocess.run(
        [sys.executable, "-m", "acdrive.cli", *map(str, args)],
        check=False,
        capture_output=True,
        text=True,
        cwd=cwd,
    )


def _tree(folder):
    """Every file below ``folder`` with its content, to prove a folder unchanged."""
    return sorted(
        (os.path.relpath(os.path.join(d, f), folder), open(os.path.join(d, f), "rb").read())
        for d, _, files in os.walk(folder)
        for f in files
    )


def _one_error_line(stderr: str, field: str):
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in stderr, stderr
    assert lines[0].startswith(f"acdrive: error: {field}:"), stderr


def _wait_for(predicate, proc, what, timeout=60.0):
    deadline = time.monotonic() + timeout
    while not predicate():
        assert proc.poll() is None, f"the command ended before {what}"
        assert time.monotonic() < deadline, f"no {what} within {timeout} s"
        time.sleep(0.02)


# ---------------------------------------------------------------------------------------------
# acdrive icad --sweep
# ---------------------------------------------------------------------------------------------


def _icad_cases(tmp_path):
    """(name, --out, files that must stay as they are) for each refused --out."""
    work = tmp_path / "work"
    work.mkdir()
    blocker = work / "file"
    blocker.write_text("user data")
    real = work / "real-folder"
    real.mkdir()
    (real / "keep.txt").write_text("user data")
    (work / "link").symlink_to(real, target_is_directory=True)
    return work, {
        "a file": blocker,
        "below a file": blocker / "figs",
        "a symbolic link to a folder": work / "link",
        "the current folder": ".",
        "the parent folder": "..",
    }


@pytest.mark.parametrize(
    "case", ["a file", "below a file", "a symbolic link to a folder", "the current folder"]
)
def test_icad_refuses_a_bad_out_before_any_analysis(tmp_path, case):
    work, cases = _icad_cases(tmp_path)
    before = _tree(tmp_path)
    start = time.monotonic()
    result = _cli(*SLOW_SWEEP, "--out", cases[case], cwd=work)
    elapsed = time.monotonic() - start
    assert result.returncode == 2, result.stderr
    _one_error_line(result.stderr, "--out")
    assert elapsed < 30, "the analysis ran before --out was checked"
    assert _tree(tmp_path) == before
    assert (work / "link").is_symlink()
    assert sorted(p.name for p in work.iterdir()) == ["file", "link", "real-folder"]


def test_icad_default_folder_is_icad_machine(tmp_path, monkeypatch):
    from pathlib import Path

    from acdrive._commands.icad import _figure_folder

    monkeypatch.chdir(tmp_path)
    with _figure_folder(None, "pmsg-2mw") as output:
        assert output.target == Path("icad-pmsg-2mw")
        assert output.staging.parent.resolve() == tmp_path.resolve()
    assert list(tmp_path.iterdir()) == []  # the unused staging folder is gone


def test_icad_rerun_replaces_the_old_figures_whole(tmp_path):
    out = tmp_path / "out"
    figs = out / "figs"
    figs.mkdir(parents=True)
    (figs / "stale.png").write_text("from an older sweep")
    (out / "neighbour.txt").write_text("user data")
    result = _cli(*SWEEP, "--out", figs)
    assert result.returncode == 0, result.stderr
    assert {p.name for p in figs.iterdir()} == FIGURES
    report = json.loads(result.stdout)
    assert sorted(report["figures"]) == sorted(str(figs / name) for name in FIGURES)
    assert all((figs / name).stat().st_size > 1000 for name in FIGURES)
    assert sorted(p.name for p in out.iterdir()) == ["figs", "neighbour.txt"]  # nothing hidden
    assert (out / "neighbour.txt").read_text() == "user data"


@pytest.mark.parametrize("signum, code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_interrupted_icad_sweep_keeps_the_old_figures(tmp_path, signum, code):
    out = tmp_path / "out"
    (out / "figs").mkdir(parents=True)
    (out / "figs" / "old.png").write_text("complete old output")
    old = _tree(out)
    proc = subprocess.Popen(
        [sys.executable, "-m", "acdrive.cli", *SLOW_SWEEP, "--out", str(out / "figs")],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    _wait_for(
        lambda: any(p.name.startswith(".figs.partial-") for p in out.iterdir()),
        proc,
        "staging folder",
    )
    time.sleep(0.3)
    proc.send_signal(signum)
    _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == code, stderr
    assert stderr.count("\n") == 1 and "Traceback" not in stderr
    assert _tree(out) == old
    assert sorted(p.name for p in out.iterdir()) == ["figs"]


def test_icad_sweep_terminated_while_writing_figures_leaves_old_or_new(tmp_path):
    """SIGTERM as soon as the first figure is in the staging folder: the target holds the
    complete old figures (or, if the swap won the race, the complete new ones), never a mix."""
    out = tmp_path / "out"
    (out / "figs").mkdir(parents=True)
    (out / "figs" / "old.png").write_text("complete old output")
    old = _tree(out)
    proc = subprocess.Popen(
        [sys.executable, "-m", "acdrive.cli", *SWEEP, "--out", str(out / "figs")],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )

    def first_figure_staged():
        return any(
            any(f.suffix == ".png" for f in p.iterdir())
            for p in out.iterdir()
            if p.name.startswith(".figs.partial-")
        )

    _wait_for(first_figure_staged, proc, "staged figure")
    proc.send_signal(signal.SIGTERM)
    _, stderr = proc.communicate(timeout=60)
    assert "Traceback" not in stderr
    assert sorted(p.name for p in out.iterdir()) == ["figs"]
    if proc.returncode == 143:
        assert _tree(out) == old
    else:  # the figures were all written and swapped in before the signal arrived
        assert proc.returncode == 0, stderr
        assert {p.name for p in (out / "figs").iterdir()} == FIGURES


# ---------------------------------------------------------------------------------------------
# acdrive reproduce
# ---------------------------------------------------------------------------------------------

#: runs `acdrive reproduce ...` with the icad report writer replaced by a fake; FAKE_MODE says how
#: it behaves: "ok" writes a report and one figure, "slow" writes part of them and waits to be
#: interrupted, "no-figures" leaves out the figure folder (a broken writer)
DRIVER = textwrap.dedent(
    """
    import os, sys, time
    from pathlib import Path
    import acdrive._report.icad_reproduction as module
    from acdrive.cli import main

    def fake(out_dir):
        out = Path(out_dir)
        mode = os.environ["FAKE_MODE"]
        if mode != "no-figures":
            (out / "icad").mkdir()
            (out / "icad" / "fig.png").write_text("new figure")
        if mode == "slow":
            print("writing", flush=True)
            time.sleep(120)
        (out / "icad.md").write_text("new report")
        return out / "icad.md"

    module.write_report = fake
    sys.exit(main(sys.argv[1:]))
    """
)


def _old_reports(out):
    """An --out folder holding an old icad report, another paper's report and user data."""
    (out / "icad").mkdir(parents=True)
    (out / "icad.md").write_text("old report")
    (out / "icad" / "old.png").write_text("old figure")
    (out / "bodson").mkdir()
    (out / "bodson.md").write_text("another paper")
    (out / "notes.txt").write_text("user data")


def _reproduce(tmp_path, mode, out, popen=False):
    driver = tmp_path / "driver.py"
    driver.write_text(DRIVER)
    argv = [sys.executable, str(driver), "reproduce", "icad", "--out", str(out)]
    env = {**os.environ, "FAKE_MODE": mode}
    if popen:
        return subprocess.Popen(
            argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
        )
    return subprocess.run(argv, capture_output=True, text=True, env=env, check=False)


def test_reproduce_replaces_report_and_figures_together(tmp_path):
    out = tmp_path / "out"
    _old_reports(out)
    result = _reproduce(tmp_path, "ok", out)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == str(out / "icad.md")
    assert (out / "icad.md").read_text() == "new report"
    assert [p.name for p in (out / "icad").iterdir()] == ["fig.png"]  # old figure gone
    assert (out / "bodson.md").read_text() == "another paper"
    assert (out / "notes.txt").read_text() == "user data"
    assert sorted(p.name for p in out.iterdir()) == [
        "bodson", "bodson.md", "icad", "icad.md", "notes.txt"
    ]  # fmt: skip


def test_reproduce_into_a_new_folder(tmp_path):
    out = tmp_path / "new" / "reports"
    result = _reproduce(tmp_path, "ok", out)
    assert result.returncode == 0, result.stderr
    assert sorted(p.name for p in out.iterdir()) == ["icad", "icad.md"]


@pytest.mark.parametrize("signum, code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_interrupted_reproduce_keeps_the_old_report(tmp_path, signum, code):
    out = tmp_path / "out"
    _old_reports(out)
    old = _tree(out)
    proc = _reproduce(tmp_path, "slow", out, popen=True)
    assert proc.stdout.readline().strip() == "writing"  # half of the new report is staged
    proc.send_signal(signum)
    _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == code, stderr
    assert stderr.count("\n") == 1 and "Traceback" not in stderr
    assert _tree(out) == old
    assert sorted(p.name for p in out.iterdir()) == [
        "bodson", "bodson.md", "icad", "icad.md", "notes.txt"
    ]  # fmt: skip


def test_a_writer_that_leaves_out_the_figures_keeps_the_old_report(tmp_path):
    out = tmp_path / "out"
    _old_reports(out)
    old = _tree(out)
    result = _reproduce(tmp_path, "no-figures", out)
    assert result.returncode == 70  # a bug in the writer, reported in one line
    assert result.stderr.count("\n") == 1 and "missing icad" in result.stderr
    assert _tree(out) == old
    assert sorted(p.name for p in out.iterdir()) == [
        "bodson", "bodson.md", "icad", "icad.md", "notes.txt"
    ]  # fmt: skip


@pytest.mark.parametrize("case", ["out is a file", "icad.md is a folder", "icad is a file",
                                  "icad is a symbolic link"])  # fmt: skip
def test_reproduce_refuses_a_bad_out_before_computing(tmp_path, case):
    out = tmp_path / "out"
    out.mkdir()
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "keep.png").write_text("user data")
    if case == "out is a file":
        out.rmdir()
        out.write_text("user data")
    elif case == "icad.md is a folder":
        (out / "icad.md").mkdir()
        (out / "icad.md" / "keep.txt").write_text("user data")
    elif case == "icad is a file":
        (out / "icad").write_text("user data")
    else:
        (out / "icad").symlink_to(elsewhere, target_is_directory=True)
    before = _tree(tmp_path)
    start = time.monotonic()
    result = _cli("reproduce", "icad", "--out", out)  # the real writer: half a minute if run
    assert result.returncode == 2, result.stderr
    _one_error_line(result.stderr, "--out")
    assert time.monotonic() - start < 20, "the report was computed before --out was checked"
    assert _tree(tmp_path) == before
    if out.is_dir():
        assert not [p for p in out.iterdir() if p.name.startswith(".")]


# ---------------------------------------------------------------------------------------------
# OutputEntries itself
# ---------------------------------------------------------------------------------------------


def test_a_failed_swap_puts_the_old_entries_back(tmp_path, monkeypatch):
    from acdrive import _output as output_module
    from acdrive._output import FILE, FOLDER, OutputEntries

    out = tmp_path / "out"
    _old_reports(out)
    old = _tree(out)
    entries = OutputEntries(out, {"icad.md": FILE, "icad": FOLDER})
    (entries.staging / "icad.md").write_text("new report")
    (entries.staging / "icad").mkdir()
    real_rename = os.rename
    calls = []

    def failing_rename(src, dst):
        calls.append((src, dst))
        if len(calls) == 4:  # two old entries moved aside, one new one in: the second fails
            raise OSError(28, "No space left on device")
        real_rename(src, dst)

    monkeypatch.setattr(output_module.os, "rename", failing_rename)
    with entries, pytest.raises(OSError):
        entries.publish()
    monkeypatch.setattr(output_module.os, "rename", real_rename)
    assert _tree(out) == old
    assert not [p for p in out.iterdir() if p.name.startswith(".")]


def test_entry_names_are_one_safe_component(tmp_path):
    from acdrive._output import FILE, OutputEntries
    from acdrive.errors import InputError

    for name in ("../x.md", ".hidden", "a/b", ""):
        with pytest.raises(InputError, match="paper"):
            OutputEntries(tmp_path / "out", {name: FILE}, name_field="paper")
    assert not (tmp_path / "out").exists()


def test_folders_created_for_out_are_removed_when_nothing_is_published(tmp_path):
    from acdrive._output import FILE, OutputEntries, OutputFolder

    (tmp_path / "keep").mkdir()
    for make in (
        lambda: OutputFolder(tmp_path / "new" / "deeper" / "out", "figs"),
        lambda: OutputEntries(tmp_path / "new" / "deeper" / "out", {"icad.md": FILE}),
    ):
        with make() as output:
            assert output.staging.parent == tmp_path / "new" / "deeper" / "out"
        assert sorted(p.name for p in tmp_path.iterdir()) == ["keep"]
