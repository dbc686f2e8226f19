"""Kernels without the table search for parts whose tables have one point in every variant
(sim._one_point, used by the lockstep loop): the same numbers bit for bit, and the choice of
parts from the packed parameters."""

import numpy as np
import pytest
from numba import njit

from acdrive.batch import prepare_variant
from acdrive.machines._dfim_part import dfim_rhs
from acdrive.plant._mechanics import Shaft, shaft_rhs
from acdrive.sim._lockstep_source import lockstep_source, one_point_parts
from acdrive.sim._one_point import one_point_kernel


def _both(kernel):
    """The kernel as numba compiles it, and its one-point form."""
    original = njit(kernel.py_func)
    rebound = njit(one_point_kernel(kernel.py_func))
    return original, rebound


@pytest.mark.parametrize("tau_c", [0.0, 0.3])
def test_a_one_point_shaft_gives_the_same_bits_and_a_profile_tells_the_two_apart(tau_c):
    """The shaft looks up two tables (the load, and the brake through table_offset); with one
    point each the one-point kernel gives the original's bits at every state and time, Coulomb
    friction (a call under a branch) or not. With a two-point load profile the two differ: the
    one-point form really replaced the lookup (a test of nothing would pass the first part)."""
    original, rebound = _both(shaft_rhs)
    rng = np.random.default_rng(7)
    one = Shaft("shaft", J=3.5e-4, B=1e-4, tau_c=tau_c, load=0.07, brake=2e-4)
    for _ in range(200):
        t = float(rng.uniform(0.0, 20.0))
        x = rng.normal(0.0, 100.0, 2)
        u = rng.normal(0.0, 1.0, 1)
        y = np.zeros(2)
        a, b = np.zeros(2), np.zeros(2)
        original(t, x, u, one.p, y, a)
        rebound(t, x, u, one.p, y, b)
        assert np.array_equal(a, b)
    profile = Shaft("shaft", J=3.5e-4, tau_c=tau_c, load=[[0.0, 0.0], [1.0, 0.1]])
    x, u, y = np.array([10.0, 0.0]), np.array([0.05]), np.zeros(2)
    a, b = np.zeros(2), np.zeros(2)
    original(0.5, x, u, profile.p, y, a)
    rebound(0.5, x, u, profile.p, y, b)
    assert a[0] != b[0]  # the profile's 0.05 N m at t = 0.5 s against its first point's 0


def test_a_kernel_without_tables_is_itself():
    assert one_point_kernel(dfim_rhs.py_func) is dfim_rhs.py_func


def test_the_parts_chosen_are_those_whose_every_table_has_one_point_in_every_variant():
    system = prepare_variant("bodson-ramp", {"simulation.duration": 0.01})[2]
    P0, PO = system.pack_params()
    P = np.stack([P0, P0, P0])
    with_tables = {p.name for p in system.parts if p.PARAMS.tables}
    assert {"grid", "shaft0"} <= with_tables
    chosen = one_point_parts(system, P, PO)
    # the speed reference's ramp profile has several points; the supply and the shaft one each
    assert chosen == {p for p in with_tables if p not in ("reference0",)}
    assert "reference0" in with_tables
    # one variant whose second shaft table claims two points: the shaft keeps the search
    i = [p.name for p in system.parts].index("shaft0")
    second = int(PO[i]) + system.part("shaft0").PARAMS.fixed_size + 3
    P[1, second] = 2.0
    assert "shaft0" not in one_point_parts(system, P, PO)
    assert "grid" in one_point_parts(system, P, PO)
    source = lockstep_source(system, PO, one_point_parts(system, P, PO))
    index = [p.name for p in system.parts].index("grid")
    assert f"rebound_kernel(k{index}_rhs.py_func, ONE_POINT" in source
    assert f"rebound_kernel(k{i}_rhs.py_func, ONE_POINT" not in source
