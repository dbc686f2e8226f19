"""A short cage-IM speed run in the developer's loop: the drive's default batch metrics
(``drives.cage_im._reducers``) equal the same figures of the variant's single run, and the lines
``acdrive run`` prints for it (``drives.cage_im._headline``) carry the numbers of the
summary.json it wrote. 60 ms of ``im-foc-speed``: the drive starts magnetised at rest, the speed
reference steps to 150 rad/s at 50 ms."""

from __future__ import annotations

import json

import numpy as np
import pytest

from acdrive.batch import apply_overrides, build_variant_setup, simulate_batch
from acdrive.cli import main
from acdrive.scenarios import read_scenario
from acdrive.scenarios._files import builtin_text

SCENARIO = "im-foc-speed"
SHORT = {"simulation.duration": 0.06}
#: the speed step's time [s], the speed controller's torque limit [N m] and J [kg m^2]
STEP, TAU_MAX, J = 0.05, 0.83, 0.000711


def test_cage_im_default_batch_metrics_are_the_single_runs():
    from acdrive.drives.cage_im._outcome import run_im_scenario

    row = simulate_batch(SCENARIO, [SHORT]).rows[0]
    assert row["status"] == "ok"
    setup = build_variant_setup(apply_overrides(read_scenario(SCENARIO), SHORT))
    result = run_im_scenario(setup).main
    i_s, tau, w = (result.signal(n) for n in ("i_s", "tau_e", "w"))
    assert row["peak_stator_current_a"] == pytest.approx(np.max(np.abs(i_s)), rel=1e-12)
    assert row["peak_torque_nm"] == pytest.approx(np.max(np.abs(tau)), rel=1e-12)
    assert row["final_speed_rad_s"] == pytest.approx(w[-1], rel=1e-12)
    # physics: the shaft stays at rest until the step, then accelerates, no faster than the
    # torque limit allows (friction only slows it): 0 < w_end <= TAU_MAX / J (t_end - STEP)
    t = result.t
    assert np.all(w[t < STEP] == 0.0)
    assert 0.0 < w[-1] <= TAU_MAX / J * (t[-1] - STEP)


def test_acdrive_run_of_a_cage_im_scenario_prints_its_summary(tmp_path, capsys):
    text = builtin_text(SCENARIO).replace("duration = 1.2", "duration = 0.06")
    assert "duration = 0.06" in text
    path = tmp_path / "im-short.toml"
    path.write_text(text)
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--no-figures"]) == 0
    out = capsys.readouterr().out
    summary = json.loads(next((tmp_path / "out").rglob("summary.json")).read_text())
    (run,) = summary["runs"].values()
    assert f"{run['current_rms_error_a']:.3g} A" in out
    assert f"{run['speed_final_rad_s']:.2f} rad/s for" in out
    events = ", ".join(f"{k} {v}" for k, v in run["events"].items() if v) or "none"
    assert "events (samples)" in out and events in out
