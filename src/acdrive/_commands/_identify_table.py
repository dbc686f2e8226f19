"""What every form of ``acdrive identify`` shares: the log suffixes it reads and the table of
estimates it prints (quantity, value, unit, both 95 % intervals, meaning)."""

from __future__ import annotations

LOG_SUFFIXES = (".csv", ".parquet", ".mat")
#: the intervals printed beside each value
INTERVAL_HEADER = (
    "quantity",
    "value",
    "unit",
    "95% CI (Jacobian)",
    "95% CI (bootstrap)",
    "meaning",
)


def print_table(title: str, rows) -> None:
    """``title``, then one line per (quantity, ``Estimate``): value, unit, both intervals and
    meaning, in aligned columns."""
    from acdrive._commands._table import format_value

    def interval(pair):
        return f"[{format_value(pair[0])}, {format_value(pair[1])}]"

    cells = [INTERVAL_HEADER] + [
        (name, format_value(e.value), e.unit, interval(e.jacobian), interval(e.bootstrap),
         e.meaning) for name, e in rows
    ]  # fmt: skip
    widths = [max(len(row[i]) for row in cells) for i in range(5)]
    print(title)
    for row in cells:
        print("  ".join(f"{c:<{w}}" if i != 1 else f"{c:>{w}}"
                        for i, (c, w) in enumerate(zip(row[:5], widths, strict=True)))
              + "  " + row[5])  # fmt: skip
