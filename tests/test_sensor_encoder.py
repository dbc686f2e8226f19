"""The quadrature encoder and its counter (acdrive.plant.QuadratureEncoder): the reading
truncates to the count (error in [0, one count)) or, centred, is within half a count, the
register's wrap gives no speed spike, the
index bounds the drift of lost edges to one revolution's losses, and bad parameters are refused
naming the field."""

from __future__ import annotations

import numpy as np
import pytest

from acdrive.errors import InputError
from acdrive.plant import QuadratureEncoder

TWO_PI = 2.0 * np.pi
T_S = 1e-4


def step_through(part, inputs: np.ndarray, T_s: float = T_S) -> tuple[np.ndarray, np.ndarray]:
    """Run a sampled part's compiled ``step`` kernel over the rows of ``inputs`` (one row per
    sample, at t = k T_s): its outputs (one row per sample) and the event bits per sample."""
    inputs = np.asarray(inputs, dtype=float).reshape(len(inputs), -1)
    p, s = np.array(part.p, dtype=float), np.array(part.initial_state(), dtype=float)
    y = np.zeros(part.OUTPUTS.fixed_size)
    outputs, events = np.empty((len(inputs), part.OUTPUTS.fixed_size)), np.empty(len(inputs), int)
    step = type(part).step
    for k, u in enumerate(inputs):
        events[k] = step(k * T_s, T_s, np.ascontiguousarray(u), p, s, y)
        outputs[k] = y
    return outputs, events


def column(part, name: str) -> int:
    return part.OUTPUTS.slot(name)


def wrapped(x):
    """x in [-pi, pi)."""
    return (np.asarray(x) + np.pi) % TWO_PI - np.pi


def random_trajectory(n: int, seed: int, w_peak: float) -> np.ndarray:
    """A shaft angle whose speed wanders through both directions up to about w_peak."""
    rng = np.random.default_rng(seed)
    w = w_peak * np.sin(np.cumsum(rng.normal(0.0, 0.01, n)) + rng.uniform(0, TWO_PI))
    return 0.3 + np.cumsum(w) * T_S


def test_the_reading_truncates_to_the_count():
    """Over a random trajectory in both directions (no edge lost) the angle read lies within one
    count below the disc angle theta + offset, mod 2 pi: the counter truncates; the electrical
    angle is pole_pairs times the angle read, wrapped."""
    encoder = QuadratureEncoder("enc", lines=500, pole_pairs=4, offset=0.7)
    theta = random_trajectory(40_000, 1, 300.0)
    assert np.ptp(theta) > 4 * TWO_PI  # several revolutions and reversals
    y, _ = step_through(encoder, theta)
    count = TWO_PI / 2000
    read = y[:, column(encoder, "theta")]
    error = wrapped(theta + 0.7 - read)
    assert error.min() >= -1e-9 and error.max() < count + 1e-9
    assert error.max() > 0.99 * count  # the whole count is used: a truncation, not a rounding
    assert np.all((read >= 0.0) & (read < TWO_PI))
    theta_e = y[:, column(encoder, "theta_e")]
    assert np.all((theta_e >= 0.0) & (theta_e < TWO_PI))
    assert np.max(np.abs(wrapped(theta_e - 4 * read))) < 1e-9
    counts = y[:, column(encoder, "count")]
    assert np.array_equal(counts, np.floor(counts)) and counts.max() < 2000


def test_a_centred_reading_is_within_half_a_count():
    """With ``centred`` the angle is read at the count's centre: the error to the disc angle is
    within half a count either way, and both halves are reached."""
    encoder = QuadratureEncoder("enc", lines=500, pole_pairs=4, offset=0.7, centred=1)
    theta = random_trajectory(40_000, 2, 300.0)
    y, _ = step_through(encoder, theta)
    half = TWO_PI / 2000 / 2
    read = y[:, column(encoder, "theta")]
    error = wrapped(theta + 0.7 - read)
    assert np.max(np.abs(error)) <= half * (1 + 1e-9)
    assert error.max() > 0.99 * half and error.min() < -0.99 * half
    assert np.all((read >= 0.0) & (read < TWO_PI))
    theta_e = y[:, column(encoder, "theta_e")]
    assert np.all((theta_e >= 0.0) & (theta_e < TWO_PI))
    assert np.max(np.abs(wrapped(theta_e - 4 * read))) < 1e-9


def test_the_wrap_gives_no_speed_spike():
    """At a constant speed through many wraps of the register, the speed read equals the
    speed of the disc's count difference over each sample on every sample, the wraps included:
    within one count per sample of the true speed, never the -2 pi / T_s a wrapped angle's
    difference gives."""
    lines, w = 256, 157.0  # 2.5 revolutions per second
    encoder = QuadratureEncoder("enc", lines=lines, offset=0.2)
    k = np.arange(20_000)
    theta = w * k * T_S
    y, _ = step_through(encoder, theta)
    n = 4 * lines
    read, speed = y[:, column(encoder, "theta")], y[:, column(encoder, "w")]
    assert np.count_nonzero(np.diff(read) < -np.pi) >= 4  # the register wrapped
    edges = np.floor((theta + 0.2) * n / TWO_PI)
    expected = np.diff(edges) * TWO_PI / n / T_S
    assert np.allclose(speed[1:], expected, rtol=0.0, atol=1e-9 * w)
    assert speed[0] == 0.0
    assert np.max(np.abs(speed[1:] - w)) <= TWO_PI / n / T_S * (1 + 1e-9)


def _edge_errors(index: bool, lose_every: int, lines: int, revolutions: float):
    """(register - the disc's true count) wrapped to [-N/2, N/2) per sample, the index events,
    the revolutions crossed, at a constant speed."""
    n = 4 * lines
    encoder = QuadratureEncoder("enc", lines=lines, index=float(index), lose_every=lose_every)
    w = 80.0
    theta = w * np.arange(int(revolutions * TWO_PI / w / T_S)) * T_S
    y, events = step_through(encoder, theta)
    edges = np.floor(theta * n / TWO_PI)
    error = (y[:, column(encoder, "count")] - edges + n / 2) % n - n / 2
    return error, events, edges, n


def test_lost_edges_drift_without_the_index_and_are_bounded_with_it():
    """Every 7th edge lost: without the index the register falls behind by one count per 7
    edges passed (the stated model, exactly), beyond a revolution's losses; with it the error
    never exceeds the edges lost in one revolution, ceil(N / 7), and the index is seen once per
    revolution."""
    lines, k, revolutions = 100, 7, 6.5
    drift, events, edges, n = _edge_errors(False, k, lines, revolutions)
    assert np.all((drift + (edges - edges[0]) // k) % n == 0)
    assert events.any()
    error, events, edges, n = _edge_errors(True, k, lines, revolutions)
    bound = np.ceil(n / k)
    assert np.max(np.abs(error)) <= bound
    assert np.max(np.abs(drift)) > bound  # the index is what holds it
    assert np.count_nonzero(events & 1) == int(edges[-1] // n)
    last_revolution = edges >= edges[-1] - n
    assert np.max(np.abs(error[last_revolution])) <= bound  # no drift from one turn to the next


@pytest.mark.parametrize(("field", "value"), [("lines", 0), ("lines", 2.5), ("lines", 2**31),
                                              ("pole_pairs", 0), ("lose_every", -1),
                                              ("index", 2), ("centred", 0.5)])  # fmt: skip
def test_bad_parameters_are_refused_naming_the_field(field, value):
    with pytest.raises(InputError, match=rf"^enc\.{field}: "):
        QuadratureEncoder("enc", **{"lines": 100, field: value})
