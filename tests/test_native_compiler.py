"""Which compiler the native tier takes (sim._native.compiler_command): the machine's C compiler,
else the clang of the ``ziglang`` package from PyPI, else none, and then the native tier names
the missing compiler as its obstacle. With ziglang installed, its build of a drive's loop gives
the machine compiler's results bit for bit."""

import sys

import numpy as np
import pytest

from acdrive.sim import _native


def test_the_machines_compiler_comes_first(monkeypatch):
    monkeypatch.setattr(_native, "compiler", lambda: "/usr/bin/cc")
    assert _native.compiler_command() == ["/usr/bin/cc"]


def test_without_one_the_ziglang_package_compiles(monkeypatch):
    import importlib.util

    monkeypatch.setattr(_native, "compiler", lambda: None)
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name: object() if name == "ziglang" else None)  # fmt: skip
    assert _native.compiler_command() == [sys.executable, "-m", "ziglang", "cc"]


def test_without_either_the_native_tier_names_what_is_missing(monkeypatch):
    import importlib.util

    from acdrive.scenarios import load_scenario
    from acdrive.drives.cage_im._drive import IMDrive

    monkeypatch.setattr(_native, "compiler", lambda: None)
    monkeypatch.setattr(importlib.util, "find_spec", lambda name: None)
    assert _native.compiler_command() is None
    setup = load_scenario("im-foc-speed")
    system = IMDrive(setup.runs()[0][1] if setup.runs() else setup).system
    obstacle = _native.native_obstacle(system)
    assert "no C compiler" in obstacle and "ziglang" in obstacle


@pytest.mark.skipif(__import__("importlib.util").util.find_spec("ziglang") is None,
                    reason="the ziglang package is not installed")  # fmt: skip
def test_ziglangs_build_equals_the_machine_compilers(monkeypatch, tmp_path):
    """The cage IM's speed drive over 0.05 s, its library built by each compiler into a folder
    of its own: the logged outputs and the final state agree bit for bit."""
    import dataclasses

    from acdrive.drives.cage_im._drive import IMDrive
    from acdrive.scenarios import load_scenario

    setup = load_scenario("im-foc-speed")
    setup = dataclasses.replace(setup.runs()[0][1] if setup.runs() else setup, duration=0.05)
    monkeypatch.setenv("ACDRIVE_LOOP_TIER", "native")
    runs = {}
    for which in ("machine", "ziglang"):
        if which == "ziglang":
            monkeypatch.setattr(_native, "compiler", lambda: None)
            assert _native.compiler_command()[1:] == ["-m", "ziglang", "cc"]
        monkeypatch.setattr(_native, "_folder", lambda which=which: tmp_path / which)
        (tmp_path / which).mkdir()
        drive = IMDrive(setup)
        compiled = drive.compile()
        assert compiled.tier == "native"
        initial, held = drive.initial()
        runs[which] = compiled.run(setup.duration, setup.sample_time, substeps=setup.substeps,
                                   initial=initial, held=held)  # fmt: skip
    a, b = runs["machine"], runs["ziglang"]
    assert np.array_equal(a.data, b.data) and np.array_equal(a.final_state, b.final_state)
