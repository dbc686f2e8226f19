"""The two tiers of the compiled loop (``acdrive.sim._tier``): the generic loop, which runs any
topology from tables calling the part kinds' kernels, gives the same numbers as the specialised
loop of that topology, bit for bit; a topology the generic loop cannot run falls back to the
specialised compile and says why; damaged or interrupted cache entries are rebuilt, never a
crash; a run reports its compile or load time apart from its simulation time."""

from __future__ import annotations

import json
import os
import pickle
import signal
import subprocess
import sys
import textwrap
import time
import uuid
from pathlib import Path

import numpy as np
import pytest

from acdrive.sim._system import System


def _compiled(system, tier, monkeypatch):
    monkeypatch.setenv("ACDRIVE_LOOP_TIER", tier)
    compiled = system.compile()
    assert compiled.tier == tier
    return compiled


#: The tiers run the same statements, and the fast-math flags (acdrive._jit.FAST_MATH_FLAGS) leave
#: the compiler no reordering, fusing or reciprocals, whose use depends on what surrounds the
#: kernel (inlined into the specialised loop, or compiled alone for the generic one): the tiers
#: give the same bits. Before those flags (reassociation and fused multiply-adds allowed) they
#: differed by up to 1.2e-11 of a signal's peak (0.05 s of the PM drive).


def _assert_same_run(system, monkeypatch, **run):
    """The generic and the specialised loop of ``system`` give the same results, bit for bit."""
    generic = _compiled(system, "generic", monkeypatch).run(**run)
    specialised = _compiled(system, "specialised", monkeypatch).run(**run)
    assert generic.tier == "generic" and specialised.tier == "specialised"
    assert generic.columns == specialised.columns
    assert np.array_equal(generic.data, specialised.data)
    assert np.array_equal(generic.final_state, specialised.final_state)
    assert np.array_equal(generic.event_log, specialised.event_log)
    assert generic.events == specialised.events
    # the comparison means something: the runs moved the plant away from its start
    assert np.ptp(specialised.data, axis=0).max() > 0.0


def _scenario_run(setup, drive, duration):
    initial, held = drive.initial()
    ports = drive.log_ports()
    return {"duration": duration, "sample_time": setup.sample_time, "substeps": setup.substeps,
            "initial": initial, "held": held,
            "log": list(ports.values()) if isinstance(ports, dict) else ports}  # fmt: skip


def test_generic_loop_equals_specialised_on_the_dfim_drive(monkeypatch):
    from acdrive.drives.dfim._drive import DFIMDrive
    from acdrive.scenarios import load_scenario

    setup = load_scenario("bodson-ramp")
    drive = DFIMDrive(setup)
    _assert_same_run(drive.system, monkeypatch, **_scenario_run(setup, drive, 0.3))


def test_generic_loop_equals_specialised_on_the_im_with_a_switching_inverter(monkeypatch):
    from acdrive.drives.cage_im._drive import IMDrive
    from acdrive.scenarios import load_scenario

    setup = load_scenario("im-foc-speed")
    setup = setup.runs()[0][1] if setup.runs() else setup
    assert setup.inverter.model == "switching"  # several segments per sample: the merged loop
    drive = IMDrive(setup)
    _assert_same_run(drive.system, monkeypatch, **_scenario_run(setup, drive, 0.05))


def test_generic_loop_equals_specialised_on_the_pm_drive(monkeypatch):
    from acdrive.drives.pm._build import build
    from acdrive.scenarios import load_scenario

    setup = load_scenario("pm-bly171d-svpwm")
    built = build(setup)
    run = {"duration": 0.05, "sample_time": setup.sample_time, "substeps": setup.substeps,
           "initial": built.initial, "held": built.held, "log": list(built.log.values())}  # fmt: skip
    _assert_same_run(built.system, monkeypatch, **run)


def test_generic_loop_equals_specialised_with_the_sixth_order_method(monkeypatch):
    from acdrive.control._open_loop import VoltageProgram
    from acdrive.machines._cage_part import CageInductionMachine
    from acdrive.machines._induction import UGALDE_IM_300W
    from acdrive.plant._converter import AveragedConverter
    from acdrive.plant._mechanics import Shaft

    im = CageInductionMachine.from_params("im", UGALDE_IM_300W)
    shaft = Shaft("shaft", J=UGALDE_IM_300W.J, B=1e-5, load=[[0.0, 0.0], [0.02, 0.05]])
    program = VoltageProgram("program", V_pk=100.0, f=50.0)
    inverter = AveragedConverter("inverter", V_dc=310.0)
    wires = [(program.out.v_ref, inverter.inp.v_ref), (inverter.out.v, im.inp.v_s),
             (shaft.out.w, im.inp.w), (im.out.tau_e, shaft.inp.tau_e)]  # fmt: skip
    rk6 = System([im, shaft, program, inverter], wires, method="rk6")
    _assert_same_run(rk6, monkeypatch, duration=0.05, sample_time=1e-4, substeps=2,
                     log=[im.out.i_s, shaft.out.w])  # fmt: skip


