"""Robustness maps (``acdrive.robustness``): the plant-only perturbation seams, the map's points
against single runs, the design kept on the nominal machine, a trend theory predicts, and bad
input (one line naming the option or field, exit 2, before any simulation).

Small maps of short runs: each test runs a few variants of at most 1 s.
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import pytest

from acdrive.batch import simulate_batch
from acdrive.cli import main
from acdrive.drives import for_data
from acdrive.errors import InputError
from acdrive.robustness import PAPER_PERTURBATION, MapSpec, robustness_map
from acdrive.scenarios._files import read_scenario
from acdrive.scenarios._loader import build_setup


def _dfim_step() -> dict:
    """Bodson's DFIM, voltage command: speed steps at 0.1 s (to 1500 rpm) and 0.3 s (to 1400
    rpm), 1 s in all, so the last 0.25 s are settled."""
    d = read_scenario("bodson-step")
    d.pop("compare_modes")
    d["simulation"]["duration"] = 1.0
    d["motor"][0]["speed_reference_rpm"] = [[0, 0], [0.1, 0], [0.1, 1500], [0.3, 1500],
                                            [0.3, 1400], [1.0, 1400]]  # fmt: skip
    return d


def _im_perturbed_short() -> dict:
    d = read_scenario("im-perturbed")
    d["simulation"]["duration"] = 0.1
    return d


def _figures(row: dict) -> dict:
    return {k: v for k, v in row.items() if isinstance(v, float) and k not in ("value",)}


def _same(a: dict, b: dict) -> None:
    keys = set(_figures(a)) & set(_figures(b))
    assert keys
    for k in keys:
        x, y = a[k], b[k]
        assert (math.isnan(x) and math.isnan(y)) or x == y, k


def test_zero_error_gives_the_nominal_run_exactly():
    d = _dfim_step()
    seam = for_data(d).robustness()
    alone = simulate_batch(d, [{}], reducers=seam.reducers).rows[0]
    ones = simulate_batch(d, [{"motor[0].perturbation": dict.fromkeys(seam.fields.values(), 1.0)}],
                          reducers=seam.reducers).rows[0]  # fmt: skip
    m = robustness_map(d, MapSpec(params=("R_r",), points=2, low=0.8, high=1.25), linear=False)
    assert m.rows[0]["axis"] == "nominal" and m.rows[0]["factors"] == {}
    _same(m.rows[0], alone)
    _same(ones, alone)
    # the nominal drive tracks, keeps its limits and settles: the criteria pass there
    assert all(m.rows[0]["verdicts"].values()), m.rows[0]["verdicts"]


def test_a_map_point_equals_the_single_run_with_that_perturbation():
    """The severity-1 point of the paper axis is Amezquita-Brooks et al.'s perturbed plant, the
    built-in scenario im-perturbed (Fig. 23) as it stands; an R_r point is the scenario with that
    one factor."""
    d = _im_perturbed_short()
    m = robustness_map(d, MapSpec(params=("R_r", "paper"), points=3, low=0.5, high=2.0,
                                  severity_max=2.0), linear=False)  # fmt: skip
    seam = for_data(d).robustness()
    scenario = simulate_batch(d, [{}], reducers=seam.reducers).rows[0]
    paper = [r for r in m.rows if r["axis"] == "paper" and r["value"] == 1.0]
    assert len(paper) == 1 and paper[0]["factors"] == PAPER_PERTURBATION
    _same(paper[0], scenario)
    assert (
        m.summary["paper_point"]["current_error_rms_settled_a"]
        == paper[0]["current_error_rms_settled_a"]
    )
    # Figs. 21-22 at the same point: gamma of the perturbed plant with (20) does not encircle
    # (1, 0) at any speed (the paper's finding, as the ICAD report's section on perturbed plants)
    assert m.summary["paper_point"]["analysis"]["conditions_hold"] is True
    r_r = next(r for r in m.rows if r["axis"] == "R_r" and r["value"] == 2.0)
    alone = simulate_batch(d, [{"machine.perturbation": {"R_r": 2.0}}], reducers=seam.reducers)
    _same(r_r, alone.rows[0])
    # the map's nominal is the unperturbed machine, not the scenario's perturbed one
    assert m.rows[0]["current_error_rms_settled_a"] != scenario["current_error_rms_settled_a"]


def test_the_design_stays_on_the_nominal_machine():
    """A perturbed plant leaves every design quantity as the unperturbed scenario designs it:
    Bodson's gains (27) and (49), the controller's estimates; the cage IM's IFOC estimates and the
    speed PI designed from the nominal J."""
    d = _dfim_step()
    truth = build_setup(d).motors[0]
    d["motor"][0]["perturbation"] = {"R_r": 2.0, "M": 0.95, "J": 3.0}
    pert = build_setup(d).motors[0]
    assert pert.controller.gains == truth.controller.gains
    assert pert.controller.params == truth.machine
    assert pert.controller.current_gains(pert.machine) == truth.controller.current_gains(
        truth.machine
    )
    assert pert.machine.R_r == 2.0 * truth.machine.R_r and pert.machine.J == 3.0 * truth.machine.J

    im = read_scenario("im-foc-speed")
    im.setdefault("speed_controller", {})
    im["speed_controller"] = {"bandwidth_rad_s": 20.0}
    for key in ("K_P", "K_I"):
        im["speed_controller"].pop(key, None)
    base = build_setup(im)
    im["machine"]["perturbation"] = {"J": 2.0, "R_r": 1.5}
    pert = build_setup(im)
    assert pert.speed_pi == base.speed_pi
    assert pert.machine == base.machine and pert.estimates == base.estimates
    assert pert.mechanics.J == 2.0 * base.mechanics.J
    assert pert.plant.R_r == 1.5 * base.plant.R_r


def test_current_error_grows_with_the_stator_resistance():
    """Locked rotor, imposed 300 rad/s currents: where the loop gain |C G| is large the error is
    about |r| |Z(jw)| / |C(jw)|, and |Z| = |R_s + ...| grows with R_s, so the settled RMS error
    grows with the plant's R_s factor (the controller is the same)."""
    d = read_scenario("im-locked-rotor")
    d.pop("compare_controllers")
    d["current_control"]["controller"] = "paper-20"
    d["simulation"]["duration"] = 0.1
    m = robustness_map(d, MapSpec(params=("R_s",), points=4, low=1.0, high=4.0), linear=True)
    rows = sorted(m.rows, key=lambda r: r["value"])
    errors = [r["current_error_rms_settled_a"] for r in rows]
    assert [r["value"] for r in rows] == pytest.approx([1.0, 4 ** (1 / 3), 4 ** (2 / 3), 4.0])
    assert all(b > a for a, b in itertools.pairwise(errors)), errors
    # the prediction (spectral radius of the sampled current loop) stands beside every point
    assert all("spectral_radius" in r["linear"] for r in rows)
    assert m.summary["linear_vs_simulation"]["compared"] == len(rows)


