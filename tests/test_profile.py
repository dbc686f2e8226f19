"""Profiles have one meaning per form: a number, ``Profile(times, values)`` or a list of
``[time_s, value]`` points; a bare tuple, which reads both ways, is refused in one line."""

from __future__ import annotations

import dataclasses
import pickle
import re

import numpy as np
import pytest

from acdrive.core import Profile, table_at
from acdrive.core._signals import pack_table
from acdrive.errors import InputError
from acdrive.plant import Shaft, ThreePhaseSource
from acdrive.scenarios import builtin_names, load_scenario

ACCEPTED = "a number, Profile(times, values) or a list of [time_s, value] points"


def _at(value, t: float) -> float:
    return table_at(pack_table("x", value), 0, t)


def test_profile_and_points_are_the_same_ramp():
    ramp = Profile([0.0, 1.0], [0.0, 180.0])
    assert np.array_equal(pack_table("x", ramp), pack_table("x", [[0.0, 0.0], [1.0, 180.0]]))
    assert _at(ramp, 0.25) == pytest.approx(45.0)  # linear between points
    assert _at(ramp, -1.0) == 0.0 and _at(ramp, 3.0) == 180.0  # held outside them


def test_a_repeated_time_is_a_step_and_the_later_point_holds_after_it():
    step = Profile.step(0.3, 1.0, 5.0)
    assert step == Profile([0.0, 0.3, 0.3], [1.0, 1.0, 5.0])
    assert _at(step, 0.2999) == 1.0 and _at(step, 0.3) == 5.0 and _at(step, 0.4) == 5.0
    points = [[0.0, 0.0], [0.0, 180.0]]  # the points form: a step to 180 at t = 0
    assert _at(points, 1e-9) == 180.0 and _at(points, 1.0) == 180.0


def test_a_bare_tuple_is_refused_in_one_line_naming_the_parameter_and_the_forms():
    with pytest.raises(InputError) as info:
        ThreePhaseSource("grid", V_pk=([0, 1], [0, 180]))
    message = str(info.value)
    assert message.startswith("grid.V_pk: ") and ACCEPTED in message and "\n" not in message


@pytest.mark.parametrize(
    "bad", [[[0.0, 1.0, 2.0]], "180", {"t": 0.0}, [[0.0, "a"], [1.0, 2.0]], [1.0, 2.0], []]
)
def test_a_malformed_profile_says_the_accepted_form(bad):
    with pytest.raises(InputError, match=r"^shaft\.load: .*" + re.escape(ACCEPTED)):
        Shaft("shaft", J=1.0, load=bad)


def test_profile_arrays_are_checked():
    with pytest.raises(InputError, match="as many times as values"):
        Shaft("shaft", J=1.0, load=Profile([0.0, 1.0], [2.0]))
    with pytest.raises(InputError, match=r"^Profile times: must be a flat sequence"):
        Profile([[0.0, 1.0]], [1.0, 2.0])
    with pytest.raises(InputError, match=r"^grid\.V_pk: must be >= 0, got -1$"):
        ThreePhaseSource("grid", V_pk=Profile([0.0, 1.0], [1.0, -1.0]))


def test_a_profile_is_its_times_and_values_and_survives_pickling():
    profile = Profile.from_points([[0.0, 2.0], [1.5, 3.0]])
    times, _ = profile
    assert times.tolist() == [0.0, 1.5] and profile.values.tolist() == [2.0, 3.0]
    assert pickle.loads(pickle.dumps(profile)) == profile
    assert Profile.constant(4.0) == Profile([0.0], [4.0]) != Profile([0.0], [5.0])
    assert repr(profile) == "Profile(times=[0.0, 1.5], values=[2.0, 3.0])"


def _bare_tuples(value, path: str):
    """Paths of 2-tuples of arrays that are not a Profile, anywhere inside a setup."""
    if isinstance(value, Profile):
        return []
    if (
        isinstance(value, tuple)
        and len(value) == 2
        and all(isinstance(a, np.ndarray) for a in value)
    ):
        return [path]
    found = []
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        for f in dataclasses.fields(value):
            found += _bare_tuples(getattr(value, f.name), f"{path}.{f.name}")
    elif isinstance(value, (tuple, list)):
        for i, item in enumerate(value):
            found += _bare_tuples(item, f"{path}[{i}]")
    return found


@pytest.mark.parametrize("name", builtin_names())
def test_the_scenarios_profiles_load_as_profiles(name):
    """The scenario files keep their one form ([[t, value], ...]); the loader makes Profiles."""
    assert _bare_tuples(load_scenario(name), name) == []


def test_scenario_profiles_reach_the_parts():
    """The file's points [[0, 11.1], [1.5, 11.1], [3.0, 8.0], ...] arrive in the source's table."""
    from acdrive.drives import DFIMDrive, IMDrive

    setup = load_scenario("bodson-varying-supply")
    grid = DFIMDrive(setup).grid
    start = grid.PARAMS.table_start  # V_pk is the first table
    n = int(grid.p[start])
    assert grid.p[start + 1 : start + 1 + n].tolist() == [0.0, 1.5, 3.0, 4.5, 5.5]
    assert grid.p[start + 1 + n : start + 1 + 2 * n].tolist() == [11.1, 11.1, 8.0, 8.0, 11.1]
    assert _at(setup.supply.voltage_pk, 2.25) == pytest.approx((11.1 + 8.0) / 2)
    IMDrive(load_scenario("im-foc-speed"))  # every IM table packs
