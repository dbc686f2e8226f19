"""``acdrive identify LOG --kind pm | dfim | mechanics`` assumes of a measured log what the built-in
tests of that kind do (``identify._builtin.measured_window``): the commands of
docs/guide/identification.md run as printed, without ``--base-frequency-hz``, ``--settle-s`` or
``--spin-settle-s``, on the logs of the kind's built-in bench, simulated as ``acdrive identify
NAME --kind KIND`` simulates them, and their intervals hold the bench's true values."""

from __future__ import annotations

import json
import math
import shlex
from pathlib import Path

import pytest

from acdrive.cli import main
from acdrive.identify._builtin import builtin_bench, builtin_names, measured_window

GUIDE = Path(__file__).resolve().parents[1] / "docs" / "guide" / "identification.md"


def documented_command(kind: str) -> list[str]:
    """The arguments of the guide's command for a measured log of ``kind`` (after
    ``acdrive``), as printed."""
    text = GUIDE.read_text()
    section = text[text.index("## From the command line") :]
    for line in section.splitlines():
        if not line.startswith("    acdrive identify "):
            continue
        words = shlex.split(line, comments=True)
        measured = Path(words[2]).suffix in (".csv", ".parquet", ".mat")  # not a built-in name
        if measured and "--kind" in words and words[words.index("--kind") + 1] == kind:
            return words[1:]
    raise AssertionError(f"no measured-log command for --kind {kind} in {GUIDE.name}")


def pm_logs(folder: Path, seed: int = 0) -> dict[str, Path]:
    """The BLY171D bench's tests, seeded as ``acdrive identify bly171d --kind pm --seed SEED``
    seeds them (``_commands._identify_kinds._pm``), by the file names of the guide's command."""
    from acdrive.identify import axis_test, dc_test, spin_test, write_log, write_spin_log

    bench = builtin_bench("pm", "bly171d")
    m, plan, s = bench.machine, bench.standstill, 4 * seed
    return {
        "dc.csv": write_log(dc_test(m, plan, seed=s), folder / "dc.csv"),
        "d.csv": write_log(axis_test(m, plan, "d", s + 1).log, folder / "d.csv"),
        "q.csv": write_log(axis_test(m, plan, "q", s + 2).log, folder / "q.csv"),
        "spin.mat": write_spin_log(spin_test(m, bench.spin, seed=s + 3).log, folder / "spin.mat"),
    }


def dfim_logs(folder: Path, seed: int = 0) -> dict[str, Path]:
    """The Bodson DFIM bench's injections, seeded as ``_identify_kinds._dfim`` seeds them."""
    from acdrive.identify import dfim_test, write_log

    bench = builtin_bench("dfim", "bodson-dfim")
    m, plan, s = bench.machine, bench.standstill, 3 * seed
    opened = dfim_test(m, plan, "open", "injection", seed=s + 1)
    shorted = dfim_test(m, plan, "shorted", "injection", seed=s + 2)
    return {"open.csv": write_log(opened, folder / "open.csv"),
            "shorted.csv": write_log(shorted, folder / "shorted.csv")}  # fmt: skip


def mechanics_logs(folder: Path, seed: int = 0) -> dict[str, Path]:
    """The BLY171D speed drive's staircase, as ``_identify_kinds._mechanics`` runs it."""
    from acdrive.identify import speed_step_test, write_mechanics_log

    bench = builtin_bench("mechanics", "bly171d")
    log = speed_step_test(bench.scenario("bly171d"), bench.plan, seed=seed)
    return {"steps.csv": write_mechanics_log(log, folder / "steps.csv")}


def run_documented(kind: str, logs: dict[str, Path], folder: Path, capsys) -> dict:
    """The guide's command for ``kind`` on ``logs`` (its file names replaced by their paths),
    with ``--json``: its exit code must be 0; the printed JSON."""
    argv = documented_command(kind)
    for flag in ("--base-frequency-hz", "--settle-s", "--spin-settle-s"):
        assert flag not in argv, (kind, flag)
    for name in logs:
        assert name in argv, (kind, name)
    argv = [str(logs.get(word, word)) for word in argv]
    capsys.readouterr()
    assert main([*argv, "--json", "--out", str(folder / f"{kind}.toml")]) == 0
    return json.loads(capsys.readouterr().out)


