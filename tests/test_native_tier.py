"""The native tier of the loop (``acdrive.sim._native``): the whole sampled-data loop as C from
the parts' C (``acdrive.sim._ccode``, the text the export writes), compiled by the machine's C
compiler. It gives the specialised loop's numbers bit for bit (the same operations in the same
order), under strict IEEE arithmetic and with numba's default fast-math flags alike; a system it cannot run falls back to numba's tiers and says why; a damaged or half-built
library is never used."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from acdrive._jit import jit
from acdrive.errors import InputError, SimulationDiverged
from acdrive.sim import _native
from acdrive.sim._system import System

needs_cc = pytest.mark.skipif(_native.compiler() is None, reason="no C compiler on this machine")


def _compiled(system, tier, monkeypatch):
    monkeypatch.setenv("ACDRIVE_LOOP_TIER", tier)
    compiled = system.compile()
    assert compiled.tier == tier
    return compiled


def _open_loop_im(method="rk4", load_points=2):
    """A cage IM fed by an open-loop V/f program through an averaged converter (every kind has C;
    the program's table and the shaft's load step make the run move)."""
    from acdrive.control._open_loop import VoltageProgram
    from acdrive.machines._cage_part import CageInductionMachine
    from acdrive.machines._induction import UGALDE_IM_300W
    from acdrive.plant._converter import AveragedConverter
    from acdrive.plant._mechanics import Shaft

    im = CageInductionMachine.from_params("im", UGALDE_IM_300W)
    load = [[0.0, 0.0]] + [[0.02 + 1e-3 * k, 0.05] for k in range(load_points - 1)]
    shaft = Shaft("shaft", J=UGALDE_IM_300W.J, B=1e-5, load=load)
    program = VoltageProgram(
        "program", V_pk=[[0.0, 20.0], [0.05, 100.0]], f=[[0.0, 10.0], [0.05, 50.0]]
    )
    inverter = AveragedConverter("inverter", V_dc=310.0)
    wires = [(program.out.v_ref, inverter.inp.v_ref), (inverter.out.v, im.inp.v_s),
             (shaft.out.w, im.inp.w), (im.out.tau_e, shaft.inp.tau_e)]  # fmt: skip
    return System([im, shaft, program, inverter], wires, method=method), im, shaft


@needs_cc
@pytest.mark.parametrize("method", ["rk4", "rk6"])
def test_native_equals_specialised_in_the_default_build(method, monkeypatch):
    """numba with its default fast-math flags against the strict C: the same run bit for bit
    (``acdrive._jit.FAST_MATH_FLAGS`` allow no reordering, fusing or reciprocals, and both sides
    compute sin, cos and |z| alike), the events and the run's length too."""
    system, im, shaft = _open_loop_im(method)
    run = {"duration": 0.08, "sample_time": 1e-4, "substeps": 2, "log": [im.out.i_s, shaft.out.w]}
    native = _compiled(system, "native", monkeypatch).run(**run)
    specialised = _compiled(system, "specialised", monkeypatch).run(**run)
    assert native.tier == "native" and specialised.tier == "specialised"
    assert native.columns == specialised.columns and native.steps == specialised.steps
    assert np.ptp(specialised.data, axis=0).min() > 0.0  # the run moves every logged signal
    assert np.array_equal(native.data, specialised.data)
    assert np.array_equal(native.final_state, specialised.final_state)
    assert native.events == specialised.events


