"""The cage-IM current controller designed from machine parameters (``controller = "imc-pi"``,
``drives.cage_im._current_design``) and its re-design on estimates (issue 23, item 4); the
built-in published controllers (Amezquita-Brooks et al.'s (20)) stay fixed."""

from __future__ import annotations

import pytest

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
