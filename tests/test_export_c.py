"""The C export (issue 22, item 1): the generated C99 compiles warning-free and pedantic in both
precisions, has no dynamic memory, no recursion and only fixed-bound loops, uses only the libm
functions a microcontroller has; a part without C is named in a one-line error (exit 2 on the
command line); ``acdrive export c`` writes into a checked output folder and never replaces a
user's folder."""

from __future__ import annotations

import re
import shutil
import subprocess
from typing import ClassVar

import pytest

from acdrive.core._parts import SampledPart
from acdrive.core._signals import Layout, real
from acdrive.errors import InputError
from acdrive.export import to_c
from acdrive.export._scenario import export_setup
from acdrive.scenarios._loader import load_scenario
from acdrive.sim._system import System

needs_gcc = pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc is not installed")
#: C99 <math.h> functions newlib's libm also has: the only ones the export may call
MCU_LIBM = {"sqrt", "sin", "cos", "atan2", "acos", "hypot", "exp", "log", "floor", "fmod", "fabs",
            "nextafter"}


@pytest.fixture(scope="module")
def exported():
    return export_setup(load_scenario("bodson-sensor-fault"))


@needs_gcc
@pytest.mark.parametrize("build", [[], ["-DACDRIVE_FLOAT"]], ids=["double", "float"])
def test_compiles_pedantic(exported, tmp_path, build):
    (tmp_path / exported.header_name).write_text(exported.header)
    (tmp_path / exported.source_name).write_text(exported.source)
    done = subprocess.run(
        ["gcc", "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O2", *build, "-c",
         str(tmp_path / exported.source_name), "-o", str(tmp_path / "chain.o")],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr


def _functions(source: str) -> dict[str, str]:
    """Name -> body of every function defined at file level (bodies end at a line '}')."""
    found = {}
    for m in re.finditer(r"^[a-z][^\n;]*?\b(\w+)\(([^;{]*?)\)\s*\n\{\n(.*?)\n\}$", source,
                         re.DOTALL | re.MULTILINE):  # fmt: skip
        found[m.group(1)] = m.group(3)
    return found


def test_no_dynamic_memory_recursion_or_open_loops(exported):
    text = re.sub(r"/\*.*?\*/", "", exported.header + exported.source, flags=re.DOTALL)
    for word in ("malloc", "calloc", "realloc", "free", "alloca"):
        assert not re.search(rf"\b{word}\s*\(", text), word
    for word in ("goto", "while", "setjmp"):
        assert not re.search(rf"\b{word}\b", text), word
    # no hidden globals: every file-level statement is a declaration of a type or a function
    for line in text.splitlines():
        if line.endswith(";") and not line.startswith((" ", "}", "typedef")):
            assert "(" in line, line
    functions = _functions(exported.source)
    assert f"{exported.name}_step" in functions and len(functions) > 10
    # the call graph is acyclic: no function reaches itself
    calls = {f: {g for g in functions if g != f and re.search(rf"\b{g}\(", body)}
             for f, body in functions.items()}  # fmt: skip
    for f, body in functions.items():
        assert not re.search(rf"\b{f}\(", body), f"{f} calls itself"
    done: set[str] = set()

    def visit(f, path):
        assert f not in path, " -> ".join([*path, f])
        if f in done:
            return
        for g in calls[f]:
            visit(g, [*path, f])
        done.add(f)

    for f in functions:
        visit(f, [])
    # every loop has a literal bound
    for header in re.findall(r"\bfor \(([^)]*)\)", text):
        condition = header.split(";")[1]
        assert re.search(r"<\s*\d+", condition), header


def test_only_microcontroller_libm(exported):
    used = set(re.findall(r"#define ACD_[A-Z0-9]+ ([a-z0-9]+)\n", exported.header))
    names = {u.removesuffix("f") if u.endswith("f") and u[:-1] in MCU_LIBM else u for u in used}
    assert names <= MCU_LIBM
    assert "#include <math.h>" in exported.source


def test_names_units_in_comments(exported):
    # every declared input of the controller appears with its unit and description
    from acdrive.control._bodson import SpeedController

    for v in SpeedController.INPUTS:
        assert f"{v.name}; /* [{v.unit or '-'}] {v.doc} */" in exported.header


class _NoC(SampledPart):
    """A sampled part kind whose kernel is outside the kernel language (a while loop), so it
    has no C."""

    PARAMS = Layout(real("k", "", "a gain"))
    OUTPUTS = Layout(real("y", "", "an output"))
    DEFAULTS: ClassVar[dict] = {"k": 1.0}

    @staticmethod
    def step(t, T_s, u, p, s, y):  # pragma: no cover (never simulated)
        y[0] = p[0]
        while y[0] > 1.0:
            y[0] -= 1.0
        return 0


def test_part_without_c_is_named():
    """One line naming the part, its kind, and the kernel's line and construct the C could not
    be generated from."""
    system = System([_NoC("toy")], [])
    with pytest.raises(InputError) as caught:
        to_c(system, 1e-4)
    message = str(caught.value)
    assert "toy" in message and "_NoC" in message and "\n" not in message
    assert "the statement While" in message and "_NoC.step (line " in message


#: run in a fresh interpreter: the PM drive's controller parts built and their C looked up, then
#: a subclass of one (another kind, whose C is its own)
_DRIVE_KIND_LOOKUP = """
import json, sys
from acdrive.sim._ccode import _kinds
from acdrive.drives.pm import PMSpeedPI, controller_parts
from acdrive.scenarios import load_scenario
parts = controller_parts(load_scenario("pm-bly171d-speed"))
before = sorted(k.__name__ for k in _kinds._REGISTRY)
found = {type(p).__name__: _kinds.c_step_of(p).from_kernel for p in parts.values()}
class MySpeedPI(PMSpeedPI):
    pass
mine = MySpeedPI("mine", **parts["speed_pi"].values)
print(json.dumps({"before": before, "found": found, "mine": _kinds.c_step_of(mine).from_kernel,
                  "same": _kinds._REGISTRY[MySpeedPI].body == _kinds._REGISTRY[PMSpeedPI].body,
                  "source": _kinds._REGISTRY[PMSpeedPI].source}))
"""


def test_a_drive_kinds_c_is_generated_on_its_first_look_up():
    """The registry below the drives names no part: the PM controller kinds' C is generated
    from their kernels when one of them is first looked up, named by the class's ``SOURCE``; a
    subclass (another kind) gets its own, the same as its parent's."""
    import json
    import sys

    done = subprocess.run([sys.executable, "-c", _DRIVE_KIND_LOOKUP], capture_output=True,
                          text=True, check=True)  # fmt: skip
    seen = json.loads(done.stdout)
    assert seen["before"] == []
    assert seen["found"] == dict.fromkeys(
        ["PMSpeedPI", "PMTorqueReference", "RotorFrameCurrentController"], True
    )
    assert seen["mine"] and seen["same"]
    assert seen["source"].startswith("Bodson (25)") and "generated from its kernels" in seen["source"]


def test_cli_part_without_c_exit_2(tmp_path, capsys, monkeypatch):
    """A kind without C (here the speed reference's entry taken out of the registry and its
    kernel marked outside the language): one line naming the part, exit 2, nothing written."""
    from acdrive.control._speed import SpeedReference
    from acdrive.sim._ccode import _kinds as kinds

    monkeypatch.delitem(kinds._REGISTRY, SpeedReference, raising=False)
    monkeypatch.setitem(kinds._UNTRANSLATABLE, SpeedReference, "a construct (marked by the test)")
    assert _cli("export", "c", "bodson-ramp", "--out", str(tmp_path / "out")) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "reference0: part kind SpeedReference has no C implementation" in err[0]
    assert not (tmp_path / "out").exists()


def _cli(*args):
    from acdrive.cli import main

    return main(list(args))


@needs_gcc
def test_cli_writes_and_keeps_users_folder(tmp_path, capsys):
    out = tmp_path / "out"
    assert _cli("export", "c", "bodson-ramp", "--out", str(out)) == 0
    folder = out / "bodson-ramp"
    assert (folder / "bodson_ramp.h").read_text().startswith("/* Generated by acdrive")
    assert "void bodson_ramp_step(" in (folder / "bodson_ramp.c").read_text()
    assert _cli("export", "c", "bodson-ramp", "--out", str(out)) == 0  # its own: replaced
    mine = out / "bodson-sync"
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    assert _cli("export", "c", "bodson-sync", "--out", str(out)) == 2
    assert (mine / "notes.txt").read_text() == "mine"
    assert sorted(p.name for p in mine.iterdir()) == ["notes.txt"]


def test_cli_comparison_scenario_refused(tmp_path, capsys):
    """A scenario comparing two runs (both DFIM modes) names the rule: one line, exit 2."""
    assert _cli("export", "c", "bodson-step", "--out", str(tmp_path / "out")) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "compares 2 runs" in err[0]
    assert not (tmp_path / "out").exists()


def test_missing_compiler_is_one_line(tmp_path, capsys, monkeypatch):
    """export sil without gcc: one line naming the tool and the rule, exit 2, before any run;
    export c needs no compiler (the files are for the user's toolchain)."""
    from acdrive.export import _sil

    monkeypatch.setattr(_sil.shutil, "which", lambda name: None)
    assert _cli("export", "sil", "bodson-ramp", "--duration", "0.01") == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "gcc was not found on PATH" in err[0]
    assert _cli("export", "c", "bodson-ramp", "--out", str(tmp_path / "out")) == 0


def test_a_list_of_parts_is_refused_in_one_line():
    """to_c takes a System: a list of parts has no wiring (which plant outputs the chain reads,
    which commands it gives), so it is refused by name."""
    with pytest.raises(InputError) as caught:
        to_c([_NoC("toy")], 1e-4)
    message = str(caught.value)
    assert message.startswith("system: must be a System") and "a list of parts" in message
    assert "\n" not in message
