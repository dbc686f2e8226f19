"""The speed-error summary computed with array operations equals, bit for bit, the state the
compiled kernel the batch runs on line (``sim._metrics.speed_error_update``) leaves after taking
the same samples one by one: relay closings, excluded windows, peaks that repeat."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from acdrive.sim._metrics import (
    TrackingRule,
    speed_error_state,
    speed_error_state_by_kernel,
)


@settings(max_examples=60, deadline=None)
@given(
    n=st.integers(1, 400),
    seed=st.integers(0, 2**31 - 1),
    relay=st.booleans(),
    windows=st.integers(0, 3),
    quantised=st.booleans(),
)
def test_array_state_equals_the_kernel(n, seed, relay, windows, quantised):
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 1e-3
    w_ref = np.repeat(rng.normal(0.0, 50.0, size=n // 40 + 1), 40)[:n]
    w = w_ref + rng.normal(0.0, 2.0, size=n)
    if quantised:  # repeated |e| values: the first largest is the peak
        w = w_ref + np.round(rng.normal(0.0, 2.0, size=n))
    closed = (rng.random(n // 25 + 1) > 0.4).astype(float).repeat(25)[:n]
    starts = np.sort(rng.uniform(0.0, t[-1] + 1e-3, size=windows))
    rule = TrackingRule(
        windows=tuple((float(a), float(a + rng.uniform(0.0, 0.05))) for a in starts),
        slew_s_per_rad_s=float(rng.uniform(0.0, 1e-3)),
        settle_s=float(rng.uniform(0.0, 0.02)),
        relay=relay,
    )
    s_array, mask_array, until_array = speed_error_state(t, w, w_ref, closed, rule)
    s_kernel, mask_kernel, until_kernel = speed_error_state_by_kernel(t, w, w_ref, closed, rule)
    assert np.array_equal(s_array, s_kernel)
    assert np.array_equal(mask_array, mask_kernel)
    assert np.array_equal(until_array, until_kernel)


@settings(max_examples=200, deadline=None)
@given(
    k=st.one_of(st.integers(0, 10**6), st.integers(2**40, 2**40 + 10**6)),
    every=st.integers(1, 5000),
    T_s=st.sampled_from([1e-4, 2e-4, 1 / 3e3, 5e-5, 1e-3]),
)
def test_logged_time_is_the_integer_arithmetic_of_the_logged_rows(k, every, T_s):
    """The reducers' floating-point test of "sample k is logged" (it vectorises over lockstep
    lanes) gives the integer arithmetic of the logged rows, k % every and (k // every) T_s every,
    exactly: the same samples and the same times as ``SystemResult.t``."""
    from acdrive._reducer_parts import _logged_time

    t = k * T_s  # the loop's control time at sample k (t0 = 0)
    logged, t_log = _logged_time(t, T_s, float(every))
    n = int(t / T_s + 0.5)  # the sample index the time stands for
    assert logged == (n % every == 0)
    if logged:
        assert t_log == float(n // every) * T_s * every  # SystemResult.t: arange(rows) T_s every
    else:
        assert t_log == t
