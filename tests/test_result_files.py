"""Result files explain themselves: every column has a unit and a description (Parquet metadata,
columns.md, the .mat structs), the scaling is in the name (_pk phase peak, _sv power-invariant
space vector), every format reads back, and names a format cannot hold are refused in one line."""

import json
import re

import numpy as np
import pytest

from acdrive._frames import K_PEAK
from acdrive.cli import main
from acdrive.columns import FORMATS, Column, check_names, read_units, write_table
from acdrive.drives.dfim._result import LOG_NAMES, N_LOG, DriveResult
from acdrive.errors import InputError

SCENARIO = """
name = "short"
[simulation]
duration = 0.2
[[motor]]
speed_reference_rpm = [[0, 0], [0.2, 100]]
[motor.controller]
speed_bandwidth = 100.0
"""


def _run(tmp_path, fmt, capsys):
    path = tmp_path / "short.toml"
    path.write_text(SCENARIO)
    out = tmp_path / f"out-{fmt}"
    code = main(["run", str(path), "--out", str(out), "--format", fmt, "--no-figures"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    return out / "short", captured.out


def _markdown_rows(folder):
    """(name, unit, description) of every row of the table in columns.md."""
    rows = re.findall(
        r"^\| `([^`]+)` \| ([^|]*) \| (.*) \|$", (folder / "columns.md").read_text(), re.MULTILINE
    )
    return [(n, "" if u.strip() == "-" else u.strip(), d.replace("\\|", "|")) for n, u, d in rows]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The short scenario written in every format (one simulation each: the loop is shared)."""
    tmp = tmp_path_factory.mktemp("formats")
    path = tmp / "short.toml"
    path.write_text(SCENARIO)
    folders = {}
    for fmt in FORMATS:
        out = tmp / fmt
        assert main(["run", str(path), "--out", str(out), "--format", fmt, "--no-figures"]) == 0
        folders[fmt] = out / "short"
    return folders


def test_default_is_parquet_with_units_and_descriptions_in_the_schema(tmp_path, capsys):
    folder, stdout = _run(tmp_path, "parquet", capsys)
    assert sorted(p.name for p in folder.iterdir()) == [
        ".acdrive-output.json",  # the marker: acdrive wrote this folder (acdrive._output)
        "columns.md",
        "data.parquet",
        "summary.json",
    ]
    assert f"wrote {folder}/: data.parquet and columns.md, summary.json" in stdout
    meta = read_units(folder / "data.parquet")
    rows = _markdown_rows(folder)
    assert [r[0] for r in rows] == list(meta)  # columns.md lists every column, in order
    for name, unit, description in rows:
        assert meta[name]["unit"] == unit and meta[name]["description"] == description
        assert description
    assert meta["t"]["unit"] == "s" and meta["w"]["unit"] == "rad/s"
    assert meta["i_r_pk"]["unit"] == "A" and "peak phase" in meta["i_r_pk"]["description"]
    assert "space-vector" in meta["i_r_d_sv"]["description"]


def test_phase_peak_columns_are_what_the_summary_reports(runs):
    import pandas as pd

    frame = pd.read_parquet(runs["parquet"] / "data.parquet")
    summary = json.loads((runs["parquet"] / "summary.json").read_text())
    assert frame["i_r_pk"].max() == pytest.approx(summary["peak_rotor_current_a"], rel=1e-12)
    assert frame["i_s_pk"].max() == pytest.approx(summary["peak_stator_current_a"], rel=1e-12)
    # the magnitude of the _sv components is sqrt(3/2) times the phase peak (Bodson (8))
    magnitude = np.hypot(frame["i_r_com_d_sv"], frame["i_r_com_q_sv"])
    assert np.allclose(magnitude / K_PEAK, frame["i_r_com_pk"], rtol=1e-9, atol=1e-12)
    assert frame["i_r_com_pk"].max() > 0.1  # a command was given


def test_csv_and_mat_read_back_with_the_same_columns(runs):
    import pandas as pd
    import scipy.io

    reference = pd.read_parquet(runs["parquet"] / "data.parquet")
    names = list(reference.columns)
    csv = pd.read_csv(runs["csv"] / "data.csv")
    assert list(csv.columns) == names
    assert np.allclose(csv["w"], reference["w"], rtol=1e-12, atol=0)
    mat = scipy.io.loadmat(runs["mat"] / "data.mat", squeeze_me=True, struct_as_record=False)
    assert list(mat["data"]._fieldnames) == names
    assert np.allclose(mat["data"].w, reference["w"], rtol=0, atol=0)
    assert mat["units"].w == "rad/s" and mat["units"].i_r_pk == "A"
    assert "peak phase" in mat["descriptions"].i_r_pk
    assert "_pk" in mat["conventions"]
    for fmt in ("csv", "mat"):  # columns.md beside every format names the same columns
        assert [r[0] for r in _markdown_rows(runs[fmt])] == names
        assert f"`{FORMATS[fmt]}`" in (runs[fmt] / "columns.md").read_text()


def test_several_motors_name_their_columns_by_motor():
    t = np.arange(5) * 1e-3
    result = DriveResult("two", t, np.zeros((5, 2, N_LOG)), 1e-3, np.zeros(1))
    names = [c.name for c in result.table_columns()]
    assert names[0] == "t" and "w_m1" in names and "i_r_pk_m2" in names
    assert len(names) == 1 + 2 * (len(names) - 1) // 2 and len(set(names)) == len(names)
    assert all(
        c.description.startswith("motor 2: ")
        for c in result.table_columns()
        if c.name.endswith("_m2")
    )


def test_save_creates_its_folder(tmp_path):
    t = np.arange(4) * 1e-3
    signals = np.zeros((4, 1, N_LOG))
    signals[:, 0, LOG_NAMES.index("w")] = [1.0, 2.0, 3.0, 4.0]
    folder = tmp_path / "not" / "there"
    written = DriveResult("x", t, signals, 1e-3, np.zeros(1)).save(folder)
    assert [p.name for p in written] == ["data.parquet", "columns.md"]
    assert all(p.exists() for p in written)


BAD_FOR_MAT = ["dfim.i_s.re", "1st", "_x", "end", "a" * 64, "i s"]
BAD_FOR_ALL = ["", "bad\udcffname", "tab\there"]


@pytest.mark.parametrize("name", BAD_FOR_MAT)
def test_mat_refuses_names_matlab_cannot_hold(name):
    columns = [Column(name, np.zeros(2), "", "x")]
    with pytest.raises(InputError, match=r"not a MATLAB variable name") as info:
        check_names(columns, "mat")
    assert repr(name) in str(info.value) and "\n" not in str(info.value)
    check_names(columns, "parquet")  # Arrow holds them
    check_names(columns, "csv")


@pytest.mark.parametrize("name", BAD_FOR_ALL)
def test_every_format_refuses_names_arrow_cannot_hold(name, tmp_path):
    columns = [Column(name, np.zeros(2), "", "x")]
    for fmt in FORMATS:
        with pytest.raises(InputError, match=r"^--format: column name"):
            write_table(tmp_path, columns, fmt)
    assert not any(tmp_path.iterdir())  # refused before anything was written


def test_duplicate_names_are_refused():
    columns = [Column("w", np.zeros(2), "", "x"), Column("w", np.zeros(2), "", "y")]
    with pytest.raises(InputError, match="appears twice"):
        check_names(columns, "parquet")


def test_an_unrepresentable_name_is_one_line_exit_2_and_nothing_written(
    tmp_path, capsys, monkeypatch
):
    original = DriveResult.table_columns

    def renamed(self, separator="."):
        columns = original(self, separator)
        return [Column("rotor.i", c.values, c.unit, c.description) if c.name == "i_rx" else c
                for c in columns]  # fmt: skip

    monkeypatch.setattr(DriveResult, "table_columns", renamed)
    path = tmp_path / "short.toml"
    path.write_text(SCENARIO)
    out = tmp_path / "out"
    code = main(["run", str(path), "--out", str(out), "--format", "mat", "--no-figures"])
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if not line.startswith("acdrive: note:")]
    assert code == 2 and len(lines) == 1, err
    assert lines[0].startswith("acdrive: error: --format: mat: column 'rotor.i'")
    assert not out.exists()  # the output folder this run created is removed again
