"""A batch of a system the native loop runs goes through the native loop, variant by variant
(``CompiledSystem._native_batch``): each variant's trace is its native single run, bit for bit,
its metrics are those of numba's per-variant batch loop bit for bit, and no numba loop is
compiled for it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from acdrive.batch import simulate_batch
from acdrive.sim import _native
from test_batch import BASE, _alone, _variants

pytestmark = pytest.mark.skipif(_native.compiler() is None, reason="no C compiler")


def _same(a, b) -> bool:
    return a == b or (isinstance(a, float) and math.isnan(a) and math.isnan(b))


def test_a_native_batch_equals_the_native_single_runs(monkeypatch):
    monkeypatch.setenv("ACDRIVE_LOOP_TIER", "auto")
    variants = _variants()
    batch = simulate_batch(BASE, variants, reducers=[], log=["shaft0.w", "dfim0.i_s"],
                           log_every=1)  # fmt: skip
    assert batch.loops == ("native",)
    assert all(row["status"] == "ok" for row in batch.rows)
    for i, v in enumerate(variants):
        alone = _alone(v)
        assert alone.tier == "native"
        assert np.array_equal(batch.traces[i].final_state, alone.final_state)
        assert np.array_equal(batch.traces[i].data[:, 0], alone.data[:, 0])  # shaft0.w
    assert not np.array_equal(batch.traces[0].data, batch.traces[1].data)


@pytest.mark.slow
def test_a_native_batchs_metrics_are_numbas_per_variant_loops(monkeypatch):
    """The default reducers (the stats part, the speed error with its relay gate) in C against
    numba's per-variant batch loop: every metric of every variant the same (NaN where both
    are)."""
    variants = _variants()
    monkeypatch.setenv("ACDRIVE_LOOP_TIER", "auto")
    native = simulate_batch(BASE, variants, log=["shaft0.w"], log_every=1)
    monkeypatch.setenv("ACDRIVE_LOOP_TIER", "specialised")
    numba_batch = simulate_batch(BASE, variants, log=["shaft0.w"], log_every=1, lockstep=False)
    assert native.loops == ("native",) and numba_batch.loops == ("per-variant",)
    for mine, theirs in zip(native.rows, numba_batch.rows, strict=True):
        assert mine.keys() == theirs.keys()
        assert all(_same(mine[k], theirs[k]) for k in mine), mine
    assert native.rows[0]["speed_rms_error_whole_run_rpm"] > 0.0


def test_lockstep_false_keeps_the_native_loop_and_true_asks_for_numbas(monkeypatch):
    """``lockstep=False`` runs one variant at a time, here in the native loop; ``lockstep=True``
    is numba's lockstep loop, refused by name where the system cannot run it."""
    from acdrive.errors import InputError

    monkeypatch.setenv("ACDRIVE_LOOP_TIER", "auto")
    variants = _variants()[:1]
    assert simulate_batch(BASE, variants, reducers=[], lockstep=False).loops == ("native",)
    with pytest.raises(InputError, match="lockstep"):
        simulate_batch(BASE, variants, reducers=[], lockstep="yes")
