"""Sphinx configuration of acdrive's documentation site.

Build (warnings are errors, the gallery's examples run):
    python -m sphinx -W --keep-going -b html docs docs/_build/html

Markdown pages are read by MyST; the API reference comes from the docstrings (autodoc); the
gallery (``examples/``) is executed by sphinx-gallery at build time, so an example that raises
fails the build.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import acdrive

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "docs"))  # the docstring filter below

project = "acdrive"
author = "the acdrive developers"
copyright = "2026, the acdrive developers"
version = release = acdrive.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "sphinx_gallery.gen_gallery",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
# run folders of the reproduction reports carry a columns.md beside their data (not pages)
exclude_patterns = ["_build", "auto_examples/*.ipynb", "auto_examples/*.py", "**/*.zip",
                    "reproduction/*/**/columns.md"]  # fmt: skip
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3
# The theory and reproduction pages link to source files and to the papers outside the site
# (relative links that are meaningful in the repository); MyST cannot resolve those as documents.
suppress_warnings = ["myst.xref_missing"]

autodoc_member_order = "bysource"
autodoc_typehints = "none"  # signatures are shown as written; types live in the docstrings
autosummary_generate = False
nitpicky = False

html_theme = "pydata_sphinx_theme"
html_title = f"acdrive {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "footer_start": ["copyright"],
    # three short links in the header, the long theory and reproduction titles under "More"
    "header_links_before_dropdown": 3,
    # gallery pages: the code needs the width more than an "on this page" list of two headings
    # (patterns may not overlap: "*" stops at a "/")
    "secondary_sidebar_items": {
        **{pattern: ["page-toc", "sourcelink"] for pattern in ("*", "guide/*", "reproduction/*")},
        "auto_examples/*": [],
    },
}
# the landing page and the API page have no sibling pages to navigate
html_sidebars = {"index": [], "api": []}
html_static_path: list[str] = []

sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "abort_on_example_error": True,
    "only_warn_on_example_error": False,
    "download_all_examples": False,
    "remove_config_comments": True,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "within_subsection_order": "FileNameSortKey",
}

os.environ.setdefault("MPLBACKEND", "Agg")


def setup(app):
    from docstring_filter import render_or_verbatim

    app.connect("autodoc-process-docstring", render_or_verbatim)
