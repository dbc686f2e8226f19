"""``acdrive reproduce im`` regenerates the committed docs/reproduction/im-current-control.md byte
for byte, and the same set of figure files (compared by name: their pixels depend on the plotting
library and fonts; the numbers they show are the report's). The report's simulations run on the
switching inverter and are not chaotic, so their printed digits do not depend on the machine;
round-off-level differences are printed as their bound (``acdrive._verdicts.ROUNDOFF_FLOOR``).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from acdrive._report import im_reproduction

COMMITTED = Path(__file__).resolve().parents[1] / "docs" / "reproduction"
#: Written by the ``acdrive reproduce`` command (its output-safety marker), not by the report.
OUTPUT_MARKER = ".acdrive-output.json"


def _files(folder: Path) -> set[str]:
    return {
        str(p.relative_to(folder))
        for p in folder.rglob("*")
        if p.is_file() and p.name != OUTPUT_MARKER
    }


@pytest.mark.slow  # about 2 min of CPU
def test_im_report_regenerates_identically(tmp_path):
    path = im_reproduction.write_report(tmp_path)
    new = path.read_text().splitlines()
    old = (COMMITTED / f"{im_reproduction.STEM}.md").read_text().splitlines()
    changed = [
        f"line {i + 1}:\n  committed: {a}\n  now:       {b}"
        for i, (a, b) in enumerate(zip(old, new))
        if a != b
    ]
    assert not changed and len(new) == len(old), "\n".join(changed[:10]) or "length differs"
    assert path.read_bytes() == (COMMITTED / f"{im_reproduction.STEM}.md").read_bytes()
    assert _files(tmp_path / im_reproduction.STEM) == _files(COMMITTED / im_reproduction.STEM)