@pytest.mark.slow
def test_strict_math_tiers_are_bit_identical_on_the_dfim_drive(tmp_path):
    """With strict IEEE arithmetic the compiler may not reorder, so the generic loop, the same
    statements as the specialised one, must give the same bits (in a process of its own: strict
    math is chosen at import, with a cache folder of its own)."""
    code = textwrap.dedent(
        """
        import os, numpy as np
        from acdrive.drives.dfim._drive import DFIMDrive
        from acdrive.scenarios import load_scenario
        setup = load_scenario("bodson-ramp")
        drive = DFIMDrive(setup)
        initial, held = drive.initial()
        out = []
        for tier in ("generic", "specialised"):
            os.environ["ACDRIVE_LOOP_TIER"] = tier
            r = drive.system.compile().run(0.3, setup.sample_time, substeps=setup.substeps,
                                           initial=initial, held=held, log=drive.log_ports())
            out.append(r)
        print(np.array_equal(out[0].data, out[1].data), np.ptp(out[1].data, axis=0).max() > 0)
        """
    )
    env = {**os.environ, "ACDRIVE_STRICT_MATH": "1", "ACDRIVE_BACKGROUND_COMPILE": "0"}
    done = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["True", "True"]


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


def test_a_kind_without_compiled_kernels_falls_back_to_the_specialised_compile_and_says_why(
    tmp_path, monkeypatch
):
    from acdrive.errors import Notice
    from acdrive.sim import _codegen as codegen
    from acdrive.sim import _tier

    from acdrive.sim._ccode import _kinds

    user = _user_kind(tmp_path)
    # the kind's C would be generated from its kernel (the native tier would run it): kept out
    # here, so that the numba tiers' own fallback is what runs
    monkeypatch.setitem(_kinds._UNTRANSLATABLE, user.Decay, "kept out of C by this test")
    monkeypatch.setenv("ACDRIVE_LOOP_TIER", "auto")
    monkeypatch.setenv("ACDRIVE_COMPILE_NOTICE", "1")
    monkeypatch.setenv("ACDRIVE_BACKGROUND_COMPILE", "0")
    one = user.Decay("d", a=20.0)
    with pytest.warns(Notice) as caught:
        compiled = System([one], []).compile()
    said = [str(w.message) for w in caught if issubclass(w.category, Notice)]
    assert len(said) == 1
    assert said[0].startswith("compiling the specialised simulation loop for this topology")
    assert "no compiled kernels for the part kind(s) Decay" in said[0]
    assert compiled.tier == "specialised"
    result = compiled.run(**_RUN, log=[one.out.y])
    assert result.tier == "specialised" and result.compiled_now and result.compile_time > 0.0
    _assert_decays(result, 20.0)

    # once the kind's kernels are compiled (what the background compile does), a topology never
    # seen before runs in the generic loop without compiling a loop of its own
    _tier.compile_generic_tier(System([one], []))
    fast, slow = user.Decay("fast", a=20.0), user.Decay("slow", a=5.0)
    compiled = System([fast, slow], []).compile()
    assert compiled.tier == "generic"
    with pytest.warns(Notice, match="a new topology: running the generic loop, no compile"):
        result = compiled.run(**_RUN, log=[fast.out.y, slow.out.y])
    assert result.tier == "generic"
    assert not compiled.module.run.overloads and not codegen.is_cached(compiled.module.run)
    _assert_decays(result, 20.0, 5.0)


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
           "ACDRIVE_BACKGROUND_COMPILE": "0", **env}  # fmt: skip
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


_START_BACKGROUND = """
import sys
sys.path.insert(0, sys.argv[1])
import importlib
user = importlib.import_module(sys.argv[2])
from acdrive.sim import _tier
from acdrive.sim._system import System
system = System([user.Decay("d", a=20.0)], [])
process = _tier.start_background(kinds=[user.Decay], specialised_source=system.source(), size=1)
print(process.pid)
"""


def _readable_indexes(cache: Path) -> int:
    """How many numba index files under ``cache`` (all must unpickle: no broken entry)."""
    count = 0
    for path in cache.rglob("*.nbi"):
        with open(path, "rb") as handle:
            pickle.load(handle)
            pickle.loads(handle.read())
        count += 1
    return count


