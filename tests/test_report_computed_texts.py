"""Sentences of the ICAD and IM reports that state a finding are computed from numbers: the
rounding analysis of the printed matrices, the reading of the printed C of Ugalde-Loo (80), the
Figs. 18/20 overshoot order and the explanation of the overshoot gap, round-off printed as a
bound, and the linear step response with a loop delay."""

from __future__ import annotations

import numpy as np
import pytest

from acdrive import _verdicts as V
from acdrive._report import icad_targets as targets
from acdrive._report.icad.rounding import matrix_entries, rounding_reach, rounding_rows
from acdrive._report.icad.ugalde_im import c_of_80_row
from acdrive._report.im import settings as im_settings
from acdrive._report.im import verdicts as im_verdicts
from acdrive.control import PAPER_20
from acdrive.drives.cage_im._outputs import delayed_linear_step_response, linear_step_response
from acdrive.machines import DELORENZO_IM, DELORENZO_IM_13, UGALDE_IM_300W

# --- round-off printed as a bound ---------------------------------------------------------------


def test_roundoff_below_the_floor_is_printed_as_the_bound_and_the_verdict_is_unchanged():
    plain = V.within_rel(1.0 + 4e-15, 1.0, 1e-7)
    floored = V.within_rel(1.0 + 4e-15, 1.0, 1e-7, floor=1e-12)
    assert plain.holds and floored.holds
    assert "e-15" in plain.text and "< 1e-12" in floored.text and "e-15" not in floored.text
    # an exact 0 is round-off too (another machine may give 1e-16): the same bound
    assert "relative difference < 1e-12," in V.within_rel(1.0, 1.0, 1e-7, floor=1e-12).text
    assert "relative difference 0," in V.within_rel(1.0, 1.0, 1e-7).text  # no floor: as it is
    assert "1e-10" in V.within_rel(1.0 + 1e-10, 1.0, 1e-7, floor=1e-12).text  # above the floor
    assert "< 1e-12" in V.error_within(4e-16, 1e-8, floor=1e-12).text
    assert not V.error_within(1e-6, 1e-8, floor=1e-12).holds
    d = V.printed_digits("359.2", 359.2 * (1 + 2e-15), floor=1e-12)
    assert d.holds and "< 1e-12 relative" in d.text
    assert "< 1e-12" not in V.printed_digits("359.2", 359.21, floor=1e-12).text


# --- rounding of the printed parameters ----------------------------------------------------------


@pytest.fixture(scope="module")
def reach13():
    return rounding_reach(targets.DELORENZO_APPENDIX_PRINTED, targets.DELORENZO_MATRIX_13)


def test_matrix_entries_are_those_of_the_state_space():
    e = matrix_entries([16.2, 23.2, 1.44, 1.5, 1.42])
    sigma_ls = 1.44 - 1.42**2 / 1.5
    assert e[5] == pytest.approx(1.0 / sigma_ls, rel=1e-12)  # b_11 = 1/(sigma L_s)
    assert e[4] == pytest.approx(-23.2 / 1.5, rel=1e-12)  # a_33 = -R_r/L_r
    assert e[3] == pytest.approx(1.42 * 23.2 / 1.5, rel=1e-12)  # a_31 = L_m R_r/L_r


def test_appendix_rounding_reaches_13_and_the_point_is_a_certificate(reach13):
    lo = np.array([16.15, 23.15, 1.435, 1.45, 1.415])
    hi = np.array([16.25, 23.25, 1.445, 1.55, 1.425])
    assert np.all(reach13.point >= lo - 1e-12) and np.all(reach13.point <= hi + 1e-12)
    assert reach13.reachable and reach13.best_ratio <= 1.0
    # the certificate: every entry at the point rounds to the printed one
    assert all(v.holds for v in reach13.entry_verdicts().values())
    # while the printed Appendix values themselves do not give (13) (the report's rows above)
    e = matrix_entries([16.2, 23.2, 1.44, 1.5, 1.42])
    assert abs(e[5] - 9.7) > 0.05


def test_entry_ranges_are_the_analytic_extremes(reach13):
    # a_33 = -R_r / L_r is monotone in both: its extremes are at the box corners
    assert reach13.ranges[4, 0] == pytest.approx(-23.25 / 1.45, rel=1e-9)
    assert reach13.ranges[4, 1] == pytest.approx(-23.15 / 1.55, rel=1e-9)
    # a_31 = L_m R_r / L_r
    assert reach13.ranges[3, 0] == pytest.approx(1.415 * 23.15 / 1.55, rel=1e-9)
    assert reach13.ranges[3, 1] == pytest.approx(1.425 * 23.25 / 1.45, rel=1e-9)


