"""The step-response metrics (``sim._step_response``) against closed forms: a first-order lag's
10-90 % rise time tau ln 9 = 2.197 tau and 2 % settling time tau ln 50, a second-order
response's overshoot exp(-zeta pi / sqrt(1 - zeta^2)) and settling time inside the last half
period before its envelope enters the band, a load-step dip of known depth and recovery time;
the events read from the scenario's profiles; the on-line kernel equal to the array version;
bad arguments refused by name."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from acdrive.errors import InputError
from acdrive.sim._step_response import (
    BAND_FRACTION,
    RECOVERY_MIN_RAD_S,
    event_params,
    events,
    initial_state,
    state_from_samples,
    step_response,
    step_response_update,
)

DT = 1e-5  # s, the logging period of the synthetic traces
T_STEP = 0.1  # s


def _one(t, w, w_ref, found, **kw):
    """The figures of the first event of ``found`` for the trace (t, w, w_ref)."""
    return step_response(t, w, w_ref, found, **kw)["events"][0]


def _step_profile(r0, r1, at=T_STEP, end=1.0):
    return [[0.0, r0], [at, r0], [at, r1], [end, r1]]


@pytest.mark.parametrize(("r0", "r1"), [(0.0, 100.0), (100.0, 40.0), (-20.0, 30.0)])
def test_first_order_rise_and_settling_times_are_the_closed_forms(r0, r1):
    """w = r1 + (r0 - r1) exp(-(t - t_a) / tau): rise 10-90 % = tau ln 9, settling into 2 % of
    the step = tau ln 50, no overshoot, no steady-state error; exact to one logging period."""
    tau, duration = 0.02, 0.5
    t = np.arange(0.0, duration, DT)
    after = t >= T_STEP
    w_ref = np.where(after, r1, r0)
    w = np.where(after, r1 + (r0 - r1) * np.exp(-(t - T_STEP) / tau), r0)
    e = _one(t, w, w_ref, events(_step_profile(r0, r1), {}, duration))
    assert e["rise_time_s"] == pytest.approx(tau * math.log(9.0), abs=2 * DT)
    assert e["settling_time_s"] == pytest.approx(tau * math.log(1 / BAND_FRACTION), abs=2 * DT)
    assert e["overshoot_pct"] == 0.0
    assert e["steady_state_error_rad_s"] == pytest.approx(0.0, abs=1e-6 * abs(r1 - r0))
    assert e["settling_band_rad_s"] == pytest.approx(BAND_FRACTION * abs(r1 - r0))


def test_steady_state_error_is_the_offset_a_loop_keeps():
    """A first-order loop reaching r1 - d (a proportional loop's offset d): the steady-state
    error is d; it overshoots nothing and, d being beyond the band, never settles."""
    tau, d, duration = 0.01, 5.0, 0.4
    t = np.arange(0.0, duration, DT)
    w_ref = np.where(t >= T_STEP, 100.0, 0.0)
    w = np.where(t >= T_STEP, (100.0 - d) * (1 - np.exp(-(t - T_STEP) / tau)), 0.0)
    e = _one(t, w, w_ref, events(_step_profile(0.0, 100.0), {}, duration))
    assert e["steady_state_error_rad_s"] == pytest.approx(d, rel=1e-9)
    assert e["settling_time_s"] is None


@pytest.mark.parametrize("zeta", [0.2, 0.45, 0.7])
def test_second_order_overshoot_and_settling_follow_the_closed_forms(zeta):
    """y = 1 - exp(-zeta w_n t) sin(w_d t + acos zeta) / sqrt(1 - zeta^2): overshoot
    exp(-zeta pi / sqrt(1 - zeta^2)), peak at pi / w_d; the last exit from the 2 % band lies
    within the last half period before the envelope exp(-zeta w_n t) / sqrt(1 - zeta^2) enters
    it; rise time 10-90 % from the closed form's own crossings (bisection)."""
    w_n, step, duration = 100.0, 50.0, 1.5
    w_d = w_n * math.sqrt(1 - zeta**2)

    def y(x):
        return 1 - np.exp(-zeta * w_n * x) * np.sin(w_d * x + math.acos(zeta)) / math.sqrt(
            1 - zeta**2
        )

    def crossing(level):  # y rises monotonically up to its peak at pi / w_d
        lo, hi = 0.0, math.pi / w_d
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if y(mid) < level else (lo, mid)
        return lo

    t = np.arange(0.0, duration, DT)
    after = t >= T_STEP
    w_ref = np.where(after, step, 0.0)
    w = np.where(after, step * y(np.maximum(t - T_STEP, 0.0)), 0.0)
    e = _one(t, w, w_ref, events(_step_profile(0.0, step), {}, duration))
    overshoot = 100 * math.exp(-zeta * math.pi / math.sqrt(1 - zeta**2))
    assert e["overshoot_pct"] == pytest.approx(overshoot, rel=1e-4)
    assert e["peak_at_s"] - T_STEP == pytest.approx(math.pi / w_d, abs=2 * DT)
    envelope = math.log(1 / (BAND_FRACTION * math.sqrt(1 - zeta**2))) / (zeta * w_n)
    assert envelope - math.pi / w_d < e["settling_time_s"] <= envelope + DT
    assert e["rise_time_s"] == pytest.approx(crossing(0.9) - crossing(0.1), abs=2 * DT)


def test_load_step_dip_and_recovery_are_the_closed_forms():
    """After a load step the error e = D x e^(1 - x), x = (t - t_a) / tau: the dip is D at
    t_a + tau; the speed is back in the band max(2 % of the reference, 2 rpm) where
    D x e^(1 - x) falls to it (x > 1, bisection); the steady-state error decays to 0."""
    D, tau, ref, t_load, duration = 10.0, 0.01, 100.0, 0.3, 0.6
    t = np.arange(0.0, duration, DT)
    x = np.maximum(t - t_load, 0.0) / tau
    w_ref = np.full(t.size, ref)
    w = ref - D * x * np.exp(1 - x)
    load = [[0.0, 0.0], [t_load, 0.0], [t_load, 2.0]]
    found = events(ref, {"load torque": (load, "N m")}, duration)
    assert [(f["kind"], f["start_s"]) for f in found] == [("load step", t_load)]
    e = _one(t, w, w_ref, found)
    band = max(BAND_FRACTION * ref, RECOVERY_MIN_RAD_S)
    lo, hi = 1.0, 50.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if D * mid * math.exp(1 - mid) > band else (lo, mid)
    assert e["dip_rad_s"] == pytest.approx(D, rel=1e-8)
    assert e["dip_at_s"] == pytest.approx(t_load + tau, abs=DT)
    assert e["recovery_band_rad_s"] == pytest.approx(band)
    assert e["recovery_time_s"] == pytest.approx(lo * tau, abs=2 * DT)
    assert e["steady_state_error_rad_s"] == pytest.approx(0.0, abs=1e-6)


def test_events_are_the_changes_the_profiles_declare():
    """A step, a ramp (its sloped segments one change) and a load step, each judged up to the
    next; a load given at t = 0 is the starting condition; a change after the run is none."""
    reference = [[0.0, 0.0], [0.1, 0.0], [0.1, 50.0], [0.5, 50.0], [0.6, 80.0], [0.7, 100.0],
                 [5.0, 100.0], [5.0, 0.0]]  # fmt: skip
    load = [[0.0, 1.0], [0.9, 1.0], [0.9, 3.0]]
    found = events(reference, {"load torque": (load, "N m")}, 2.0)
    assert [(f["kind"], f["start_s"], f["stop_s"]) for f in found] == [
        ("reference change", 0.1, 0.5),
        ("reference change", 0.5, 0.9),
        ("load step", 0.9, 2.0),
    ]
    assert (found[1]["r0"], found[1]["r1"]) == (50.0, 100.0)
    assert "ramp over 0.2 s" in found[1]["what"]
    assert found[2]["r0"] == found[2]["r1"] == 100.0
    assert found[0]["steady_from_s"] == pytest.approx(0.5 - 0.1 * 0.4)


@settings(max_examples=40, deadline=None)
@given(n=st.integers(1, 600), seed=st.integers(0, 2**31 - 1), every=st.integers(1, 4))
def test_array_figures_equal_the_kernel_the_batch_runs(n, seed, every):
    """``state_from_samples`` (a summary's) equals, bit for bit, the state the on-line kernel
    ``step_response_update`` leaves after the same samples in order (noisy speeds, repeated
    peaks, samples before the first and after the last event)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 1e-3 * every
    duration = float(t[-1] + 1e-3)
    reference = [[0.0, 0.0], [0.2 * duration, 0.0], [0.2 * duration, 10.0],
                 [0.5 * duration, 10.0], [0.6 * duration, -5.0]]  # fmt: skip
    load = [[0.0, 0.0], [0.8 * duration, 0.0], [0.8 * duration, 1.0]]
    found = events(reference, {"load torque": (load, "N m")}, duration)
    w_ref = np.interp(t, [r[0] for r in reference], [r[1] for r in reference])
    w = w_ref + np.round(rng.normal(0.0, 2.0, size=n))
    p = event_params(found)
    s = initial_state(len(found))
    for k in range(n):
        step_response_update(t[k], w[k], w_ref[k], p, s)
    assert np.array_equal(s, state_from_samples(t, w, w_ref, p))


@pytest.mark.parametrize("name", ["band", "steady_fraction"])
@pytest.mark.parametrize("value", [0.0, -0.02, 1.0, math.nan])
def test_a_band_or_window_outside_zero_to_one_is_refused_by_name(name, value):
    with pytest.raises(InputError, match=f"^{name}: ") as info:
        events([[0.0, 0.0], [0.1, 1.0]], {}, 1.0, **{name: value})
    assert "\n" not in str(info.value)


def test_a_step_response_metric_without_reference_is_refused_by_name():
    from acdrive.batch import Reducer, check_reducer

    with pytest.raises(InputError, match=r"^metrics\[0\]\.reference: "):
        check_reducer(Reducer("speed_step", "step_response", "shaft.w"), "metrics[0]")
