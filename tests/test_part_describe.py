"""Parts explain themselves: repr, describe(), help(), ``acdrive parts`` and the API reference
all show the parameters, states, inputs and outputs a part declares, with units, kinds and rules."""

from __future__ import annotations

import inspect
import pydoc
import re
import subprocess
import sys
from pathlib import Path

import docutils.core
import pytest

from acdrive._part_catalog import find_part_kind, part_kinds
from acdrive.cli import main
from acdrive.core._describe import COLUMNS
from acdrive.errors import InputError
from acdrive.plant import AveragedConverter, Shaft, ThreePhaseSource

ROOT = Path(__file__).resolve().parents[1]
LAYOUTS = {"parameters": "PARAMS", "states": "STATES", "inputs": "INPUTS", "outputs": "OUTPUTS"}
KINDS = part_kinds()


def test_repr_shows_the_name_and_every_parameter_with_its_unit():
    assert repr(AveragedConverter("conv", V_dc=30.0)) == "AveragedConverter('conv', V_dc=30 V)"
    shaft = Shaft("shaft", J=0.02, B=1e-3)
    assert repr(shaft) == (
        "Shaft('shaft', J=0.02 kg m^2, B=0.001 N m s/rad, tau_c=0 N m, load=0 N m, "
        "brake=0 N m s/rad)"
    )
    ramp = ThreePhaseSource("grid", V_pk=[[0.0, 0.0], [0.5, 180.0]], f=60.0)
    assert "V_pk=profile, 2 points, 0..0.5 s" in repr(ramp) and "f=60 Hz" in repr(ramp)


def test_ports_list_their_unit_and_kind():
    conv = AveragedConverter("conv", V_dc=30.0)
    assert repr(conv.inp) == "<conv inputs: v_ref [V, complex]>"
    assert repr(conv.out) == "<conv outputs: v [V, complex]>"
    assert repr(Shaft("s", J=1.0).inp) == "<s inputs: tau_e [N m, real]>"


@pytest.mark.parametrize("name", sorted(KINDS))
def test_describe_lists_exactly_the_declarations(name):
    kind = KINDS[name]
    description = kind.describe()
    assert description.value_label == "default" and description.title == name
    for title, attribute in LAYOUTS.items():
        section = description.section(title)
        if attribute in kind.PER_INSTANCE:
            assert section.note and not section.rows
            continue
        layout = getattr(kind, attribute)
        assert [r.name for r in section.rows] == [v.name for v in layout]
        for row, var in zip(section.rows, layout, strict=True):
            assert row.unit == var.unit and row.description == var.doc
            assert row.kind == {"table": "profile", "table2d": "2-D table"}.get(var.kind, var.kind)
        if title == "parameters":
            for row in section.rows:
                assert (row.value == "required") == (row.name not in kind.DEFAULTS)
    # the rules across parameters (sigma > 0, a magnet or saliency) are shown, each once
    rules = [r.rule for r in getattr(kind.PARAMS, "relations", ())]
    assert description.relations == tuple(rules)
    text = description.table()
    for rule in rules:
        assert text.count(f"across parameters: {rule}") == 1


def test_the_machines_cross_field_rules_are_described():
    from acdrive.machines import CageInductionMachine, DoublyFedMachine, PermanentMagnetMachine

    for kind in (DoublyFedMachine, CageInductionMachine):
        assert any("sigma" in r for r in kind.describe().relations)
    assert any("psi_m" in r for r in PermanentMagnetMachine.describe().relations)


def test_an_instance_describes_its_values_and_a_kind_its_defaults():
    kind_rows = {r.name: r for r in Shaft.describe().section("parameters").rows}
    assert kind_rows["J"].value == "required" and kind_rows["B"].value == "0"
    assert kind_rows["J"].rule == "> 0" and kind_rows["B"].rule == ">= 0"
    rows = {r.name: r for r in Shaft("s", J=2.5, B=0.1).describe().section("parameters").rows}
    assert rows["J"].value == "2.5" and rows["B"].value == "0.1"
    text = str(Shaft("s", J=2.5).describe())
    header = next(line for line in text.splitlines() if line.strip().startswith("name"))
    assert header.split() == ["name", "value", "unit", "kind", "rule", "description"]
    doc = re.escape(Shaft.PARAMS.var("J").doc)
    assert re.search(rf"^\s+J\s+2\.5\s+kg m\^2\s+real\s+> 0\s+{doc}$", text, re.MULTILINE)


def test_help_and_the_signature_show_the_parameters():
    text = pydoc.render_doc(AveragedConverter, renderer=pydoc.plaintext)
    for word in ("V_dc", "DC-link voltage", "v_ref", "commanded voltage space vector", "> 0"):
        assert word in text, word
    signature = inspect.signature(Shaft)
    assert list(signature.parameters) == ["name", "J", "B", "tau_c", "load", "brake"]
    assert signature.parameters["J"].default is inspect.Parameter.empty
    assert signature.parameters["B"].default == Shaft.DEFAULTS["B"]