def test_an_unreachable_printed_matrix_is_reported_as_not_reached():
    far = targets.PrintedIMMatrix("test", "(x)", -359.2, 141.8, 9.2, 21.9, -20.0, 9.7)
    reach = rounding_reach(targets.DELORENZO_APPENDIX_PRINTED, far)
    assert not reach.reachable and reach.best_ratio > 1.0
    rows = rounding_rows(reach, "Appendix", "(x)")
    assert rows[-1].note.startswith("not reached")
    assert "OUTSIDE" in rows[4].note  # a_33's interval lies outside its attainable range


def test_80_is_reachable_from_the_rounded_sec_45_parameters():
    reach = rounding_reach(targets.UGALDE_IM_PRINTED, targets.UGALDE_IM_MATRIX_80)
    assert reach.reachable
    assert rounding_rows(reach, "sec. 4.5", "(80)")[-1].note.startswith("reachable")


# --- C of (80) -------------------------------------------------------------------------------


def test_c_of_80_reading_is_computed_from_the_printed_rows(monkeypatch):
    row = c_of_80_row(UGALDE_IM_300W)
    assert "rows of 3, 4, 4 entries" in row.note and "typesetting misprint" in row.note
    assert "1 -> 1; 2 -> 2; 3 -> 2" in row.note
    monkeypatch.setattr(targets, "UGALDE_IM_C_80_ROWS", ((1, 0, 0, 1), (0, 1, 0, 0)))
    other = c_of_80_row(UGALDE_IM_300W)
    assert "open" in other.note and "misprint" not in other.note


# --- Figs. 18/20 ---------------------------------------------------------------------------------


def test_overshoot_order_flips_at_its_stated_tolerance():
    tol = im_settings.TOLERANCES["overshoot_order_abs"]
    yes = im_verdicts.overshoot_order(0.30, 0.30 - 2 * tol, tol, "A more", "A not more")
    no = im_verdicts.overshoot_order(0.30, 0.30 - 0.5 * tol, tol, "A more", "A not more")
    assert yes.holds and not no.holds
    assert f"at least {im_settings.pct(tol)}" in yes.text and "A not more" in no.text


def _numbers(sim, lin, delayed):
    n = {"steps_hold_delay_s": 1e-4}
    for label in ("icad", "inner_pi", "high_ki_pi"):
        n[f"step_overshoot_{label}"] = sim[label]
        n[f"step_overshoot_linear_{label}"] = lin[label]
        n[f"step_overshoot_linear_delayed_{label}"] = delayed[label]
    return n


NAMES = {"icad": "(20)", "inner_pi": "inner PI", "high_ki_pi": "high PI"}


def test_hold_explanation_only_where_the_delay_model_closes_the_gap():
    t = im_settings.TOLERANCES
    sim = {"icad": 0.22, "inner_pi": 0.09, "high_ki_pi": 0.45}
    lin = {"icad": 0.21, "inner_pi": 0.09, "high_ki_pi": 0.32}
    closes = im_verdicts.hold_explanation(n=_numbers(sim, lin, dict(sim)), t=t, names=NAMES)
    assert "accounts for the difference" in closes and "open" not in closes
    fails = im_verdicts.hold_explanation(
        _numbers(sim, lin, {"icad": 0.31, "inner_pi": 0.10, "high_ki_pi": 0.55}), t, NAMES
    )
    assert "cause of the gap is open" in fails and "accounts for" not in fails
    assert "moves (20) beyond the tolerance" in fails
    none = im_verdicts.hold_explanation(_numbers(sim, sim, sim), t, NAMES)
    assert "no gap to explain" in none


def test_delayed_step_response_is_causal_and_tends_to_the_continuous_one():
    t = np.arange(0.0, 0.01, 2e-5)
    continuous = linear_step_response(DELORENZO_IM_13, 375.0, PAPER_20, t)
    tiny = 2e-6
    short = delayed_linear_step_response(DELORENZO_IM_13, 375.0, PAPER_20, t, tiny, substeps=1)
    # a delay shifts the response by at most (its largest slope) x (the delay); the largest slope
    # is the initial one, k(inf) / (sigma L_s) per unit step
    slope = float(PAPER_20.D[0, 0]) / (DELORENZO_IM_13.sigma * DELORENZO_IM_13.L_s)
    assert np.max(np.abs(short - continuous)) <= 1.1 * slope * tiny
    delay = 1e-4
    late = delayed_linear_step_response(DELORENZO_IM, 375.0, PAPER_20, t, delay)
    assert np.all(late[t < delay] == 0.0)  # nothing reaches the plant before the delay
    assert abs(late[-1, 0] - 1.0) < 0.02  # integral action: the step is reached
