"""The documentation site builds with warnings as errors, and its gallery examples run.

The build works on a copy of ``docs/`` and ``examples/`` in a temporary folder (sphinx-gallery
writes its generated pages into the source tree), so the checkout is left as it was. An example
that raises, a broken cross-reference, a docstring that fails to render or a missing page fails
this test, and with it CI.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

pytest.importorskip("sphinx")
pytest.importorskip("sphinx_gallery")
pytest.importorskip("pydata_sphinx_theme")
pytest.importorskip("myst_parser")


@pytest.mark.slow
def test_site_builds_without_warnings_and_runs_every_example(tmp_path):
    for folder in ("docs", "examples"):
        shutil.copytree(ROOT / folder, tmp_path / folder,
                        ignore=shutil.ignore_patterns("_build", "auto_examples"))  # fmt: skip
    out = tmp_path / "html"
    run = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
         str(tmp_path / "docs"), str(out)],
        capture_output=True, text=True, check=False, env={"MPLBACKEND": "Agg", **_env()},
    )  # fmt: skip
    assert run.returncode == 0, run.stderr[-4000:]
    examples = sorted(p.stem for p in (ROOT / "examples").glob("plot_*.py"))
    assert len(examples) >= 10
    for name in examples:  # every example ran and produced its page
        page = out / "auto_examples" / f"{name}.html"
        assert page.exists(), name
    api = (out / "api.html").read_text()
    for name in ("DFIMParams", "System", "LTI", "analyse", "IMDrive"):
        assert name in api
    # each part's declarations table (generated from its layouts): e.g. the converter's input
    assert "v_ref" in api and "commanded voltage space vector" in api
    assert "plot_winding_thermal" in examples  # the gallery writes its own part
    assert "plot_pm_field_weakening" in examples  # the PM drive, MTPA and field weakening
    assert "plot_export_m4" in examples  # ICAD design -> C -> SIL -> Cortex-M4 count
    index = (out / "index.html").read_text()
    assert "Getting started" in index and "Gallery" in index


def _env() -> dict:
    import os

    return {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}
