"""Every drive kind's headline (``acdrive run``) and ``summary.json`` carry the step-response
metrics of the steps its scenario declares (``sim._step_response``), a batch row the same
figures as the single run's summary, and a sweep report judges an over-limit count against its
stated tolerance, apart from the limiters that acted."""

import json
import math
import textwrap
import tomllib

import numpy as np
import pandas as pd
import pytest

from acdrive.cli import main
from acdrive.sim._step_response import BAND_FRACTION, flat


def _run(name, tmp_path, capsys) -> tuple[dict, str]:
    """(summary.json, printed headline) of ``acdrive run NAME --no-figures``."""
    assert main(["run", name, "--out", str(tmp_path), "--no-figures"]) == 0
    summary = json.loads((tmp_path / name / "summary.json").read_text())
    return summary, capsys.readouterr().out


def _printed(events, out, unit, label=""):
    """Each event's row (its name after ``label``) is printed with its figures from the
    summary."""
    shown = unit.replace("_", "/")
    for e in events:
        name = f"  {label}{e['what']} at {e['start_s']:g} s"
        row = next(line for line in out.splitlines() if line.startswith(name))
        if e["kind"] == "reference change":
            assert f"rise {e['rise_time_s']:.4g} s" in row
            assert f"overshoot {e['overshoot_pct']:.2f} %" in row
            assert f"+-{e[f'settling_band_{unit}']:.3g} {shown} (2 % of the step)" in row
            assert f"after {e['settling_time_s']:.4g} s" in row
        else:
            assert f"dip {e[f'dip_{unit}']:.3g} {shown}" in row
            assert f"after {e['recovery_time_s']:.4g} s" in row


def _sane_reference_change(e, r0, r1, start, unit):
    """A settled step of a stable loop: its figures in their order, the band 2 % of the step."""
    assert (e["kind"], e["start_s"]) == ("reference change", start)
    assert e[f"step_{unit}"] == pytest.approx(r1 - r0)
    assert e[f"settling_band_{unit}"] == pytest.approx(BAND_FRACTION * abs(r1 - r0))
    assert 0.0 < e["rise_time_s"] < e["settling_time_s"] < e["judged_until_s"] - start
    assert 0.0 <= e["overshoot_pct"] < 100.0
    assert abs(e[f"steady_state_error_{unit}"]) < e[f"settling_band_{unit}"]


def test_pm_headline_summary_and_batch_row_carry_the_step_metrics(tmp_path, capsys):
    """pm-ipmsm-speed: a speed step 0 -> 750 rpm at 0.01 s and a 14 N m load step at 0.3 s (its
    profiles); the summary's figures are printed and a batch row holds them by name."""
    from acdrive.batch import simulate_batch

    summary, out = _run("pm-ipmsm-speed", tmp_path, capsys)
    step = summary["step_response"]
    assert step["band_fraction"] == BAND_FRACTION and "10-90 %" in step["rule"]
    ref, load = step["events"]
    _sane_reference_change(ref, 0.0, 750 * math.pi / 30, 0.01, "rad_s")
    assert (load["kind"], load["start_s"]) == ("load step", 0.3)
    assert load["dip_rad_s"] > load["recovery_band_rad_s"]  # the load is felt
    assert 0.3 < load["dip_at_s"] < 0.3 + load["recovery_time_s"]
    _printed(step["events"], out, "rad_s")
    row = simulate_batch("pm-ipmsm-speed", [{}]).rows[0]
    for key, value in flat(step, "rad_s").items():
        assert row[key] == pytest.approx(value, rel=1e-12, abs=1e-12), key


def test_dfim_headline_and_summary_carry_each_modes_step_metrics(tmp_path, capsys):
    """bodson-step compares voltage and current command: each mode's speed step 0 -> 1500 rpm
    at 0.1 s (its profile) is judged, in rpm, and printed."""
    summary, out = _run("bodson-step", tmp_path, capsys)
    for suffix, mode in (("vc", "voltage"), ("cc", "current")):
        (e,) = summary[f"step_response_{suffix}"]["events"]
        _sane_reference_change(e, 0.0, 1500.0, 0.1, "rpm")
        _printed([e], out, "rpm", f"{mode}: ")


