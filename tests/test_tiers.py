"""The compiled loop's tiers (``acdrive.sim._tier``) and its cache: a part kind outside the
language the C translator takes falls back to numba's specialised compile and says why; damaged
cache entries are rebuilt, never a crash; a run reports its compile or load time apart from its
simulation time. That the native loop and the specialised loop give the same bits is
``tests/test_native_tier.py``'s."""

from __future__ import annotations

import os
import subprocess
import sys
import uuid
from pathlib import Path

import numpy as np
import pytest

from acdrive.sim._system import System


# --- a part kind of the user's ------------------------------------------------------------------
_DECAY = """
# {tag}
from numba import njit
from acdrive.core._parts import ContinuousPart
from acdrive.core._signals import Layout, real


@njit
def decay_outputs(t, x, p, y):
    y[0] = x[0]


@njit
def decay_rhs(t, x, u, p, y, dx):
    dx[0] = -p[0] * x[0]


class Decay(ContinuousPart):
    PARAMS = Layout(real("a", "1/s", "decay rate", "positive"))
    STATES = Layout(real("x", "", "the decaying quantity"))
    OUTPUTS = Layout(real("y", "", "the decaying quantity"))
    INITIAL = {{"x": 1.0}}
    state_outputs = decay_outputs
    rhs = decay_rhs
"""

#: a run of the decay: 0.1 s in samples of 1 ms, 4 RK4 steps each (h a = 5e-3 at a = 20 1/s:
#: RK4's error per unit time (h a)^4 a / 120 ~ 1e-10 relative)
_RUN = {"duration": 0.1, "sample_time": 1e-3, "substeps": 4}


def _user_kind(folder: Path):
    """A module with the part kind ``Decay`` (dx/dt = -a x), new to this machine (a fresh tag in
    its source gives its kernels a fingerprint no cache has seen)."""
    import importlib

    name = f"user_decay_{uuid.uuid4().hex[:12]}"
    (folder / f"{name}.py").write_text(_DECAY.format(tag=uuid.uuid4().hex))
    sys.path.insert(0, str(folder))
    try:
        return importlib.import_module(name)
    finally:
        sys.path.remove(str(folder))


def _assert_decays(result, *rates):
    """Each logged decay follows x(t) = exp(-a t) (the run logs before each sample's step)."""
    for j, a in enumerate(rates):
        assert np.allclose(result.data[:, j], np.exp(-a * result.t), rtol=1e-8, atol=0.0)


def test_a_kind_outside_the_c_language_falls_back_to_the_specialised_compile_and_says_why(
    tmp_path, monkeypatch
):
    from acdrive.errors import Notice
    from acdrive.sim._ccode import _kinds

    user = _user_kind(tmp_path)
    # the kind's C would be generated from its kernel: kept out here, so that the fallback runs
    monkeypatch.setitem(_kinds._UNTRANSLATABLE, user.Decay, "kept out of C by this test")
    monkeypatch.setenv("ACDRIVE_LOOP_TIER", "auto")
    monkeypatch.setenv("ACDRIVE_COMPILE_NOTICE", "1")
    one = user.Decay("d", a=20.0)
    with pytest.warns(Notice) as caught:
        compiled = System([one], []).compile()
    said = [str(w.message) for w in caught if issubclass(w.category, Notice)]
    assert len(said) == 1
    assert said[0].startswith("compiling the specialised simulation loop for this topology")
    assert "the native loop cannot run it" in said[0] and "kept out of C by this test" in said[0]
    assert compiled.tier == "specialised"
    result = compiled.run(**_RUN, log=[one.out.y])
    assert result.tier == "specialised" and result.compiled_now and result.compile_time > 0.0
    _assert_decays(result, 20.0)


_RUN_DECAY = """
import json, sys, warnings
sys.path.insert(0, sys.argv[1])
import importlib
user = importlib.import_module(sys.argv[2])
from acdrive.sim._system import System
part = user.Decay("d", a=20.0)
result = System([part], []).compile().run(0.1, 1e-3, 4, log=[part.out.y])
print(json.dumps({"tier": result.tier, "compiled": result.compiled_now,
                  "compile_time": result.compile_time, "wall_time": result.wall_time,
                  "repr": repr(result), "y": result.data[:, 0].tolist()}))
"""