def test_grid_and_monte_carlo_points():
    spec = MapSpec(params=("R_s", "J", "paper"), points=5, low=0.5, high=2.0, severity_max=2.0)
    points = spec.points_of()
    assert points[0] == ("nominal", 1.0, {})
    assert len(points) == spec.size == 1 + 4 + 4 + 4  # the nominal point is shared
    assert ("paper", 1.0, PAPER_PERTURBATION) in points
    assert MapSpec(kind="monte-carlo").params == ("R_s", "R_r", "L_s", "L_r", "L_m", "J")
    assert MapSpec().params[-1] == "paper"
    mc = MapSpec(kind="monte-carlo", params=("R_s", "R_r"), variants=50, low=0.5, high=2.0)
    draws = mc.points_of()
    assert len(draws) == 50 and mc.points_of() == draws  # seeded
    assert all(0.5 <= f <= 2.0 for _, _, fs in draws[1:] for f in fs.values())
    # the default maps hold at least 1,000 variants (issue 23)
    assert MapSpec().size >= 1000
    assert MapSpec(kind="monte-carlo", params=("R_s", "R_r", "L_s", "L_r", "L_m", "J")).size >= 1000


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"params": ("R_x",)}, "params"),
        ({"params": ()}, "params"),
        ({"points": 1}, "points"),
        ({"low": -0.5}, "low"),
        ({"low": 2.0, "high": 1.0}, "high"),
        ({"severity_max": 0.0}, "severity_max"),
        ({"kind": "monte-carlo", "params": ("paper",)}, "params"),
        ({"kind": "sobol"}, "kind"),
        ({"resolution": 0.0}, "resolution"),
        ({"resolution": 1e-12}, "resolution"),
        ({"resolution": float("nan")}, "resolution"),
    ],
)
def test_bad_map_specifications_name_the_argument(kwargs, field):
    with pytest.raises(InputError) as exc:
        MapSpec(**kwargs)
    assert exc.value.field == field


