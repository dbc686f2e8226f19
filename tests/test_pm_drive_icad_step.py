"""Seed 001's PMSG current subsystem in the time domain (``drives/pm/_icad_step.py``, scenario
``pm-pmsg-2mw-icad-coupling``): a step on the d reference under ICAD's diagonal PI, the
cross-coupling into i_q measured from the step response by (S) and compared with ICAD's (10)
(``analysis._coupling.icad_coupling``) at the coupling report's frequencies."""

import math

import numpy as np
import pytest

from acdrive._report.im import settings as report
from acdrive.analysis import CouplingSetup, icad_coupling, measure_coupling, pmsg_pi
from acdrive.control import LTI
from acdrive.drives.pm import _icad_step as st
from acdrive.drives.pm import run_scenario
from acdrive.drives.pm._schema import SCENARIO_DIR, builtin, load
from acdrive.errors import InputError
from acdrive.machines import PMSG_2MW

NAME = "pm-pmsg-2mw-icad-coupling"


@pytest.fixture(scope="module")
def step():
    return st.run(builtin(NAME))


def test_scenario_is_the_coupling_report_s_comparison():
    setup = builtin(NAME)
    assert setup.machine == PMSG_2MW
    assert setup.electrical_speed == pytest.approx(report.PMSG_SPEED, rel=1e-15)
    assert setup.bandwidth == report.PMSG_BANDWIDTH
    assert setup.frequencies == report.PMSG_FREQUENCIES
    assert setup.step == report.PMSG_AMPLITUDE
    k, ref = setup.controller, pmsg_pi(PMSG_2MW, report.PMSG_BANDWIDTH)
    w = np.array(setup.frequencies)
    np.testing.assert_allclose(k.freqresp(w), ref.freqresp(w), rtol=1e-15)
    # the step lies in the middle of a sample, where (S) puts it
    assert (setup.step_time / setup.sample_time) % 1.0 == pytest.approx(0.5, abs=1e-6)


def test_pi_gains_are_read_off_the_controller():
    a = 1000.0
    K_P, K_I = st.pi_gains(pmsg_pi(PMSG_2MW, a))
    assert (K_P, K_I) == pytest.approx((a * PMSG_2MW.L_d, a * PMSG_2MW.R_s), rel=1e-15)
    with pytest.raises(InputError, match="controller"):
        st.pi_gains(LTI.paper_20())


def test_step_transfer_of_a_first_order_step_response():
    """(S) on the exact step response 1 - e^{-(t - t_0) / tau} of 1 / (tau s + 1): the transfer
    function, to the order (w T)^2 of the piecewise-linear interpolation (and the tail e^-50)."""
    tau, T, t_0 = 0.01, 1e-5, 0.002
    t = np.arange(0.0, t_0 + 50 * tau, T)
    y = np.where(t >= t_0, 1.0 - np.exp(-(t - t_0) / tau), 0.0)
    w = np.array([10.0, 100.0, 1000.0, 5000.0])
    H = st.step_transfer(t, y, t_0, w)
    np.testing.assert_allclose(H, 1.0 / (1.0 + 1j * w * tau), rtol=(w.max() * T) ** 2)


def test_measured_coupling_is_icad_s_10(step):
    setup, s = step.setup, step.summary
    W = np.array(setup.frequencies)
    measured = st.step_transfer(step.t, step.step_response.imag, step.t_0, W)  # r_d -> i_q
    icad = icad_coupling(setup.machine, setup.electrical_speed, setup.controller, W)
    err = np.abs(measured - icad) / np.abs(icad)
    compared = W <= st.ICAD_W_MAX
    assert np.all(err[compared] <= st.ICAD_REL_TOL), err  # 1.4 % at most, at 1000 rad/s
    delayed = icad_coupling(setup.machine, setup.electrical_speed, setup.controller, W,
                            setup.delay)  # fmt: skip
    assert np.all(np.abs(measured - delayed) / np.abs(delayed) <= st.DELAYED_REL_TOL)
    # the summary's verdict and rows are read from the same numbers
    assert s["coupling_matches_icad"] is True
    assert s["relative_error_max"] == np.max(err[compared])
    rows_db = [r["measured_db"] for r in s["rows"]]
    np.testing.assert_allclose(rows_db, 20 * np.log10(np.abs(measured)), rtol=1e-14)
    # a strong coupling: about -11 ... -24 dB over the band (a sign the test is not trivial)
    assert np.all(20 * np.log10(np.abs(measured)) > -25.0)


