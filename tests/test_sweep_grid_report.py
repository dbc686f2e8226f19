"""A grid sweep's report plots each metric against the swept parameters and writes grid values
to their grid's resolution (`acdrive.sweep._grid_figures`, `sweep._report`)."""

import math
import textwrap
import tomllib

import matplotlib
import numpy as np
import pandas as pd
import pytest

from acdrive.sweep import read_table, run_sweep
from acdrive.sweep._grid_figures import draw, grid_labels, grid_plot
from acdrive.sweep._spec import build_spec, load_sweep
from acdrive.sweep._variants import count, grid_values, variant

matplotlib.use("Agg")


def _spec(text):
    return build_spec(tomllib.loads(textwrap.dedent(text)))


@pytest.mark.parametrize(
    "values, expected",
    [
        (np.linspace(0.1, 0.5, 5), ["0.1", "0.2", "0.3", "0.4", "0.5"]),  # 0.30000000000000004
        (np.linspace(0.0, 0.3, 4), ["0", "0.1", "0.2", "0.3"]),  # 0.09999999999999999
        ([0.0, 0.25, 0.5, 0.75], ["0", "0.25", "0.5", "0.75"]),  # a step of 0.25 keeps it
        ([1e3, 2e3, 3e3], ["1000", "2000", "3000"]),
        (["a", "b"], ["a", "b"]),
    ],
)
def test_grid_values_are_written_to_their_grids_resolution(values, expected):
    labels = grid_labels(list(values))
    assert [labels[v] for v in values] == expected


def test_a_geometric_grid_is_rounded_to_each_values_own_step():
    """Rounded to one digit finer than the step to the nearest neighbour: within 5 % of that
    step of the value, and all distinct."""
    values = list(np.geomspace(1e-3, 1.0, 7))
    labels = grid_labels(values)
    assert len(set(labels.values())) == 7
    for i, v in enumerate(values):
        step = min(abs(v - values[j]) for j in (i - 1, i + 1) if 0 <= j < 7)
        assert abs(float(labels[v]) - v) <= 0.05 * step, (v, labels[v])
        assert len(labels[v]) <= 6, labels[v]  # no float noise


THREE = """
name = "three"
base = "bodson-ramp"
[[vary]]
field = "motor[0].load_torque"
low = 0.0
high = 0.3
points = 4
[[vary]]
field = "motor[0].controller.speed_bandwidth"
low = 100.0
high = 400.0
points = 3
log = true
[[vary]]
field = "motor[0].converter_device_drop"
values = [0.0, 0.35, 0.7]
"""


def _table(spec, f):
    """A sweep table of ``spec`` whose metric "m" is ``f`` of the varied values, with the variant
    of index 5 invalid (no value)."""
    rows = []
    for i in range(count(spec)):
        v = variant(spec, i)
        value = math.nan if i == 5 else f(*v.values())
        rows.append({"variant": i, **{f"vary.{k}": x for k, x in v.items()}, "m": value})
    return pd.DataFrame(rows)


def test_one_line_per_value_of_the_second_parameter_holds_the_table_values():
    spec = _spec(THREE.split('[[vary]]\nfield = "motor[0].converter_device_drop"')[0])
    table = _table(spec, lambda load, bw: 10 * load + bw / 100)
    plot = grid_plot(spec, table, "m")
    assert plot.kind == "lines" and plot.x_field == "motor[0].load_torque"  # 4 values > 3
    assert plot.x_values == grid_values(spec.vary[0])
    bandwidths = grid_values(spec.vary[1])
    assert [text for text, _ in plot.lines] == [
        f"motor[0].controller.speed_bandwidth = {label}" for label in ("100", "200", "400")
    ]  # geomspace(100, 400, 3)[1] is 200.00000000000003
    invalid = variant(spec, 5)
    for (_, y), bw in zip(plot.lines, bandwidths, strict=True):
        expected = [
            math.nan if (load, bw) == tuple(invalid.values()) else 10 * load + bw / 100
            for load in plot.x_values
        ]
        np.testing.assert_array_equal(y, expected)
    assert np.isnan(np.concatenate([y for _, y in plot.lines])).sum() == 1
    fig = draw(plot)
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == ["0", "0.1", "0.2", "0.3"]
    assert ax.get_xlabel() == "motor[0].load_torque" and ax.get_ylabel() == "m"
    assert len(ax.get_legend().get_texts()) == 3