def test_the_catalog_holds_every_part_kind_the_public_namespaces_export():
    import acdrive.control
    import acdrive.machines
    import acdrive.plant
    from acdrive.core import Part

    exported = {
        name
        for module in (acdrive.machines, acdrive.plant, acdrive.control)
        for name in module.__all__
        if isinstance(getattr(module, name), type) and issubclass(getattr(module, name), Part)
    }
    assert set(KINDS) == exported
    assert {"AveragedConverter", "CageInductionMachine", "SpeedPI"} <= exported


def test_a_misspelt_kind_names_the_close_ones():
    with pytest.raises(InputError, match="did you mean AveragedConverter"):
        find_part_kind("AveragedConvertor")
    with pytest.raises(InputError, match="did you mean Shaft"):
        find_part_kind("shaft")


def test_acdrive_parts_lists_every_kind_with_a_description(capsys):
    assert main(["parts"]) == 0
    lines = capsys.readouterr().out.splitlines()
    for name in KINDS:
        line = next(x for x in lines if x.split()[:1] == [name])
        assert len(line.split()) > 2, line  # a description follows the name


def test_acdrive_parts_name_prints_the_table(capsys):
    assert main(["parts", "AveragedConverter"]) == 0
    out = capsys.readouterr().out
    assert "from acdrive.plant import AveragedConverter" in out
    assert re.search(
        r"^\s+v_ref\s+V\s+complex\s+commanded voltage space vector$", out, re.MULTILINE
    )
    assert re.search(r"^\s+V_dc\s+required\s+V\s+real\s+> 0\s+DC-link voltage$", out, re.MULTILINE)


def test_acdrive_parts_typo_is_one_line_with_exit_2():
    run = subprocess.run(
        [sys.executable, "-m", "acdrive.cli", "parts", "AveragedConvertor"],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert run.returncode == 2 and run.stdout == ""
    assert run.stderr.count("\n") == 1 and "did you mean AveragedConverter" in run.stderr


def _api_members() -> dict[str, set[str]]:
    """Namespace -> the names its ``automodule`` block in docs/api.rst documents."""
    text = (ROOT / "docs" / "api.rst").read_text()
    blocks = re.findall(
        r"\.\. automodule:: (\S+)\n   :members: ((?:.*\n)(?:             .*\n)*)", text
    )
    return {module: set(re.findall(r"\w+", members)) for module, members in blocks}


def test_the_api_page_documents_every_part_kind_with_a_table_of_its_declarations():
    sys.path.insert(0, str(ROOT / "docs"))
    try:
        from docstring_filter import _parses_cleanly
    finally:
        sys.path.remove(str(ROOT / "docs"))
    from acdrive._part_catalog import namespace_of

    members = _api_members()
    for name, kind in KINDS.items():
        assert name in members[namespace_of(kind)], f"{name} is missing from docs/api.rst"
        rst = kind.describe().rst()
        assert _parses_cleanly(rst), name
        rendered = docutils.core.publish_doctree(rst).astext()
        for attribute in LAYOUTS.values():
            if attribute in kind.PER_INSTANCE:
                continue
            for var in getattr(kind, attribute):
                assert var.name in rendered and var.doc in rendered, f"{name}.{var.name}"
    assert set(COLUMNS) == set(LAYOUTS)


@pytest.mark.slow
def test_the_built_api_page_shows_each_parts_ports(tmp_path):
    """docs/api.rst built on its own (autodoc with the project's docstring filter): each part
    kind's section holds each of its declared ports, e.g. the converter's v_ref."""
    pytest.importorskip("sphinx")
    source = tmp_path / "src"
    source.mkdir()
    for name in ("api.rst", "docstring_filter.py"):
        (source / name).write_text((ROOT / "docs" / name).read_text())
    (source / "conf.py").write_text(
        "import sys, os\nsys.path.insert(0, os.path.dirname(__file__))\n"
        "extensions = ['sphinx.ext.autodoc']\nroot_doc = 'api'\nautodoc_typehints = 'none'\n"
        "def setup(app):\n    from docstring_filter import render_or_verbatim\n"
        "    app.connect('autodoc-process-docstring', render_or_verbatim)\n"
    )
    run = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
         str(source), str(tmp_path / "out")],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr[-3000:]
    html = (tmp_path / "out" / "api.html").read_text()
    from acdrive._part_catalog import namespace_of

    for name, kind in KINDS.items():
        start = html.index(f'id="{namespace_of(kind)}.{name}"')
        end = html.find('<dl class="py class">', start)
        section = re.sub(r"<[^>]+>", " ", html[start : end if end > 0 else None])
        for attribute in ("INPUTS", "OUTPUTS"):
            if attribute in kind.PER_INSTANCE:
                continue
            for var in getattr(kind, attribute):
                assert re.search(rf"\b{var.name}\b", section), f"{name}.{var.name}"
    assert "v_ref" in html
