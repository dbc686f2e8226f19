"""Report figures: the min/max envelope of long traces keeps every extreme, figures are saved at
their size without pyplot, and the current limits drawn are the scenario's."""

import math

import numpy as np
import pytest
from PIL import Image

from acdrive._figures import (
    DPI,
    ENVELOPE_BINS,
    TIME_PLOT_MARGINS_IN,
    envelope,
    new_figure,
    plot_trace,
    save_figure,
)
from acdrive._frames import K_PEAK
from acdrive.drives.dfim import _figures as dfim_figures
from acdrive.drives.dfim._figures import current_limits, drive_figures
from acdrive.drives.dfim._result import LOG_NAMES, N_LOG, DriveResult

# --- the envelope ----------------------------------------------------------------------------


def _kept_indices(t, t_kept):
    """Indices into the original trace of the kept samples (times are unique there)."""
    index = np.searchsorted(t, t_kept)
    assert np.array_equal(t[index], t_kept), "a kept time is not a time of the trace"
    return index


def _check_envelope(t, y, bins):
    t_kept, y_kept = envelope(t, y, bins)
    index = _kept_indices(t, t_kept)
    assert np.all(np.diff(t_kept) > 0), "times must be strictly increasing"
    assert np.array_equal(y_kept, y[index], equal_nan=True), "kept values are the trace's own"
    assert y_kept.size <= 4 * bins
    assert np.nanmax(y_kept) == np.nanmax(y) and np.nanmin(y_kept) == np.nanmin(y)
    # the runs as documented: ceil(n / bins) consecutive samples each, the last one shorter
    size = math.ceil(y.size / bins)
    kept = set(index.tolist())
    for lo in range(0, y.size, size):
        hi = min(lo + size, y.size)
        assert lo in kept and hi - 1 in kept, "first and last sample of every run are kept"
        inside = y[sorted(i for i in range(lo, hi) if i in kept)]
        run = y[lo:hi]
        if np.any(np.isfinite(run)):
            drawn = inside[np.isfinite(inside)]
            assert drawn.max() == run[np.isfinite(run)].max()
            assert drawn.min() == run[np.isfinite(run)].min()
        if not np.all(np.isfinite(run)):
            assert not np.all(np.isfinite(inside)), "a gap (NaN) in a run stays a gap"
    return t_kept, y_kept


