"""Sweeps (acdrive.sweep, `acdrive sweep`): variant generation, resume after SIGKILL without
loss or duplication, local and Dask backends giving the same table, one-line errors, refusal
of an oversized sweep, the report."""

import os
import signal
import socket
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from acdrive.cli import main
from acdrive.sweep import _variants as V
from acdrive.sweep import read_table, run_sweep
from acdrive.sweep._spec import build_spec, load_sweep

TINY = """
name = "tiny"
base = "bodson-ramp"
chunk = {chunk}

[fixed]
"simulation.duration" = {duration}

[[vary]]
field = "motor[0].load_torque"
values = {loads}

[[vary]]
field = "motor[0].controller.speed_bandwidth"
low = 100.0
high = 300.0
points = 2
"""


def _write(tmp_path, text, name="s.toml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def _tiny(tmp_path, chunk=2, duration=0.05, loads="[0.0, 0.05, 0.1]"):
    return _write(tmp_path, TINY.format(chunk=chunk, duration=duration, loads=loads))


def _cli(*args, timeout=300):
    env = {**os.environ, "NUMBA_CACHE_DIR": os.environ.get("NUMBA_CACHE_DIR", "")}
    env = {k: v for k, v in env.items() if v}
    return subprocess.run([sys.executable, "-m", "acdrive.cli", *args], capture_output=True,
                          text=True, timeout=timeout, env=env, check=False)  # fmt: skip


def test_grid_covers_every_combination_once_in_a_fixed_order(tmp_path):
    spec = load_sweep(str(_tiny(tmp_path)))
    assert V.count(spec) == 6
    combos = [tuple(V.variant(spec, i).values()) for i in range(6)]
    assert len(set(combos)) == 6
    assert combos[0] == (0.0, 100.0) and combos[1] == (0.0, 300.0) and combos[5] == (0.1, 300.0)


def test_random_variants_are_reproducible_and_within_their_bounds(tmp_path):
    text = """
    base = "bodson-ramp"
    [sampling]
    method = "random"
    samples = 200
    seed = 7
    [[vary]]
    field = "motor[0].params.R_r"
    relative = 0.5
    [[vary]]
    field = "motor[0].load_torque"
    low = -0.1
    high = 0.1
    """
    spec = load_sweep(str(_write(tmp_path, text)))
    first = [V.variant(spec, i) for i in range(200)]
    assert first == [V.variant(spec, i) for i in range(200)]  # same seed, same variants
    assert V.variant(spec, 150) == first[150]  # a variant does not depend on the others
    r_r = np.array([v["motor[0].params.R_r"] for v in first])
    assert r_r.min() >= 0.94 * 0.5 and r_r.max() <= 0.94 * 1.5  # Bodson's R_r +- 50 %
    assert r_r.max() - r_r.min() > 0.8 * 0.94  # spread over the range, not a constant
    other = build_spec({**_data(text), "sampling": {"method": "random", "samples": 200, "seed": 8}})
    assert V.variant(other, 0) != first[0]
    ids = [V.variant_id(i, v) for i, v in enumerate(first)]
    assert len(set(ids)) == 200


def _data(text):
    import tomllib

    return tomllib.loads(textwrap.dedent(text))


def _sweep_until_first_chunk(spec_path, out, text: bool = False):
    """Start ``acdrive sweep`` of ``spec_path`` into ``out`` in a process and return it, with the
    table folder, once the first chunk is written (or the process ended, or 240 s passed)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "acdrive.cli", "sweep", str(spec_path), "--out", str(out),
         "--quiet", "--no-report"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=text,
    )  # fmt: skip
    table_dir = out / "tiny" / "table"
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline and proc.poll() is None:
        if table_dir.is_dir() and any(table_dir.glob("chunk-*.parquet")):
            break
        time.sleep(0.005)
    return proc, table_dir


@pytest.mark.slow
def test_resume_after_sigkill_loses_and_duplicates_nothing(tmp_path):
    spec_path = _tiny(tmp_path, chunk=1, duration=1.5, loads="[0.0, 0.02, 0.04, 0.06, 0.08]")
    out = tmp_path / "out"
    proc, table_dir = _sweep_until_first_chunk(spec_path, out)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    done_at_kill = len(list(table_dir.glob("chunk-*.parquet")))
    assert 1 <= done_at_kill < 10, "the kill came too late to test a resume"
    # a torn write of the next chunk: only a temporary file can be left behind
    (table_dir / ".chunk-000009.parquet.99999.tmp").write_bytes(b"PAR1 torn")
    again = _cli("sweep", str(spec_path), "--out", str(out), "--quiet")
    assert again.returncode == 0, again.stderr
    resumed = read_table(out / "tiny")
    assert list(resumed["variant"]) == list(range(10))
    assert resumed["variant_id"].is_unique
    assert not list(table_dir.glob(".*.tmp"))
    # the resumed table equals an uninterrupted run's
    spec = load_sweep(str(spec_path))
    whole = read_table(run_sweep(spec, tmp_path / "whole", progress=False, report=False))
    pd.testing.assert_frame_equal(resumed, whole)


@pytest.mark.slow
def test_repeated_sigkills_at_random_moments_lose_and_duplicate_nothing(tmp_path):
    """SIGKILL at seeded random moments, run after run, then one run to the end: every variant is
    in the table exactly once, the table equals an uninterrupted run's, and no temporary file is
    left. The moments are drawn relative to the sweep's own progress (after 0, 1 or 2 more
    finished chunks, plus a random delay: during start-up, inside a chunk or its write), so the
    test kills as often on a fast idle machine as on a loaded one."""
    rng = np.random.default_rng(19)
    spec_path = _tiny(tmp_path, chunk=1, duration=10.0, loads="[0.0, 0.02, 0.04, 0.06, 0.08]")
    out = tmp_path / "out"
    table_dir = out / "tiny" / "table"
    argv = [sys.executable, "-m", "acdrive.cli", "sweep", str(spec_path), "--out", str(out),
            "--quiet"]  # fmt: skip

    def finished():
        return len(list(table_dir.glob("chunk-*.parquet"))) if table_dir.is_dir() else 0

    kills = 0
    for _ in range(12):
        more = int(rng.integers(0, 3))  # 0: during start-up (imports, loading the loop)
        target = finished() + more
        delay = float(rng.uniform(0.0, 0.3 if more == 0 else 0.03))
        proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 300
        while proc.poll() is None and finished() < target and time.monotonic() < deadline:
            time.sleep(0.002)
        time.sleep(delay)
        if proc.poll() is not None:
            assert proc.returncode == 0
            break  # it finished on its own
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        kills += 1
    assert kills >= 3, "too few kills to test repeated resumes"
    final = _cli("sweep", str(spec_path), "--out", str(out), "--quiet")
    assert final.returncode == 0, final.stderr
    table = read_table(out / "tiny")
    assert list(table["variant"]) == list(range(10))  # each variant once, in order
    assert table["variant_id"].is_unique
    assert not list((out / "tiny").rglob("*.tmp"))
    assert (out / "tiny" / "report.md").is_file()
    spec = load_sweep(str(spec_path))
    whole = read_table(run_sweep(spec, tmp_path / "whole", progress=False, report=False))
    pd.testing.assert_frame_equal(table, whole)


def test_local_and_dask_backends_give_the_same_table(tmp_path):
    distributed = pytest.importorskip("distributed")
    spec = load_sweep(str(_tiny(tmp_path)))
    local = read_table(run_sweep(spec, tmp_path / "local", progress=False, report=False))
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  host="127.0.0.1", protocol="tcp://", scheduler_port=0,
                                  dashboard_address=None) as cluster:  # fmt: skip
        folder = run_sweep(spec, tmp_path / "dask", scheduler=cluster.scheduler_address,
                           progress=False, report=False)  # fmt: skip
    remote = read_table(folder)
    assert len(local) == 6 and local["valid"].all()
    pd.testing.assert_frame_equal(local, remote)


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_unreachable_scheduler_is_one_line_after_a_bounded_time(tmp_path):
    spec_path = _tiny(tmp_path)
    start = time.monotonic()
    r = _cli("sweep", str(spec_path), "--out", str(tmp_path / "o"),
             "--scheduler", f"tcp://127.0.0.1:{_free_port()}", "--timeout", "2")  # fmt: skip
    assert time.monotonic() - start < 60
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("acdrive: error: --scheduler:"), r.stderr
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    ("text", "field"),
    [
        ("[[vary]]\nfield = 'motor[0].load_torque'\n", "vary[0].values"),
        ("[[vary]]\nfield = 'motor[0].load_torque'\nlow = 1.0\nhigh = 0.0\npoints = 2\n",
         "vary[0].high"),
        ("chunk = 0\n[[vary]]\nfield = 'motor[0].load_torque'\nvalues = [0.0]\n", "chunk"),
        ("[sampling]\nmethod = 'sobol'\n", "sampling.method"),
        ("[[vary]]\nfield = 'motor[0].load_torque'\nvalues = [0.0]\nbogus = 1\n",
         "vary[0].bogus"),
        ("[[vary]]\nfield = 'motor[0].controller.K_P'\nrelative = 0.5\n", "vary[0].relative"),
        ("name = '../x'\n[[vary]]\nfield = 'a'\nvalues = [1]\n", "name"),
        ("[[vary]]\nfield = 'motor[0].load_torque'\nvalues = [0.0]\n[metrics]\ndefault = 3\n",
         "metrics.default"),
        ("base = 'no-such-scenario'\n", "base"),
        # issue 19: a motor the one-motor base does not have (every row was invalid, exit 0)
        ("[[vary]]\nfield = 'motor[3].load_torque'\nvalues = [0.0, 0.1]\n", "vary[0].field"),
        # a value of the wrong type (exit 70 and a half-written folder)
        ("[[vary]]\nfield = 'motor[0].load_torque'\nvalues = ['heavy', 0.1]\n",
         "vary[0].values[0]"),
        ("[fixed]\n'motor[0].load_torque' = 'heavy'\n[[vary]]\nfield = 'simulation.duration'\n"
         + "values = [0.01]\n", "fixed.motor[0].load_torque"),
        ("[[vary]]\nfield = 'motor[0].controller.mode'\nvalues = ['current', 1.0]\n",
         "vary[0].values[1]"),
    ],
)  # fmt: skip
def test_malformed_sweep_file_is_one_line_naming_the_field(tmp_path, capsys, text, field):
    path = _write(tmp_path, text)
    assert main(["sweep", str(path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"acdrive: error: {field}:"), err
    assert not (tmp_path / "o").exists()


def test_a_billion_point_grid_is_refused_at_once(tmp_path, capsys):
    """The variants are counted as the product of the axes' lengths, never materialised: a grid
    of 1e9 points (which hung) is refused by the 1e6 limit in well under a second's work."""
    text = """
    base = "bodson-ramp"
    [[vary]]
    field = "motor[0].load_torque"
    low = 0.0
    high = 0.1
    points = 1000000000
    [[vary]]
    field = "motor[0].controller.speed_bandwidth"
    values = [100.0, 200.0]
    """
    path = _write(tmp_path, text)
    start = time.process_time()
    assert main(["sweep", str(path), "--out", str(tmp_path / "o")]) == 2
    assert time.process_time() - start < 5.0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("acdrive: error: vary[0].points:"), err
    assert "2e+09 variants" in err[0] and "1000000000 x 2" in err[0]
    assert not (tmp_path / "o").exists()