def test_more_combinations_than_lines_make_a_heat_map_per_value_of_the_third():
    spec = _spec(THREE)  # 4 x 3 x 3: the 9 combinations besides the load are too many lines
    table = _table(spec, lambda load, bw, drop: load * bw - drop)
    plot = grid_plot(spec, table, "m")
    assert plot.kind == "heatmap" and plot.x_field == "motor[0].load_torque"
    assert plot.y_field == "motor[0].controller.speed_bandwidth"  # the first of the longest
    drops = grid_values(spec.vary[2])
    assert [text for text, _ in plot.panels] == [
        f"motor[0].converter_device_drop = {d:g}" for d in drops
    ]
    invalid = tuple(variant(spec, 5).values())
    for (_, grid), drop in zip(plot.panels, drops, strict=True):
        expected = [
            [math.nan if (x, y, drop) == invalid else x * y - drop for x in plot.x_values]
            for y in plot.y_values
        ]
        np.testing.assert_array_equal(grid, expected)
    assert sum(np.isnan(grid).sum() for _, grid in plot.panels) == 1
    fig = draw(plot)
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == ["0", "0.1", "0.2", "0.3"]
    assert [t.get_text() for t in ax.get_yticklabels()] == ["100", "200", "400"]


def test_a_random_sweep_has_no_grid_plot():
    import dataclasses

    spec = _spec(THREE)
    table = _table(spec, lambda *v: 1.0)
    spec = dataclasses.replace(spec, method="random", samples=len(table))
    assert grid_plot(spec, table, "m") is None


TINY_GRID = """
name = "tiny-grid"
base = "bodson-ramp"
[fixed]
"simulation.duration" = 0.05
[[vary]]
field = "motor[0].load_torque"
low = 0.0
high = 0.3
points = 4
[[vary]]
field = "motor[0].controller.speed_bandwidth"
values = [100.0, 300.0]
"""


@pytest.mark.slow
def test_a_real_grid_sweep_report_plots_every_metric_against_the_grid(tmp_path):
    """8 variants of the cheapest built-in scenario, 0.05 s each: the report's figures of each
    metric against load and bandwidth hold the table's values, and no table or label of the
    report shows the grid's float noise (np.linspace(0, 0.3, 4)[1] is 0.09999999999999999)."""
    path = tmp_path / "g.toml"
    path.write_text(textwrap.dedent(TINY_GRID))
    spec = load_sweep(str(path))
    folder = run_sweep(spec, tmp_path / "out", progress=False)
    table = read_table(folder)
    report = (folder / "report.md").read_text()
    section = report.split("## Metrics against the swept parameters\n")[1].split("\n## ")[0]
    files = [line[line.index("(") + 1 : -1] for line in section.splitlines() if line]
    assert len(files) >= 5 and all((folder / f).is_file() for f in files)
    metric = "peak_rotor_current_a"
    assert f"figures/grid-{metric}.png" in files
    plot = grid_plot(spec, table, metric)
    assert plot.kind == "lines" and [text for text, _ in plot.lines] == [
        "motor[0].controller.speed_bandwidth = 100",
        "motor[0].controller.speed_bandwidth = 300",
    ]
    indexed = table.set_index(["vary.motor[0].load_torque",
                               "vary.motor[0].controller.speed_bandwidth"])[metric]  # fmt: skip
    for (_, y), bw in zip(plot.lines, (100.0, 300.0), strict=True):
        np.testing.assert_array_equal(y, [indexed[(x, bw)] for x in plot.x_values])
    assert np.isfinite(np.concatenate([y for _, y in plot.lines])).all()
    assert 0.09999999999999999 in set(table["vary.motor[0].load_torque"])  # the noise is there
    assert "0.0999" not in report and "0.30000" not in report and "e-17" not in report
    worst = report.split("## Worst cases")[1].split("\n## ")[0]
    loads = {line.split(" | ")[1] for line in worst.splitlines() if line.startswith("| 0")}
    assert loads and loads <= {"0", "0.1", "0.2", "0.3"}


def test_a_long_axis_labels_every_kth_grid_value():
    spec = _spec(THREE.split("[[vary]]")[0] + "[[vary]]" + THREE.split("[[vary]]")[1].replace(
        "points = 4", "points = 31"))  # fmt: skip
    table = _table(spec, lambda load: load)
    plot = grid_plot(spec, table, "m")
    ticks = [t.get_text() for t in draw(plot).axes[0].get_xticklabels()]
    labels = [grid_labels(plot.x_values)[x] for x in plot.x_values]
    assert len(plot.x_values) == 31
    assert ticks == labels[::3] and len(ticks) == 11  # every ceil(31 / 12) = 3rd value
    assert ticks[:2] == ["0", "0.03"]  # steps of 0.01 (0.3 / 30)
