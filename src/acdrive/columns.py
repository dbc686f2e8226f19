"""Result tables that explain themselves: named columns with a unit and a one-line description,
written as Parquet (the default), CSV or MATLAB ``.mat``, with ``columns.md`` beside the data.

Where each format keeps the units and descriptions:

- Parquet (``data.parquet``): in each field's metadata (``unit``, ``description``) and, for the
  whole table, in the schema metadata ``acdrive.columns`` (JSON: name -> unit, description) and
  ``acdrive.conventions`` (the scaling conventions, the text of :data:`CONVENTIONS`);
  ``pyarrow.parquet.read_schema(path).field("w").metadata``.
- CSV (``data.csv``): a plain header of names (any CSV reader reads it); units only in
  ``columns.md``.
- MATLAB (``data.mat``): the struct ``data`` (one field per column), the structs ``units`` and
  ``descriptions`` with the same field names, and the char array ``conventions``;
  ``load('data.mat'); plot(data.t, data.w); units.w``.

Names a format cannot hold are refused before anything is written, as one line naming the column
and the rule (:func:`check_names`): every format needs unique, non-empty names of printable UTF-8
text (Arrow stores names as UTF-8); ``.mat`` needs MATLAB variable names (a letter, then letters,
digits or ``_``, at most 63 characters, not a keyword).

Scaling convention of space vectors (Bodson (8)): the simulator computes power-invariant space
vectors, whose magnitude is sqrt(3/2) times the peak phase value. A column name says which
scaling it carries: ``_pk`` a peak phase value (a magnitude divided by sqrt(3/2): what
summary.json and the figures report), ``_sv`` a component of the power-invariant space vector.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from acdrive.errors import InputError

__all__ = [
    "DEFAULT_FORMAT",
    "FORMATS",
    "Column",
    "check_names",
    "read_units",
    "unit_from_name",
    "write_table",
]

if TYPE_CHECKING:  # numpy is imported where data is written: `acdrive run --help` stays light
    import numpy as np

#: output format -> data file name
FORMATS = {"parquet": "data.parquet", "csv": "data.csv", "mat": "data.mat"}
DEFAULT_FORMAT = "parquet"

CONVENTIONS = (
    "Space vectors are power-invariant (Bodson (8)): a space-vector magnitude is sqrt(3/2) times "
    "the peak phase value. Suffix _pk: peak phase value (space-vector magnitude / sqrt(3/2), the "
    "scaling of summary.json and the figures); suffix _sv: component of the power-invariant "
    "space vector (divide by sqrt(3/2) for the amplitude-invariant, phase-peak scaling)."
)

#: a MATLAB variable or struct field name (``isvarname``; ``namelengthmax`` is 63)
_MATLAB_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,62}")
_MATLAB_KEYWORDS = frozenset(
    ("break", "case", "catch", "classdef", "continue", "else", "elseif", "end", "for",
     "function", "global", "if", "otherwise", "parfor", "persistent", "return", "spmd", "switch",
     "try", "while")
)  # fmt: skip


#: the unit a metric's name ends with (summary.json keys and batch columns carry their unit in
#: their name: ``peak_rotor_current_a``, ``speed_rms_error_tracking_rpm``), longest first
UNIT_SUFFIXES = (
    ("_pct", "%"), ("_rad_s2", "rad/s^2"), ("_rad_s", "rad/s"), ("_n_m", "N m"), ("_rpm", "rpm"),
    ("_rad", "rad"),
    ("_var", "var"), ("_hz", "Hz"), ("_wb", "Wb"), ("_a", "A"), ("_v", "V"), ("_w", "W"),
    ("_j", "J"), ("_s", "s"),
)  # fmt: skip


def unit_from_name(name: str) -> str:
    """The unit a metric's name declares by its suffix (``UNIT_SUFFIXES``), "" if none."""
    for suffix, unit in UNIT_SUFFIXES:
        if name.endswith(suffix):
            return unit
    return ""


@dataclass(frozen=True)
class Column:
    """One column of a result table: its ``name``, ``values`` (1-D), SI ``unit`` ("" if
    dimensionless) and a one-line ``description``."""

    name: str
    values: np.ndarray
    unit: str
    description: str


def check_names(columns: list[Column], fmt: str, field: str = "--format") -> None:
    """Raise InputError (one line, naming the column and the rule) unless every column name can
    be held by the format ``fmt`` (module docstring)."""
    if fmt not in FORMATS:
        raise InputError(field, f"must be one of {', '.join(FORMATS)}, got {fmt!r}")
    seen = set()
    for column in columns:
        name = column.name
        if not isinstance(name, str) or not name:
            raise InputError(field, f"column name {name!r} must be a non-empty string")
        try:
            name.encode("utf-8")
        except UnicodeEncodeError:
            raise InputError(field, f"column name {name!r} is not valid UTF-8 text") from None
        if not name.isprintable():
            raise InputError(field, f"column name {name!r} contains a control character")
        if name in seen:
            raise InputError(field, f"column name {name!r} appears twice")
        seen.add(name)
        if fmt == "mat" and (not _MATLAB_NAME.fullmatch(name) or name in _MATLAB_KEYWORDS):
            raise InputError(
                field,
                f"{fmt}: column {name!r} is not a MATLAB variable name (a letter, then letters, "
                "digits or '_', at most 63 characters, not a keyword); choose --format parquet "
                "or csv",
            )


