"""The cage-IM current controller designed from machine parameters (``controller = "imc-pi"``,
``drives.cage_im._current_design``) and its re-design on estimates (issue 23, item 4); the
built-in published controllers (Amezquita-Brooks et al.'s (20)) stay fixed; and ``controller =
"icad-proposed"``, ``analysis.propose_controller`` on the design machine's ICAD plant."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from acdrive.analysis import PAPER_SPECS, propose_controller
from acdrive.cli import main
from acdrive.drives.cage_im._current_design import specifications
from acdrive.errors import InputError
from acdrive.robustness import design_comparison
from acdrive.scenarios._files import read_scenario
from acdrive.scenarios._loader import build_setup

ESTIMATES = {"R_s": 17.0, "R_r": 20.0, "L_s": 1.40, "L_r": 1.46, "L_m": 1.38}


def _speed(controller: dict) -> dict:
    d = read_scenario("im-foc-speed")
    d["simulation"]["duration"] = 0.2
    d["current_control"] = controller
    return d


def _transient(p: dict) -> tuple[float, float]:
    """sigma L_s and R_s + R_r (L_m / L_r)^2, from the parameters by hand."""
    sigma = 1.0 - p["L_m"] ** 2 / (p["L_s"] * p["L_r"])
    return sigma * p["L_s"], p["R_s"] + p["R_r"] * (p["L_m"] / p["L_r"]) ** 2


def test_the_designed_pi_is_the_internal_model_of_the_transient_impedance():
    d = _speed({"controller": "imc-pi", "bandwidth_rad_s": 3000.0})
    m = build_setup(d).machine
    K_P, K_I = build_setup(d).current_control.pi_gains
    sl, r = _transient({k: getattr(m, k) for k in ("R_s", "R_r", "L_s", "L_r", "L_m")})
    assert K_P == pytest.approx(3000.0 * sl, rel=1e-12)
    assert K_I == pytest.approx(3000.0 * r, rel=1e-12)
    # the PI zero cancels the transient pole: K_I / K_P = (R_s + R_R) / (sigma L_s)
    assert K_I / K_P == pytest.approx(r / sl, rel=1e-12)


def test_estimates_re_derive_the_designed_pi_and_leave_20_fixed():
    c = design_comparison(_speed({"controller": "imc-pi", "bandwidth_rad_s": 3000.0}), ESTIMATES)
    t, e = c.rows["truth"]["design"], c.rows["estimates"]["design"]
    sl, r = _transient(ESTIMATES)
    assert e["current_K_P"] == pytest.approx(3000.0 * sl, rel=1e-12)
    assert e["current_K_I"] == pytest.approx(3000.0 * r, rel=1e-12)
    assert e["current_K_P"] != t["current_K_P"]
    assert e["current_controller_design"].startswith("re-derived")
    fixed = design_comparison(_speed({"controller": "paper-20"}), ESTIMATES)
    t, e = fixed.rows["truth"]["design"], fixed.rows["estimates"]["design"]
    assert e["current_controller"] == t["current_controller"] == "paper-20"
    assert e["current_controller_design"].startswith("fixed")
    assert "current_K_P" not in e
    # the same controller on the same plant: the sampled current loop is the same
    assert e["current_loop_spectral_radius"] == t["current_loop_spectral_radius"]


def test_a_design_on_the_truth_equals_the_existing_design():
    d = _speed({"controller": "imc-pi", "bandwidth_rad_s": 3000.0})
    m = build_setup(d).machine
    c = design_comparison(d, {k: getattr(m, k) for k in ("R_s", "R_r", "L_s", "L_r", "L_m")})
    t, e = c.rows["truth"], c.rows["estimates"]
    assert t["design"] == e["design"]
    floats = [k for k, v in t.items() if isinstance(v, float)]
    assert floats and all(t[k] == e[k] for k in floats)


@pytest.mark.parametrize(("table", "field"), [
    ({"controller": "imc-pi"}, "current_control.bandwidth_rad_s"),
    ({"controller": "paper-20", "bandwidth_rad_s": 3000.0}, "current_control.bandwidth_rad_s"),
    ({"controller": "imc-pi", "bandwidth_rad_s": -1.0}, "current_control.bandwidth_rad_s"),
])  # fmt: skip
def test_bad_current_designs_name_the_field(table, field):
    with pytest.raises(InputError) as exc:
        build_setup(_speed(table))
    assert exc.value.field == field


# ---------------------------------------------------------------------------------------------
# controller = "icad-proposed": analysis.propose_controller on the design machine's ICAD plant


def _same_lti(a, b) -> bool:
    return all(np.array_equal(getattr(a, k), getattr(b, k)) for k in ("A", "B", "C", "D"))


def test_the_icad_proposal_on_the_truth_is_propose_controllers_output():
    setup = build_setup(_speed({"controller": "icad-proposed"}))
    direct = propose_controller(setup.machine, None, PAPER_SPECS)  # not the loader's cache
    assert _same_lti(setup.current_control.lti, direct.controller)
    assert setup.current_control.proposal.candidate == direct.candidate
    assert direct.check.met_all  # the paper's specs are met on the paper's machine


def test_estimates_re_derive_the_icad_proposal_and_the_plant_stays_the_truth():
    truth = build_setup(_speed({"controller": "icad-proposed"}))
    d = _speed({"controller": "icad-proposed"})
    d["design"] = {"params": dict(ESTIMATES)}
    est = build_setup(d)
    estimated = dataclasses.replace(truth.machine, **ESTIMATES)
    assert est.machine == estimated
    direct = propose_controller(estimated, None, PAPER_SPECS)
    assert _same_lti(est.current_control.lti, direct.controller)
    assert (
        est.current_control.proposal.candidate.gain != truth.current_control.proposal.candidate.gain
    )
    assert est.plant == truth.plant == truth.machine  # the simulated machine is the truth


def test_the_design_comparison_reports_the_icad_check():
    c = design_comparison(_speed({"controller": "icad-proposed"}), ESTIMATES)
    t, e = c.rows["truth"]["design"], c.rows["estimates"]["design"]
    for row in (t, e):
        assert row["current_controller"] == "icad-proposed"
        assert row["current_controller_design"].startswith("re-derived from the design machine")
    est_check = propose_controller(
        dataclasses.replace(build_setup(_speed({})).machine, **ESTIMATES), None, PAPER_SPECS
    ).check
    assert e["current_icad_specs_met"] == (
        "all" if est_check.met_all else "unmet: " + ", ".join(est_check.unmet)
    )
    assert t["current_icad_specs_met"] == "all"
    assert e["current_icad_gain"] != t["current_icad_gain"]
    assert any(line.startswith("current_icad_specs_met") for line in c.lines())


def test_specifications_replace_the_papers():
    specs = specifications({"pm_deg": 45, "w_r_max": 200.0}, "current_control.specs")
    assert specs == dataclasses.replace(PAPER_SPECS, pm_deg=45, w_r_max=200.0)
    assert specifications({}, "current_control.specs") == PAPER_SPECS


@pytest.mark.parametrize(("specs", "field", "words"), [
    ({"gain_margin": 10.0}, "current_control.specs.gain_margin", "unknown specification"),
    ({"pm_deg": 200.0}, "current_control.specs.pm_deg", "< 180"),
    ({"w_r_min": 10.0, "w_r_max": 5.0}, "current_control.specs.w_r_max", ">= w_r_min"),
    ({"bandwidth_rad_s": -1.0}, "current_control.specs.bandwidth_rad_s", "> 0"),
])  # fmt: skip
def test_bad_specifications_name_the_field(specs, field, words):
    with pytest.raises(InputError) as exc:
        build_setup(_speed({"controller": "icad-proposed", "specs": specs}))
    assert exc.value.field == field
    assert words in exc.value.rule


def test_specs_apply_to_the_icad_proposal_only():
    with pytest.raises(InputError) as exc:
        build_setup(_speed({"controller": "paper-20", "specs": {"pm_deg": 45.0}}))
    assert exc.value.field == "current_control.specs"


def test_a_bad_specification_is_one_line_and_exit_2(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text('drive = "cage-im"\nname = "bad"\n[reference]\nmode = "current"\n'
                    '[current_control]\ncontroller = "icad-proposed"\n'
                    '[current_control.specs]\npm_deg = 190.0\n')  # fmt: skip
    code = main(["run", str(path), "--out", str(tmp_path / "out"), "--no-figures"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("acdrive: error: current_control.specs.pm_deg:")
    assert not (tmp_path / "out").exists()
