"""Aligned text tables for the commands' plain output (``acdrive icad``, ``acdrive limits``).

One row per quantity: its name (the key of the command's ``--json`` output, dotted for a nested
key, so the two outputs name a number the same way), the value, the unit and what it means.
Values are written for a reader, never as Python reprs: numbers to 4 significant digits,
``yes``/``no`` for truth values, lists as comma-separated values, and :data:`NOT_AVAILABLE` for a
value that is undefined or infinite (``null`` in the JSON).
"""

from __future__ import annotations

import math

#: What a value that is None (``null`` in the JSON) prints as.
NOT_AVAILABLE = "n/a"
#: The unit cell of a quantity without a unit (a count, a truth value, a name).
NO_UNIT = "-"
HEADER = ("quantity", "value", "unit", "meaning")


def format_value(value) -> str:
    """``value`` as a reader writes it (module docstring)."""
    import numpy as np

    if value is None:
        return NOT_AVAILABLE
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        value = float(value)
        return f"{value:.4g}" if math.isfinite(value) else str(value)
    if isinstance(value, (list, tuple, np.ndarray)):
        return ", ".join(format_value(v) for v in value)
    return str(value)


def aligned(rows) -> list[str]:
    """Lines of a table of ``(quantity, value, unit, meaning)`` rows under :data:`HEADER`: names
    and units left-aligned, values right-aligned, columns two spaces apart."""
    cells = [HEADER] + [(q, format_value(v), u, m) for q, v, u, m in rows]
    widths = [max(len(row[i]) for row in cells) for i in range(3)]
    lines = []
    for q, v, u, m in cells:
        lines.append(f"{q:<{widths[0]}}  {v:>{widths[1]}}  {u:<{widths[2]}}  {m}".rstrip())
    return lines