@needs_cc
@pytest.mark.slow
@pytest.mark.parametrize("strict", ["1", "0"], ids=["strict-math", "default-flags"])
def test_native_equals_specialised_bit_for_bit(tmp_path, strict):
    """The native loop repeats the specialised loop's operations in the same order: every logged
    value, event bit and final state is equal, on the DFIM drive (relay, supply bus, averaged
    converter), the cage IM with the switching SVPWM inverter (segments inside a sample) and the
    PM drive; with ACDRIVE_STRICT_MATH=1 (numba without fast-math) and with numba's default
    flags (acdrive._jit.FAST_MATH_FLAGS, which allow no reordering, fusing or reciprocals)."""
    script = textwrap.dedent(
        """
        import json, os, sys
        import numpy as np
        from acdrive.scenarios import load_scenario
        from acdrive.drives import for_setup

        out = {}
        for name, duration in (("bodson-sync", 1.0), ("im-foc-speed", 0.05),
                               ("pm-bly171d-svpwm", 0.05)):
            setup = load_scenario(name)
            runs = setup.runs() if hasattr(setup, "runs") and callable(setup.runs) else []
            setup = runs[0][1] if runs else setup
            results = {}
            for tier in ("native", "specialised"):
                os.environ["ACDRIVE_LOOP_TIER"] = tier
                drive = for_setup(setup).build(setup)
                initial, held = drive.initial()
                compiled = drive.system.compile()
                r = compiled.run(duration, setup.sample_time, setup.substeps, initial=initial,
                                 held=held)
                results[tier] = r
            a, b = results["native"], results["specialised"]
            out[name] = {
                "tiers": [a.tier, b.tier],
                "data_equal": bool(np.array_equal(a.data, b.data)),
                "events_equal": bool(np.array_equal(a.event_log, b.event_log)),
                "state_equal": bool(np.array_equal(a.final_state, b.final_state)),
                "moved": float(np.ptp(b.data, axis=0).max()),
            }
        print(json.dumps(out))
        """
    )
    env = dict(os.environ, ACDRIVE_STRICT_MATH=strict, ACDRIVE_COMPILE_NOTICE="0")  # fmt: skip
    done = subprocess.run([sys.executable, "-c", script], env=env, check=False,
                          capture_output=True, text=True, timeout=1800, cwd=tmp_path)  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    found = json.loads(done.stdout.strip().splitlines()[-1])
    for name, row in found.items():
        assert row["tiers"] == ["native", "specialised"], name
        assert row["moved"] > 0.0, name
        assert row["data_equal"] and row["events_equal"] and row["state_equal"], (name, row)


@needs_cc
def test_native_reports_a_diverging_run_as_the_specialised_loop_does(monkeypatch):
    """A step far too long for the machine's electrical time constant: both tiers stop at the
    same sample with the same one-line error (never NaN in a result)."""
    system, im, _ = _open_loop_im()
    run = {"duration": 0.5, "sample_time": 0.05, "substeps": 1, "log": [im.out.i_s]}
    errors = []
    for tier in ("native", "specialised"):
        with pytest.raises(SimulationDiverged) as caught:
            _compiled(system, tier, monkeypatch).run(**run)
        errors.append(str(caught.value))
    assert errors[0] == errors[1]


@needs_cc
def test_a_damaged_library_is_built_again_with_a_notice(tmp_path):
    """A cached library that does not load (truncated, overwritten) is removed and built again,
    with one line; never a crash."""
    system, _, _ = _open_loop_im()
    source = _native.native_source(system)
    path = _native.library_path(source, tmp_path)
    path.write_bytes(b"not a shared library")
    said = []
    loop, _, compiled = _native.build(source, notice=said.append, folder=tmp_path)
    assert compiled and loop.path == path
    assert len(said) == 1 and "built again" in said[0] and path.name in said[0]
    assert path.read_bytes()[:4] == b"\x7fELF"
    assert not [p for p in tmp_path.iterdir() if p.name.startswith("acdrive-native-")]


@needs_cc
def test_a_failed_compile_leaves_nothing_and_the_numba_tiers_run(monkeypatch, tmp_path):
    """A compiler that fails (or is interrupted) leaves no library in the cache; the auto tier
    then runs numba's loop, and ACDRIVE_LOOP_TIER=native names the cause."""
    failing = tmp_path / "cc"
    failing.write_text("#!/bin/sh\necho 'cc: interrupted' >&2\nexit 1\n")
    failing.chmod(0o755)
    monkeypatch.setenv("CC", str(failing))
    # a table length no other test uses: a library nobody built (the struct's size is in its C)
    system, _, _ = _open_loop_im(load_points=3 + int(tmp_path.stat().st_ino % 9973))
    path = _native.library_path(_native.native_source(system))
    assert not path.exists()
    with pytest.raises(InputError) as caught:
        _compiled(system, "native", monkeypatch)
    assert caught.value.field == "ACDRIVE_LOOP_TIER" and "interrupted" in str(caught.value)
    assert not path.exists()
    assert not [p for p in path.parent.iterdir() if p.name.startswith("acdrive-native-")]
    monkeypatch.setenv("ACDRIVE_LOOP_TIER", "auto")
    assert system.compile().tier == "specialised"