def test_a_negative_perturbation_factor_names_the_field():
    d = _dfim_step()
    d["motor"][0]["perturbation"] = {"R_s": -2.0}
    with pytest.raises(InputError) as exc:
        build_setup(d)
    assert exc.value.field == "motor[0].perturbation.R_s"
    d["motor"][0]["perturbation"] = {"X": 2.0}
    with pytest.raises(InputError) as exc:
        build_setup(d)
    assert exc.value.field == "motor[0].perturbation.X"


@pytest.mark.parametrize(
    ("argv", "field"),
    [
        (["--params", "R_s,Q"], "--params"),
        (["--points", "1"], "--points"),
        (["--low", "-1"], "--low"),
        (["--current-tolerance", "-0.1"], "--current-tolerance"),
        (["--map", "monte-carlo", "--variants", "0"], "--variants"),
        (["--map", "monte-carlo", "--seed", "-1"], "--seed"),
        (["--resolution", "0"], "--resolution"),
        (["--map", "monte-carlo", "--resolution", "0.01"], "--resolution"),
    ],
)
def test_the_command_refuses_bad_input_in_one_line(tmp_path, capsys, argv, field):
    try:
        code = main(["robustness", "bodson-ramp", *argv, "--out", str(tmp_path / "out")])
    except SystemExit as exc:
        code = exc.code
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1 and err.startswith(f"acdrive: error: {field}:"), err
    assert not (tmp_path / "out").exists()


def test_a_scenario_comparing_runs_is_refused_before_work():
    with pytest.raises(InputError) as exc:
        robustness_map("im-locked-rotor", MapSpec(params=("R_s",), points=2))
    assert "compare" in exc.value.field + exc.value.rule


def test_a_drive_without_a_perturbation_table_is_refused():
    from acdrive.drives import Drive

    with pytest.raises(InputError) as exc:
        Drive().robustness()
    assert exc.value.field == "drive"
    assert dataclasses.is_dataclass(MapSpec())


# --- design from estimates (issue 23, item 4) -------------------------------------------------


def test_a_design_on_the_truth_equals_the_existing_design():
    """Estimates equal to the truth: the run designed on them is the scenario's own, bit for bit,
    and so are Bodson's gains (27), (49) and the controller's estimates."""
    from acdrive.machines import BODSON_DFIM
    from acdrive.robustness import design_comparison

    d = _dfim_step()
    c = design_comparison(d, BODSON_DFIM)
    t, e = c.rows["truth"], c.rows["estimates"]
    _same(t, e)
    assert t["design"] == e["design"]
    assert set(c.from_estimates) >= {"R_s", "R_r", "L_s", "L_r", "M", "J"}


