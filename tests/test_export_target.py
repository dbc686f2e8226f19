"""Cost on the target (issue 22, item 3): the counting method of ``acdrive export m4`` checked on
a loop whose instruction count is read from its disassembly, the papers' chains cross-compiled
for the Cortex-M4F and counted on QEMU's mps2-an386 over replayed inputs, and the one-line errors
of a missing tool. The cross tools come from scripts/install-cross-tools.sh (CI runs it)."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

from acdrive.export._target import TOOLS, known_loop_instructions, statement_instructions

ROOT = Path(__file__).resolve().parents[1]
MISSING = [tool for tool in TOOLS if shutil.which(tool) is None]
needs_cross_tools = pytest.mark.skipif(
    bool(MISSING) or shutil.which("gcc") is None,
    reason=f"cross tools missing ({', '.join(MISSING) or 'gcc'}): "
    "scripts/install-cross-tools.sh installs them",
)


def _cli(*args):
    from acdrive.cli import main

    return main(list(args))


@needs_cross_tools
def test_counting_method_on_a_known_loop(tmp_path):
    """``movw r0, #N; 1: subs r0, r0, #1; bne 1b; bx lr`` executes 2 N + 2 instructions (its
    disassembly has exactly these four). Measured by the controller's own measuring loop, the
    count of N = 1000 exceeds that of N = 10 by exactly 2 x 990, and each is 2 N + 2 plus the
    same small call overhead (the bl and the loop's branch back: a whole number, 1 to 3)."""
    counts = {}
    for n in (10, 1000):
        folder = tmp_path / str(n)
        folder.mkdir()
        measured = known_loop_instructions(n, folder)
        assert measured["mnemonics"] == ["movw", "subs", "bne.n", "bx"]
        counts[n] = measured
    resolution = counts[10]["resolution"]
    assert resolution <= 0.1
    slope = counts[1000]["instructions_per_step"] - counts[10]["instructions_per_step"]
    assert abs(slope - 2 * 990) <= 2 * resolution
    overheads = [counts[n]["instructions_per_step"] - (2 * n + 2) for n in counts]
    for overhead in overheads:
        assert abs(overhead - round(overhead)) <= resolution
        assert 1 <= round(overhead) <= 3
    assert round(overheads[0]) == round(overheads[1])
    # the longest single window holds the 2003-odd instructions, to one 40-instruction tick
    assert abs(counts[1000]["longest_step_window"] - 2 * 1000 - 2) <= 40 + 10


@needs_cross_tools
def test_dfim_modes_and_ifoc_on_the_board(capsys):
    """The DFIM voltage- and current-command chains and IFOC + (20) on the board model: every
    count is exact to its stated resolution, the fractions follow from the count (168 MHz, one
    instruction per cycle), the sizes are those of a real object, and the voltage-vs-current
    comparison is computed from the two counts. Bodson's current command adds the PI current
    loop (43)-(49) to what the voltage command computes, so its step costs more."""
    assert _cli("export", "m4", "dfim-voltage", "dfim-current", "ifoc-20", "--json") == 0
    report = json.loads(capsys.readouterr().out)
    assert report["board"] == "mps2-an386"
    assert [c["case"] for c in report["cases"]] == ["dfim-voltage", "dfim-current", "ifoc-20"]
    for case in report["cases"]:
        (row,) = case["chains"]
        n = row["instructions_per_step"]
        assert 50 < n < 100_000
        assert row["resolution"] == pytest.approx(80 / case["samples"])
        assert row["fraction_of_period"]["5000"] == pytest.approx(n / 168e6 * 5e3, rel=1e-12)
        assert row["fraction_of_period"]["10000"] == pytest.approx(n / 168e6 * 1e4, rel=1e-12)
        assert row["fraction_of_own_period"] == pytest.approx(
            n / 168e6 * case["sample_rate_hz"], rel=1e-12
        )
        assert row["object"]["text"] > row["functions"][f"{row['chain']}_step"] > 0
        assert row["image"]["text"] > row["object"]["text"]
        # the chain's RAM is in the caller's structs: the object itself has none
        assert row["object"]["data"] == row["object"]["bss"] == 0
        assert all(v > 0 and v % 4 == 0 for v in row["structs"].values())
        # the mean step lies within the shortest and longest single windows (to one tick)
        assert row["shortest_step_window"] - 40 <= n <= row["longest_step_window"] + 40
    assert report["cases"][0]["samples"] == 1500  # 0.3 s at 5 kHz
    assert report["cases"][2]["samples"] == 5000  # 0.1 s at 50 kHz
    vc = report["voltage_vs_current"]
    v = report["cases"][0]["chains"][0]["instructions_per_step"]
    i = report["cases"][1]["chains"][0]["instructions_per_step"]
    assert vc["voltage_over_current"] == pytest.approx(v / i, rel=1e-12)
    assert vc["voltage_cheaper_by"] == pytest.approx(1 - v / i, rel=1e-12)
    assert v < i


@needs_cross_tools
def test_out_folder_keeps_the_built_files(tmp_path, capsys):
    out = tmp_path / "out"
    assert _cli("export", "m4", "ifoc-pi", "--duration", "0.01", "--out", str(out)) == 0
    folder = out / "m4" / "ifoc-pi"
    assert {"ifoc_pi.c", "ifoc_pi.h", "ifoc_pi.elf", "startup.c", "board.ld"} <= {
        p.name for p in folder.iterdir()
    }
    report = json.loads((out / "m4" / "report.json").read_text())
    assert report["cases"][0]["samples"] == 500  # 0.01 s at 50 kHz
    assert "instructions per step" in capsys.readouterr().out


@pytest.mark.parametrize("tool", ["arm-none-eabi-gcc", "qemu-system-arm"])
def test_missing_tool_is_one_line(tmp_path, capsys, monkeypatch, tool):
    """A missing cross tool: one line naming it and the script that installs it, exit 2, before
    any run, and no output folder (the other tools are taken as present: nothing runs)."""
    from acdrive.export import _target

    real_which = shutil.which

    def which(name):
        return None if name == tool else (real_which(name) or f"/usr/bin/{name}")

    monkeypatch.setattr(_target.shutil, "which", which)
    out = tmp_path / "out"
    assert _cli("export", "m4", "ifoc-20", "--out", str(out)) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert tool in err[0] and "scripts/install-cross-tools.sh" in err[0]
    assert not out.exists()


def test_unknown_target_is_one_line(capsys):
    if MISSING or shutil.which("gcc") is None:
        pytest.skip("cross tools missing: the tools are checked first")
    assert _cli("export", "m4", "no-such-case") == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


@needs_cross_tools
@pytest.mark.skipif(shutil.which("clang") is None, reason="clang missing: the script installs it")
def test_install_script_does_nothing_when_present():
    done = subprocess.run(
        ["bash", str(ROOT / "scripts" / "install-cross-tools.sh")],
        capture_output=True, text=True, check=False, timeout=60,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "nothing to install" in done.stdout


def test_ci_runs_the_install_script_before_pytest():
    ci = (ROOT / ".ci" / "run").read_text()
    assert ci.index("scripts/install-cross-tools.sh") < ci.index("\npytest")
    assert "scripts/install-cross-tools.sh" in (ROOT / "README.md").read_text()


@needs_cross_tools
def test_newlib_sine_of_a_large_angle_is_expensive(tmp_path):
    """Why the PM chain's count grows as the rotor turns (docs/guide/export.md): newlib's sinf
    reduces an argument beyond 2^7 pi/2 (about 201 rad) the long way."""
    counts = {}
    for x in ("1.0f", "300.0f"):
        folder = tmp_path / x
        folder.mkdir()
        decls = f"static volatile float acd_x = {x}, acd_y;"
        counts[x] = statement_instructions("acd_y = sinf(acd_x);", decls, folder)
    assert 20 < counts["1.0f"] < 300
    assert counts["300.0f"] > 10 * counts["1.0f"]


@needs_cross_tools
def test_a_failing_target_leaves_nothing_in_the_output_folder(tmp_path, capsys):
    """The second target is a scenario comparing two runs (refused in one line, exit 2) after
    the first was built: the staged files are discarded, no m4 folder appears."""
    out = tmp_path / "out"
    assert _cli("export", "m4", "ifoc-pi", "bodson-step", "--duration", "0.005",
                "--out", str(out)) == 2  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "compares 2 runs" in err[0]
    assert not (out / "m4").exists()
    assert not out.exists() or not any(out.iterdir())


@needs_cross_tools
def test_a_scenario_of_one_run_is_a_target(capsys):
    """A scenario that is not one of the cases: replayed over the given seconds, named after
    the scenario."""
    assert _cli("export", "m4", "bodson-ramp", "--duration", "0.01", "--json") == 0
    (case,) = json.loads(capsys.readouterr().out)["cases"]
    assert case["scenario"] == "bodson-ramp" and case["run"] is None
    assert case["samples"] == 50  # 0.01 s at 5 kHz
    assert case["chains"][0]["chain"] == "bodson_ramp"
    assert case["chains"][0]["instructions_per_step"] > 50
