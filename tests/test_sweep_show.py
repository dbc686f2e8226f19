"""``acdrive sweep --show NAME``: a built-in sweep printed as a file that runs as the built-in."""

import pytest

from acdrive.cli import main
from acdrive.sweep import builtin_sweeps
from acdrive.sweep._spec import load_sweep


@pytest.mark.parametrize("name", builtin_sweeps())
def test_show_prints_a_file_that_defines_the_same_sweep(name, tmp_path, capsys):
    assert main(["sweep", "--show", name]) == 0
    out = capsys.readouterr().out
    copy = tmp_path / f"{name}.toml"
    copy.write_text(out)
    # the printed text, saved and read as a user's own file, is the built-in sweep itself
    assert load_sweep(str(copy)) == load_sweep(name)


def test_an_unknown_name_is_refused_naming_it_and_the_known_names(capsys):
    assert main(["sweep", "--show", "dfim-bandwith"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    (line,) = captured.err.splitlines()
    assert line.startswith("acdrive: error: --show:") and "'dfim-bandwith'" in line
    assert all(name in line for name in builtin_sweeps())


@pytest.mark.parametrize(
    "extra, named",
    [(["dfim-bandwidth"], "--show"), (["--list"], "--list"), (["--out", "x"], "--out"),
     (["--quiet"], "--quiet")],
)
def test_show_runs_nothing_and_refuses_the_options_of_a_run(extra, named, tmp_path, capsys,
                                                            monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["sweep", "--show", "dfim-bandwidth", *extra]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith(f"acdrive: error: {named}:")
    assert not any(tmp_path.iterdir())  # nothing written


def test_the_sweeps_guide_shows_the_builtin_sweep_file_as_it_is(capsys):
    """The guide's sweep file is ``acdrive sweep --show dfim-bandwidth``, character by character."""
    import re
    from pathlib import Path

    guide = Path(__file__).resolve().parents[1] / "docs" / "guide" / "sweeps.md"
    section = guide.read_text().split("## A sweep file", 1)[1]
    shown = re.search(r"```toml\n(.*?)```", section, re.DOTALL).group(1)
    assert main(["sweep", "--show", "dfim-bandwidth"]) == 0
    assert shown == capsys.readouterr().out
