"""Results in a notebook: a one-line repr whose numbers are the result's own, and ``plot()``
drawing the logged signals themselves (checked through the lines' data)."""

from __future__ import annotations

import dataclasses

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

from acdrive.scenarios.loader import load_scenario
from acdrive.sim.im_drive import IMDrive
from acdrive.sim.setup import simulate


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
