"""The lockstep batch loop (sim._lockstep_source): variants advanced together over SIMD lanes
give each variant the result of the per-variant batch loop bit for bit (itself bit-identical to
a single run, tests/test_batch.py); a system whose modulator switches within a sample runs per variant."""

from typing import ClassVar

import numpy as np
import pytest
from numba import njit

from acdrive.batch import prepare_variant
from acdrive.control._open_loop import VoltageProgram
from acdrive.core import Layout, cplx, real
from acdrive.core._parts import Modulator
from acdrive.errors import InputError, Notice
from acdrive.machines._cage_part import CageInductionMachine
from acdrive.machines._induction import UGALDE_IM_300W
from acdrive.plant._converter import AveragedConverter
from acdrive.plant._mechanics import PrescribedSpeed
from acdrive.sim._lockstep_source import (
    LANES,
    lockstep_broken,
    lockstep_plan,
    lockstep_refusal,
    lockstep_source,
    one_point_parts,
)
from acdrive.sim._system import System

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
            "part:shaft0.J": float(3.5e-4 * (0.8 + 0.4 * rng.random())),
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
    # the supply's and the shaft's tables have one point in every variant: their kernels run
    # without the table search here (sim._one_point), and must agree all the same
    assert {"grid", "shaft0"} <= one_point_parts(group[0].system, group[1], group[2])
    before = group[0].compile_time
    lock = _run(*group, lockstep=True)
    # the lockstep loop's compile (or cache load) is counted as compile time, not run time
    assert group[0].compile_time > before
    alone = _run(*group, lockstep=False)
    LOG, ELOG, ECOUNT, DONE, STATUS, _X, _S = lock
    assert (STATUS == 0).all() and (DONE == alone[3]).all()
    # the variants really differ (copies of one variant would pass trivially)
    assert np.abs(LOG[0] - LOG[1]).max() > 1e-3 * np.abs(LOG[0]).max()
    # events (converter saturation, current limits) counted and logged alike, sample by sample
    assert np.array_equal(ELOG, alone[1]) and np.array_equal(ECOUNT, alone[2])
    # IEEE operations in the written order, in the default fast math as under strict math
    # (acdrive._jit.FAST_MATH_FLAGS): the same bits, logs, final states and discrete states
    for mine, theirs in zip(lock, alone, strict=True):
        assert np.array_equal(mine, theirs)


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


# --- a hand-built cage-IM system: averaged converter, and a modulator that breaks the rule ------

HOLD_PARAMS = Layout(real("share", "", "fraction of the sample the held segment spans", "positive"))
HOLD_INPUTS = Layout(cplx("v_ref", "V", "commanded voltage"))
HOLD_OUTPUTS = Layout(cplx("v", "V", "applied voltage"))


@njit
def partial_hold_segments(T_s, u, p, s, dt, v):
    """One segment of ``share`` T_s (the plant is not advanced over the rest of the sample)."""
    dt[0] = p[0] * T_s
    v[0, 0], v[0, 1] = u[0], u[1]
    return 1, 0


class PartialHold(Modulator):
    """A one-segment modulator whose segment may end before the sample does."""

    PARAMS, INPUTS, OUTPUTS = HOLD_PARAMS, HOLD_INPUTS, HOLD_OUTPUTS
    EVENTS: ClassVar[tuple] = ()
    segments = partial_hold_segments


def _cage_system(modulator):
    """A locked-rotor cage IM fed by a 50 Hz voltage program through ``modulator``."""
    im = CageInductionMachine.from_params("im", UGALDE_IM_300W)
    program = VoltageProgram("program", V_pk=20.0, f=50.0)
    rotor = PrescribedSpeed("rotor", w=0.0)
    wires = [(program.out.v_ref, modulator.inp.v_ref), (modulator.out.v, im.inp.v_s),
             (rotor.out.w, im.inp.w)]  # fmt: skip
    return System([program, modulator, im, rotor], wires)


def _cage_variants(n, share=None):
    rng = np.random.default_rng(5)
    variants = []
    for b in range(n):
        v = {"program": {"V_pk": float(10.0 + 20.0 * rng.random()), "f": float(40 + 20 * rng.random())},
             "im": {"R_s": float(UGALDE_IM_300W.R_s * (0.8 + 0.4 * rng.random()))}}  # fmt: skip
        if share is not None:
            v["hold"] = {"share": share(b)}
        variants.append(v)
    return variants


@pytest.mark.slow
def test_lockstep_equals_per_variant_on_a_cage_machine_behind_an_averaged_converter():
    compiled = _cage_system(AveragedConverter("converter", V_dc=310.0)).compile()
    variants = _cage_variants(LANES + 3)
    run = {"duration": 0.01, "sample_time": 1e-4, "log_every": 1}
    lock = compiled.run_batch(variants, lockstep=True, **run)
    assert compiled.last_batch_loop == "lockstep"
    alone = compiled.run_batch(variants, lockstep=False, **run)
    assert compiled.last_batch_loop == "per-variant"
    assert not np.array_equal(lock[0].data, lock[1].data)
    for mine, theirs in zip(lock, alone, strict=True):
        assert mine.extra["status"] == theirs.extra["status"] == "ok"
        assert mine.events == theirs.events
        assert np.array_equal(mine.data, theirs.data)
        assert np.array_equal(mine.final_state, theirs.final_state)


@pytest.mark.slow
def test_a_segment_shorter_than_the_sample_sends_the_batch_back_to_the_per_variant_loop():
    compiled = _cage_system(PartialHold("hold", share=1.0)).compile()
    run = {"duration": 0.005, "sample_time": 1e-4, "log_every": 1}
    # every segment spans the sample: lockstep keeps the result
    whole = compiled.run_batch(_cage_variants(LANES, share=lambda b: 1.0), lockstep=True, **run)
    assert compiled.last_batch_loop == "lockstep"
    # one variant's segment ends at half the sample: the lockstep loop notices, the batch reruns
    # per variant and gives exactly what the per-variant loop gives
    variants = _cage_variants(LANES, share=lambda b: 0.5 if b == 3 else 1.0)
    with pytest.warns(Notice, match="reruns one variant at a time"):
        rerun = compiled.run_batch(variants, lockstep=True, **run)
    assert compiled.last_batch_loop == "per-variant"
    alone = compiled.run_batch(variants, lockstep=False, **run)
    for mine, theirs in zip(rerun, alone, strict=True):
        assert np.array_equal(mine.data, theirs.data)
        assert np.array_equal(mine.final_state, theirs.final_state)
    # the half-sample variant's currents are not its full-sample twin's; the other variants'
    # are, bit for bit
    assert np.abs(rerun[3].data - whole[3].data).max() > 1e-3 * np.abs(whole[3].data).max()
    assert np.array_equal(rerun[2].data, whole[2].data)


def test_simulate_batch_passes_its_lockstep_choice_to_the_compiled_batch():
    """``simulate_batch(..., lockstep=True/False)`` runs the chosen loop; the rows' metrics agree
    bit for bit."""
    from acdrive.batch import simulate_batch

    variants = [
        {"simulation.duration": DURATION, "motor[0].load_torque": 0.02 * k} for k in range(3)
    ]
    rows = {}
    for choice in (True, False):
        result = simulate_batch(BASE, variants, lockstep=choice)
        assert result.loops == ("lockstep" if choice else "per-variant",)
        rows[choice] = result.rows
    for a, b in zip(rows[True], rows[False], strict=True):
        assert a["status"] == b["status"] == "ok"
        for key, value in b.items():
            if isinstance(value, float) and np.isfinite(value) and key in a:
                assert a[key] == value, (key, a[key], value)