def test_a_parameter_file_designs_the_controllers_and_the_plant_stays(tmp_path, capsys):
    """A machine parameter file as ``acdrive identify`` writes it ([machine.params], L_m): the
    cage IM's IFOC takes its estimates, the plant keeps the scenario's machine; the command
    prints both runs side by side."""
    from acdrive.robustness import design_comparison

    path = tmp_path / "estimates.toml"
    path.write_text("[machine.params]\nR_s = 17.0\nR_r = 20.0\nL_s = 1.40\nL_r = 1.46\n"
                    "L_m = 1.38\nn_p = 1\n")  # fmt: skip
    d = read_scenario("im-foc-speed")
    d["simulation"]["duration"] = 0.2
    c = design_comparison(d, str(path))
    assert c.rows["estimates"]["design"]["ifoc_R_r"] == 20.0
    assert c.rows["truth"]["design"]["ifoc_R_r"] == build_setup(d).plant.R_r
    assert c.from_estimates == ("R_s", "R_r", "L_s", "L_r", "L_m", "n_p")
    setup = build_setup({**d, "design": {"machine_file": str(path)}})
    assert setup.plant == build_setup(d).plant and setup.machine.L_m == 1.38
    # a wrong rotor-resistance estimate mis-orients the IFOC: the speed error differs
    assert (
        c.rows["estimates"]["speed_rms_error_whole_run_rad_s"]
        != c.rows["truth"]["speed_rms_error_whole_run_rad_s"]
    )
    for row in c.rows.values():
        assert set(row["verdicts"]) == {"tracking", "current_limit", "stability"}


def test_bad_design_tables_name_the_field(tmp_path):
    d = _dfim_step()
    d["motor"][0]["design"] = {"params": {"R_r": -1.0}}
    with pytest.raises(InputError) as exc:
        build_setup(d)
    assert exc.value.field == "motor[0].design.params.R_r"
    d["motor"][0]["design"] = {"machine_file": str(tmp_path / "none.toml")}
    with pytest.raises(InputError) as exc:
        build_setup(d)
    assert exc.value.field == "motor[0].design.machine_file"
    d["motor"][0]["design"] = {"params": {"Q": 1.0}}
    with pytest.raises(InputError) as exc:
        build_setup(d)
    assert exc.value.field == "motor[0].design.params.Q"


def test_the_command_writes_its_report_and_json(tmp_path, capsys):
    """``acdrive robustness --json --out``: the JSON's paper point is the row it names, the
    report states its verdicts, and a folder acdrive did not write is never replaced."""
    import json

    argv = ["robustness", "im-perturbed", "--params", "paper", "--points", "2",
            "--duration", "0.06", "--json"]  # fmt: skip
    assert main([*argv, "--out", str(tmp_path)]) == 0
    doc = json.loads(capsys.readouterr().out)
    point = doc["summary"]["paper_point"]
    row = doc["rows"][point["variant"]]
    assert row["factors"] == PAPER_PERTURBATION and row["axis"] == "paper"
    assert point["current_error_rms_settled_a"] == row["current_error_rms_settled_a"]
    folder = tmp_path / "im-perturbed-robustness"
    assert {p.name for p in folder.iterdir()} >= {"map.json", "report.md", "map.png"}
    assert "Amezquita-Brooks et al. sec. VIII (severity 1)" in (folder / "report.md").read_text()
    users = tmp_path / "users"
    (users / "im-perturbed-robustness").mkdir(parents=True)
    (users / "im-perturbed-robustness" / "notes.txt").write_text("mine")
    try:
        code = main([*argv, "--out", str(users)])
    except SystemExit as exc:
        code = exc.code
    assert code == 2 and "--out" in capsys.readouterr().err
    assert (users / "im-perturbed-robustness" / "notes.txt").read_text() == "mine"


def _synthetic_rows(axis: str, values, breaks_from: float) -> list[dict]:
    """Judged rows of one axis whose single criterion passes below ``breaks_from`` (a factor,
    or a severity on the paper axis) and breaks from it on: a boundary known exactly."""
    from acdrive.robustness._map import _log_distance, paper_factors

    def row(value):
        factors = {} if value is None else (
            paper_factors(value) if axis == "paper" else {axis: value})
        passes = value is None or (value < breaks_from if value >= (0 if axis == "paper" else 1)
                                   else True)  # fmt: skip
        return {"axis": "nominal" if value is None else axis,
                "value": 1.0 if value is None else value, "factors": factors,
                "log_distance": _log_distance(axis, value, factors), "valid": True,
                "verdicts": {"current_limit": passes}}  # fmt: skip

    return [row(None), *(row(v) for v in values)]


