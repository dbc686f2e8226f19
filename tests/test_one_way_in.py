"""One way in: ``acdrive.drives.run_scenario(load_scenario(name))`` runs a scenario of every drive
kind and returns an ``acdrive.drives.Outcome`` whose common members are what ``acdrive run``
gives for that scenario: its summary is summary.json (less ``log``, the logging the command
chose and states), its headline the lines printed after the run's announcement, its
figures the PNG files drawn. One short built-in scenario per drive kind (durations shortened in
a copy of its file), each comparing runs where the drive can."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from acdrive._output import strict_json
from acdrive.cli import main
from acdrive.drives import Outcome, for_setup, run_scenario
from acdrive.scenarios import load_scenario
from acdrive.scenarios._files import builtin_text
from acdrive.sim._timing import run_timing

#: drive kind -> (built-in scenario, its shortened duration [s])
SHORT = {
    "dfim": ("bodson-step", 0.3),  # compares the voltage and the current command
    "cage-im": ("im-step-responses", 0.04),  # compares current controllers, steps vs linear
    "pm": ("pm-bly171d-speed", 0.05),
}
#: summary keys that time the run itself (differ between two runs of one scenario)
TIMING_KEYS = set(run_timing([]))


def _short_copy(name: str, duration: float, folder: Path) -> Path:
    text, n = re.subn(r"(?m)^duration = .*$", f"duration = {duration}", builtin_text(name))
    assert n == 1
    path = folder / f"{name}.toml"
    path.write_text(text)
    return path


def _without_timing(value):
    """``value`` (a summary read back from JSON) without the timing keys, at any depth."""
    if isinstance(value, dict):
        return {k: _without_timing(v) for k, v in value.items() if k not in TIMING_KEYS}
    if isinstance(value, list):
        return [_without_timing(v) for v in value]
    return value


@pytest.mark.parametrize("kind", list(SHORT))
def test_run_scenario_gives_what_acdrive_run_writes(kind, tmp_path, monkeypatch, capsys):
    name, duration = SHORT[kind]
    path = _short_copy(name, duration, tmp_path)
    setup = load_scenario(path)
    drive = for_setup(setup)
    assert drive.kind == kind
    ran = []  # the outcome acdrive run writes, kept as it passes
    run = type(drive).run

    def keep(self, setup, on_run=None):
        ran.append(run(self, setup, on_run))
        return ran[-1]

    monkeypatch.setattr(type(drive), "run", keep)
    assert main(["run", str(path), "--out", str(tmp_path / "cli")]) == 0
    printed = capsys.readouterr().out.splitlines()
    monkeypatch.undo()
    folder = tmp_path / "cli" / setup.name
    written = json.loads((folder / "summary.json").read_text())

    (cli_outcome,) = ran
    assert json.loads(strict_json(cli_outcome.summary)) == written
    assert printed[0].startswith(f"running {setup.name}: ")  # the run and its log, announced
    assert cli_outcome.headline() == printed[1:-1]  # then "wrote <folder>/: ..."
    assert printed[-1].startswith("wrote ")
    drawn = cli_outcome.figures(tmp_path / "figures")
    assert drawn and all(p.suffix == ".png" and p.is_file() for p in drawn)
    assert sorted(p.relative_to(tmp_path / "figures") for p in drawn) == sorted(
        p.relative_to(folder) for p in folder.rglob("*.png")
    )

    outcome = run_scenario(load_scenario(path))
    assert isinstance(outcome, Outcome) and type(outcome) is type(cli_outcome)
    assert (outcome.kind, outcome.name) == (kind, setup.name)
    assert list(outcome.results) == list(cli_outcome.results)
    assert (len(outcome.results) > 1) == (kind != "pm")  # the compared runs, one each
    assert outcome.main is next(iter(outcome.results.values()))
    assert all(r.wall_time > 0 for r in outcome.results.values())
    # less the log's choice, which acdrive run states (``--log-every`` is the command's)
    command_made = {k: v for k, v in written.items() if k != "log"}
    assert "log" in written and "log" not in outcome.summary
    assert _without_timing(json.loads(strict_json(outcome.summary))) == _without_timing(command_made)
    lines = outcome.headline()
    assert setup.name in lines[0] and all(isinstance(x, str) for x in lines)
    assert outcome.write(tmp_path / "again", figures=False) == outcome.summary
    again = json.loads((tmp_path / "again" / "summary.json").read_text())
    assert again == json.loads(strict_json(outcome.summary))



def test_the_getting_started_own_pm_motor_runs_as_printed():
    """docs/getting-started.md's datasheet motor in Python: a ``PMSMParams`` (the PM record under
    a motor's name, the same class as ``PMSGParams``) in a ``PMDriveSetup``, run through
    ``run_scenario``; its speed PI (an integrator, constant load) ends on the 300 rad/s asked."""
    from acdrive.machines import PMSGParams, PMSMParams

    assert PMSMParams is PMSGParams
    text = (Path(__file__).resolve().parents[1] / "docs" / "getting-started.md").read_text()
    section = text.split("### Your own PM motor from Python", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.DOTALL).group(1)
    scope: dict = {}
    exec(compile(code, "getting-started.md", "exec"), scope)  # noqa: S102  (the page's example)
    outcome = scope["outcome"]
    assert isinstance(scope["motor"], PMSMParams)
    assert (outcome.kind, outcome.name) == ("pm", "my-pmsm")
    assert outcome.summary["speed_final_rad_s"] == pytest.approx(300.0, rel=1e-3)
