"""What a part declares, as text: ``repr(part)``, ``part.describe()``, the section of the class
docstring that ``help(PartClass)`` and the API reference show, and ``acdrive parts``.

Everything here is read from the part's declarations (``PARAMS``, ``STATES``, ``INPUTS``,
``OUTPUTS``, ``DEFAULTS``, ``INITIAL``, ``EVENTS``; ``core._signals``): nothing is typed twice, so
the tables cannot drift from the kernels that read the same layouts.
"""

from __future__ import annotations

import inspect
import re
from dataclasses import dataclass

import numpy as np

from acdrive.core._signals import RULES, Var, pack_table, pack_table2d, unpack_table2d

#: (section title, layout attribute) in the order a table lists them
SECTIONS = (
    ("parameters", "PARAMS"),
    ("states", "STATES"),
    ("inputs", "INPUTS"),
    ("outputs", "OUTPUTS"),
)
#: columns of each section (the value column is "value" for an instance, "default" for a kind)
COLUMNS = {
    "parameters": ("name", "value", "unit", "kind", "rule", "description"),
    "states": ("name", "value", "unit", "kind", "description"),
    "inputs": ("name", "unit", "kind", "description"),
    "outputs": ("name", "unit", "kind", "description"),
}


@dataclass(frozen=True)
class Row:
    """One declared quantity as the tables show it (``value`` already formatted)."""

    name: str
    unit: str
    kind: str
    description: str
    value: str = ""
    rule: str = ""

    def cell(self, column: str) -> str:
        return getattr(self, column)


@dataclass(frozen=True)
class Section:
    """The rows of one layout, or ``note`` when the constructor sets the layout per instance."""

    title: str
    rows: tuple[Row, ...]
    note: str = ""


@dataclass(frozen=True)
class PartDescription:
    """``part.describe()``: the part's declarations as rows, printed as an aligned table.

    ``sections`` are parameters, states, inputs and outputs (:class:`Section`, rows of
    :class:`Row`); ``value_label`` is "value" for a part instance and "default" for a part kind
    (where "required" marks a parameter without default)."""

    title: str
    summary: str
    part_kind: str
    sections: tuple[Section, ...]
    events: tuple[str, ...]
    value_label: str
    #: the rules over several parameters (``Layout.relations``), each as its phrase
    relations: tuple[str, ...] = ()

    def section(self, title: str) -> Section:
        for s in self.sections:
            if s.title == title:
                return s
        raise KeyError(title)

    def table(self, indent: str = "", summary: bool = True) -> str:
        """Aligned plain text: a heading per section, one line per declared quantity."""
        lines = [f"{self.title}: {self.part_kind} part"]
        if summary and self.summary:
            lines.append(self.summary)
        for s in self.sections:
            lines.append("")
            if s.note:
                lines.append(f"{s.title.capitalize()}: {s.note}")
                continue
            if not s.rows:
                lines.append(f"{s.title.capitalize()}: none")
                continue
            lines.append(f"{s.title.capitalize()}:")
            columns = COLUMNS[s.title]
            if s.title == "parameters" and self.relations:
                rules = [f"  across parameters: {r}" for r in self.relations]
            else:
                rules = []
            header = [self.value_label if c == "value" else c for c in columns]
            cells = [[_cell(r.cell(c)) for c in columns] for r in s.rows]
            widths = [max(len(h), *(len(row[i]) for row in cells)) for i, h in enumerate(header)]
            for row in [header, *cells]:
                text = "  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True))
                lines.append("  " + text.rstrip())
            lines += rules
        if self.events:
            lines += ["", f"Events: {', '.join(self.events)}"]
        return "\n".join(indent + line if line else line for line in lines)

    def rst(self) -> str:
        """The same table as reStructuredText (one ``list-table`` per section), for the API
        reference."""
        lines = [f"**{self.part_kind.capitalize()} part.**", ""]
        for s in self.sections:
            title = s.title.capitalize()
            if s.note or not s.rows:
                lines += [f"*{title}:* {_rst_text(s.note or 'none')}", ""]
                continue
            columns = COLUMNS[s.title]
            header = [self.value_label if c == "value" else c for c in columns]
            lines += [f".. list-table:: {title}", "   :header-rows: 1", ""]
            for row in [header, *([_cell(r.cell(c)) for c in columns] for r in s.rows)]:
                lines.append(f"   * - {_rst_text(row[0])}")
                lines += [f"     - {_rst_text(cell)}" for cell in row[1:]]
            lines.append("")
            if s.title == "parameters" and self.relations:
                lines += [f"*Across parameters:* {_rst_text(r)}" for r in self.relations]
                lines.append("")
        if self.events:
            lines += [f"*Events:* {_rst_text(', '.join(self.events))}", ""]
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.table()

    def __repr__(self) -> str:  # the REPL shows the table
        return self.table()