def test_step_response_is_clean(step):
    s, dy = step.summary, step.step_response
    assert s["cross_before_step"] == 0.0  # superposition: the two runs agree before the step
    assert s["tail"] <= st.TAIL_TOL  # settled: d at the step, q back to 0 (integral action)
    assert dy[-1].real == pytest.approx(1.0, abs=st.TAIL_TOL)
    assert s["controller_limited_samples"] == 0
    # the peak of the cross-coupling in time is a fraction of the step, after the step
    assert 0.0 < s["cross_peak_per_step"] < 1.0 and s["cross_peak_after_step_s"] > 0.0
    # the direct channel is the closed loop's (1, 1) entry
    assert s["direct_relative_error_max"] <= st.DELAYED_REL_TOL


def test_run_scenario_returns_the_step_run_and_its_summary():
    # through the entry the registry calls (the compiled loop is cached by the fixture's run)
    result, summary = run_scenario(builtin(NAME))
    assert summary["coupling_matches_icad"] is True
    setup = builtin(NAME)
    assert result.t[-1] == pytest.approx(setup.duration - setup.sample_time, rel=1e-9)


def test_current_step_table_errors_name_the_field():
    import tomllib

    data = tomllib.loads((SCENARIO_DIR / f"{NAME}.toml").read_text())
    data["comparison"]["frequencies_rad_s"] = [20.0, -1.0]
    with pytest.raises(InputError, match=r"^comparison\.frequencies_rad_s: must be > 0"):
        load(data)
    data["comparison"]["frequencies_rad_s"] = [1e6]  # beyond pi / T_s
    with pytest.raises(InputError, match=r"^comparison\.frequencies_rad_s: must be positive"):
        load(data)
    data["comparison"]["frequencies_rad_s"] = [20.0]
    data["reference"]["step_time"] = 2.0
    with pytest.raises(InputError, match=r"^reference\.step_time: must be before"):
        load(data)
    data["reference"]["step_time"] = 0.01
    data["control"]["gain"] = 1.0
    with pytest.raises(InputError, match=r"^control\.gain: unknown key"):
        load(data)


@pytest.mark.slow  # the sinusoidal measurement compiles its own loop
def test_step_and_sinusoid_measurements_agree(step):
    """The coupling measured two ways in simulation: from this step (S) and by the sinusoidal
    injection of ``analysis._coupling.measure_coupling`` (its own loop: Tustin controller in the
    stationary frame), each against (10) with the hold's delay and against each other."""
    setup = step.setup
    W = (200.0, 1000.0)
    sine = measure_coupling(CouplingSetup(setup.machine, setup.controller, setup.electrical_speed,
                                          W, amplitude=setup.step, name="pmsg"))  # fmt: skip
    rows = {r["frequency_rad_s"]: r for r in step.summary["rows"]}
    for i, w in enumerate(W):
        r = rows[w]
        from_step = 10 ** (r["measured_db"] / 20) * np.exp(
            1j * math.radians(r["measured_phase_deg"])
        )
        assert abs(from_step - sine.measured[i]) / abs(sine.measured[i]) <= st.ICAD_REL_TOL / 4


def test_outcome_is_written_with_its_summary(tmp_path):
    import json

    from acdrive.drives.pm import _entry

    setup = builtin(NAME)
    assert _entry.runs(setup) == 2
    seen = []
    outcome = _entry.run_outcome(setup, on_run=seen.append)
    assert seen == ["step and base"] and set(outcome.results) == {"step", "base"}
    summary = _entry.write(outcome, tmp_path, figures=False, fmt="csv")
    assert json.loads((tmp_path / "summary.json").read_text()) == summary
    assert (tmp_path / "step" / "data.csv").exists() and (tmp_path / "base" / "data.csv").exists()
    first, rows = _entry.headline(outcome, summary)
    # three summary rows, one per injected frequency, and the timing row (simulation apart from
    # the compile or load of its loop)
    assert "matches ICAD" in first and len(rows) == 3 + len(setup.frequencies) + 1
    assert rows[-1][0] == "simulation" and "simulated in" in rows[-1][1]