def misses(estimates: dict, truth: dict) -> int:
    """How many of the named estimates' 95 % Jacobian intervals miss their true values."""
    count = 0
    for name, true in truth.items():
        low, high = estimates[name]["ci95_jacobian"]
        count += not low <= true <= high
    return count


def test_the_window_of_a_measured_log_is_that_of_its_kinds_benches():
    """Every bench's tones are multiples of the kind's base frequency, the kind's settling time
    is the longest, and after it every bench's injection still holds one whole period: each
    bench's own log is analysed at all of its tones."""
    for kind in ("pm", "dfim"):
        window = measured_window(kind)
        for name in builtin_names(kind):
            plan = builtin_bench(kind, name).standstill
            multiple = plan.base_frequency / window.base_frequency
            assert multiple == round(multiple) >= 1, (kind, name)
            assert plan.settle <= window.settle, (kind, name)
            assert plan.injection_duration() >= window.settle + 1.0 / window.base_frequency
    pm = measured_window("pm")
    assert (pm.base_frequency, pm.settle) == (1.0, 0.5)  # BLY171D 2 Hz, IPMSM 1 Hz; both 0.5 s
    assert pm.spin_settle == max(builtin_bench("pm", n).spin.settle for n in builtin_names("pm"))


@pytest.mark.slow
def test_the_documented_pm_command_runs_as_printed_on_the_pm_benchs_logs(tmp_path, capsys):
    """The log of the bench's own analysis: the estimates equal those of ``acdrive identify
    bly171d --kind pm`` (the same logs at the bench's 2 Hz: the same window and tones) and hold
    the machine's values."""
    bench = builtin_bench("pm", "bly171d")
    m = bench.machine
    found = run_documented("pm", pm_logs(tmp_path), tmp_path, capsys)["estimates"]
    truth = {"pm_standstill.R_s": m.R_s, "pm_standstill.L_d": m.L_d, "pm_standstill.L_q": m.L_q,
             "spin.psi_m": m.psi_m, "dc_steps.R_s": m.R_s, "dc_steps.U_err": 0.0}  # fmt: skip
    # six 95 % intervals: two misses or more have probability 3.3 % if they are right
    assert misses(found, truth) <= 1
    assert main(["identify", "bly171d", "--kind", "pm", "--json", "--out",
                 str(tmp_path / "builtin.toml")]) == 0  # fmt: skip
    builtin = json.loads(capsys.readouterr().out)["estimates"]
    assert set(found) == set(builtin)
    for name, entry in found.items():
        assert math.isclose(entry["value"], builtin[name]["value"], rel_tol=1e-9), name


@pytest.mark.slow
def test_the_documented_dfim_and_mechanics_commands_run_as_printed_on_their_benchs_logs(
    tmp_path, capsys
):
    m = builtin_bench("dfim", "bodson-dfim").machine
    argv = documented_command("dfim")
    assert float(argv[argv.index("--stator-resistance-ohm") + 1]) == m.R_s
    found = run_documented("dfim", dfim_logs(tmp_path), tmp_path, capsys)["estimates"]
    truth = {"dfim.R_r": m.R_r, "dfim.L_r": m.L_r, "dfim.M": m.M, "dfim.L_s": m.L_s,
             "dfim.L_sigma_r": m.L_r - m.M**2 / m.L_s, "dfim.L_M": m.M**2 / m.L_s,
             "dfim.R_S": m.R_s * (m.M / m.L_s) ** 2}  # fmt: skip
    # seven 95 % intervals: two misses or more have probability 4 % if they are right
    assert misses(found, truth) <= 1
    shaft = builtin_bench("mechanics", "bly171d")
    found = run_documented("mechanics", mechanics_logs(tmp_path), tmp_path, capsys)["estimates"]
    truth = {"mechanics.J": shaft.machine.J, "mechanics.B": shaft.viscous_friction,
             "mechanics.tau_c": shaft.plan.tau_c}  # fmt: skip
    # three 95 % intervals (conservative for the encoder's correlated error): none may miss
    assert misses(found, truth) == 0
