"""A profile of a continuous part acts at its instant: the integration splits at every point of
a load profile and the stages of a step that ends on a load step read the load before it
(``sim._loop_source.advance_lines``), in every tier of the loop, in lockstep batches and in the
slow path's Radau reference.

The system is the shaft of ``tests/test_mechanics.py`` behind a de-energised cage motor (no
voltage, no flux, exactly zero torque), loaded by a step tau_L at t_L: J dw/dt = -tau_L for
t > t_L, so w = -tau_L (t - t_L) / J and theta = -tau_L (t - t_L)^2 / (2 J) exactly. A Runge-Kutta
method integrates a polynomial of degree 2 in t without error when no step straddles t_L and no
stage of a step before t_L sees the load: what is left is rounding. A stage that read the load
h/6 of a step early (RK4's last stage) would put w off by tau_L h / (6 J) = 1.7e-3 rad/s here.
"""

from __future__ import annotations

import numpy as np
import pytest

from acdrive.core import Profile
from acdrive.errors import InputError
from acdrive.sim import _native
from acdrive.sim._lockstep_source import LANES
from acdrive.sim._reference import simulate_reference
from test_mechanics import cage_drive
from acdrive.machines import UGALDE_IM_300W
from acdrive.plant import Shaft

J, TAU_L, T_S = 0.015, 6.0, 1e-4
#: rounding of the sums of up to 16,000 steps of |dw| <= 0.025 rad/s (w up to 4 rad/s)
W_ROUNDING, THETA_ROUNDING = 1e-12, 1e-14
#: where a step of tau_L h / (6 J), h = T_S / 4, would show
EARLY = TAU_L * T_S / 4 / (6 * J)

ON_A_SAMPLE = (0.05, 0.75)  # 0.75 / 1e-4 rounds the other way than 0.05 / 1e-4
BETWEEN_SAMPLES = (0.05 + 0.37 * T_S, 0.05 + 0.25 * T_S)  # inside a substep; on one of four


def _shaft_system(t_L, method="rk4"):
    shaft = Shaft("shaft", J=J, load=Profile.step(t_L, 0.0, TAU_L))
    _, system = cage_drive(UGALDE_IM_300W, shaft, V_pk=0.0, method=method)
    return system, shaft


def _exact(t, t_L):
    after = np.maximum(t - t_L, 0.0)
    return -TAU_L * after / J, -TAU_L * after**2 / (2.0 * J)


def _check(result, shaft, t_L):
    w, theta = result.signal(shaft.out.w), result.signal(shaft.out.theta)
    w_exact, theta_exact = _exact(result.t, t_L)
    assert np.count_nonzero(w) > 50  # the load acted within the run
    assert np.max(np.abs(w - w_exact)) < W_ROUNDING < EARLY * 1e-6
    assert np.max(np.abs(theta - theta_exact)) < THETA_ROUNDING


def _compiled(system, tier, monkeypatch):
    monkeypatch.setenv("ACDRIVE_LOOP_TIER", tier)
    compiled = system.compile()
    assert compiled.tier == tier
    return compiled


TIERS = ["specialised",
         pytest.param("native", marks=pytest.mark.skipif(_native.compiler() is None,
                                                          reason="no C compiler"))]  # fmt: skip


@pytest.mark.parametrize("tier", TIERS)
@pytest.mark.parametrize("substeps", [1, 4, 16])
@pytest.mark.parametrize("t_L", ON_A_SAMPLE + BETWEEN_SAMPLES)
def test_a_load_step_acts_at_its_instant_with_rk4(tier, substeps, t_L, monkeypatch):
    system, shaft = _shaft_system(t_L)
    compiled = _compiled(system, tier, monkeypatch)
    result = compiled.run(t_L + 0.01, T_S, substeps, log=[shaft.out.w, shaft.out.theta])
    _check(result, shaft, t_L)


@pytest.mark.parametrize("tier", ["specialised", TIERS[1]])
@pytest.mark.parametrize("t_L", ON_A_SAMPLE + BETWEEN_SAMPLES)
def test_a_load_step_acts_at_its_instant_with_rk6(tier, t_L, monkeypatch):
    system, shaft = _shaft_system(t_L, method="rk6")
    compiled = _compiled(system, tier, monkeypatch)
    result = compiled.run(t_L + 0.01, T_S, 1, log=[shaft.out.w, shaft.out.theta])
    _check(result, shaft, t_L)


def test_a_load_ramp_is_integrated_exactly_through_its_corners(monkeypatch):
    """Corners between samples: tau_L rises linearly from t_a to t_b, so w is piecewise cubic
    in t; RK4 is exact for it when no step straddles a corner."""
    t_a, t_b = 0.01 + 0.3 * T_S, 0.02 + 0.6 * T_S
    shaft = Shaft("shaft", J=J, load=[[0.0, 0.0], [t_a, 0.0], [t_b, TAU_L]])
    _, system = cage_drive(UGALDE_IM_300W, shaft, V_pk=0.0)
    result = _compiled(system, "specialised", monkeypatch).run(0.03, T_S, 1, log=[shaft.out.w])
    t, slope = result.t, TAU_L / (t_b - t_a)
    ramp = -slope * np.clip(t - t_a, 0.0, t_b - t_a) ** 2 / (2.0 * J)
    held = -TAU_L * np.maximum(t - t_b, 0.0) / J
    assert np.max(np.abs(result.signal(shaft.out.w) - (ramp + held))) < W_ROUNDING


def test_the_radau_reference_splits_at_the_same_instants():
    t_L = BETWEEN_SAMPLES[0]
    system, shaft = _shaft_system(t_L)
    result = simulate_reference(system.compile(), 0.052, T_S, method="Radau",
                                log=[shaft.out.w])  # fmt: skip
    w_exact, _ = _exact(result.t, t_L)
    assert np.max(np.abs(result.signal(shaft.out.w) - w_exact)) < 1e-9


@pytest.mark.slow
def test_a_lockstep_batch_shares_the_instants_or_runs_variant_by_variant():
    """A batch whose variants load the shaft at one instant (with other loads) runs in lockstep
    and splits where each variant alone does; one whose variants differ in the instant runs
    variant by variant (lanes stepping together cannot split at different times)."""
    t_L = BETWEEN_SAMPLES[0]
    system, shaft = _shaft_system(t_L)
    compiled = system.compile()
    run = {"duration": 0.06, "sample_time": T_S, "substeps": 4, "log": [shaft.out.w]}
    loads = [TAU_L * (1 + b / LANES) for b in range(LANES)]
    same = [{"shaft": {"load": Profile.step(t_L, 0.0, tau)}} for tau in loads]
    results = compiled.run_batch(same, lockstep=True, **run)
    assert compiled.last_batch_loop == "lockstep"
    for tau, result in zip(loads, results, strict=True):
        w_exact = -tau * np.maximum(result.t - t_L, 0.0) / J
        assert np.max(np.abs(result.signal(shaft.out.w) - w_exact)) < W_ROUNDING
    instants = [t_L + 1e-5 * b for b in range(LANES)]
    differ = [{"shaft": {"load": Profile.step(t, 0.0, TAU_L)}} for t in instants]
    with pytest.raises(InputError, match="profiles of shaft have their points at other times"):
        compiled.run_batch(differ, lockstep=True, **run)
    results = compiled.run_batch(differ, **run)
    assert compiled.last_batch_loop == "per-variant"
    for t, result in zip(instants, results, strict=True):
        w_exact, _ = _exact(result.t, t)
        assert np.max(np.abs(result.signal(shaft.out.w) - w_exact)) < W_ROUNDING
