"""`acdrive icad` and `acdrive limits` print aligned tables with units, not Python reprs.

Each row names a quantity by its --json key (dotted when nested), so the test reads the same
command's JSON and checks every printed value against it (to the 4 significant digits printed),
every number against its unit, and every row's cells against the header's columns."""

import json

import pytest

from acdrive.cli import main

#: Fragments of Python reprs that must never reach a user's terminal.
REPRS = ("np.float64(", "np.int64(", "array(", "{'", "['", "[", "None", "True", "False", "0x")
UNITS = {"N m", "dB", "deg", "rad/s", "-"}

#: ``limits`` is closed-form (well under a second): it stays in the developer's loop and keeps
#: the table writer (``_commands._table``) there; the ICAD commands design and verify controllers.
COMMANDS = [
    ["limits"],
    ["limits", "--current-limit-pk", "0.1"],  # infeasible rotor limit: zeros and "no"
    pytest.param(["icad", "ugalde-im-300w", "--speed", "100"], marks=pytest.mark.slow),
    # undefined IM-only figures: n/a
    pytest.param(["icad", "pmsg-2mw", "--speed", "50"], marks=pytest.mark.slow),
    pytest.param(
        ["icad", "delorenzo-im", "--sweep", "--speeds", "0", "300", "2", "--no-verify"],
        marks=pytest.mark.slow,
    ),
]


def _flat(value, prefix=""):
    if isinstance(value, dict):
        out = {}
        for key, item in value.items():
            out.update(_flat(item, f"{prefix}{key}."))
        return out
    return {prefix[:-1]: value}


def _parse(cell: str):
    if cell in ("yes", "no"):
        return cell == "yes"
    if cell == "n/a":
        return None
    if ", " in cell:
        return [_parse(c) for c in cell.split(", ")]
    return float(cell)


def _run(capsys, argv):
    assert main(argv) == 0
    return capsys.readouterr().out


@pytest.mark.parametrize("argv", COMMANDS, ids=lambda a: " ".join(a[:3]))
def test_plain_output_is_an_aligned_table_with_units_and_the_json_values(argv, capsys, tmp_path):
    if "--sweep" in argv:
        argv = [*argv, "--out", str(tmp_path / "figures")]
    text = _run(capsys, argv)
    expected = _flat(json.loads(_run(capsys, [*argv, "--json"])))
    lines = text.splitlines()
    for line in lines:
        assert not any(r in line for r in REPRS), line
    head = next(i for i, line in enumerate(lines) if line.split()[:4] == ["quantity", "value",
                                                                          "unit", "meaning"])  # fmt: skip
    header = lines[head]
    value_end = header.index("value") + len("value")
    unit_at, meaning_at = header.index("unit"), header.index("meaning")
    rows = []
    for line in lines[head + 1 :]:
        name = line.split()[0]
        if name not in expected:
            break  # the table ends (a note or the figure list follows)
        rows.append(name)
        assert line[value_end - 1] != " " and line[value_end] == " ", line  # values right-aligned
        unit = line[unit_at:meaning_at].strip()
        assert unit in UNITS and line[meaning_at - 1] == " " and line[meaning_at] != " ", line
        cell = line[:unit_at].split(maxsplit=1)[1].strip()
        value, want = _parse(cell), expected[name]
        if isinstance(want, bool) or want is None or isinstance(want, list):
            assert value == want, (name, cell, want)
        else:
            assert value == pytest.approx(want, rel=5e-4, abs=1e-12), (name, cell, want)
            counted = name.startswith("encirclements")
            assert unit != "-" or counted, f"{name} is a number without a unit"
    # every number of the JSON (not the names, speeds list and figure paths) has its row
    shown = {k for k, v in expected.items() if isinstance(v, (bool, float, int)) or v is None}
    shown |= {k for k in expected if k.startswith("encirclements")}
    assert shown - {"speed_rad_s"} <= set(rows), sorted(shown - set(rows))
    if any(expected[name] is None for name in rows):
        assert any(line.startswith("n/a: ") for line in lines)
