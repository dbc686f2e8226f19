"""The scenario field reference (docs/guide/scenario-fields.md) is what the drives' schemas say
now: the committed page equals ``acdrive.scenarios._fields.reference()``, and what it records
is what the schemas do (a required key is refused when removed, a default is the one loaded)."""

from __future__ import annotations

from pathlib import Path

import pytest

from acdrive.errors import InputError
from acdrive.scenarios import load_scenario
from acdrive.scenarios._fields import recorded_fields, reference

PAGE = Path(__file__).resolve().parents[1] / "docs" / "guide" / "scenario-fields.md"


def test_the_committed_page_is_what_the_schemas_say_now():
    assert PAGE.read_text() == reference(), (
        "docs/guide/scenario-fields.md is stale: "
        "python -m acdrive.scenarios._fields > docs/guide/scenario-fields.md"
    )


@pytest.mark.parametrize("kind", ["dfim", "cage-im", "pm"])
def test_every_table_a_built_in_scenario_sets_is_listed(kind):
    """Each key of each built-in scenario's own tables is a row of its drive's table."""
    from acdrive.drives._registry import DEFAULT_KIND
    from acdrive.scenarios import builtin_names, read_scenario

    listed = {(f.table, f.key) for f in recorded_fields(kind)}
    for name in builtin_names():
        data = read_scenario(name)
        if data.get("drive", DEFAULT_KIND) != kind:
            continue
        for table in ("simulation", "converter", "control", "inverter", "foc", "supply"):
            for key, value in data.get(table, {}).items():
                if not isinstance(value, dict):  # key_profile: the row of key
                    row = (table, key.removesuffix("_profile"))
                    assert (table, key) in listed or row in listed, (name, table, key)


def test_a_key_listed_required_is_refused_when_missing(tmp_path):
    """pm: simulation.duration is listed required; a scenario without it is refused naming it."""
    from acdrive.scenarios._files import builtin_text

    rows = {(f.table, f.key): f for f in recorded_fields("pm")}
    assert rows[("simulation", "duration")].required
    text = builtin_text("pm-bly171d-speed")
    missing = tmp_path / "missing.toml"
    missing.write_text("\n".join(x for x in text.splitlines() if not x.startswith("duration")))
    with pytest.raises(InputError, match=r"^simulation\.duration: "):
        load_scenario(missing)
