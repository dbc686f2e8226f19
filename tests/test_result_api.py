"""Results in a notebook: a one-line repr whose numbers are the result's own, and ``plot()``
drawing the logged signals themselves (checked through the lines' data)."""

from __future__ import annotations

import dataclasses

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

from acdrive._frames import K_PEAK
from acdrive.drives.cage_im import IMDrive
from acdrive.drives.dfim import simulate
from acdrive.drives.dfim._result import LOG_NAMES, N_LOG, SIGNALS, DriveResult
from acdrive.machines import CageInductionMachine
from acdrive.scenarios import load_scenario
from acdrive.sim._result import envelope


@pytest.fixture(scope="module")
def dfim_result():
    setup = dataclasses.replace(load_scenario("bodson-step"), duration=0.6)
    return simulate(setup)


@pytest.fixture(scope="module")
def im_result():
    setup = dataclasses.replace(load_scenario("im-locked-rotor"), duration=0.02)
    return IMDrive(setup).run()


def test_dfim_repr_is_one_line_with_the_results_numbers(dfim_result):
    text = repr(dfim_result)
    assert "\n" not in text and len(text) < 300 and "'bodson-step'" in text
    assert f"{dfim_result.t.size} samples" in text and "parts (dfim0)" in text
    peak = dfim_result.summary["peak_rotor_current_a"]
    assert f"{peak:.3g} A (phase peak)" in text
    assert f"{float(np.max(dfim_result.speed_rpm())):.0f} rpm" in text


def test_dfim_plot_draws_the_logged_signals_on_one_time_axis(dfim_result):
    fig = dfim_result.plot()
    ax_w, ax_i, ax_t = fig.axes  # one axis per unit: rad/s, A, N m
    assert [ax.get_ylabel() for ax in fig.axes] == ["[rad/s]", "[A]", "[N m]"]
    speed = next(line for line in ax_w.lines if line.get_label() == "dfim0.w")
    np.testing.assert_array_equal(speed.get_ydata(), dfim_result.signal("w"))
    rotor = next(line for line in ax_i.lines if line.get_label() == "dfim0.i_r_mag")
    np.testing.assert_allclose(
        np.max(rotor.get_ydata()) / K_PEAK, dfim_result.summary["peak_rotor_current_a"]
    )
    assert ax_t.get_xlabel() == "time [s]"
    assert ax_w.get_shared_x_axes().joined(ax_w, ax_t)
    matplotlib.pyplot.close(fig)


def test_dfim_per_part_access_is_the_old_signal(dfim_result):
    """``result.dfim.x`` (one motor: the kind reaches its only part) and ``result.dfim0.x`` are
    the arrays of ``signal(x)`` and of the drive's signal table, for every logged signal, with
    the unit and description of the signal's declaration."""
    assert dfim_result.parts == ["dfim0"]
    for j, name in enumerate(LOG_NAMES):
        expected = dfim_result.signals[:, 0, j]
        np.testing.assert_array_equal(getattr(dfim_result.dfim, name), expected)
        np.testing.assert_array_equal(getattr(dfim_result.dfim0, name), expected)
        np.testing.assert_array_equal(dfim_result.signal(name, 0), expected)
        assert (dfim_result.unit(name), dfim_result.description(name)) == SIGNALS[name]
    assert dfim_result.dfim.units["i_s_mag"] == "A"
    assert "space-vector magnitude" in dfim_result.dfim.descriptions["i_s_mag"]
    with pytest.raises(AttributeError, match="no signal 'psi'"):
        _ = dfim_result.dfim.psi


def test_two_motors_are_reached_by_part_name_not_by_kind():
    """Several motors: ``dfim0``, ``dfim1`` (the machine parts' names); the kind alone is
    ambiguous and the error names the parts; ``signal(name, k)`` reads motor k."""
    rng = np.random.default_rng(1)
    t = np.arange(50) * 1e-3
    signals = rng.normal(size=(50, 2, N_LOG))
    result = DriveResult("two", t, signals, 1e-3, np.zeros(1))
    assert result.parts == ["dfim0", "dfim1"]
    np.testing.assert_array_equal(result.dfim1.w, signals[:, 1, LOG_NAMES.index("w")])
    np.testing.assert_array_equal(result.signal("w", 1), signals[:, 1, LOG_NAMES.index("w")])
    np.testing.assert_array_equal(result.signal("dfim1.tau_e"), result.dfim1.tau_e)
    np.testing.assert_array_equal(result.signal("w"), result.dfim0.w)  # bare name: motor 0
    with pytest.raises(AttributeError, match="ambiguous: name one of dfim0, dfim1"):
        _ = result.dfim
    assert [c.name for c in result.table_columns()][:3] == ["t", "w_m1", "w_ref_m1"]


