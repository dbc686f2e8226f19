"""The PM drive through the registry: ``acdrive run`` of a built-in PM scenario (found in the
drive's own folder), and a batch of its variants, checked against the drive's steady state:
the speed settles on its reference and the machine's torque carries the load plus the viscous
friction, tau_e = tau_L + B w."""

from __future__ import annotations

import json

import pytest

from acdrive.batch import Reducer, simulate_batch
from acdrive.cli import main
from acdrive.drives import for_setup, kinds
from acdrive.scenarios import builtin_names, load_scenario

SCENARIO = "pm-bly171d-speed"
#: its reference speed [rad/s], load [N m] after 0.1 s and viscous friction [N m s/rad]
W_REF, LOAD, B = 300.0, 0.04, 1.1604e-5


def test_the_pm_drive_is_registered_and_its_scenarios_are_built_in():
    assert "pm" in kinds()
    names = builtin_names()
    for name in ("pm-bly171d-speed", "pm-ipmsm-speed", "pm-ipmsm-field-weakening"):
        assert name in names
    assert for_setup(load_scenario(SCENARIO)).kind == "pm"


def test_acdrive_run_runs_a_pm_scenario(tmp_path, capsys):
    assert main(["run", SCENARIO, "--out", str(tmp_path), "--no-figures"]) == 0
    folder = tmp_path / SCENARIO
    summary = json.loads((folder / "summary.json").read_text())
    assert (folder / "data.parquet").is_file() and (folder / "columns.md").is_file()
    assert summary["speed_final_rad_s"] == pytest.approx(W_REF, abs=0.05)
    assert summary["torque_final_n_m"] == pytest.approx(LOAD + B * W_REF, rel=0.01)
    out = capsys.readouterr().out
    assert out.startswith(f"{SCENARIO}: final speed")


def test_a_batch_of_pm_variants_carries_each_load():
    loads = [0.02, 0.04]
    variants = [
        {"machine.load_torque_profile": [[0.0, 0.0], [0.1, 0.0], [0.1, tau], [1.0, tau]]}
        for tau in loads
    ]
    reducers = [
        Reducer("torque_final_n_m", "mean", "machine.tau_e", start=0.18),
        Reducer("speed_final_rad_s", "mean", "shaft.w", start=0.18),
    ]
    rows = simulate_batch(SCENARIO, variants, reducers=reducers).rows
    for tau, row in zip(loads, rows, strict=True):
        assert row["status"] == "ok"
        assert row["speed_final_rad_s"] == pytest.approx(W_REF, abs=0.05)
        assert row["torque_final_n_m"] == pytest.approx(tau + B * W_REF, rel=0.01)