@jit
def looping_step(t, T_s, u, p, s, y):
    """A user's kernel outside the kernel language: a while loop (numba compiles it)."""
    k = 0
    while k < 2:
        y[k] = 0.0
        k += 1
    return 0


def _with_user_program(system, kind):
    """``system`` with its V/f program replaced by an instance of the user's ``kind``."""
    im, shaft, inverter = (system.part(n) for n in ("im", "shaft", "inverter"))
    mine = kind("mine", **system.part("program").values)
    return System([im, shaft, mine, inverter],
                  [(mine.out.v_ref, inverter.inp.v_ref), (inverter.out.v, im.inp.v_s),
                   (shaft.out.w, im.inp.w), (im.out.tau_e, shaft.inp.tau_e)])  # fmt: skip


@needs_cc
def test_a_users_part_runs_natively_from_its_kernel(monkeypatch):
    """A user's part kind, declared with the public API and registered nowhere, gets its C
    generated from its kernel: the system runs on the native tier, equal bit for bit to the
    specialised numba loop."""
    from acdrive.control._open_loop import VoltageProgram
    from acdrive.core._parts import SampledPart

    class MyProgram(SampledPart):
        """A V/f program written by a user (VoltageProgram's declarations and kernel)."""

        PARAMS, STATES, OUTPUTS = VoltageProgram.PARAMS, VoltageProgram.STATES, VoltageProgram.OUTPUTS
        step = VoltageProgram.step

    system, _, _ = _open_loop_im()
    user = _with_user_program(system, MyProgram)
    assert _native.native_obstacle(user) is None
    run = {"duration": 0.05, "sample_time": 1e-4, "substeps": 2, "log": [user.part("shaft").out.w]}
    native = _compiled(user, "native", monkeypatch).run(**run)
    reference = _compiled(user, "specialised", monkeypatch).run(**run)
    assert native.data[-1, 0] > 1.0  # the program drove the shaft
    assert np.array_equal(native.data, reference.data)


def test_a_part_outside_the_kernel_language_is_named_and_numba_runs_it(monkeypatch):
    """A user's kind whose kernel is outside the kernel language (a while loop) has no C: the
    native tier names the kind, the kernel's line and the construct, and the auto tier runs
    numba."""
    from acdrive.control._open_loop import VoltageProgram
    from acdrive.core._parts import SampledPart

    class MyLoop(SampledPart):
        """A program whose kernel loops while a condition holds."""

        PARAMS, STATES, OUTPUTS = VoltageProgram.PARAMS, VoltageProgram.STATES, VoltageProgram.OUTPUTS
        step = looping_step

    system, _, _ = _open_loop_im()
    user = _with_user_program(system, MyLoop)
    reason = _native.native_obstacle(user)
    assert reason is not None and ("MyLoop" in reason or "compiler" in reason)
    if "compiler" not in reason:
        assert "looping_step (line " in reason and "the statement While" in reason
    monkeypatch.setenv("ACDRIVE_LOOP_TIER", "native")
    with pytest.raises(InputError, match="native cannot run this system"):
        user.compile()


@needs_cc
def test_one_library_serves_every_parameter_set(monkeypatch):
    """The library names no parameter value: re-parametrised parts (``run(parts=...)``) run in
    it without a compile and give the specialised loop's run with the same parts; tables of
    other lengths than its structs hold run in the specialised loop."""
    system, _, shaft = _open_loop_im()
    heavier = [shaft.with_params(J=3.0 * shaft.values["J"])]
    run = {"duration": 0.05, "sample_time": 1e-4, "substeps": 2, "log": [shaft.out.w]}
    native = _compiled(system, "native", monkeypatch)
    light, heavy = native.run(**run), native.run(**run, parts=heavier)
    assert heavy.tier == "native" and heavy.compile_time == 0.0
    assert light.data[-1, 0] > 1.5 * heavy.data[-1, 0] > 0.0  # three times the inertia: slower
    reference = _compiled(system, "specialised", monkeypatch).run(**run, parts=heavier)
    assert np.array_equal(heavy.data, reference.data)
    longer = [system.part("program").with_params(V_pk=[[0.0, 20.0], [0.02, 60.0], [0.05, 100.0]])]
    other = native.run(**run, parts=longer)
    assert other.tier == "specialised" and native.tier == "native"


