"""Reading and writing a standstill test log (CSV or Parquet), every column unit-checked.

The columns are those of ``identify._experiment.LOG_COLUMNS``: ``time [s]``, ``v_a [V]``,
``i_a [A]``, one row per sample instant. A CSV header names each column with its unit in
brackets (``time [s],v_a [V],i_a [A]``); a Parquet file does the same, or keeps the plain name and
the unit in the field's metadata key ``unit`` (as acdrive's result tables do, ``acdrive.columns``).

Checked on reading, before any fit, each as one line naming the column and the rule
(``InputError``): a missing, unknown or repeated column, a column without a unit or in another
unit, a value that is not a finite number, fewer than ``MIN_ROWS`` rows, and a time that is not
strictly increasing with a uniform step (relative deviation at most ``UNIFORM_RTOL``).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from acdrive.errors import InputError
from acdrive.identify._experiment import LOG_COLUMNS, StandstillLog

#: the fewest rows a log may have
MIN_ROWS = 16
#: largest relative deviation of a time step from the median step
UNIFORM_RTOL = 1e-6
FORMATS = (".csv", ".parquet")
_HEADER = re.compile(r"^\s*([^\[\]]*?)\s*\[([^\[\]]*)\]\s*$")
_EXPECTED = ", ".join(f"{name} [{unit}]" for name, (unit, _) in LOG_COLUMNS.items())


def _name_and_unit(header: str, metadata_unit: str | None, field: str) -> tuple[str, str]:
    match = _HEADER.match(header)
    if match:
        return match.group(1), match.group(2).strip()
    if metadata_unit is not None:
        return header.strip(), metadata_unit.strip()
    raise InputError(
        f"{field}: column '{header}'",
        f"has no unit; write the header as name [unit] (a standstill log has {_EXPECTED})",
    )


def check_columns(columns: dict[str, tuple[str, np.ndarray]], field: str) -> StandstillLog:
    """A ``StandstillLog`` from header name -> (unit, values), every rule of the module docstring."""
    for name, (unit, _) in columns.items():
        if name not in LOG_COLUMNS:
            raise InputError(f"{field}: column '{name}'",
                             f"unknown; a standstill log has {_EXPECTED}")  # fmt: skip
        expected = LOG_COLUMNS[name][0]
        if unit != expected:
            raise InputError(f"{field}: column '{name}'", f"must be in {expected}, got '{unit}'")
    for name in LOG_COLUMNS:
        if name not in columns:
            raise InputError(f"{field}: column '{name}'",
                             f"is missing; a standstill log has {_EXPECTED}")  # fmt: skip
    values = {}
    for name in LOG_COLUMNS:
        data = columns[name][1]
        try:
            data = np.asarray(data, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"{field}: column '{name}'", "must hold numbers") from None
        bad = np.flatnonzero(~np.isfinite(data))
        if bad.size:
            raise InputError(f"{field}: column '{name}'",
                             f"row {bad[0] + 1} is not a finite number")  # fmt: skip
        values[name] = data
    time = values["time"]
    if time.size < MIN_ROWS:
        raise InputError(f"{field}: column 'time'",
                         f"too short: at least {MIN_ROWS} rows, got {time.size}")  # fmt: skip
    step = np.diff(time)
    if np.any(step <= 0.0):
        row = int(np.flatnonzero(step <= 0.0)[0]) + 2
        raise InputError(f"{field}: column 'time'", f"must increase strictly (row {row})")
    median = float(np.median(step))
    worst = float(np.max(np.abs(step - median))) / median
    if worst > UNIFORM_RTOL:
        raise InputError(
            f"{field}: column 'time'",
            f"samples must be uniformly spaced (step {median:.6g} s; a step deviates by "
            f"{worst:.2g} of it, at most {UNIFORM_RTOL:g} allowed)",
        )
    return StandstillLog(time, values["v_a"], values["i_a"], field)


def read_log(path, field: str = "TEST_FILE") -> StandstillLog:
    """The log in ``path`` (``.csv`` or ``.parquet``), checked (module docstring)."""
    path = Path(path)
    if path.suffix not in FORMATS:
        raise InputError(field, f"must be a {' or '.join(FORMATS)} file, got '{path.name}'")
    if not path.is_file():
        raise InputError(field, f"'{path}' is not a readable file")
    columns: dict[str, tuple[str, np.ndarray]] = {}
    if path.suffix == ".csv":
        import pandas as pd

        try:
            frame = pd.read_csv(path)
        except (ValueError, OSError) as exc:  # pandas' parser errors are ValueErrors
            raise InputError(field, f"'{path}' is not a readable CSV file ({exc})") from None
        pairs = [(str(h), frame[h].to_numpy(), None) for h in frame.columns]
    else:
        import pyarrow as pa
        import pyarrow.parquet as pq

        try:
            table = pq.read_table(path)
        except (pa.ArrowException, OSError) as exc:
            raise InputError(field, f"'{path}' is not a readable Parquet file ({exc})") from None
        pairs = []
        for f in table.schema:
            unit = (f.metadata or {}).get(b"unit")
            pairs.append((f.name, table.column(f.name).to_numpy(),
                          None if unit is None else unit.decode()))  # fmt: skip
    for header, data, metadata_unit in pairs:
        name, unit = _name_and_unit(header, metadata_unit, field)
        if name in columns:
            raise InputError(f"{field}: column '{name}'", "appears twice")
        columns[name] = (unit, data)
    return check_columns(columns, field)


def write_log(log: StandstillLog, path) -> Path:
    """Write ``log`` as CSV or Parquet (by the suffix of ``path``) with unit-carrying headers;
    times and values in full precision (``repr``), so reading it back gives the same numbers."""
    path = Path(path)
    if path.suffix not in FORMATS:
        raise InputError("path", f"must end in {' or '.join(FORMATS)}")
    headers = [f"{name} [{unit}]" for name, (unit, _) in LOG_COLUMNS.items()]
    data = [log.time, log.v_a, log.i_a]
    if path.suffix == ".csv":
        with open(path, "w", encoding="utf-8") as handle:
            handle.write(",".join(headers) + "\n")
            handle.writelines(",".join(repr(float(x)) for x in row) + "\n"
                              for row in zip(*data, strict=True))  # fmt: skip
    else:
        import pyarrow as pa
        import pyarrow.parquet as pq

        fields = [
            pa.field(name, pa.float64(), metadata={"unit": unit, "description": doc})
            for name, (unit, doc) in LOG_COLUMNS.items()
        ]
        pq.write_table(pa.table(data, schema=pa.schema(fields)), path)
    return path
