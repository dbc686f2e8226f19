"""Limit-cycle quantities rounded to their spread, and steady-state claims gated by settling
(the Bodson report's bench-converter side effect)."""

import math

import numpy as np
import pytest

from acdrive._report.limit_cycle_summary import Shown
from acdrive._spread import (
    mean_and_spread,
    order_of_magnitude,
    peak_spread,
    round_to_spread,
    rounding_step,
)
from acdrive._verdicts import judge_settling
from acdrive.drives.dfim._converter_effect import SideEffect, steady_settling, steady_stretches


@pytest.mark.parametrize(
    "value, spread, text",
    [
        (12.837, 0.21, "13"),
        (12.837, 0.04, "12.8"),
        (12.837, 0.1, "12.8"),
        (1234.0, 40.0, "1200"),
        (-0.04, 0.3, "0"),
        (-12.84, 0.02, "-12.8"),
        (-12.84, 0.01, "-12.84"),
    ],
)
def test_round_to_spread(value, spread, text):
    assert round_to_spread(value, spread) == text


def test_round_to_spread_keeps_deterministic_numbers_and_signs():
    assert round_to_spread(-12.8349, 0.0, ".2f") == "-12.83"
    assert round_to_spread(2.6, 0.3, sign=True) == "+3"
    assert round_to_spread(math.nan, 1.0) == "n/a"
    assert rounding_step(0.21) == 1.0 and rounding_step(0.0) == 0.0


def test_mean_and_spread_of_subwindow_means():
    assert mean_and_spread(np.full(100, 3.0)) == (3.0, 0.0)
    x = np.repeat(np.arange(8.0), 10)  # sub-window means 0..7
    mean, spread = mean_and_spread(x, 8)
    assert mean == pytest.approx(3.5)
    assert spread == pytest.approx(np.std(np.arange(8.0), ddof=1) / np.sqrt(8))
    assert peak_spread(x, 8) == pytest.approx(np.std(np.arange(8.0), ddof=1))


def test_a_limit_cycle_mean_prints_the_same_after_a_tiny_perturbation():
    # two trajectories of one limit cycle that part ways (another platform's last bits): the
    # printed mean, rounded to the sub-window spread, is the same; the full mean is not
    t = np.arange(0.0, 2.0, 2e-4)
    rng = np.random.default_rng(1)
    a = -12.8 + 9.0 * np.sin(2 * np.pi * 47.3 * t) + rng.normal(0.0, 2.0, t.size)
    b = a + rng.normal(0.0, 0.05, t.size)
    (ma, sa), (mb, sb) = mean_and_spread(a), mean_and_spread(b)
    assert ma != mb
    assert round_to_spread(ma, sa) == round_to_spread(mb, sb)


def test_order_of_magnitude_and_shown_numbers():
    assert order_of_magnitude(0) == "0"
    assert order_of_magnitude(7) == order_of_magnitude(16) == "~1e1"
    assert order_of_magnitude(5577) == "~1e4"
    shown = Shown(7.436, "7")
    assert f"{shown:.3f}" == "7" and repr({"x": shown}) == "{'x': 7}"
    assert shown == pytest.approx(7.436)


def _effect(q_settled: bool, offset_settled: bool = True, q_s: float = 0.5) -> SideEffect:
    return SideEffect(
        mode="voltage",
        motor=0,
        samples=100,
        q_s=q_s,
        q_com=0.0,
        tau_com=1e-3,
        tau_e=1e-3,
        q_tolerance=3.74,
        oscillation_rpm=0.0,
        q_settling=judge_settling(0.1 if q_settled else 5.0, 1.0, 1.87),
        offset_settling=judge_settling(0.0 if offset_settled else 3.0, 1.0, 0.5),
    )


def test_steady_state_verdicts_hold_only_on_settled_states():
    assert _effect(True).reactive_power().holds
    unsettled = _effect(False).reactive_power()
    assert not unsettled.holds and unsettled.text.startswith("not settled")
    assert "holds" not in unsettled.text
    assert _effect(True, True).torque().holds
    assert not _effect(True, False).torque().holds
    # a settled departure stays a departure; an unsettled one is not judged at all
    assert "departs" in _effect(True, q_s=10.0).reactive_power().text
    assert "departs" not in _effect(False, q_s=10.0).reactive_power().text
    assert not _effect(True).q_against(_effect(False)).holds


def test_steady_settling_over_stretches():
    t = np.arange(0.0, 3.0, 1e-3)
    mask = (t > 0.5) & (t < 1.0) | (t > 2.0)
    assert [(s.start, s.stop) for s in steady_stretches(mask)] == [(501, 1000), (2001, 3000)]
    ripple = 0.3 * np.sin(2 * np.pi * 50 * t)
    assert steady_settling(t, 2.0 + ripple, mask, 0.1).settled
    # a drift of 1 per second: 1 over the 1 s stretch, beyond a 0.1 tolerance
    drifting = 2.0 + ripple + np.where(t > 2.0, t - 2.0, 0.0)
    s = steady_settling(t, drifting, mask, 0.1)
    assert not s.settled and s.drift == pytest.approx(1.0, rel=0.02)
    assert steady_settling(t, drifting, np.zeros(t.size, bool), 0.1) is None


def test_spread_over_stretches_ignores_the_change_of_operating_point():
    from acdrive._spread import mean_and_spread_over_stretches

    x = np.r_[np.full(800, 5.0), np.full(800, -20.0)]
    stretches = [slice(0, 800), slice(800, 1600)]
    mean, spread = mean_and_spread_over_stretches(x, stretches)
    assert mean == pytest.approx(-7.5) and spread == 0.0
    # a cycle whose sub-window means scatter by about 1 inside each stretch
    rng = np.random.default_rng(3)
    y = x + np.repeat(rng.normal(0.0, 1.0, 16), 100)
    _, spread = mean_and_spread_over_stretches(y, stretches)
    assert 0.4 / 4 < spread < 2.0 / 4  # standard error over 16 sub-windows


def test_a_comparison_finer_than_the_limit_cycle_is_not_decidable():
    from acdrive.drives.dfim._converter_effect import judged

    base = _effect(True)
    cycling = SideEffect(**{**base.__dict__, "q_s": 10.0, "q_spread": 5.0})  # step 10 > 3.74
    verdict = cycling.reactive_power()
    assert not verdict.holds and verdict.text.startswith("not decidable") and not judged(verdict)
    fine = SideEffect(**{**base.__dict__, "q_s": 10.0, "q_spread": 0.3})  # step 1 < 3.74
    assert judged(fine.reactive_power()) and "departs" in fine.reactive_power().text


def test_round_to_spread_keeps_the_leading_digit_and_shows_the_step():
    # a largest error of 14.2 whose cycle moves it by 14: not "0" but "10"
    assert round_to_spread(14.175, 14.0, leading_digit=True) == "10"
    assert round_to_spread(14.175, 14.0) == "0"
    assert round_to_spread(-12.84, 0.3, sign=True, show_step=True) == "-13 (+-1)"
    assert round_to_spread(0.004, 0.3, sign=True, show_step=True) == "+0 (+-1)"
