"""The lockstep batch loop (sim._lockstep_source): variants advanced together over SIMD lanes
give each variant the result of the per-variant batch loop (itself bit-identical to a single run,
tests/test_batch.py); a system whose modulator switches within a sample runs per variant."""

import numpy as np
import pytest

from acdrive._jit import STRICT_MATH
from acdrive.batch import prepare_variant
from acdrive.errors import InputError, Notice
from acdrive.sim._lockstep_source import (
    FAST_MATH_AGREEMENT,
    LANES,
    lockstep_broken,
    lockstep_plan,
    lockstep_refusal,
    lockstep_source,
)

BASE = "bodson-ramp"
DURATION = 0.02  # 100 control samples: the start-up, with the converter near its limit
LOGGED = [("shaft0", "w"), ("dfim0", "i_s"), ("dfim0", "i_r"), ("dfim0", "tau_e"),
          ("converter0", "v")]  # fmt: skip


def _group(n):
    """n variants of bodson-ramp that differ in plant and controller parameters, packed as
    acdrive.batch packs a group: (compiled system, P, PO, X, S, Y, setup)."""
    rng = np.random.default_rng(21)
    members = []
    for _ in range(n):
        overrides = {
            "simulation.duration": DURATION,
            "part:shaft0.J": float(0.0035 * (0.8 + 0.4 * rng.random())),
            "motor[0].controller.speed_bandwidth": float(200.0 + 200.0 * rng.random()),
            "motor[0].params.R_r": float(0.8 + 0.8 * rng.random()),
            "motor[0].load_torque": float(0.1 * rng.random()),
        }
        setup, _drive, system, initial, held, _used = prepare_variant(BASE, overrides)
        members.append((system, initial, held))
    system = members[0][0]
    P = np.stack([m[0].pack_params()[0] for m in members])
    PO = system.pack_params()[1]
    packed = [m[0].pack_initial(m[1]) for m in members]
    X = np.stack([x for x, _ in packed])
    S = np.stack([s for _, s in packed])
    Y = np.stack([m[0].pack_held(m[2]) for m in members])
    return system.compile(), P, PO, X, S, Y, setup


def _run(compiled, P, PO, X, S, Y, setup, lockstep):
    X, S, Y = X.copy(), S.copy(), Y.copy()
    ports = [getattr(compiled.system.part(part).out, name) for part, name in LOGGED]
    LOG, ELOG, ECOUNT, DONE, STATUS, _ = compiled.run_packed(
        P, PO, X, S, Y, setup.duration, setup.sample_time, setup.substeps, log=ports,
        log_every=1, lockstep=lockstep)  # fmt: skip
    assert compiled.last_batch_loop == ("lockstep" if lockstep else "per-variant")
    return LOG, ELOG, ECOUNT, DONE, STATUS, X, S


@pytest.mark.slow
def test_lockstep_gives_each_variant_its_per_variant_result():
    # 20 variants: one full block of lanes and one padded block
    group = _group(LANES + 4)
    lock = _run(*group, lockstep=True)
    alone = _run(*group, lockstep=False)
    LOG, ELOG, ECOUNT, DONE, STATUS, X, S = lock
    assert (STATUS == 0).all() and (DONE == alone[3]).all()
    # the variants really differ (copies of one variant would pass trivially)
    assert np.abs(LOG[0] - LOG[1]).max() > 1e-3 * np.abs(LOG[0]).max()
    # events (converter saturation, current limits) counted and logged alike, sample by sample
    assert np.array_equal(ELOG, alone[1]) and np.array_equal(ECOUNT, alone[2])
    if STRICT_MATH:  # IEEE arithmetic in the written order: the same bits
        for mine, theirs in zip(lock, alone, strict=True):
            assert np.array_equal(mine, theirs)
        return
    # fast math: per signal and variant, within the stated fraction of the signal's peak
    peak = np.abs(alone[0]).max(axis=1, keepdims=True)
    assert (np.abs(LOG - alone[0]) <= FAST_MATH_AGREEMENT * peak).all()
    for mine, theirs in ((X, alone[5]), (S, alone[6])):
        scale = np.maximum(np.abs(theirs), 1.0)
        assert (np.abs(mine - theirs) <= FAST_MATH_AGREEMENT * scale).all()


def test_a_switching_inverter_refuses_lockstep_and_the_batch_runs_per_variant():
    system = prepare_variant(BASE, {})[2]
    assert lockstep_refusal(system) is None  # the averaged converter: one segment per sample
    switching = _switching_system()
    reason = lockstep_refusal(switching)
    assert reason is not None and "segment" in reason
    with pytest.raises(InputError, match="lockstep"):
        lockstep_plan(switching, switching.pack_params()[1], 1000, lockstep=True)
    with pytest.warns(Notice, match="one variant at a time"):
        assert lockstep_plan(switching, switching.pack_params()[1], 1000) is None
    with pytest.raises(ValueError):
        lockstep_source(switching, switching.pack_params()[1])
    # too few variants to fill the lanes of every thread: per variant, without a notice
    assert lockstep_plan(system, system.pack_params()[1], 2) is None


def _switching_system():
    """im-foc-speed's system: the switching SVPWM inverter (``MAX_SEGMENTS`` = 7)."""
    return prepare_variant("im-foc-speed", {})[2]


def test_a_broken_one_segment_rule_restores_the_batch_for_the_per_variant_rerun():
    X, S, Y = np.ones((3, 4)), np.ones((3, 2)), np.ones((3, 5))
    before = X.copy() * 2.0, S.copy() * 3.0, Y.copy() * 4.0
    LOG, ECOUNT = np.ones((3, 7, 2)), np.ones((3, 1, 64), dtype=np.int64)
    with pytest.warns(Notice, match="reruns one variant at a time"):
        lockstep_broken(before, (X, S, Y), (LOG, ECOUNT))
    for array, saved in zip((X, S, Y), before, strict=True):
        assert np.array_equal(array, saved)
    assert not LOG.any() and not ECOUNT.any()
