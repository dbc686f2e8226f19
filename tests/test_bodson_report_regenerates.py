"""`acdrive reproduce bodson --out docs/reproduction` regenerates the committed
docs/reproduction/bodson.md byte for byte.

The report is written into a temporary folder and compared with the committed one: the Markdown
byte for byte, the figures by the set of files written (their pixels depend on the plotting
library; the numbers they show are the report's). Quantities of limit-cycling runs are printed
to the precision their spread allows (``acdrive._spread``), so the comparison also holds
on another x86-64 machine.
"""

from pathlib import Path

import pytest

from acdrive._report.bodson_reproduction import write_report

COMMITTED = Path(__file__).resolve().parents[1] / "docs" / "reproduction"


#: Written by the ``acdrive reproduce`` command (its output-safety marker), not by the report.
OUTPUT_MARKER = ".acdrive-output.json"


def _files(folder: Path) -> set[str]:
    return {
        str(p.relative_to(folder))
        for p in folder.rglob("*")
        if p.is_file() and p.name != OUTPUT_MARKER
    }


@pytest.mark.slow  # about 1.5 min of CPU; over 5 min wall on a loaded machine
def test_bodson_report_regenerates_identically(tmp_path):
    path = write_report(tmp_path)
    new = path.read_text().splitlines()
    old = (COMMITTED / "bodson.md").read_text().splitlines()
    changed = [
        f"line {i + 1}:\n  committed: {a}\n  now:       {b}"
        for i, (a, b) in enumerate(zip(old, new))
        if a != b
    ]
    assert not changed and len(new) == len(old), "\n".join(changed[:10]) or "length differs"
    assert path.read_bytes() == (COMMITTED / "bodson.md").read_bytes()
    assert _files(tmp_path / "bodson") == _files(COMMITTED / "bodson")