def _run_decay(folder: Path, module: str, **env):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(folder / "cache"), "ACDRIVE_COMPILE_NOTICE": "1",
           **env}  # fmt: skip
    done = subprocess.run([sys.executable, "-c", _RUN_DECAY, str(folder), module], env=env,
                          capture_output=True, text=True, check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr
    import json

    return json.loads(done.stdout.strip().splitlines()[-1]), done.stderr


def _notice_lines(stderr: str, text: str) -> int:
    return sum(text in line for line in stderr.splitlines() if "Notice" in line)


@pytest.mark.slow
def test_a_damaged_cache_file_is_rebuilt_with_one_line(tmp_path):
    user = _user_kind(tmp_path)
    name = user.__name__
    first, _ = _run_decay(tmp_path, name, ACDRIVE_LOOP_TIER="specialised")
    assert first["compiled"] and first["tier"] == "specialised"
    # System.compile() compiled: the run's own time is the simulation alone, told apart
    assert first["wall_time"] < first["compile_time"]
    assert "compiling the specialised loop" in first["repr"]
    cache = tmp_path / "cache"
    # numba's index of the loop unreadable
    indexes = [p for p in cache.rglob("*.nbi") if "acdrive_system" in p.name]
    assert indexes
    for path in indexes:
        path.write_bytes(b"not a pickle")
    second, stderr = _run_decay(tmp_path, name, ACDRIVE_LOOP_TIER="specialised")
    assert _notice_lines(stderr, "could not be read") == 1
    assert second["compiled"] and second["y"] == first["y"]
    # the generated module truncated
    (module,) = [p for p in (cache / "systems").glob("acdrive_system_*.py")
                 if "acdrive.sim._loop_source" in p.read_text()]  # fmt: skip
    text = module.read_text()
    module.write_text(text[: len(text) // 2])
    third, stderr = _run_decay(tmp_path, name, ACDRIVE_LOOP_TIER="specialised")
    assert _notice_lines(stderr, "was damaged") == 1
    assert third["y"] == first["y"] and module.read_text() == text
    # a data file of the loop's machine code damaged (its index reads well)
    data = [p for p in cache.rglob("*.nbc") if "acdrive_system" in p.name]
    assert data
    for path in data:
        path.write_bytes(path.read_bytes()[:64])
    again, stderr = _run_decay(tmp_path, name, ACDRIVE_LOOP_TIER="specialised")
    assert _notice_lines(stderr, "could not be read") == 1
    assert again["compiled"] and again["y"] == first["y"]
    # and then a plain load
    fourth, stderr = _run_decay(tmp_path, name, ACDRIVE_LOOP_TIER="specialised")
    assert not fourth["compiled"] and "Notice" not in stderr and fourth["y"] == first["y"]
    assert "loading the specialised loop" in fourth["repr"]
    t = np.arange(100) * 1e-3
    assert np.allclose(first["y"], np.exp(-20.0 * t), rtol=1e-8, atol=0.0)


_RUN_DECAYS = """
import json, sys, warnings
sys.path.insert(0, sys.argv[1])
import importlib
user = importlib.import_module(sys.argv[2])
from acdrive.errors import Notice
from acdrive.sim._system import System
parts = [user.Decay(f"d{i}", a=20.0) for i in range(int(sys.argv[3]))]
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    result = System(parts, []).compile().run(0.01, 1e-3, 4, log=[parts[0].out.y])
notes = [str(w.message) for w in caught if issubclass(w.category, Notice)]
print(json.dumps({"notes": notes, "compile_time": result.compile_time}))
"""


@pytest.mark.slow
def test_the_compile_notice_names_the_tier_and_the_time_measured_for_the_size(tmp_path):
    """One notice when a loop compiles, none when it loads; a loop of another size is announced
    with the time measured here, scaled to its number of parts."""
    import json

    user = _user_kind(tmp_path)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache"), "ACDRIVE_COMPILE_NOTICE": "1",
           "ACDRIVE_LOOP_TIER": "specialised"}  # fmt: skip
    runs = []
    for n_parts in (1, 1, 2):
        done = subprocess.run([sys.executable, "-c", _RUN_DECAYS, str(tmp_path), user.__name__,
                               str(n_parts)], env=env, capture_output=True, text=True, check=False)  # fmt: skip
        assert done.returncode == 0, done.stderr
        runs.append(json.loads(done.stdout.strip().splitlines()[-1]))
    (first, loaded, other) = runs
    assert len(first["notes"]) == 1
    assert first["notes"][0].startswith("compiling the specialised simulation loop")
    assert "about" not in first["notes"][0]  # nothing measured on this machine yet
    assert loaded["notes"] == [] and loaded["compile_time"] < first["compile_time"]
    assert len(other["notes"]) == 1
    expected = f"about {2 * first['compile_time']:.2g} s as measured on this machine for 2 parts"
    assert expected in other["notes"][0]


# --- honest timing --------------------------------------------------------------------------
def test_timing_tells_the_simulation_apart_from_the_compile_or_load():
    from types import SimpleNamespace

    from acdrive.sim._timing import run_timing, simulated_in

    compiled = SimpleNamespace(wall_time=0.13, compile_time=12.154, compiled_now=True,
                               tier="specialised")  # fmt: skip
    loaded = SimpleNamespace(wall_time=0.5, compile_time=0.04, compiled_now=False, tier="native")
    warm = SimpleNamespace(wall_time=0.25, compile_time=0.0, compiled_now=False, tier="native")
    assert (
        simulated_in([compiled]) == "simulated in 0.13 s (+ 12.15 s compiling the specialised loop)"
    )
    assert simulated_in([loaded]) == "simulated in 0.50 s (+ 0.04 s loading the native loop)"
    assert simulated_in([warm]) == "simulated in 0.25 s (native loop)"
    timing = run_timing([compiled, warm])
    assert timing["wall_time_s"] == pytest.approx(0.38)
    assert timing["compile_time_s"] == pytest.approx(12.154)
    assert timing["loop_compiled"] is True
    assert timing["compiled_loop_tier"] == "native and specialised"


def test_a_run_reports_its_loop_time_once(monkeypatch):
    """The compile or load of ``System.compile()`` is reported by the first run only; the
    second run of the same compiled system has nothing to load."""
    from acdrive.plant._sources import ThreePhaseSource

    grid = ThreePhaseSource("grid", V_pk=100.0)
    compiled = System([grid], []).compile()
    assert compiled.tier in ("native", "specialised")
    first = compiled.run(0.02, 1e-3, log=[grid.out.v])
    second = compiled.run(0.02, 1e-3, log=[grid.out.v])
    assert first.tier == second.tier == compiled.tier
    assert first.compile_time > 0.0 and second.compile_time == 0.0
    assert f"({compiled.tier} loop)" in repr(second)
    assert np.array_equal(first.data, second.data)
