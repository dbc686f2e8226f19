"""The exported C on any C99 compiler (issue 37, item 3): the controller chains that
``acdrive export c`` writes for every built-in scenario it takes, and the plant C
(``to_plant_c``) of the same scenarios, compile with gcc and with clang under ``-std=c99 -Wall
-Wextra -Wpedantic -Werror``, in double and in float (``-DACDRIVE_FLOAT``): a file defines no
helper its code does not call (clang warns of an unused ``static inline`` function). The
functions of <math.h> the compiled objects call are exactly those the prelude's docstring and
the guides list.

Each scenario is exported over its first 10 ms (``export._scenario.shortened``): what a longer
run changes in the C is the number of points of a profile table sampled over the run (the
im-perturbed reference: 15,001 points over 0.3 s, 3.3 MB of C), not the code that is compiled.
A scenario that compares runs is refused by ``export c``; each of its runs whose chain has a
kind of C not exported otherwise (the saturated P speed loop, the stationary PI of
im-icad-vs-pi) is compiled as well, as ``export m4`` takes such runs."""

from __future__ import annotations

import re
import shutil
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from acdrive.errors import InputError
from acdrive.export._cost import one_run
from acdrive.export._scenario import built, c_name, export_setup, shortened
from acdrive.scenarios import builtin_names, load_scenario
from acdrive.sim._ccode import _prelude
from acdrive.sim._ccode._helpers import helper_text
from acdrive.sim._ccode._plant_source import to_plant_c
from acdrive.sim._ccode._prelude import HELPERS, PRELUDE