def test_im_repr_and_plot(im_result):
    text = repr(im_result)
    assert "\n" not in text and "mode current" in text
    assert f"{im_result.current_rms_error():.3g} A" in text
    fig = im_result.plot()
    assert len(fig.axes) == 2  # current mode: current (A) and torque (N m)
    line = next(ln for ln in fig.axes[0].lines if ln.get_label() == "im.i_s (re)")
    np.testing.assert_array_equal(line.get_ydata(), im_result.signal("i_s").real)
    matplotlib.pyplot.close(fig)


def test_im_per_part_access_is_the_old_signal(im_result):
    """``result.im.x`` is ``signals[x]``: complex space vectors stay complex, units and
    descriptions those of the logged ports' declarations."""
    assert im_result.parts == ["im"]
    for name, values in im_result.signals.items():
        np.testing.assert_array_equal(getattr(im_result.im, name), values)
        np.testing.assert_array_equal(im_result.signal(name), values)
    assert np.iscomplexobj(im_result.im.i_s)
    i_s = CageInductionMachine.OUTPUTS.var("i_s")
    assert im_result.unit("i_s") == i_s.unit == "A"
    assert im_result.im.descriptions["i_s"].startswith(i_s.doc)


@pytest.mark.parametrize("fmt", ["parquet", "csv", "mat"])
def test_im_view_save_round_trip(im_result, fmt, tmp_path):
    """The cage-IM view writes its own layout (components ``_alpha_sv`` / ``_beta_sv``) through
    the one ``save``; every format reads back the values of the view's signals."""
    paths = im_result.save(tmp_path, fmt)
    assert [p.name for p in paths] == [f"data.{fmt}", "columns.md"]
    if fmt == "parquet":
        import pyarrow.parquet as pq

        table = pq.read_table(paths[0])
        read = {n: table.column(n).to_numpy() for n in table.column_names}
        assert table.schema.field("i_s_alpha_sv").metadata[b"unit"] == b"A"
    elif fmt == "csv":
        import pandas as pd

        frame = pd.read_csv(paths[0])
        read = {n: frame[n].to_numpy() for n in frame.columns}
    else:
        import scipy.io

        data = scipy.io.loadmat(paths[0])["data"]
        read = {n: data[n][0, 0][:, 0] for n in data.dtype.names}
    np.testing.assert_allclose(read["i_s_alpha_sv"], im_result.im.i_s.real, rtol=1e-15)
    np.testing.assert_allclose(read["i_s_beta_sv"], im_result.im.i_s.imag, rtol=1e-15)
    np.testing.assert_allclose(read["tau_e"], im_result.im.tau_e, rtol=1e-15)
    assert list(read) == [c.name for c in im_result.table_columns()]


def test_summary_is_attached_and_computed_once(dfim_result, im_result):
    assert dfim_result.summary is dfim_result.summary  # computed on first read, then kept
    assert dfim_result.summary["scenario"] == "bodson-step"
    assert im_result.summary["controller"] == im_result.setup.current_control.controller


def test_pm_run_per_part_access_and_summary():
    """The PM drive returns the engine's result with its summary attached; every logged port
    is reached as ``result.<part>.<output>`` with the same array as ``signal(port)``."""
    from acdrive.drives.pm import build, builtin, run

    setup = dataclasses.replace(builtin("pm-bly171d-speed"), duration=0.01)
    result, summary = run(setup)
    assert result.summary is summary
    log = build(setup).log
    assert np.iscomplexobj(result.part(log["i_s"].part.name).i_s)
    for port in log.values():
        part, name = port.path.split(".")
        values = getattr(result.part(part), name)
        np.testing.assert_array_equal(values, result.signal(port))
        assert result.unit(port) == port.var.unit
        assert result.description(port) == port.var.doc


def test_envelope_keeps_each_bins_min_and_max():
    """A long signal is drawn per time bin by its minimum and maximum at the times they occur:
    the drawn points of each bin are exactly the bin's extremes of the data."""
    rng = np.random.default_rng(0)
    t = np.arange(10_001) * 1e-4
    y = np.sin(2 * np.pi * 7 * t) + 0.1 * rng.normal(size=t.size)
    bins = 37
    x, drawn = envelope(t, y, bins)
    assert drawn.size == 2 * bins
    edges = np.linspace(0, y.size, bins + 1).astype(np.int64)
    for b in range(bins):
        chunk = y[edges[b] : edges[b + 1]]
        pair = drawn[2 * b : 2 * b + 2]
        assert sorted(pair) == [chunk.min(), chunk.max()]
    assert np.all(np.diff(x) >= 0)  # in time order
    at = np.searchsorted(t, x)  # drawn at the data's own times
    np.testing.assert_array_equal(t[at], x)
    np.testing.assert_array_equal(y[at], drawn)
    _, short_y = envelope(t[:50], y[:50], bins)
    np.testing.assert_array_equal(short_y, y[:50])