def columns_markdown(columns: list[Column], title: str, data_file: str) -> str:
    """The text of ``columns.md``: what ``data_file`` holds, the scaling conventions and one row
    per column (name, unit, description) in the file's order."""
    rows = len(columns[0].values) if columns else 0
    lines = [
        f"# {title}",
        "",
        f"`{data_file}`: {len(columns)} columns, {rows} rows, one row per logged sample.",
        "",
        CONVENTIONS,
        "",
        "| column | unit | description |",
        "|---|---|---|",
    ]
    for c in columns:
        description = c.description.replace("|", "\\|")
        lines.append(f"| `{c.name}` | {c.unit or '-'} | {description} |")
    return "\n".join(lines) + "\n"


def _arrow_array(values):
    """``values`` as a pyarrow Array, numbers without a copy beyond making them contiguous.

    A 1-D array of numbers (integers, floats) or booleans is wrapped from its buffer
    (``pyarrow.Array.from_buffers``): the same values, type and NaNs that ``pyarrow.array``
    gives, without that function's pandas check, which imports pandas (0.4 CPU-s, a third of a
    warm ``acdrive run``) for a table that never sees a DataFrame. Anything else (text, objects)
    goes through ``pyarrow.array``."""
    import numpy as np
    import pyarrow as pa

    array = np.ascontiguousarray(values)
    native = array.dtype.byteorder in "=|"
    if array.ndim == 1 and native and array.dtype.kind in "iuf":
        buffer = pa.py_buffer(array)
        return pa.Array.from_buffers(pa.from_numpy_dtype(array.dtype), len(array), [None, buffer])
    if array.ndim == 1 and array.dtype.kind == "b":
        bits = pa.py_buffer(np.packbits(array, bitorder="little"))  # Arrow booleans are bits
        return pa.Array.from_buffers(pa.bool_(), len(array), [None, bits])
    return pa.array(array)


def _write_parquet(columns: list[Column], path: Path) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    fields, arrays = [], []
    for c in columns:
        array = _arrow_array(c.values)
        meta = {"unit": c.unit, "description": c.description}
        fields.append(pa.field(c.name, array.type, metadata=meta))
        arrays.append(array)
    table_meta = {
        "acdrive.columns": json.dumps(
            {c.name: {"unit": c.unit, "description": c.description} for c in columns}
        ),
        "acdrive.conventions": CONVENTIONS,
    }
    table = pa.Table.from_arrays(arrays, schema=pa.schema(fields, metadata=table_meta))
    # no dictionary encoding (measured signals rarely repeat: it costs time and saves nothing);
    # zstd: smaller than snappy at about the same speed
    pq.write_table(table, path, use_dictionary=False, compression="zstd")


def _write_csv(columns: list[Column], path: Path) -> None:
    import pyarrow as pa
    import pyarrow.csv as pacsv

    table = pa.Table.from_arrays(
        [_arrow_array(c.values) for c in columns], names=[c.name for c in columns]
    )
    pacsv.write_csv(table, path)


def _write_mat(columns: list[Column], path: Path) -> None:
    import numpy as np
    import scipy.io

    scipy.io.savemat(
        path,
        {
            "data": {c.name: np.asarray(c.values) for c in columns},
            "units": {c.name: c.unit for c in columns},
            "descriptions": {c.name: c.description for c in columns},
            "conventions": CONVENTIONS,
        },
        long_field_names=True,
        oned_as="column",
    )


_WRITERS = {"parquet": _write_parquet, "csv": _write_csv, "mat": _write_mat}


def write_table(
    folder: Path, columns: list[Column], fmt: str = DEFAULT_FORMAT, title: str = "Result columns"
) -> list[Path]:
    """Write ``columns`` into ``folder`` as ``FORMATS[fmt]`` with ``columns.md`` beside it;
    return both paths. Names the format cannot hold are refused (:func:`check_names`) before
    anything is written; ``folder`` is created if needed."""
    check_names(columns, fmt)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    data = folder / FORMATS[fmt]
    _WRITERS[fmt](columns, data)
    notes = folder / "columns.md"
    notes.write_text(columns_markdown(columns, title, data.name))
    return [data, notes]


def read_units(path: Path) -> dict[str, dict[str, str]]:
    """Name -> {"unit", "description"} of every column of a ``data.parquet`` written here."""
    import pyarrow.parquet as pq

    schema = pq.read_schema(path)
    return {f.name: {k.decode(): v.decode() for k, v in (f.metadata or {}).items()} for f in schema}


def written(target, fmt: str) -> str:
    """What ``target`` holds, counted from the files there: '<data>, columns.md, summary.json,
    N figures' (per run sub-folder: 'in each of a/, b/')."""
    subs = sorted(p.name + "/" for p in target.iterdir() if p.is_dir())
    figures = sum(1 for _ in target.rglob("*.png"))
    where = f" (in {', '.join(subs)})" if subs else ""
    text = f"{FORMATS[fmt]} and columns.md{where}, summary.json"
    return text + (f", {figures} figure{'s' * (figures != 1)}" if figures else "")


def headline_lines(rows: list[tuple[str, str]], summary: dict) -> list[str]:
    """The aligned ``rows`` (label, value) of a run's headline, then the summary's finding,
    warnings and note where it has them."""
    width = max((len(label) for label, _ in rows), default=0)
    lines = [f"  {label:<{width}} {value}" for label, value in rows]
    if "finding" in summary:
        lines.append(f"  finding: {summary['finding']}")
    lines += [f"  warning: {warning}" for warning in summary.get("warnings", [])]
    if "note" in summary:
        lines.append(f"  note: {summary['note']}")
    return lines


def print_headline(rows: list[tuple[str, str]], summary: dict, target, fmt: str) -> None:
    """The end of a run command's output: ``headline_lines`` and what was written where."""
    for line in headline_lines(rows, summary):
        print(line)
    print(f"wrote {target}/: {written(target, fmt)}")