def _cell(text: str) -> str:
    return text if text else "-"


#: characters that mean markup in reStructuredText, escaped so a cell reads as written
RST_SPECIAL = re.compile(r"([\\*`|_\[\]<>:])")


def _rst_text(text: str) -> str:
    return RST_SPECIAL.sub(r"\\\1", text)


def rule_text(var: Var) -> str:
    """The declared rule, short: "> 0", ">= 0", "a positive integer", "between 0 and 1"."""
    return RULES[var.rule].removeprefix("must be ")


def kind_text(var: Var) -> str:
    return {"table": "profile", "table2d": "2-D table"}.get(var.kind, var.kind)


def format_number(x) -> str:
    """A number as a table or a repr shows it (6 significant digits)."""
    if isinstance(x, (complex, np.complexfloating)):
        z = complex(x)
        return f"{z.real:.6g}{z.imag:+.6g}j"
    if isinstance(x, (int, float, np.number)) and not isinstance(x, bool):
        return f"{float(x):.6g}"
    return repr(x)


def format_value(var: Var, value) -> str:
    """A parameter value without its unit: a number, or a profile's point count and span."""
    if var.kind == "table2d":
        try:
            x, y, _ = unpack_table2d(pack_table2d(var.name, value))
        except (ValueError, TypeError):
            return repr(value)
        x_span = f"{format_number(x[0])}..{format_number(x[-1])}"
        y_span = f"{format_number(y[0])}..{format_number(y[-1])}"
        return f"2-D table, {len(x)} x {len(y)} points, x {x_span}, y {y_span}"
    if var.kind != "table":
        return format_number(value)
    try:
        packed = pack_table(var.name, value)
    except (ValueError, TypeError):
        return repr(value)
    n = int(packed[0])
    times, values = packed[1 : 1 + n], packed[1 + n :]
    if n == 1 or np.all(values == values[0]):
        return format_number(values[0])
    return f"profile, {n} points, {format_number(times[0])}..{format_number(times[-1])} s"


def with_unit(text: str, unit: str) -> str:
    return f"{text} {unit}" if unit and not text.startswith(("profile", "2-D table")) else text


#: a full stop that ends a sentence: followed by a capital, not the dot of "et al." or "e.g."
SENTENCE_END = re.compile(r"(?<!\bal)(?<!\be\.g)(?<!\bi\.e)(?<!\bcf)\.\s+(?=[A-Z])")


def summary_of(cls, width: int | None = None) -> str:
    """First sentence of the part class's own docstring on one line, cut to ``width``."""
    doc = getattr(cls, "_own_doc", "") or ""
    paragraph = " ".join(doc.split("\n\n", 1)[0].replace("``", "").split())
    end = SENTENCE_END.search(paragraph)
    sentence = paragraph if end is None else paragraph[: end.start() + 1]
    if width is not None and len(sentence) > width:
        sentence = sentence[: width - 3].rstrip() + "..."
    return sentence