ROOT = Path(__file__).resolve().parents[1]
FLAGS = ("-std=c99", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-O0")
PRECISIONS = {"double": (), "float": ("-DACDRIVE_FLOAT",)}
#: seconds of each scenario exported (module docstring)
EXPORTED_SECONDS = 0.01


@dataclass
class Generated:
    """The written sources: ``chains`` and ``plants`` (paths of the .c files)."""

    chains: list[Path] = field(default_factory=list)
    plants: list[Path] = field(default_factory=list)


def _kinds_key(export) -> frozenset:
    """What decides a file's helpers and kind functions: its kinds and their C."""
    return frozenset((cls, entry.body) for cls, entry in export.kinds.items())


def _write(folder: Path, export) -> Path:
    (folder / export.header_name).write_text(export.header)
    (folder / export.source_name).write_text(export.source)
    return folder / export.source_name


def _runs(setup) -> list[str]:
    """The labels of the runs a scenario compares (DFIM modes or controllers)."""
    modes = list(getattr(setup, "compare_modes", ()) or ())
    return modes or ([label for label, _ in setup.runs()] if hasattr(setup, "runs") else [])


@pytest.fixture(scope="module")
def generated(tmp_path_factory) -> Generated:
    folder = tmp_path_factory.mktemp("exported")
    files = Generated()
    chain_kinds, plant_kinds, compared = set(), set(), []

    def plant_of(setup, name: str, new_only: bool) -> None:
        drive, initial, held = built(setup)
        try:
            plant = to_plant_c(drive.system, setup.sample_time, setup.substeps, initial, held,
                               name=f"{name}_plant")  # fmt: skip
        except InputError:
            return  # a plant kind without C (fault-phase-loss's unbalanced grid)
        if not new_only or _kinds_key(plant) not in plant_kinds:
            plant_kinds.add(_kinds_key(plant))
            files.plants.append(_write(folder, plant))

    for scenario in builtin_names():
        setup = load_scenario(scenario)
        try:
            built(setup)  # `acdrive export c` refuses a scenario comparing runs
        except InputError:
            compared.append(setup)
            continue
        setup = shortened(setup, min(setup.duration, EXPORTED_SECONDS))
        export = export_setup(setup)  # what `acdrive export c` writes
        chain_kinds.add(_kinds_key(export))
        files.chains.append(_write(folder, export))
        plant_of(setup, c_name(setup.name), new_only=False)
    for setup in compared:
        for label in _runs(setup):
            run = one_run(setup, label)
            run = shortened(run, min(run.duration, EXPORTED_SECONDS))
            name = c_name(f"{setup.name}-{label}")
            try:
                export = export_setup(run, name)
            except InputError:
                continue
            if _kinds_key(export) not in chain_kinds:
                chain_kinds.add(_kinds_key(export))
                files.chains.append(_write(folder, export))
            plant_of(run, name, new_only=True)
    return files


def _compile(compiler: str, source: Path, flags) -> subprocess.CompletedProcess:
    return subprocess.run(
        [compiler, *flags, "-c", str(source), "-o", str(source.with_suffix(".o"))],
        capture_output=True, text=True, check=False, cwd=source.parent,
    )  # fmt: skip


def test_a_file_holds_the_helpers_its_code_calls_and_no_other():
    """Through the prelude's macros (ACD_SIN is acd_sin in the double build) and through the
    helpers (acd_sin calls acd_sincos): the cosine, the complex arithmetic and the rest stay
    out."""
    text = helper_text([HELPERS], "y = ACD_SIN(x) * acd_cabs(z);", PRELUDE)
    defined = set(re.findall(r"^static inline \w+ (\w+)\(", text, re.MULTILINE))
    assert defined == {"acd_sincos", "acd_sin", "acd_cabs"}
    assert text.count("#ifndef ACDRIVE_FLOAT") == 2  # each double-only helper under its guard


def test_every_built_in_scenario_is_compiled(generated):
    """The scenarios `export c` takes (all but those comparing runs) are all there, and the
    runs bring the kinds found only in comparisons."""
    written = {p.name for p in generated.chains}
    assert {"bodson_ramp.c", "im_foc_speed.c", "im_perturbed.c", "pm_bly171d_svpwm.c",
            "bodson_two_motors.c", "fault_forced_close.c"} <= written  # fmt: skip
    assert "im_icad_vs_pi_pi.c" in written or "im_icad_vs_pi_icad.c" in written
    assert len(generated.plants) >= 15


@pytest.mark.parametrize("precision", PRECISIONS)
@pytest.mark.parametrize("compiler", ["gcc", "clang"])
def test_warning_free_on_gcc_and_clang(generated, compiler, precision):
    if shutil.which(compiler) is None:
        pytest.skip(f"{compiler} is not installed (scripts/install-cross-tools.sh installs clang)")
    failed = []
    for source in [*generated.chains, *generated.plants]:
        done = _compile(compiler, source, (*FLAGS, *PRECISIONS[precision]))
        if done.returncode != 0:
            failed.append(f"{source.name}: {done.stderr.strip().splitlines()[0]}")
    assert not failed, "\n".join(failed)


def _names(listed: str | None) -> frozenset[str]:
    return frozenset(n.strip() for n in (listed or "").split(",") if n.strip())


def _documented(text: str, what: str) -> tuple[frozenset[str], frozenset[str]]:
    """(functions the double build calls, functions the float build calls, by their double
    names) as ``text`` lists them for ``what`` ("the controller chains call", "the plant
    calls"): "<what> A, in the double build also D (...), and in the float build also F"."""
    flat = " ".join(text.replace("`", "").split())
    pattern = (rf"{what} ([a-z0-9, ]+?)(?:, in the double build also ([a-z0-9, ]+?)"
               r"(?: \([^)]*\))?)?, and in the float build also ([a-z0-9, ]+)")
    m = re.search(pattern, flat)
    assert m, f"no list of the functions {what}"
    both = _names(m.group(1))
    return both | _names(m.group(2)), both | _names(m.group(3))


def _called(sources: list[Path], precision: str) -> set[str]:
    """The functions the objects of ``sources`` call (their undefined symbols), built without
    builtins so that every call of the C is a call in the object (gcc expands fabs inline
    otherwise)."""
    called = set()
    for source in sources:
        done = _compile("gcc", source, ("-std=c99", "-O0", "-fno-builtin",
                                        *PRECISIONS[precision]))  # fmt: skip
        assert done.returncode == 0, done.stderr
        symbols = subprocess.run(["nm", "-u", str(source.with_suffix(".o"))],
                                 capture_output=True, text=True, check=True).stdout  # fmt: skip
        called |= {line.split()[-1] for line in symbols.splitlines() if line.strip()}
    return called


@pytest.mark.skipif(shutil.which("gcc") is None or shutil.which("nm") is None,
                    reason="gcc or nm (binutils) is not installed")  # fmt: skip
def test_the_documented_libm_functions_are_those_called(generated):
    """Per precision, the set of <math.h> functions the chains' objects call, and the plant's,
    equals the lists of the prelude's docstring and of the guides (export.md: the chains;
    fmu.md: the plant); the float build calls only float functions."""
    texts = {
        "the controller chains call": [_prelude.__doc__,
                                       (ROOT / "docs/guide/export.md").read_text()],
        "the plant calls": [_prelude.__doc__, (ROOT / "docs/guide/fmu.md").read_text()],
    }  # fmt: skip
    sources = {"the controller chains call": generated.chains,
               "the plant calls": generated.plants}  # fmt: skip
    for what, documents in texts.items():
        lists = {_documented(text, what) for text in documents}
        assert len(lists) == 1, f"the lists of the functions {what} differ: {lists}"
        double, single = lists.pop()
        assert _called(sources[what], "double") == double, what
        float_calls = _called(sources[what], "float")
        assert all(name.endswith("f") for name in float_calls), float_calls
        assert {name[:-1] for name in float_calls} == single, what
