"""Docstrings into the API reference: as reStructuredText when they are valid reST, verbatim
otherwise.

acdrive's docstrings are written to be read in a terminal and in the source (plain text with
``literal`` names, equations such as ``x' = A x + B u`` and tables of numbers); most are valid
reST, some are not (an ``*`` in an equation, an indented continuation). Rather than bending the
docstrings to the renderer, each one is parsed on its own first; if docutils reports any problem
it is shown as a literal block, exactly as written. The documentation build then stays free of
warnings (it runs with ``-W``) without hiding a warning anywhere else.
"""

from __future__ import annotations

import docutils.core


def _parses_cleanly(text: str) -> bool:
    """True if docutils parses ``text`` and applies its transforms (substitutions, references)
    without a warning or error."""
    stream = _Collect()
    settings = {"report_level": 2, "halt_level": 5, "warning_stream": stream}
    docutils.core.publish_doctree(text, settings_overrides=settings)
    return not stream.messages


class _Collect:
    """A stream that keeps docutils' messages instead of printing them."""

    def __init__(self):
        self.messages: list[str] = []

    def write(self, text: str) -> None:
        if text.strip():
            self.messages.append(text)

    def flush(self) -> None:
        pass


def render_or_verbatim(app, what, name, obj, options, lines: list[str]) -> None:
    """``autodoc-process-docstring`` handler: keep ``lines`` if they parse cleanly as reST (with
    Sphinx roles taken as plain interpreted text), else replace them by a literal block.

    A part class's docstring ends with its declarations table, generated from its layouts
    (``acdrive.core._describe``); that part is rendered as real tables from the same
    declarations (``describe().rst()``), the written part before it as above."""
    if not lines:
        return
    table = _declarations(obj, lines)
    _written(lines)
    lines += table


def _declarations(obj, lines: list[str]) -> list[str]:
    """Cut the generated declarations off ``lines``; their reST tables (none if not a part)."""
    from acdrive.core._describe import DECLARATIONS_HEADING

    if not isinstance(obj, type) or DECLARATIONS_HEADING not in lines:
        return []
    del lines[lines.index(DECLARATIONS_HEADING) :]
    return ["", *obj.describe().rst().splitlines(), ""]


def _written(lines: list[str]) -> None:
    if not "".join(lines).strip():
        return
    text = "\n".join(lines)
    probe = text.replace(":class:", "").replace(":func:", "").replace(":meth:", "")
    probe = probe.replace(":mod:", "").replace(":attr:", "").replace(":data:", "")
    if _parses_cleanly(probe):
        return
    lines[:] = ["::", ""] + ["    " + line for line in text.splitlines()] + [""]
