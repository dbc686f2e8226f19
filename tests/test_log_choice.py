"""What a run logs, chosen before the run: a long run keeps every k-th sample by default, the
thinned log is every k-th row of the full log bit for bit, the memory stated before the run is
the bytes of the log arrays, and summary.json states the choice."""

import dataclasses
import json

import numpy as np
import pytest

from acdrive.cli import main
from acdrive.drives import for_setup
from acdrive.drives.dfim._drive import DFIMDrive
from acdrive.scenarios._loader import builtin_text, load_scenario
from acdrive.sim import _log_plan
from acdrive.sim._log_plan import LogPlan, default_log_every, logged_rows

#: logged samples kept by default in these tests (the default's rule at a size a test can run)
ROWS = 1000


@pytest.fixture
def small_default(monkeypatch):
    monkeypatch.setattr(_log_plan, "DEFAULT_LOG_ROWS", ROWS)


def _ramp(tmp_path, duration: float = 1.0, extra: str = "") -> str:
    """bodson-ramp shortened to ``duration`` seconds, with ``extra`` lines in [simulation]."""
    text = builtin_text("bodson-ramp")
    text = text.replace("duration = 14.0", f"duration = {duration}\n{extra}", 1)
    path = tmp_path / "ramp.toml"
    path.write_text(text)
    return str(path)


def _bits(array: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(array).view(np.uint64)


def test_default_keeps_every_sample_up_to_the_limit_then_every_kth():
    assert default_log_every(1) == 1 and default_log_every(_log_plan.DEFAULT_LOG_ROWS) == 1
    for n in (_log_plan.DEFAULT_LOG_ROWS + 1, 499_999, 500_000, 500_001, 10**9):
        k = default_log_every(n)
        assert logged_rows(n, k) <= _log_plan.DEFAULT_LOG_ROWS < logged_rows(n, k - 1)


def test_a_long_run_logs_every_kth_sample_of_the_full_log_bit_for_bit(tmp_path, small_default):
    setup = load_scenario(_ramp(tmp_path))  # 5000 samples of 200 us, no log_every given
    steps = round(setup.duration / setup.sample_time)
    k = -(-steps // ROWS)
    assert k == 5 and setup.log_every == k
    thinned = DFIMDrive(setup).run()
    full = DFIMDrive(dataclasses.replace(setup, log_every=1)).run()
    assert full.t.size == steps and thinned.t.size == logged_rows(steps, k) == ROWS
    assert np.array_equal(_bits(thinned.data), _bits(full.data[::k]))
    assert np.array_equal(thinned.event_log, full.event_log[::k])
    assert np.array_equal(_bits(thinned.t), _bits(full.t[::k]))


@pytest.mark.parametrize("log_every", [1, 7])
def test_the_memory_stated_before_the_run_is_the_bytes_of_the_log(tmp_path, log_every):
    setup = dataclasses.replace(load_scenario(_ramp(tmp_path)), log_every=log_every)
    steps = round(setup.duration / setup.sample_time)
    plan = LogPlan(steps, log_every, *for_setup(setup).log_width(setup))
    result = DFIMDrive(setup).run()
    assert plan.rows == result.t.size
    assert plan.bytes == result.data.nbytes + result.event_log.nbytes


def _run(argv, capsys):
    assert main(argv) == 0
    return capsys.readouterr().out.splitlines()


@pytest.mark.parametrize(
    ("extra", "flag", "every", "chosen_by"),
    [
        ("", [], 5, "default"),
        ("log_every = 10", [], 10, "simulation.log_every"),
        ("log_every = 10", ["--log-every", "2"], 2, "--log-every"),
        ("", ["--log-every", "1"], 1, "--log-every"),
    ],
)
def test_the_run_states_its_log_before_it_and_in_the_summary(
    tmp_path, capsys, small_default, extra, flag, every, chosen_by
):
    scenario = _ramp(tmp_path, extra=extra)
    out = tmp_path / "out"
    lines = _run(["run", scenario, "--out", str(out), "--no-figures", *flag], capsys)
    setup = load_scenario(scenario)
    columns, events = for_setup(setup).log_width(setup)
    rows = logged_rows(5000, every)
    size = rows * (columns + events) * 8
    assert lines[0].startswith("running bodson-ramp: 1 s, 5,000 samples; logging every")
    assert f"({chosen_by}): {rows:,} samples x {columns + events} values" in lines[0]
    assert f"{size / 1e6:.3g} MB" in lines[0]
    log = json.loads((out / "bodson-ramp" / "summary.json").read_text())["log"]
    assert log["log_every"] == every and log["chosen_by"] == chosen_by
    assert log["logged_samples"] == rows and log["samples"] == 5000
    assert log["log_bytes"] == size
    import pandas as pd

    assert len(pd.read_parquet(out / "bodson-ramp" / "data.parquet")) == rows