def describe(target) -> PartDescription:
    """The declarations of a part instance (its values) or of a part kind (its defaults)."""
    is_kind = isinstance(target, type)
    cls = target if is_kind else type(target)
    varies = getattr(cls, "PER_INSTANCE", {}) if is_kind else {}
    if is_kind:
        values = dict(cls.DEFAULTS)
        initial = {v.name: cls.INITIAL.get(v.name, 0.0) for v in cls.STATES}
    else:
        values = target.values
        initial = _initial_values(target)
    sections = []
    for title, attribute in SECTIONS:
        if attribute in varies:
            sections.append(Section(title, (), varies[attribute]))
            continue
        rows = []
        for v in getattr(target, attribute):
            value = rule = ""
            if title == "parameters":
                value = format_value(v, values[v.name]) if v.name in values else "required"
                rule = rule_text(v)
            elif title == "states" and v.name in initial:
                value = format_number(initial[v.name])
            rows.append(Row(v.name, v.unit, kind_text(v), v.doc, value, rule))
        sections.append(Section(title, tuple(rows)))
    title = cls.__name__ if is_kind else f"{cls.__name__}({target.name!r})"
    return PartDescription(
        title=title,
        summary=summary_of(cls),
        part_kind=cls.KIND,
        sections=tuple(sections),
        events=tuple(cls.EVENTS),
        value_label="default" if is_kind else "value",
        relations=tuple(r.rule for r in getattr(cls.PARAMS, "relations", ())),
    )


def _initial_values(part) -> dict:
    try:
        return part.STATES.unpack(part.initial_state())
    except (ValueError, TypeError):  # an initial state that needs run-time values
        return {}


def part_repr(part) -> str:
    """``Kind('name', p=value unit, ...)`` from the declared parameters and their values."""
    items = [repr(part.name)]
    for v in part.PARAMS:
        if v.name in part.values:
            items.append(f"{v.name}={with_unit(format_value(v, part.values[v.name]), v.unit)}")
    return f"{type(part).__name__}({', '.join(items)})"


def layout_text(layout) -> str:
    """``v_ref [V, complex], v_dc [V, real]``: the names, units and kinds of a layout."""
    return ", ".join(f"{v.name} [{v.unit or '-'}, {kind_text(v)}]" for v in layout) or "none"


def ports_repr(part_name: str, layout, direction: str) -> str:
    """``<conv inputs: v_ref [V, complex], ...>``."""
    what = "inputs" if direction == "in" else "outputs"
    return f"<{part_name} {what}: {layout_text(layout)}>"


#: the line that starts the generated part of a part class's docstring (the API reference
#: replaces what follows it by ``PartDescription.rst()``)
DECLARATIONS_HEADING = "Declarations (generated from PARAMS, STATES, INPUTS and OUTPUTS)::"


def class_docstring(cls) -> str:
    """The part class's own docstring followed by its declarations table, as a literal block
    (plain text in ``help()``, preformatted in the API reference)."""
    own = cls._own_doc
    declared = any(len(getattr(cls, a)) for _, a in SECTIONS) or cls.PER_INSTANCE
    if not declared:  # a base kind (ContinuousPart, ...): nothing to tabulate
        return own
    table = describe(cls).table(indent="    ", summary=False)
    heading = DECLARATIONS_HEADING
    return f"{own}\n\n{heading}\n\n{table}\n" if own else f"{heading}\n\n{table}\n"


def signature(cls) -> inspect.Signature:
    """``(name, *, p1, p2=default, ...)`` from ``PARAMS`` and ``DEFAULTS``, for a part whose
    constructor is ``Part.__init__`` (``help()`` and editors then show the parameters)."""
    keyword = inspect.Parameter.KEYWORD_ONLY
    params = [inspect.Parameter("name", inspect.Parameter.POSITIONAL_OR_KEYWORD, annotation=str)]
    required = [v for v in cls.PARAMS if v.name not in cls.DEFAULTS]
    optional = [v for v in cls.PARAMS if v.name in cls.DEFAULTS]
    params += [inspect.Parameter(v.name, keyword) for v in required]
    params += [inspect.Parameter(v.name, keyword, default=cls.DEFAULTS[v.name]) for v in optional]
    return inspect.Signature(params)


def own_doc(cls) -> str:
    doc = cls.__dict__.get("__doc__")
    return inspect.cleandoc(doc) if doc else ""
