"""The documentation's examples run as printed and do what they say, and its command table is the
parser's: the system from parts (docs/guide/parts.md), the scenario with every mode it compares
(docs/getting-started.md), the command table (docs/guide/commands.md)."""

import math
import re
from pathlib import Path

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

DOCS = Path(__file__).resolve().parents[1] / "docs"
PARTS = DOCS / "guide" / "parts.md"
GETTING_STARTED = DOCS / "getting-started.md"
COMMANDS = DOCS / "guide" / "commands.md"


def test_parts_example_runs_and_the_shorted_dfim_runs_up_to_synchronous_speed():
    text = PARTS.read_text()
    section = text[text.index("## A system from parts") :]
    code = re.search(r"```python\n(.*?)```", section, re.DOTALL).group(1)
    scope: dict = {}
    exec(compile(code, str(PARTS), "exec"), scope)  # noqa: S102  (the guide's example itself)
    result, dfim = scope["result"], scope["dfim"]
    w = result.signal("shaft.w")
    synchronous = 2 * math.pi * 60.0 / 2  # 60 Hz, two pole pairs
    # a shorted-rotor DFIM is a cage motor: it runs up to just below synchronous speed, no load
    assert 0.99 * synchronous < w[-1] < synchronous
    # near synchronous speed the rotor carries almost nothing: i_s = v_s / (R_s + j w_e L_s) (19)
    from acdrive.machines import BODSON_DFIM as p

    no_load = math.sqrt(1.5) * 11.1 / abs(p.R_s + 1j * 2 * math.pi * 60.0 * p.L_s)
    i_s = np.abs(result.signal(dfim.out.i_s))
    assert i_s[-100:].max() == pytest.approx(no_load, rel=0.01)
    assert i_s[: len(i_s) // 10].max() > 2 * no_load  # the starting current


def test_scenario_example_runs_every_mode_and_saves_into_new_folders(tmp_path, monkeypatch):
    """A two-mode scenario gives both modes, and save() creates its folder (the scenario is
    shortened here; the code is the getting-started page's)."""
    import dataclasses

    from acdrive.scenarios import _loader as loader

    text = GETTING_STARTED.read_text()
    section = text[text.index("### Every mode a scenario compares") :]
    code = re.search(r"```python\n(.*?)```", section, re.DOTALL).group(1)
    original = loader.load_scenario
    monkeypatch.setattr(
        loader, "load_scenario", lambda name: dataclasses.replace(original(name), duration=0.2)
    )
    monkeypatch.chdir(tmp_path)
    scope: dict = {}
    exec(compile(code, str(GETTING_STARTED), "exec"), scope)  # noqa: S102  (the page's example)
    outcome = scope["outcome"]
    modes = set(original("bodson-step").compare_modes)
    assert set(outcome.results) == modes == {"voltage", "current"}
    for mode in outcome.results:
        assert (tmp_path / "bodson-step" / mode / "data.parquet").exists()
        assert (tmp_path / "bodson-step" / mode / "columns.md").exists()
    assert "units" in scope["frame"].attrs


def _command_table() -> dict[str, str]:
    """The command table of the commands page: command name -> the row's first cell (synopsis)."""
    text = COMMANDS.read_text()
    section = text[text.index("# Commands") :]
    section = section[: section.index("\n\n", section.index("| command |"))]
    rows = {}
    for line in section.splitlines():
        cells = re.split(r"(?<!\\)\|", line)  # a cell may hold an escaped \|
        match = re.match(r" `acdrive ([a-z][a-z-]*)", cells[1]) if len(cells) > 2 else None
        if match:
            rows[match.group(1)] = cells[1]
    return rows


def _subcommands() -> dict:
    """Every subcommand of the ``acdrive`` parser (each with its full parser)."""
    import argparse

    from acdrive.cli import build_parser

    parser = build_parser()  # without argv: every command's full parser
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


def test_command_table_lists_every_command_of_the_parser():
    """Derived from the parser, so a new command without its row in the table fails here."""
    commands = _subcommands()
    rows = _command_table()
    assert {"run", "sweep", "bench"} <= set(commands)  # the parser is really read
    missing = sorted(set(commands) - set(rows))
    assert not missing, f"commands missing from docs/guide/commands.md: {missing}"


def test_options_in_the_command_table_exist():
    """Every ``--option`` a row's synopsis shows is an option of that command."""
    commands = _subcommands()
    for name, synopsis in _command_table().items():
        if name not in commands:
            continue  # a command of another branch, not built here
        options = {s for a in commands[name]._actions for s in a.option_strings}
        shown = set(re.findall(r"--[a-z][a-z-]*", synopsis))
        assert shown <= options, (name, sorted(shown - options))