@pytest.mark.slow
def test_an_interrupted_background_compile_leaves_no_broken_entry(tmp_path):
    user = _user_kind(tmp_path)
    cache = tmp_path / "cache"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "ACDRIVE_BACKGROUND_COMPILE": "1",
           "PYTHONPATH": os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")])}  # fmt: skip
    started = subprocess.run([sys.executable, "-c", _START_BACKGROUND, str(tmp_path),
                              user.__name__], env=env, capture_output=True, text=True, check=False)  # fmt: skip
    assert started.returncode == 0, started.stderr
    pid = int(started.stdout.split()[-1])
    # interrupt it while it compiles the loop: once the kind's kernels are in the cache
    deadline = time.monotonic() + 120.0
    while time.monotonic() < deadline and not any(
        "user_decay" in p.name for p in cache.rglob("*.nbi")
    ):
        time.sleep(0.05)
    try:
        os.killpg(pid, signal.SIGKILL)
    except ProcessLookupError:
        pass  # it finished first: what follows must hold all the same
    _readable_indexes(cache)
    again, _ = _run_decay(tmp_path, user.__name__)
    assert again["tier"] in ("generic", "specialised")
    after, _ = _run_decay(tmp_path, user.__name__, ACDRIVE_LOOP_TIER="specialised")
    assert _readable_indexes(cache) > 0
    t = np.arange(100) * 1e-3
    for result in (again, after):
        assert np.allclose(result["y"], np.exp(-20.0 * t), rtol=1e-8, atol=0.0)


# --- honest timing --------------------------------------------------------------------------
def test_timing_tells_the_simulation_apart_from_the_compile_or_load():
    from types import SimpleNamespace

    from acdrive.sim._timing import run_timing, simulated_in

    compiled = SimpleNamespace(wall_time=0.13, compile_time=12.154, compiled_now=True,
                               tier="specialised")  # fmt: skip
    loaded = SimpleNamespace(wall_time=0.5, compile_time=0.04, compiled_now=False, tier="generic")
    warm = SimpleNamespace(wall_time=0.25, compile_time=0.0, compiled_now=False, tier="generic")
    assert (
        simulated_in([compiled]) == "simulated in 0.13 s (+ 12.15 s compiling the specialised loop)"
    )
    assert simulated_in([loaded]) == "simulated in 0.50 s (+ 0.04 s loading the generic loop)"
    assert simulated_in([warm]) == "simulated in 0.25 s (generic loop)"
    timing = run_timing([compiled, warm])
    assert timing["wall_time_s"] == pytest.approx(0.38)
    assert timing["compile_time_s"] == pytest.approx(12.154)
    assert timing["loop_compiled"] is True
    assert timing["compiled_loop_tier"] == "generic and specialised"


def test_a_run_reports_its_loop_time_once(monkeypatch):
    """The compile or load of ``System.compile()`` is reported by the first run only; the
    second run of the same compiled system has nothing to load."""
    from acdrive.plant._sources import ThreePhaseSource

    monkeypatch.setenv("ACDRIVE_BACKGROUND_COMPILE", "0")
    grid = ThreePhaseSource("grid", V_pk=100.0)
    compiled = System([grid], []).compile()
    assert compiled.tier in ("generic", "specialised")
    first = compiled.run(0.02, 1e-3, log=[grid.out.v])
    second = compiled.run(0.02, 1e-3, log=[grid.out.v])
    assert first.tier == second.tier == compiled.tier
    assert first.compile_time > 0.0 and second.compile_time == 0.0
    assert f"({compiled.tier} loop)" in repr(second)
    assert np.array_equal(first.data, second.data)


@pytest.mark.slow
def test_a_background_compile_finds_kernels_generated_beside_the_loop(tmp_path):
    """A loop with a batch's stats reducer imports that reducer's step from a generated module
    (``_reducer_parts._stats_source``). The background process never built the reducer, so it
    never loaded that module: it finds it in the folder of the generated loops, compiles the
    loop into the cache, and this process then loads it without compiling."""
    from acdrive._reducer_parts import _stats_class
    from acdrive.sim import _codegen as codegen

    user = _user_kind(tmp_path)
    decay = user.Decay("d", a=20.0)
    stats = _stats_class((("", False, False),))("stats", every=1.0, start0=0.0, stop0=1.0,
                                                limit0=0.5)  # fmt: skip
    system = System([decay, stats], [(decay.out.y, stats.inp.x0)])
    source = system.source()
    assert "import stats_step" in source and "from acdrive_system_" in source
    module = codegen.load_module(source)  # written to the cache folder; nothing compiled yet
    assert not codegen.is_cached(module.run)
    job = {"kinds": [], "generic": False, "specialised": str(codegen.module_path(source)),
           "size": 2}  # fmt: skip
    env = {**os.environ,
           "PYTHONPATH": os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")])}  # fmt: skip
    done = subprocess.run([sys.executable, "-m", "acdrive.sim._background", json.dumps(job)],
                          env=env, capture_output=True, text=True, check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert codegen.is_cached(module.run)
