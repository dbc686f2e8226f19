"""``export sil`` names each event whose record differs between acdrive's run and the C's, with
the samples each raised it on and the first time the records part (export._scenario)."""

from types import SimpleNamespace

import numpy as np

from acdrive.export._scenario import event_differences

NAMES = [("limiter", ("saturated", "windup")), ("relay", ("closed",))]


def run(bits: dict, counts: dict, samples: int = 6):
    """A stand-in run: ``bits[(column, bit)]`` the samples on which that event is raised."""
    log = np.zeros((samples, len(NAMES)), dtype=np.int64)
    for (column, bit), rows in bits.items():
        log[rows, column] |= 1 << bit
    return SimpleNamespace(t=0.5 + 1e-3 * np.arange(samples), event_log=log, events=counts)


def counts(saturated, windup, closed):
    return {"limiter": {"saturated": saturated, "windup": windup}, "relay": {"closed": closed}}


def test_equal_records_differ_nowhere():
    a = run({(0, 1): [2, 3]}, counts(0, 2, 0))
    assert event_differences(a, a, NAMES) == []


def test_each_differing_event_is_named_with_its_first_time_in_time_order():
    reference = run({(0, 0): [4], (0, 1): [2, 3], (1, 0): [5]}, counts(1, 2, 1))
    c = run({(0, 0): [4], (0, 1): [3], (1, 0): [1, 5]}, counts(1, 1, 2))
    rows = event_differences(reference, c, NAMES)
    assert [r["event"] for r in rows] == ["relay.closed", "limiter.windup"]
    assert rows[0] == {"event": "relay.closed", "acdrive": 1, "c": 2,
                       "first_difference_s": 0.5 + 1e-3}  # fmt: skip
    assert rows[1]["first_difference_s"] == 0.5 + 2e-3
    assert (rows[1]["acdrive"], rows[1]["c"]) == (2, 1)


def test_counts_that_differ_between_logged_samples_are_named_without_a_time():
    """With a log kept every k-th sample, two runs can raise an event on different unlogged
    samples: the counts tell, the record does not."""
    a = run({(0, 0): [1]}, counts(3, 0, 0))
    b = run({(0, 0): [1]}, counts(4, 0, 0))
    assert event_differences(a, b, NAMES) == [
        {"event": "limiter.saturated", "acdrive": 3, "c": 4, "first_difference_s": None}
    ]