def test_plot_draws_the_envelope(dfim_result):
    fig = dfim_result.plot(["w"], bins=40)
    (line,) = fig.axes[0].lines
    w = dfim_result.signal("w")
    edges = np.linspace(0, w.size, 41).astype(np.int64)
    drawn = line.get_ydata().reshape(40, 2)
    for b in range(40):
        chunk = w[edges[b] : edges[b + 1]]
        assert (drawn[b].min(), drawn[b].max()) == (chunk.min(), chunk.max())
    matplotlib.pyplot.close(fig)


# --- a system assembled from parts ---------------------------------------------------------------


@pytest.fixture(scope="module")
def system_result():
    from acdrive.control import VoltageProgram
    from acdrive.machines import UGALDE_IM_300W, CageInductionMachine
    from acdrive.plant import AveragedConverter, PrescribedSpeed
    from acdrive.sim import System

    im = CageInductionMachine.from_params("im", UGALDE_IM_300W)
    shaft = PrescribedSpeed("shaft", w=0.0)
    program = VoltageProgram("program", V_pk=50.0, f=50.0)
    inverter = AveragedConverter("inverter", V_dc=310.0)
    system = System([im, shaft, program, inverter], [(program.out.v_ref, inverter.inp.v_ref),
                    (inverter.out.v, im.inp.v_s), (shaft.out.w, im.inp.w)])  # fmt: skip
    result = system.compile().run(0.04, 1e-4, 4, log=[im.out.i_s, im.out.tau_e, shaft.out.w])
    return im, shaft, result


@pytest.mark.slow
def test_system_repr_counts_what_the_run_logged(system_result):
    _, _, result = system_result
    text = repr(result)
    assert "\n" not in text
    assert f"{result.t.size} samples" in text and f"{result.steps} steps" in text
    assert "3 signals of 2 parts (im, shaft)" in text
    assert "events raised: none" in text  # an averaged converter within its limits


def test_system_plot_groups_the_signals_by_unit(system_result):
    im, _, result = system_result
    fig = result.plot()
    units = {result.units[c] for c in result.columns}
    assert len(fig.axes) == len(units)  # A, N m, rad/s
    lines = {line.get_label(): line for ax in fig.axes for line in ax.lines}
    np.testing.assert_array_equal(lines["im.i_s (re)"].get_ydata(), result.signal(im.out.i_s).real)
    np.testing.assert_array_equal(lines["im.tau_e"].get_ydata(), result.signal("im.tau_e"))
    matplotlib.pyplot.close(fig)
    with pytest.raises(KeyError, match="not logged"):
        result.plot(["im.psi_s"])


@pytest.mark.parametrize("fmt", ["parquet", "csv", "mat"])
def test_system_save_keeps_values_units_and_descriptions(system_result, fmt, tmp_path):
    im, _, result = system_result
    paths = result.save(tmp_path / "out", fmt)
    assert [p.name for p in paths] == [f"data.{fmt}", "columns.md"]
    sep = "_" if fmt == "mat" else "."
    i_s_re = f"im{sep}i_s{sep}re"
    if fmt == "parquet":
        import pyarrow.parquet as pq

        table = pq.read_table(paths[0])
        values = table.column(i_s_re).to_numpy()
        assert table.schema.field(i_s_re).metadata[b"unit"] == b"A"
    elif fmt == "csv":
        import pandas as pd

        values = pd.read_csv(paths[0])[i_s_re].to_numpy()
    else:
        import scipy.io

        values = scipy.io.loadmat(paths[0])["data"][i_s_re][0, 0][:, 0]
    np.testing.assert_allclose(values, result.signal(im.out.i_s).real, rtol=1e-15)
    notes = paths[1].read_text()
    assert f"| `{i_s_re}` | A | {im.OUTPUTS.var('i_s').doc} (real part) |" in notes


def test_system_per_part_access_units_and_descriptions(system_result):
    im, _, result = system_result
    assert result.parts == ["im", "shaft"]
    np.testing.assert_array_equal(result.im.i_s, result.signal(im.out.i_s))
    assert np.iscomplexobj(result.im.i_s)
    np.testing.assert_array_equal(result.shaft.w, result.signal("shaft.w"))
    np.testing.assert_array_equal(result.signal("tau_e"), result.im.tau_e)  # one part logs it
    i_s = im.OUTPUTS.var("i_s")
    assert result.im.units == {"i_s": i_s.unit, "tau_e": im.OUTPUTS.var("tau_e").unit}
    assert result.im.descriptions["i_s"] == i_s.doc
    assert result.summary == {}  # the engine's run: no drive, no summary until one is attached
    frame = result.to_dataframe()
    assert frame.attrs["units"]["im.i_s.re"] == "A"
    np.testing.assert_array_equal(frame["im.i_s.im"], result.im.i_s.imag)
    with pytest.raises(AttributeError, match="no attribute or part 'dfim'"):
        _ = result.dfim
