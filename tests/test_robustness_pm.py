"""The PM speed drive in robustness maps and designs from estimates (issue 23, items 4 and 5):
the plant-only perturbation table ``[machine.perturbation]`` (R_s, L_d, L_q, psi_m, J) and the
``[design]`` table, through the same ``Drive.robustness()`` seam as the induction drives.

Short runs of the BLY171D scenario (0.2 s at 50 us).
"""

from __future__ import annotations

import math

import pytest

from acdrive.batch import simulate_batch
from acdrive.drives import for_data
from acdrive.errors import InputError
from acdrive.robustness import MapSpec, design_comparison, robustness_map
from acdrive.scenarios._files import read_scenario
from acdrive.scenarios._loader import build_setup

SCENARIO = "pm-bly171d-speed"


def _figures(row: dict) -> dict:
    return {k: v for k, v in row.items() if isinstance(v, float) and k != "value"}


def _same(a: dict, b: dict) -> None:
    keys = set(_figures(a)) & set(_figures(b))
    assert keys
    for k in keys:
        x, y = a[k], b[k]
        assert (math.isnan(x) and math.isnan(y)) or x == y, k


def test_the_default_axes_are_the_pm_parameters():
    m = MapSpec(points=2)
    seam = for_data(read_scenario(SCENARIO)).robustness()
    assert m.for_fields(seam.fields).params == ("R_s", "L_d", "L_q", "psi_m", "J")
    given = MapSpec(params=("J",), points=2)
    assert given.for_fields(seam.fields) is given
    with pytest.raises(InputError) as exc:
        robustness_map(SCENARIO, MapSpec(params=("R_r",), points=2))
    assert exc.value.field == "spec.params"


def test_zero_error_gives_the_nominal_run_exactly_and_a_point_is_its_single_run():
    d = read_scenario(SCENARIO)
    seam = for_data(d).robustness()
    alone = simulate_batch(d, [{}], reducers=seam.reducers).rows[0]
    ones = dict.fromkeys(seam.fields.values(), 1.0)
    with_ones = simulate_batch(d, [{"machine.perturbation": ones}], reducers=seam.reducers)
    _same(with_ones.rows[0], alone)
    m = robustness_map(d, MapSpec(params=("L_q", "J"), points=2, low=0.8, high=1.25))
    _same(m.rows[0], alone)
    # the nominal drive tracks the settled reference, keeps its limit and finishes finite
    assert all(m.rows[0]["verdicts"].values()), m.rows[0]["verdicts"]
    for axis, value in (("L_q", 1.25), ("J", 0.8)):
        row = next(r for r in m.rows if r["axis"] == axis and r["value"] == pytest.approx(value))
        single = simulate_batch(d, [{"machine.perturbation": {axis: row["value"]}}],
                                reducers=seam.reducers).rows[0]  # fmt: skip
        _same(row, single)
        # the current loops stay stable on these plants: the prediction says so
        assert row["linear"]["predicted_stable"] is True
        assert row["linear"]["spectral_radius"] < 1.0


def test_a_perturbed_plant_keeps_the_nominal_design():
    d = read_scenario(SCENARIO)
    base = build_setup(d)
    d["machine"]["perturbation"] = {"R_s": 2.0, "L_q": 1.5, "psi_m": 0.8, "J": 3.0}
    pert = build_setup(d)
    assert pert.controller_machine == base.machine
    assert pert.speed_design_J == base.J and pert.J == 3.0 * base.J
    assert pert.machine.R_s == 2.0 * base.machine.R_s
    assert pert.machine.psi_m == 0.8 * base.machine.psi_m
    d["machine"]["perturbation"] = {"L_d": -1.0}
    with pytest.raises(InputError) as exc:
        build_setup(d)
    assert exc.value.field == "machine.perturbation.L_d"


def test_a_design_on_the_truth_equals_the_existing_design():
    """Estimates equal to the truth (the machine record, J included): the run designed on them is
    the scenario's own, bit for bit, and so are the current and speed PI gains."""
    d = read_scenario(SCENARIO)
    c = design_comparison(d, build_setup(d).machine)
    t, e = c.rows["truth"], c.rows["estimates"]
    _same(t, e)
    assert t["design"] == e["design"]
    assert set(c.from_estimates) == {"R_s", "L_d", "L_q", "psi_m", "n_p", "J"}


def test_a_parameter_file_designs_the_controllers_and_the_plant_stays(tmp_path):
    """Internal-model current PI K_P = alpha L, K_I = alpha R_s and the speed PI with both roots at
    its bandwidth (K_P = 2 J w_b, K_I = J w_b^2): each gain scales with its estimate."""
    d = read_scenario(SCENARIO)
    truth = build_setup(d)
    m = truth.machine
    path = tmp_path / "estimates.toml"
    path.write_text(f"[machine.params]\nR_s = {1.3 * m.R_s!r}\nL_d = {0.9 * m.L_d!r}\n"
                    f"L_q = {0.9 * m.L_q!r}\npsi_m = {1.1 * m.psi_m!r}\nJ = {2.0 * truth.J!r}\n")  # fmt: skip
    setup = build_setup({**d, "design": {"machine_file": str(path)}})
    assert setup.machine == m and setup.J == truth.J  # the plant is the truth
    assert setup.controller_machine.R_s == 1.3 * m.R_s and setup.speed_design_J == 2.0 * truth.J
    c = design_comparison(d, str(path))
    t, e = c.rows["truth"]["design"], c.rows["estimates"]["design"]
    assert e["K_I_current"] / t["K_I_current"] == pytest.approx(1.3, rel=1e-12)
    assert e["K_P_q"] / t["K_P_q"] == pytest.approx(0.9, rel=1e-12)
    assert e["speed_K_P"] / t["speed_K_P"] == pytest.approx(2.0, rel=1e-12)
    assert e["speed_K_I"] / t["speed_K_I"] == pytest.approx(2.0, rel=1e-12)
    assert t["speed_K_P"] == pytest.approx(2.0 * truth.J * truth.speed_bandwidth, rel=1e-12)
    assert c.from_estimates == ("R_s", "L_d", "L_q", "psi_m", "J")
    # the plant is the same, the controller not: the runs differ
    assert c.rows["estimates"]["speed_error_rms_rad_s"] != c.rows["truth"]["speed_error_rms_rad_s"]
    d["design"] = {"params": {"L_q": -1.0}}
    with pytest.raises(InputError) as exc:
        build_setup(d)
    assert exc.value.field == "design.params.L_q"
    # MTPA needs L_q >= L_d: an estimate that breaks it names the design table, not the machine
    d["design"] = {"params": {"L_q": 0.5 * m.L_d}}
    with pytest.raises(InputError) as exc:
        build_setup(d)
    assert exc.value.field == "design.params.L_q"
