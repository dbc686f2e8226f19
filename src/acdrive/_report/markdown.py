"""Markdown building blocks of the reproduction reports: comparison tables, number formatting
and figure files.

A report is a list of ``Section``s, each with an introductory paragraph, a comparison table of
``Row``s (the paper's value beside acdrive's, with the verdict or the reason in the note), text
after the table and figures with their captions; ``render_section`` writes one as Markdown (the
PNG a section links to is written by ``acdrive._figures.save_figure``). The verdict sentences
come from ``acdrive._verdicts``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from acdrive._verdicts import num


@dataclass(frozen=True)
class Row:
    """One line of a comparison table: the paper's value and acdrive's, with the reason."""

    quantity: str
    where: str
    paper: str
    acdrive: str
    note: str = ""


@dataclass
class Section:
    """One ``##`` section of a report: ``text`` before the table of ``rows``, ``after`` it,
    then ``figures`` as (file name, caption)."""

    title: str
    text: str = ""
    rows: list[Row] = field(default_factory=list)
    figures: list[tuple[str, str]] = field(default_factory=list)  # (file name, caption)
    after: str = ""


def fmt(x, digits: int = 4) -> str:
    """Compact number formatting (``digits`` significant digits, complex as a + jb, inf / nan
    spelled out)."""
    if isinstance(x, complex):
        return f"{fmt(x.real, digits)} {'+' if x.imag >= 0 else '-'} j{fmt(abs(x.imag), digits)}"
    return num(x, digits)


def db(x: float) -> float:
    """A gain in decibels, 20 log10 x."""
    return 20.0 * math.log10(x)


def render_section(section: Section, fig_rel: str) -> list[str]:
    """The Markdown lines of ``section``: heading, text, comparison table (``|`` in cells
    escaped), text after the table, and each figure (linked from the folder ``fig_rel``) with
    its caption."""
    out = [f"## {section.title}", ""]
    if section.text:
        out += [section.text, ""]
    if section.rows:
        out += ["| quantity | where | paper | acdrive | note |", "|---|---|---|---|---|"]
        for r in section.rows:
            cells = [r.quantity, r.where, r.paper, r.acdrive, r.note]
            out.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
        out.append("")
    if section.after:
        out += [section.after, ""]
    for name, cap in section.figures:
        out += [f"![{cap}]({fig_rel}/{name})", "", f"*{cap}*", ""]
    return out
