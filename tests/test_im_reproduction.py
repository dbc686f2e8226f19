"""The IM time-domain reproduction report (``acdrive._report.im_reproduction``): its verdicts are
computed from its numbers against its tolerances, and it prints the numbers it returns."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from acdrive._report import im_reproduction as rep
from acdrive._report.markdown import fmt
from acdrive.analysis._coupling import measure_coupling


@pytest.fixture(scope="module")
def inputs():
    """The built-in scenarios as run by the report, and short coupling measurements (two
    frequencies each, a shorter settling time)."""
    outcomes = rep.run_experiments()
    couplings = {}
    for key, setup in rep.coupling_setups().items():
        short = dataclasses.replace(setup, frequencies=(375.0, 1000.0), settle=0.3, window=0.05)
        couplings[key] = measure_coupling(short)
    return outcomes, couplings


@pytest.fixture(scope="module")
def report(inputs, tmp_path_factory):
    outcomes, couplings = inputs
    fig_dir = tmp_path_factory.mktemp("rep") / rep.STEM
    text, numbers, verdicts = rep.build_report(fig_dir, outcomes, couplings)
    return text, numbers, verdicts, fig_dir


def test_report_prints_its_numbers_and_verdicts(report):
    text, n, v, fig_dir = report
    for key in (
        "fig11_rms_error_icad_a",
        "fig11_rms_error_pi_a",
        "fig16_ramp_error_icad_rad_s",
        "fig16_ramp_error_pi_rad_s",
        "fig16_slope_icad_rad_s2",
        "fig13_load_dip_rad_s",
        "fig14_load_dip_rad",
    ):
        assert fmt(n[key]) in text, key
    assert fmt(n["coupling_im_peak_db"], 4) in text
    for row in n["coupling_pmsg_rows"]:
        assert fmt(row["measured_db"], 4) in text
    for verdict in v.values():
        assert str(verdict).replace("|", "/") in text
    results = [x for x in v.values() if x.kind == "result"]
    inputs = [x for x in v.values() if x.kind == "input"]
    assert len(results) + len(inputs) == len(v)
    assert f"{sum(map(bool, results))} of {len(results)} result checks hold" in text
    assert f"{sum(map(bool, inputs))} of {len(inputs)} inputs taken from the paper" in text
    # every linked figure exists
    for line in text.splitlines():
        if line.startswith("![") and f"({rep.STEM}/" in line:
            name = line.split(f"({rep.STEM}/")[1].rstrip(")")
            assert (fig_dir / name).is_file(), name
    assert (fig_dir / "coupling.png").is_file()


def test_a_tolerance_change_flips_a_verdict(report):
    _, n, v, _ = report
    assert v["fig11_tracking"].holds
    tight = {**rep.TOLERANCES, "tracking_rel": 0.5 * n["fig11_rms_error_icad_rel"]}
    flipped = rep.compute_verdicts(n, tight)
    assert not flipped["fig11_tracking"].holds
    assert "not low" in str(flipped["fig11_tracking"])
    assert v["coupling_im"].holds
    tight = {**rep.TOLERANCES, "coupling_rel": 0.5 * n["coupling_im_max_rel_error"]}
    assert not rep.compute_verdicts(n, tight)["coupling_im"].holds
    tight = {**rep.TOLERANCES, "better_ratio": 1.5 * n["fig16_ramp_error_pi_rad_s"]
             / n["fig16_ramp_error_icad_rad_s"]}  # fmt: skip
    assert not rep.compute_verdicts(n, tight)["fig16_closer"].holds


def test_a_number_change_flips_a_verdict(report):
    _, n, v, _ = report
    assert v["fig13_final"].holds and v["fig18_overshoot"].holds
    changed = dict(n)
    changed["fig13_speed_final_rad_s"] = 140.0
    changed["step_overshoot_high_ki_pi"] = 0.5 * n["step_overshoot_icad"]
    w = rep.compute_verdicts(changed)
    assert not w["fig13_final"].holds and "differs" in str(w["fig13_final"])
    assert not w["fig18_overshoot"].holds and "differs" in str(w["fig18_overshoot"])


def test_numbers_come_from_the_runs(inputs, report):
    outcomes, couplings = inputs
    _, n, _, _ = report
    s = outcomes["fig16"].summary
    assert n["fig16_ramp_error_pi_rad_s"] == s["speed_ramp_error_pi"]
    assert n["fig11_rms_error_icad_a"] == outcomes["fig11"].summary["current_rms_error_icad_a"]
    assert n["coupling_im_peak_db"] == pytest.approx(float(max(couplings["im"].db())))
    assert n["pi_kp"] == 360.0 and n["pi_ki"] == 9000.0


def test_reproduce_im_writes_the_named_report(monkeypatch, tmp_path, capsys):
    from acdrive.cli import main

    def fake(out_dir):
        (Path(out_dir) / f"{rep.STEM}.md").write_text("report\n")
        (Path(out_dir) / rep.STEM).mkdir()
        return Path(out_dir) / f"{rep.STEM}.md"

    monkeypatch.setattr(rep, "write_report", fake)
    assert main(["reproduce", "im", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "im-current-control.md").read_text() == "report\n"
    assert (tmp_path / "im-current-control").is_dir()
    assert "im-current-control.md" in capsys.readouterr().out


def test_inputs_taken_from_the_paper_are_input_checks(report):
    _, _, v, _ = report
    for key in ("dc_link", "pwm", "sampling", "pi_kp", "controller_20", "fig16_reference",
                "fig23_factor_R_s", "fig14_load_time"):  # fmt: skip
        assert v[key].kind == "input", key
    for key in ("fig11_tracking", "fig13_modulation", "fig16_pi_steady", "coupling_im"):
        assert v[key].kind == "result", key


def test_fig16_steady_state_is_judged_on_settled_speeds(inputs, report):
    """The run is long enough: both speeds settle over the summary's steady window (their drift
    is recomputed here from the logged speed), and the verdict reads the summary's errors."""
    outcomes, _ = inputs
    _, n, v, _ = report
    tol = rep.TOLERANCES["settled_speed_abs"]
    for label, result in outcomes["fig16"].results.items():
        t, w = result.t, result.signal("w")
        window = t >= t[-1] - max(0.1 * (t[-1] - t[0]), 0.05)  # the summary's: last 10 %
        slope = np.polyfit(t[window], w[window], 1)[0]
        drift = slope * (t[window][-1] - t[window][0])
        assert drift == pytest.approx(n[f"fig16_speed_drift_{label}_rad_s"], rel=1e-6, abs=1e-9)
        assert abs(drift) <= tol, label
        run = outcomes["fig16"].summary["runs"][label]
        assert n[f"fig16_steady_error_{label}_rad_s"] == run["speed_steady_error_rad_s"]
        assert np.mean(w[window]) == pytest.approx(run["speed_final_rad_s"], rel=1e-12)
    assert not str(v["fig16_pi_steady"]).startswith("not settled")
    assert fmt(n["fig16_steady_error_pi_rad_s"], 3) in str(v["fig16_pi_steady"])
    # the same numbers with the PI speed still drifting: "not settled", never "holds"
    drifting = {**n, "fig16_speed_drift_pi_rad_s": 10 * tol}
    w = rep.compute_verdicts(drifting)["fig16_pi_steady"]
    assert not w.holds and str(w).startswith("not settled")