@pytest.mark.slow
def test_cage_im_headline_and_summary_carry_the_step_and_brake_metrics(tmp_path, capsys):
    """im-foc-speed: the speed step 0 -> 150 rad/s at 0.05 s and the eddy-current brake applied
    at 0.6 s (a load step: its coefficient's profile), each judged and printed."""
    summary, out = _run("im-foc-speed", tmp_path, capsys)
    (run,) = summary["runs"].values()
    ref, brake = run["step_response"]["events"]
    _sane_reference_change(ref, 0.0, 150.0, 0.05, "rad_s")
    assert (brake["kind"], brake["start_s"]) == ("load step", 0.6)
    assert "brake coefficient" in brake["what"]
    assert brake["dip_rad_s"] > brake["recovery_band_rad_s"] == pytest.approx(3.0)
    _printed(run["step_response"]["events"], out, "rad_s")


SWEEP = """
name = "limits"
base = "pm-ipmsm-speed"
[[vary]]
field = "control.speed_bandwidth_rad_s"
values = [40.0, 50.0]
"""


def test_a_sweep_report_flags_only_samples_beyond_the_stated_tolerance(tmp_path):
    """A count of samples beyond the limit's tolerance flags its variant; a limiter's event
    (the references at their current limit) is stated apart, not as an excursion."""
    from acdrive._output import write_marker
    from acdrive._reducer_parts import OVER_LIMIT_TOLERANCE
    from acdrive.sweep._report import write_report
    from acdrive.sweep._spec import build_spec

    spec = build_spec(tomllib.loads(textwrap.dedent(SWEEP)))
    table = pd.DataFrame({
        "variant": [0, 1], "variant_id": ["v0", "v1"], "valid": [True, True],
        "status": ["ok", "ok"], "reason": ["", ""],
        "vary.control.speed_bandwidth_rad_s": [40.0, 50.0],
        "current_over_limit": [0.0, 3.0], "events.torque_reference.current_limit": [120, 80],
    })  # fmt: skip
    write_marker(tmp_path)
    report = write_report(spec, tmp_path, table).read_text()
    beyond = report.split("## Variants beyond a limit\n")[1].split("\n## ")[0]
    tolerance = f"samples more than {100 * OVER_LIMIT_TOLERANCE:g} % above the limit"
    assert f"1 of 2 (an `*_over_limit` count > 0: {tolerance}):" in beyond
    assert "- `v1`" in beyond and "- `v0`" not in beyond
    assert "A limiter acted" in beyond and "in 2 of 2: `torque_reference.current_limit`" in beyond


def test_a_current_riding_on_its_limit_is_no_excursion():
    """The PM batch's ``current_over_limit`` counts the samples of |i_s| above the limit by more
    than OVER_LIMIT_TOLERANCE: none where a load step drives the current onto its limit, whose
    logged peak passes it by less than the tolerance on some samples (the loop's rounding)."""
    from acdrive._reducer_parts import OVER_LIMIT_TOLERANCE
    from acdrive.batch import apply_overrides, build_variant_setup, simulate_batch
    from acdrive.drives.pm import run, signals
    from acdrive.scenarios import read_scenario

    tau = 0.02
    overrides = {"machine.load_torque_profile": [[0.0, 0.0], [0.05, 0.0], [0.05, tau], [1.0, tau]],
                 "simulation.duration": 0.08}  # fmt: skip
    setup = build_variant_setup(apply_overrides(read_scenario("pm-bly171d-speed"), overrides))
    result, _ = run(setup)
    ratio = np.abs(signals(setup, result)["i_s"]) / setup.i_max
    assert 1.0 < ratio.max() < 1.0 + OVER_LIMIT_TOLERANCE
    row = simulate_batch("pm-bly171d-speed", [overrides]).rows[0]
    assert row["current_over_limit"] == 0
    assert np.isnan(row["current_over_limit_first_time"])
