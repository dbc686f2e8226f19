"""Results in a notebook: a one-line repr whose numbers are the result's own, and ``plot()``
drawing the logged signals themselves (checked through the lines' data)."""

from __future__ import annotations

import dataclasses

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

from acdrive.drives.cage_im._drive import IMDrive
from acdrive.drives.dfim._setup import simulate
from acdrive.scenarios._loader import load_scenario


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
    peak = dfim_result.summary()["peak_rotor_current_a"]
    assert f"{peak:.3g} A (phase peak)" in text
    assert f"{float(np.max(dfim_result.speed_rpm())):.0f} rpm" in text


def test_dfim_plot_draws_the_logged_signals(dfim_result):
    fig = dfim_result.plot()
    ax_w, ax_i, ax_t = fig.axes
    speed = next(line for line in ax_w.lines if line.get_label() == "speed")
    np.testing.assert_array_equal(speed.get_ydata(), dfim_result.speed_rpm())
    rotor = next(line for line in ax_i.lines if line.get_label() == "rotor |i_R|")
    np.testing.assert_allclose(
        np.max(rotor.get_ydata()), dfim_result.summary()["peak_rotor_current_a"]
    )
    assert ax_t.get_xlabel() == "time [s]"
    matplotlib.pyplot.close(fig)


def test_im_repr_and_plot(im_result):
    text = repr(im_result)
    assert "\n" not in text and "mode current" in text
    assert f"{im_result.current_rms_error():.3g} A" in text
    fig = im_result.plot()
    assert len(fig.axes) == 2  # current mode: current and torque
    line = next(ln for ln in fig.axes[0].lines if ln.get_label() == "i_alpha")
    np.testing.assert_allclose(line.get_ydata(), im_result.phase_peak("i_s").real)
    matplotlib.pyplot.close(fig)


# --- a system assembled from parts ---------------------------------------------------------------


@pytest.fixture(scope="module")
def system_result():
    from acdrive.control._open_loop import VoltageProgram
    from acdrive.machines._cage_part import CageInductionMachine
    from acdrive.machines._induction import UGALDE_IM_300W
    from acdrive.plant._converter import AveragedConverter
    from acdrive.plant._mechanics import PrescribedSpeed
    from acdrive.sim._system import System

    im = CageInductionMachine.from_params("im", UGALDE_IM_300W)
    shaft = PrescribedSpeed("shaft", w=0.0)
    program = VoltageProgram("program", V_pk=50.0, f=50.0)
    inverter = AveragedConverter("inverter", V_dc=310.0)
    system = System([im, shaft, program, inverter], [(program.out.v_ref, inverter.inp.v_ref),
                    (inverter.out.v, im.inp.v_s), (shaft.out.w, im.inp.w)])  # fmt: skip
    result = system.compile().run(0.04, 1e-4, 4, log=[im.out.i_s, im.out.tau_e, shaft.out.w])
    return im, shaft, result


def test_system_repr_counts_what_the_run_logged(system_result):
    _, _, result = system_result
    text = repr(result)
    assert "\n" not in text
    assert f"{result.steps} samples, logged {result.t.size}" in text
    assert f"{len(result.columns)} columns" in text
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