@pytest.mark.parametrize(("axis", "grid", "boundary"), [
    ("L_m", [0.5, 0.8, 1.25, 2.0], 1.2345),
    ("paper", [0.5, 1.0, 1.5, 2.0], 1.2345),
])  # fmt: skip
def test_bisection_closes_on_a_known_boundary(axis, grid, boundary):
    """The refinement's own rule on a criterion that breaks exactly from ``boundary`` on: each
    round's midpoints judged and added, the reported pair brackets the boundary and is no wider
    than the resolution (in ln f, or in severity on the paper axis), in
    ceil(log2(grid spacing / resolution)) rounds."""
    from acdrive.robustness._map import _boundaries, _midpoints

    class Criterion:
        name = "current_limit"

    rows = _synthetic_rows(axis, grid, boundary)
    first = _boundaries(rows, axis, "current_limit")["above"]
    assert first["breaks"] == (1.25 if axis == "L_m" else 1.5)  # the grid's first breaking point
    rounds = 0
    while points := _midpoints(rows, [Criterion()], 1e-4):
        rounds += 1
        rows += _synthetic_rows(axis, [v for _, v, _ in points], boundary)[1:]
    b = _boundaries(rows, axis, "current_limit")["above"]
    assert b["passes"] < boundary <= b["breaks"]
    x = (lambda v: v) if axis == "paper" else math.log
    assert b["width"] == pytest.approx(x(b["breaks"]) - x(b["passes"])) and b["width"] <= 1e-4
    assert rounds == math.ceil(math.log2(first["width"] / 1e-4))
    if axis == "L_m":
        assert _boundaries(rows, axis, "current_limit")["below"] is None  # below: passes


def test_the_current_limit_boundary_is_found_between_grid_points():
    """``bodson-ramp``'s current limit on L_m: on a 3-point grid (0.9, 1.013, 1.14) the first
    breaking point is 1.14; the map bisects (1.013, 1.14] to 1e-3 in ln f, and runs of the two ends
    alone confirm the pair: the peak phase current is within 1.05 x the limit at the passing
    factor and above it at the breaking one."""
    seam = for_data(read_scenario("bodson-ramp")).robustness()
    m = robustness_map("bodson-ramp", MapSpec(params=("L_m",), points=3, low=0.9, high=1.14),
                       linear=False)  # fmt: skip
    b = m.summary["axes"]["L_m"]["boundary_above"]["current_limit"]
    assert 1.013 < b["passes"] < b["breaks"] < 1.14
    assert b["width"] <= 1e-3 and b["width"] == pytest.approx(math.log(b["breaks"] / b["passes"]))
    assert m.summary["first_to_break"]["current_limit"] == {
        "parameter": "L_m", "factor": b["breaks"], "passes_at": b["passes"]}
    ends = simulate_batch("bodson-ramp", [{seam.table: {seam.fields["L_m"]: b["passes"]}},
                                          {seam.table: {seam.fields["L_m"]: b["breaks"]}}],
                          reducers=seam.reducers).rows  # fmt: skip
    from acdrive.batch import build_variant_setup

    nominal = build_variant_setup(read_scenario("bodson-ramp"))
    peaks = [seam.derived(nominal, row)["peak_phase_current_over_limit"] for row in ends]
    assert peaks[0] <= 1.05 < peaks[1]  # the criterion's stated tolerance, 5 % over the limit
    refined = [r for r in m.rows if r["refined"]]
    assert refined and len(m.rows) == 4 + len(refined)
    assert [r["variant"] for r in m.rows] == list(range(len(m.rows)))
