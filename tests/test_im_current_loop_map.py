"""The cage-IM drive's sampled current-loop pre-check (``drives.cage_im._current_loop``) is the
compiled loop's own carrier-period map: its spectral radius equals that of an independent,
hand-built state-space model of the same loop (plant (1) held by a zero-order hold over each
sample, the discretised controller, the command latched for the carrier period), and the loader
still refuses a loop that is unstable."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.linalg

from acdrive.control import StationaryCurrentController
from acdrive.drives.cage_im._current_loop import CarrierPeriodMap, current_loop_radius
from acdrive.machines import stator_current_ss
from acdrive.scenarios import load_scenario


def hand_built_radius(plant, w_mech: float, discrete, n_carrier: int) -> float:
    """The loop written out by hand: x_p+ = A_p x_p + B_p h over one sample (exact ZOH of (1) at
    electrical speed n_p w), controller x_c+ = A_c x_c - B_c C x_p (zero reference), the held
    command h taken as v = C_c x_c - D_c C x_p at the first sample of the carrier period and
    kept for the other n_carrier - 1."""
    A, B, C, _ = stator_current_ss(plant, plant.n_p * w_mech)
    T = discrete.T_s
    n, m = A.shape[0], B.shape[1]
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = A * T, B * T
    E = scipy.linalg.expm(M)
    Ap, Bp = E[:n, :n], E[:n, n:]
    Ac, Bc, Cc, Dc = discrete.Ad, discrete.Bd, discrete.Cd, discrete.Dd
    nc = Ac.shape[0]
    size = n + nc + 2
    xp, xc, h = slice(0, n), slice(n, n + nc), slice(n + nc, size)
    hold = np.zeros((size, size))
    hold[xp, xp], hold[xp, h] = Ap, Bp
    hold[xc, xp], hold[xc, xc] = -Bc @ C, Ac
    hold[h, h] = np.eye(2)
    latch = np.zeros((size, size))
    v_row = np.hstack([-Dc @ C, Cc, np.zeros((2, 2))])
    latch[xp, :] = np.hstack([Ap, np.zeros((n, nc + 2))]) + Bp @ v_row
    latch[xc, xp], latch[xc, xc] = -Bc @ C, Ac
    latch[h, :] = v_row
    period = np.linalg.matrix_power(hold, n_carrier - 1) @ latch
    return float(np.max(np.abs(np.linalg.eigvals(period))))


def _controller(setup, name: str, sample_time: float) -> StationaryCurrentController:
    cc = dataclasses.replace(setup.current_control, controller=name)
    return StationaryCurrentController("current", cc.lti, sample_time, cc.method, cc.prewarp,
                                       v_dc_input=True, aw_gain=cc.aw_gain)  # fmt: skip


@pytest.fixture(scope="module")
def setup():
    return load_scenario("im-step-responses")


@pytest.mark.parametrize("name", ["paper-20", "paper-22-pi", "fig18-pi"])
@pytest.mark.parametrize("w_mech", [0.0, 375.0])
@pytest.mark.parametrize("n_carrier", [1, 10])
def test_compiled_carrier_map_has_the_hand_built_radius(setup, name, w_mech, n_carrier):
    """RK4 with 4 substeps against the exact hold: equal to 1e-7 (the RK4 error at T_s = 20 us)."""
    part = _controller(setup, name, 20e-6)
    compiled = current_loop_radius(setup.plant, w_mech, part, n_carrier)
    assert compiled == pytest.approx(hand_built_radius(setup.plant, w_mech, part.discrete,
                                                         n_carrier), abs=1e-7)  # fmt: skip


def test_the_hold_can_make_the_loop_unstable_in_both_models(setup):
    """Controller (20) at 100 us samples: stable alone, unstable when the inverter holds each
    command for 10 samples; at 1 ms unstable even alone. Both models say so, with one radius."""
    for T, n, stable in ((1e-4, 1, True), (1e-4, 10, False), (1e-3, 1, False)):
        part = _controller(setup, "paper-20", T)
        a = current_loop_radius(setup.plant, 100.0, part, n)
        b = hand_built_radius(setup.plant, 100.0, part.discrete, n)
        assert (a < 1.0) == (b < 1.0) == stable
        assert a == pytest.approx(b, rel=1e-4)


def test_the_map_is_the_period_of_the_compiled_loop(setup):
    """The map's state names are the compiled system's quantities."""
    part = _controller(setup, "paper-20", 20e-6)
    smp = CarrierPeriodMap(setup.plant, 0.0, part, 10)
    assert smp.names[:4] == ("machine.i_s.re", "machine.i_s.im", "machine.psi_r.re",
                             "machine.psi_r.im")  # fmt: skip
    assert smp.names[-2:] == ("latch.v.re", "latch.v.im")
    assert smp.period_matrix().shape == (len(smp.names),) * 2