@needs_cc
def test_the_native_library_does_not_depend_on_the_period_or_the_start(monkeypatch):
    """One library per topology: the sample time, substeps and initial state are arguments of
    each run (a second period or start loads, never compiles)."""
    system, _, shaft = _open_loop_im()
    compiled = _compiled(system, "native", monkeypatch)
    first = compiled.run(0.02, 1e-4, 2, log=[shaft.out.w])
    second = compiled.run(0.02, 2e-4, 3, initial={"shaft": {"w": 10.0}}, log=[shaft.out.w])
    assert compiled.tier == "native" and second.compile_time == 0.0
    assert second.data[0, 0] == 10.0 and first.data[0, 0] == 0.0
    assert first.steps == 200 and second.steps == 100


def test_importing_and_running_natively_needs_no_numba(tmp_path):
    """A warm run of the native tier never imports numba: its import and first use would cost
    more than the whole run (issue 21). (scipy is imported, by the current controller's Tustin
    discretisation, ``control._discretise``.)"""
    if _native.compiler() is None:
        pytest.skip("no C compiler on this machine")
    script = textwrap.dedent(
        """
        import sys
        from acdrive._bench.motulator_im import SUBSTEPS, T_S, log_ports, matched_acdrive_system
        system, parts = matched_acdrive_system("averaged")
        compiled = system.compile()
        result = compiled.run(0.05, T_S, substeps=SUBSTEPS, log=log_ports(parts))
        print(compiled.tier, "numba" in sys.modules)
        """
    )
    env = dict(os.environ, ACDRIVE_LOOP_TIER="auto", ACDRIVE_COMPILE_NOTICE="0")  # fmt: skip
    done = subprocess.run([sys.executable, "-c", script], env=env, check=False,
                          capture_output=True, text=True, timeout=600, cwd=tmp_path)  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split() == ["native", "False"]


@needs_cc
def test_kept_objects_serve_a_new_controller_and_a_damaged_one_is_rebuilt(tmp_path):
    """The plant's object is kept under the hash of its C: a second topology on the same plant
    compiles only its controller and driver; an object that no longer links is removed and
    the library built again."""
    system, _, _ = _open_loop_im()
    first, _, _ = _native.build(_native.native_source(system), folder=tmp_path)
    plant_objects = sorted(tmp_path.glob("acdn_plant_*.o"))
    assert len(plant_objects) == 1 and len(list(tmp_path.glob("*.o"))) == 3
    other, _, _ = _open_loop_im()
    other.part("program").__init__("program", V_pk=50.0, f=25.0)  # a one-point table: other C
    source = _native.native_source(other)
    assert _native.library_path(source, tmp_path) != first.path
    _native.build(source, folder=tmp_path)
    assert sorted(tmp_path.glob("acdn_plant_*.o")) == plant_objects  # the plant reused
    plant_objects[0].write_bytes(b"damaged")
    _native.library_path(source, tmp_path).unlink()  # the next build links the kept objects
    loop, _, compiled = _native.build(source, folder=tmp_path)
    assert compiled and loop.path.read_bytes()[:4] == b"\x7fELF"
    assert plant_objects[0].read_bytes()[:4] == b"\x7fELF"  # compiled again


def test_every_built_in_scenario_has_c_for_every_part():
    """Every run of every built-in scenario has C for each of its part kinds, so the native tier
    runs it. A kind that lost its C would fall back to numba with the same numbers, which a
    comparison of results cannot see; this names the kind and the reason."""
    from acdrive.export._cost import one_run
    from acdrive.export._scenario import built
    from acdrive.scenarios import builtin_names, load_scenario
    from test_export_compilers import _runs

    if _native.compiler() is None:
        pytest.skip("no C compiler on this machine")
    obstacles = {}
    for name in builtin_names():
        setup = load_scenario(name)
        runs = [setup]
        try:
            built(setup)
        except InputError:  # a comparison: each of its runs
            runs = [one_run(setup, label) for label in _runs(setup)]
        for run in runs:
            drive, _, _ = built(run)
            reason = _native.native_obstacle(drive.system)
            if reason is not None:
                obstacles[f"{name}/{run.name}"] = reason
    assert obstacles == {}
