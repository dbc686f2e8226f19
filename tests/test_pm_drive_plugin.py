"""The PM drive through the registry: ``acdrive run`` of a built-in PM scenario (found in the
drive's own folder), and a batch of its variants, checked against the drive's steady state:
the speed settles on its reference and the machine's torque carries the load plus the viscous
friction, tau_e = tau_L + B w."""

from __future__ import annotations

import json

import numpy as np
import pytest

from acdrive.batch import Reducer, apply_overrides, build_variant_setup, simulate_batch
from acdrive.cli import main
from acdrive.drives import for_setup, kinds
from acdrive.scenarios import builtin_names, load_scenario
from acdrive.scenarios._files import builtin_text

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
    announced, headline = capsys.readouterr().out.splitlines()[:2]
    assert announced.startswith(f"running {SCENARIO}: ")
    assert headline.startswith(f"{SCENARIO}: final speed")


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


def test_a_pm_batch_gives_each_variant_the_metrics_of_its_single_run():
    """The PM drive's default batch metrics (``drives.pm._reducers``), computed inside the
    compiled loop, equal the same figures computed from each variant's single run: the
    summary's own figures where the names are the summary's, else from its logged signals (the
    last speed, samples above the current limit by more than its tolerance, the largest voltage
    command)."""
    from acdrive._frames import K_PEAK
    from acdrive._reducer_parts import OVER_LIMIT_TOLERANCE
    from acdrive.drives.pm import run, signals
    from acdrive.scenarios import read_scenario

    loads = [0.02, 0.04]
    variants = [
        {"machine.load_torque_profile": [[0.0, 0.0], [0.05, 0.0], [0.05, tau], [1.0, tau]],
         "simulation.duration": 0.08}
        for tau in loads
    ]  # fmt: skip
    batch = simulate_batch(SCENARIO, variants)
    data = read_scenario(SCENARIO)
    for overrides, row in zip(variants, batch.rows, strict=True):
        assert row["status"] == "ok"
        setup = build_variant_setup(apply_overrides(data, overrides))
        result, summary = run(setup)
        s = signals(setup, result)
        for name in ("speed_error_rms_rad_s", "speed_error_max_rad_s", "current_peak_a",
                     "torque_peak_n_m"):  # fmt: skip
            assert row[name] == pytest.approx(summary[name], rel=1e-12, abs=1e-12), name
        assert row["final_speed_rad_s"] == pytest.approx(s["w"][-1], rel=1e-12)
        beyond = setup.i_max * (1 + OVER_LIMIT_TOLERANCE)
        over = int(np.count_nonzero(np.abs(s["i_s"]) > beyond))
        assert row["current_over_limit"] == over
        peak_v = float(np.max(np.abs(s["v_dq_wanted"])))
        assert row["voltage_command_peak_v"] == pytest.approx(peak_v, rel=1e-12)
        assert summary["current_peak_a"] == pytest.approx(np.max(np.abs(s["i_s"])) / K_PEAK)
    # the heavier load needs more torque at the end of the run: the rows are each variant's own
    assert batch.rows[1]["torque_peak_n_m"] >= batch.rows[0]["torque_peak_n_m"]
    assert batch.units["current_peak_a"] == "A"


def test_a_current_loop_too_fast_for_the_sample_time_is_refused(tmp_path, capsys):
    """alpha T_c > 1 (``drives.pm._period``): refused on load with the scenario's field and the
    rule, exit 2 before any simulation; the built-in's alpha T_s = 0.126 passes."""
    from acdrive.drives.pm._period import CURRENT_BANDWIDTH_T_C_MAX, command_period
    from acdrive.errors import InputError
    from acdrive.scenarios import read_scenario

    setup = load_scenario(SCENARIO)
    assert setup.current_bandwidth * command_period(setup) < CURRENT_BANDWIDTH_T_C_MAX
    text = builtin_text(SCENARIO).replace(
        "current_bandwidth_rad_s = 2513.2741228718346", "current_bandwidth_rad_s = 30000.0"
    )
    assert "30000.0" in text
    path = tmp_path / "fast.toml"
    path.write_text(text)
    with pytest.raises(InputError) as refused:
        load_scenario(str(path))
    assert refused.value.field == "control.current_bandwidth_rad_s"
    assert "30000 rad/s x 5e-05 s = 1.5" in refused.value.rule
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--no-figures"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "control.current_bandwidth_rad_s" in err[0]
    assert not (tmp_path / "out").exists()
    # the limit itself: 1 / T_s is accepted, just above it is not
    data = read_scenario(SCENARIO)
    ok = apply(data, "control.current_bandwidth_rad_s", 1.0 / 5e-5)
    assert ok.current_bandwidth == pytest.approx(2e4)
    with pytest.raises(InputError):
        apply(data, "control.current_bandwidth_rad_s", 1.0001 / 5e-5)


def test_estimates_that_make_the_sampled_current_loop_unstable_are_refused():
    """alpha T_s = 0.8 passes the bandwidth rule, but a controller whose inductance estimates
    are 3 times the machine's has the loop gain of alpha T_s = 2.4: its sampled pole about
    1 - 2.4 lies outside the unit circle (``drives._period.current_loop_radius``)."""
    import dataclasses

    from acdrive.drives._period import current_loop_radius
    from acdrive.drives.pm._period import axis_radii
    from acdrive.errors import InputError

    setup = load_scenario(SCENARIO)
    alpha = 0.8 / setup.sample_time
    m = setup.machine
    good = dataclasses.replace(setup, current_bandwidth=alpha)
    assert max(axis_radii(good).values()) < 1.0
    wrong = dataclasses.replace(m, L_d=3 * m.L_d, L_q=3 * m.L_q)
    with pytest.raises(InputError, match="sampled d-axis current loop") as refused:
        dataclasses.replace(setup, current_bandwidth=alpha, estimates=wrong)
    assert refused.value.field == "current_bandwidth"
    # the radius is the sampled pole: without resistance and integral action, |1 - K_P T / L|
    assert current_loop_radius(m.L_d, 0.0, 2.4 * m.L_d / setup.sample_time, 0.0,
                               setup.sample_time) == pytest.approx(1.4)  # fmt: skip
    # a command held over 2 samples acts like one sample of twice the length
    two = current_loop_radius(
        m.L_d, 0.0, 0.3 * m.L_d / setup.sample_time, 0.0, setup.sample_time, 2
    )
    assert two == pytest.approx(abs(1 - 0.6))


def apply(data: dict, field: str, value):
    """The setup of the parsed scenario ``data`` with one field set (the loader's checks run)."""
    return build_variant_setup(apply_overrides(data, {field: value}))
