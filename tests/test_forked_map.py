"""The forked map (``acdrive._forked_map``): the serial map's list, computed in several
processes, errors raised in the parent; and a batch prepared in forked workers gives the rows
of a batch prepared in one process."""

import itertools
import math
import os

import pytest

import acdrive.batch
from acdrive._forked_map import WORKERS_VARIABLE, forked_map, worker_count
from acdrive.batch import simulate_batch

needs_two = pytest.mark.skipif(
    worker_count(1000, 1) < 2, reason="needs fork and two cores to run a worker"
)


@needs_two
def test_the_map_is_the_serial_map_and_runs_in_more_than_one_process(monkeypatch):
    monkeypatch.delenv(WORKERS_VARIABLE, raising=False)
    offset = 0.5  # a closure: the function is not pickled, only the results are
    items = list(range(257))
    got = forked_map(lambda x: (x * x + offset, os.getpid()), items, min_per_worker=16)
    assert [v for v, _ in got] == [x * x + offset for x in items]
    pids = [pid for _, pid in got]
    assert pids[0] == os.getpid()  # the parent takes the first share
    assert len(set(pids)) == worker_count(len(items), 16) >= 2
    # contiguous shares, in order: the process changes only where a share ends
    assert sum(a != b for a, b in itertools.pairwise(pids)) == len(set(pids)) - 1


def test_the_variable_caps_the_processes_and_small_lists_stay_serial(monkeypatch):
    monkeypatch.setenv(WORKERS_VARIABLE, "1")
    assert worker_count(10_000, 1) == 1
    assert {pid for pid in forked_map(lambda _: os.getpid(), list(range(100)), 1)} == {os.getpid()}
    monkeypatch.delenv(WORKERS_VARIABLE)
    assert worker_count(15, 16) == 1  # fewer items than one worker's share
    assert forked_map(str, [], 1) == []


def test_a_daemonic_process_maps_serially(monkeypatch):
    """A daemonic process (a pool's worker) may not start children: it maps in itself."""
    import multiprocessing

    class Daemonic:
        daemon = True

    monkeypatch.setattr(multiprocessing, "current_process", lambda: Daemonic())
    assert worker_count(10_000, 1) == 1


@needs_two
def test_an_error_in_a_worker_is_raised_in_the_parent(monkeypatch):
    monkeypatch.delenv(WORKERS_VARIABLE, raising=False)

    def fails_late(x):
        if x == 90:  # in the second share: a worker's
            raise ValueError(f"bad item {x}")
        return x

    with pytest.raises(ValueError, match="bad item 90"):
        forked_map(fails_late, list(range(100)), min_per_worker=10)

    class Unpicklable(Exception):  # a local class: pickling it fails
        pass

    def fails_unpicklably(x):
        if x == 95:
            raise Unpicklable("local")
        return x

    with pytest.raises(RuntimeError, match="Unpicklable"):
        forked_map(fails_unpicklably, list(range(100)), min_per_worker=10)


@needs_two
def test_a_batch_prepared_in_workers_has_the_rows_of_one_process(monkeypatch):
    """Valid and invalid variants spread over the shares, two groups (a changed substep count
    is another group key), logged traces: the same rows, in the same order, whichever process
    prepared them."""
    short = {"simulation.duration": 0.004}
    variants = []
    for k in range(12):
        v = {**short, "motor[0].load_torque": 0.01 * k}
        if k % 5 == 3:
            v["motor[0].params.R_s"] = -1.0  # invalid
        if k % 4 == 1:
            v["simulation.substeps"] = 2  # a second group
        variants.append(v)
    variants.insert(7, "not a dict")

    def run():
        return simulate_batch("bodson-ramp", variants, log=["shaft0.w"], log_every=1,
                              lockstep=False)  # fmt: skip

    monkeypatch.setattr(acdrive.batch, "PREPARE_SHARE", 2)
    assert worker_count(len(variants), 2) >= 2  # the second run prepares in forked workers
    monkeypatch.setenv(WORKERS_VARIABLE, "1")
    alone = run()
    monkeypatch.delenv(WORKERS_VARIABLE)
    forked = run()
    assert forked.groups == alone.groups == 2
    assert [r["valid"] for r in forked.rows].count(False) == 3
    assert forked.rows[7]["reason"] == "variants: each variant must be a dict"
    for a, b in zip(alone.rows, forked.rows, strict=True):
        assert a.keys() == b.keys()
        for key in a:
            same = a[key] == b[key] or (
                isinstance(a[key], float) and math.isnan(a[key]) and math.isnan(b[key])
            )
            assert same, (a["variant"], key, a[key], b[key])
    assert forked.traces.keys() == alone.traces.keys() and len(forked.traces) == 10
    for i, trace in forked.traces.items():
        assert (trace.data == alone.traces[i].data).all()