@pytest.mark.parametrize(("n", "bins"), [(140_000, ENVELOPE_BINS), (140_001, 1500), (12_345, 7)])
def test_envelope_keeps_every_run_extreme_in_time_order(n, bins):
    rng = np.random.default_rng(n)
    t = 1e-4 * np.arange(n)
    y = np.sin(2 * np.pi * 3 * t) + 0.2 * rng.standard_normal(n)
    size = math.ceil(n / bins)  # one-sample peaks and troughs, at most one per run
    runs = rng.choice(n // size, min(40, n // size), replace=False)
    spikes = runs * size + rng.integers(0, size, runs.size)
    y[spikes] += rng.choice([-5.0, 5.0], spikes.size) * rng.uniform(1, 2, spikes.size)
    t_kept, y_kept = _check_envelope(t, y, bins)
    assert set(spikes) <= set(_kept_indices(t, t_kept)), "every spike is drawn, at its time"
    assert y_kept.size < n / 4


def test_envelope_of_steps_and_gaps():
    n = 50_000
    t = np.linspace(0.0, 5.0, n)
    y = (t > 1.2345).astype(float)  # a relay closing: the step is kept at its sample
    t_kept, y_kept = _check_envelope(t, y, 100)
    assert t_kept[np.argmax(y_kept)] == t[np.argmax(y)]
    y = np.cos(t)
    y[20_000:20_050] = np.nan
    y[33_333] = np.inf
    _check_envelope(t, y, 100)


def test_short_traces_are_drawn_as_given():
    t = np.arange(4 * ENVELOPE_BINS) * 1e-3
    y = np.sin(t)
    t_kept, y_kept = envelope(t, y)
    assert t_kept is t and y_kept is y


def _written_columns(ax, t):
    """Pixel column of the written image (``DPI``) of each time ``t`` in ``ax``, from the axes'
    position and limits alone."""
    fig = ax.figure
    width_px = fig.get_figwidth() * DPI
    box = ax.get_position()
    x0, x1 = ax.get_xlim()
    return np.floor(box.x0 * width_px + (np.asarray(t) - x0) / (x1 - x0) * box.width * width_px)


@pytest.mark.parametrize("margins", [TIME_PLOT_MARGINS_IN, None])
def test_saved_trace_keeps_every_pixel_columns_highest_and_lowest_sample(tmp_path, margins):
    n = 140_000
    rng = np.random.default_rng(7)
    t = 1e-4 * np.arange(n)
    y = np.sin(2 * np.pi * 0.3 * t) + 0.3 * rng.standard_normal(n)
    y[rng.choice(n, 60, replace=False)] += rng.choice([-4.0, 4.0], 60)  # one-sample spikes
    fig, ax = new_figure((7, 3.5), margins_in=margins)
    line = plot_trace(ax, t, y, lw=1, label="trace")
    ax.set(xlabel="time (s)", ylabel="y", title="a long trace")
    ax.legend()
    save_figure(tmp_path / "trace.png", fig)
    t_drawn, y_drawn = np.asarray(line.get_xdata()), np.asarray(line.get_ydata())
    index = _kept_indices(t, t_drawn)
    assert np.array_equal(y_drawn, y[index]), "drawn samples are the trace's own, in time order"
    assert t_drawn.size < n / 10
    column, drawn_column = _written_columns(ax, t), _written_columns(ax, t_drawn)
    for c in np.unique(column):
        full, drawn = y[column == c], y_drawn[drawn_column == c]
        assert drawn.max() == full.max() and drawn.min() == full.min(), f"pixel column {c}"
        assert drawn.size <= 4
    assert t_drawn[0] == t[0] and t_drawn[-1] == t[-1]


# --- saving ----------------------------------------------------------------------------------


def test_saved_figure_has_its_size_and_no_pyplot_figure_stays_open(tmp_path):
    import matplotlib.pyplot as plt

    fig, ax = new_figure((7, 3.5))
    ax.plot([0, 1], [0, 1], label="x")
    ax.set(xlabel="time (s)", ylabel="y", title="t")
    ax.legend()
    save_figure(tmp_path / "a.png", fig)
    assert Image.open(tmp_path / "a.png").size == (7 * DPI, round(3.5 * DPI))
    fig, ax = plt.subplots(figsize=(4, 3))  # the reproduction reports still draw with pyplot
    ax.plot([0, 1], [1, 0])
    number = fig.number
    save_figure(tmp_path / "b.png", fig)
    assert Image.open(tmp_path / "b.png").size == (4 * DPI, 3 * DPI)
    assert not plt.fignum_exists(number)


# --- the current limits of the figures ---------------------------------------------------------


def _result(n=20_000, dt=1e-4):
    t = dt * np.arange(n)
    signals = np.zeros((n, 1, N_LOG))
    rng = np.random.default_rng(3)
    signals[:, 0, LOG_NAMES.index("w")] = 150.0 * t
    signals[:, 0, LOG_NAMES.index("w_ref")] = 150.0 * t
    signals[:, 0, LOG_NAMES.index("i_s_mag")] = K_PEAK * (3.0 + rng.uniform(0, 1, n))
    signals[:, 0, LOG_NAMES.index("i_r_mag")] = K_PEAK * (4.0 + rng.uniform(0, 1, n))
    signals[12_345, 0, LOG_NAMES.index("i_r_mag")] = K_PEAK * 6.789  # one-sample peak
    return DriveResult("synthetic", t, signals, dt, np.zeros(1))


def test_drive_figures_drawn_in_turn_on_one_figure_are_those_of_figures_of_their_own(tmp_path):
    result = _result()
    synchronous = float(result.speed_rpm().max()) / 2  # crossed: the rotor-current figure too
    limits = {"stator": 4.5, "rotor": 7.25}
    (tmp_path / "shared").mkdir()
    (tmp_path / "own").mkdir()
    shared = dfim_figures.write_drive_figures(result, tmp_path / "shared", synchronous, limits)
    own = drive_figures(result, synchronous, limits)
    for name, fig in own.items():
        save_figure(tmp_path / "own" / name, fig)
    assert [path.name for path in shared] == list(own)
    assert "fig7_rotor_currents.png" in own and len(own) == 5
    for path in shared:
        assert path.read_bytes() == (tmp_path / "own" / path.name).read_bytes(), path.name


def _limit_lines(fig):
    """label -> y of the horizontal limit lines of the currents figure."""
    (ax,) = fig.axes
    legend = [text.get_text() for text in ax.get_legend().get_texts()]
    out = {}
    for line in ax.get_lines():
        y = np.asarray(line.get_ydata(), dtype=float)
        if "limit" in line.get_label():
            assert line.get_label() in legend
            assert y.size == 2 and y[0] == y[1]
            out[line.get_label()] = float(y[0])
    return out


def test_currents_figure_draws_the_given_limits_and_the_true_peak():
    result = _result()
    figures = drive_figures(result, 1.0e9, {"stator": 4.5, "rotor": 7.25})
    fig = figures["fig6_currents.png"]
    assert _limit_lines(fig) == {"4.5 A stator limit": 4.5, "7.25 A rotor limit": 7.25}
    rotor = next(line for line in fig.axes[0].get_lines() if line.get_label() == "rotor")
    assert np.max(rotor.get_ydata()) == np.max(result.peak("i_r_mag"))  # the peak is drawn
    same = drive_figures(result, 1.0e9, {"stator": 5.5, "rotor": 5.5})["fig6_currents.png"]
    assert _limit_lines(same) == {"5.5 A limit (stator and rotor)": 5.5}


def test_a_scenario_limit_reaches_the_currents_figure(tmp_path, monkeypatch):
    from acdrive.drives.dfim import run_scenario
    from acdrive.drives.dfim._outputs import write_outcome
    from acdrive.scenarios import load_scenario

    path = tmp_path / "limits.toml"
    path.write_text("""
name = "limits"
[simulation]
duration = 0.1
[[motor]]
speed_reference_rpm = [[0, 0], [0.1, 50]]
[motor.controller]
speed_bandwidth = 100.0
stator_current_limit_pk = 4.75
rotor_current_limit_pk = 7.5
""")
    setup = load_scenario(path)
    assert current_limits(setup) == {"stator": 4.75, "rotor": 7.5}
    saved = {}
    # the limit lines as each figure is saved (the time plots are drawn in turn on one figure)
    monkeypatch.setattr(dfim_figures, "save_figure",
                        lambda p, fig: saved.setdefault(p.name, _limit_lines(fig)))  # fmt: skip
    write_outcome(run_scenario(setup), tmp_path / "out")
    assert saved["fig6_currents.png"] == {
        "4.75 A stator limit": 4.75,
        "7.5 A rotor limit": 7.5,
    }


# --- matplotlib imported by a command --------------------------------------------------------
_DRAW = """
import sys
from pathlib import Path
from acdrive import _figures
_figures.COMMAND_PROCESS = {command}
fig, ax = _figures.new_figure((4.0, 2.5), margins_in=_figures.TIME_PLOT_MARGINS_IN)
ax.plot([0.0, 1.0, 2.0], [0.0, 1.5, -0.5], label="a")
ax.set_xlabel("t [s]")
ax.legend()
_figures.save_figure(Path(sys.argv[1]), fig)
import matplotlib.artist as artist
from matplotlib.lines import Line2D
print(artist.kwdoc.__module__, "antialiased" in (Line2D.set.__doc__ or ""))
"""


def test_a_command_draws_the_same_figure_without_matplotlibs_property_docstrings(tmp_path):
    """``COMMAND_PROCESS`` skips only the ``set()`` docstrings of the classes matplotlib defines
    while acdrive imports it: the PNG is byte for byte the one a Python session draws, and
    ``kwdoc`` is matplotlib's own again afterwards."""
    import subprocess
    import sys

    out = {}
    for command in (False, True):
        png = tmp_path / f"{command}.png"
        done = subprocess.run([sys.executable, "-c", _DRAW.format(command=command), str(png)],
                              capture_output=True, text=True, check=True)  # fmt: skip
        out[command] = (png.read_bytes(), done.stdout.split())
    assert out[True][0] == out[False][0]
    assert out[True][1][0] == out[False][1][0] == "matplotlib.artist"  # kwdoc put back
    # the property list is in a session's docstring, not in the command's
    assert (out[False][1][1], out[True][1][1]) == ("True", "False")