def test_oversized_sweep_is_refused_before_it_starts(tmp_path, capsys):
    text = """
    base = "bodson-ramp"
    [sampling]
    method = "random"
    samples = 100000000
    [[vary]]
    field = "motor[0].load_torque"
    low = 0.0
    high = 0.1
    """
    path = _write(tmp_path, text)
    assert main(["sweep", str(path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("acdrive: error: sampling.samples:"), err
    assert not (tmp_path / "o").exists()
    # the same sweep with traces of every sample is refused for its memory/disk even when small
    traced = text.replace("100000000", "50") + '[traces]\nsignals = ["shaft0.w"]\nevery = 1\n'
    traced = traced.replace("[sampling]", '[fixed]\n"simulation.duration" = 14.0\n[sampling]')
    traced += "[limits]\nmax_table_mb = 10\n"
    assert (
        main(["sweep", str(_write(tmp_path, traced, "t.toml")), "--out", str(tmp_path / "o")]) == 2
    )
    assert "limits.max_table_mb" in capsys.readouterr().err


@pytest.mark.slow
def test_report_lists_invalid_and_unstable_variants_and_the_table_keeps_the_reason(tmp_path):
    text = """
    name = "mixed"
    base = "bodson-ramp-ideal"
    [fixed]
    "simulation.duration" = 1.5
    "motor[0].speed_reference_rpm" = [[0.0, 0.0], [0.1, 0.0], [1.1, 900.0], [1.5, 900.0]]
    [[vary]]
    field = "motor[0].params.M"
    values = [9.7e-3, 20e-3]
    [[vary]]
    field = "motor[0].controller.speed_bandwidth"
    values = [100.0, 314.0]
    [traces]
    signals = ["shaft0.w"]
    every = 100
    """
    folder = run_sweep(load_sweep(str(_write(tmp_path, text))), tmp_path / "o", progress=False)
    table = read_table(folder)
    invalid = table[~table["valid"]]
    assert len(invalid) == 2 and invalid["reason"].str.startswith("motor[0].params.M:").all()
    ok = table[table["valid"]].set_index("vary.motor[0].controller.speed_bandwidth")
    # the finding of docs/stability.md: the ideal converter's limit cycle at the paper's 314 rad/s
    assert not ok.loc[314.0, "stable"] and ok.loc[100.0, "stable"]
    report = (folder / "report.md").read_text()
    assert "## Invalid variants" in report and "sigma" in report
    assert f"`{ok.loc[314.0, 'variant_id']}`" in report.split("## Unstable variants")[1]
    assert any(Path(folder, "figures").glob("*.png"))
    traces = pd.read_parquet(folder / "traces")
    assert set(traces["variant_id"]) == set(table.loc[table["valid"], "variant_id"])
    assert traces.groupby("variant_id").size().eq(75).all()  # 7,500 samples every 100


def test_builtin_bandwidth_sweep_is_valid_and_cross_checked():
    spec = load_sweep("dfim-bandwidth")
    assert spec.crosscheck["bandwidth_field"] == "motor[0].controller.speed_bandwidth"
    assert V.count(spec) == 32


# --- the command explains itself: --list, --out, how to resume --------------------------------


def test_list_names_every_builtin_sweep_with_its_size(capsys):
    from acdrive.sweep import builtin_sweeps

    assert main(["sweep", "--list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    names = builtin_sweeps()
    assert names and len(lines) == len(names)
    for name, line in zip(names, lines, strict=True):
        spec = load_sweep(name)
        assert line.split()[0] == name
        assert f"{spec.method} of {V.count(spec)} variants on {spec.base}:" in line
        assert spec.description.split()[0] in line  # its own description, first words


def test_list_takes_no_sweep_and_a_missing_sweep_is_one_line(capsys):
    assert main(["sweep", "--list", "dfim-bandwidth"]) == 2
    assert main(["sweep"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 2 and err[0].startswith("acdrive: error: --list:")
    assert err[1].startswith("acdrive: error: sweep:") and "--list" in err[1]


def test_out_is_the_folder_the_help_says(tmp_path, capsys):
    with pytest.raises(SystemExit):
        main(["sweep", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert "DIR/<sweep name>/" in help_text and "./acdrive-sweeps" in help_text
    out = tmp_path / "o"
    assert main(["sweep", str(_tiny(tmp_path, loads="[0.0]")), "--out", str(out), "--quiet"]) == 0
    assert capsys.readouterr().out.strip() == str(out / "tiny")
    assert [p.name for p in out.iterdir()] == ["tiny"]  # DIR/<sweep name>/, nothing beside it
    assert len(read_table(out / "tiny")) == 2 and (out / "tiny" / "report.md").is_file()


def _resume_line(err: str) -> str:
    lines = [line for line in err.splitlines() if "resume with: " in line]
    assert len(lines) == 1, err
    return lines[0].split("resume with: ", 1)[1].rstrip(")")


def test_an_interrupted_sweep_prints_the_command_that_resumes_it(tmp_path, capsys, monkeypatch):
    """KeyboardInterrupt after the second chunk (progress-based): exit 130, one line with the
    command; the half-done folder says the same from Python; that very command finishes it."""
    import shlex

    from acdrive.errors import Notice
    from acdrive.sweep import _engine

    spec_path = _tiny(tmp_path, chunk=1)  # 6 variants, one per chunk
    out = tmp_path / "o"
    real, calls = _engine.run_chunk, []

    def interrupted_after_two(payload, c):
        calls.append(c)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(payload, c)

    monkeypatch.setattr(_engine, "run_chunk", interrupted_after_two)
    monkeypatch.chdir(tmp_path)
    argv = ["sweep", "s.toml", "--out", "o", "--quiet", "--no-report"]
    assert main(argv) == 130
    err = capsys.readouterr().err
    assert "acdrive: sweep tiny stopped (2 of 6 variants done; resume with:" in err
    command = _resume_line(err)
    assert command == shlex.join(
        ["acdrive", "sweep", str(spec_path), "--out", str(out), "--no-report", "--quiet"]
    )
    with pytest.warns(Notice, match=f"2 of 6 variants done; resume with: {command}"):
        assert len(read_table(out / "tiny")) == 2
    (tmp_path / "other").mkdir()
    other = _tiny(tmp_path / "other", loads="[0.5]")  # another sweep of the same name and --out
    assert main(["sweep", str(other), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert "holds a different sweep" in err and err.endswith(
        f"(that sweep is unfinished: 2 of 6 variants done; resume with: {command})"
    )
    monkeypatch.setattr(_engine, "run_chunk", real)
    monkeypatch.chdir(Path("/"))  # the command holds absolute paths: it works from anywhere
    assert main(shlex.split(command)[1:]) == 0
    assert "resuming sweep tiny: 2 of 6 variants were done" in capsys.readouterr().err
    table = read_table(out / "tiny")
    assert list(table["variant"]) == list(range(6)) and table["variant_id"].is_unique


@pytest.mark.slow
def test_sigterm_prints_the_exact_command_that_resumes(tmp_path):
    """SIGTERM after the first finished chunk (progress-based, as the SIGKILL test): exit 143,
    one line naming the command, and running that command completes the same table."""
    import shlex

    spec_path = _tiny(tmp_path, chunk=1, duration=1.5, loads="[0.0, 0.02, 0.04, 0.06, 0.08]")
    out = tmp_path / "out"
    proc, table_dir = _sweep_until_first_chunk(spec_path, out, text=True)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143, err
    assert err.splitlines()[-1] == "acdrive: terminated (SIGTERM)"
    command = _resume_line(err)
    assert shlex.split(command)[:5] == ["acdrive", "sweep", str(spec_path), "--out", str(out)]
    done = len(list(table_dir.glob("chunk-*.parquet")))
    assert 1 <= done < 10, "the signal came too late to test a resume"
    again = _cli(*shlex.split(command)[1:])
    assert again.returncode == 0, again.stderr
    table = read_table(out / "tiny")
    assert list(table["variant"]) == list(range(10)) and table["variant_id"].is_unique
