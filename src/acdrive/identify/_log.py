"""Reading and writing a test log (CSV, Parquet or MATLAB .mat), every column unit-checked.

A log kind declares its columns as name -> (unit, meaning): the standstill log's are those of
``identify._experiment.LOG_COLUMNS`` (``time [s]``, ``v_a [V]``, ``i_a [A]``), other tests
declare their own (``identify._mechanics.MECHANICS_COLUMNS``); one row per sample instant.
A CSV header names each column with its unit in brackets (``time [s],v_a [V],i_a [A]``); a
Parquet file does the same, or keeps the plain name and the unit in the field's metadata key
``unit`` (as acdrive's result tables do, ``acdrive.columns``). A ``.mat`` file (MATLAB, read and
written by ``scipy.io.loadmat`` / ``savemat``) holds each column as a vector variable of its plain
name and the units in a struct variable ``units`` with one text field per column
(``units.time = 's'``), since a MATLAB variable name cannot carry brackets; a column without a
field in ``units`` has no unit.

A log kind may also declare optional columns (the no-load run's DC-link voltage ``v_dc [V]``,
``identify._no_load.NO_LOAD_OPTIONAL``), checked by the same rules when present.

Checked on reading, before any fit, each as one line naming the column and the rule
(``InputError``): a missing, unknown or repeated column, a column without a unit or in another
unit, a value that is not a finite number, fewer than ``MIN_ROWS`` rows, and a time that is not
strictly increasing with a uniform step (relative deviation at most ``UNIFORM_RTOL``).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from acdrive._arguments import PATH, TEXT, Instance, checked
from acdrive.errors import InputError
from acdrive.identify._experiment import LOG_COLUMNS, StandstillLog

#: the fewest rows a log may have
MIN_ROWS = 16
#: largest relative deviation of a time step from the median step
UNIFORM_RTOL = 1e-6
FORMATS = (".csv", ".parquet", ".mat")
#: the .mat variable holding the units
MAT_UNITS = "units"
_HEADER = re.compile(r"^\s*([^\[\]]*?)\s*\[([^\[\]]*)\]\s*$")


def expected(spec: dict, kind: str, optional: dict | None = None) -> str:
    """'a <kind> log has name [unit], ... (optional: name [unit], ...)' for messages."""
    text = f"a {kind} log has " + ", ".join(f"{n} [{u}]" for n, (u, _) in spec.items())
    if optional:
        text += " (optional: " + ", ".join(f"{n} [{u}]" for n, (u, _) in optional.items()) + ")"
    return text


_EXPECTED = expected(LOG_COLUMNS, "standstill")


def _name_and_unit(header: str, metadata_unit: str | None, field: str,
                   listing: str = _EXPECTED) -> tuple[str, str]:  # fmt: skip
    match = _HEADER.match(header)
    if match:
        return match.group(1), match.group(2).strip()
    if metadata_unit is not None:
        return header.strip(), metadata_unit.strip()
    raise InputError(
        f"{field}: column '{header}'",
        f"has no unit; write the header as name [unit] ({listing})",
    )


def check_columns(columns: dict[str, tuple[str, np.ndarray]], field: str) -> StandstillLog:
    """A ``StandstillLog`` from header name -> (unit, values), every rule of the module docstring."""
    values = checked_values(columns, field, LOG_COLUMNS, "standstill")
    return StandstillLog(values["time"], values["v_a"], values["i_a"], field)


def checked_values(columns: dict[str, tuple[str, np.ndarray]], field: str, spec: dict,
                   kind: str, optional: dict | None = None) -> dict[str, np.ndarray]:  # fmt: skip
    """Column name -> values of a log of ``kind`` whose columns ``spec`` declares (and may add
    those of ``optional``, checked alike when present), from header name -> (unit, values),
    every rule of the module docstring."""
    listing = expected(spec, kind, optional)
    allowed = {**spec, **(optional or {})}
    for name, (unit, _) in columns.items():
        if name not in allowed:
            raise InputError(f"{field}: column '{name}'", f"unknown; {listing}")
        unit_expected = allowed[name][0]
        if unit != unit_expected:
            raise InputError(f"{field}: column '{name}'",
                             f"must be in {unit_expected}, got '{unit}'")  # fmt: skip
    for name in spec:
        if name not in columns:
            raise InputError(f"{field}: column '{name}'", f"is missing; {listing}")
    values = {}
    for name in (n for n in allowed if n in columns):
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
    return values


@checked(path=PATH, field=TEXT)
def read_log(path, field: str = "path") -> StandstillLog:
    """The standstill log in ``path`` (``.csv``, ``.parquet`` or ``.mat``), checked (module
    docstring)."""
    values = read_columns(path, LOG_COLUMNS, "standstill", field)
    return StandstillLog(values["time"], values["v_a"], values["i_a"], field)


def _mat_columns(path: Path, field: str) -> list[tuple[str, np.ndarray, str | None]]:
    """(name, values, unit or None) of every variable of a .mat file but ``units``."""
    from scipy.io import loadmat
    from scipy.io.matlab import MatReadError

    try:
        contents = loadmat(path, squeeze_me=True, chars_as_strings=True)
    except (MatReadError, ValueError, OSError, NotImplementedError, TypeError) as exc:
        raise InputError(field, f"'{path}' is not a readable .mat file ({exc})") from None
    units = contents.get(MAT_UNITS)
    unit_of: dict[str, str] = {}
    if units is not None:
        names = units.dtype.names if hasattr(units, "dtype") else None
        if not names:
            raise InputError(f"{field}: variable '{MAT_UNITS}'",
                             "must be a struct with one text field per column")  # fmt: skip
        for name in names:
            unit_of[name] = str(np.asarray(units[name]).reshape(-1)[0]).strip()
    pairs = []
    for name, data in contents.items():
        if name.startswith("__") or name == MAT_UNITS:
            continue
        pairs.append((name, np.asarray(data).reshape(-1), unit_of.get(name)))
    return pairs


def read_columns(path, spec: dict, kind: str, field: str = "TEST_FILE",
                 optional: dict | None = None) -> dict[str, np.ndarray]:  # fmt: skip
    """Column name -> values of the ``kind`` log in ``path`` whose columns ``spec`` declares
    (and ``optional`` may add), checked (module docstring)."""
    path = Path(path)
    if path.suffix not in FORMATS:
        raise InputError(field, f"must be a {', '.join(FORMATS)} file, got '{path.name}'")
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
    elif path.suffix == ".mat":
        pairs = _mat_columns(path, field)
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
    listing = expected(spec, kind, optional)
    for header, data, metadata_unit in pairs:
        if path.suffix == ".mat":  # the header is a plain variable name
            name, unit = header, metadata_unit
            if unit is None:
                raise InputError(f"{field}: column '{name}'", f"has no unit; give it in the "
                                 f"struct variable '{MAT_UNITS}' ({listing})")  # fmt: skip
        else:
            name, unit = _name_and_unit(header, metadata_unit, field, listing)
        if name in columns:
            raise InputError(f"{field}: column '{name}'", "appears twice")
        columns[name] = (unit, data)
    return checked_values(columns, field, spec, kind, optional)


@checked(log=Instance(StandstillLog), path=PATH)
def write_log(log: StandstillLog, path) -> Path:
    """Write the standstill ``log`` (module docstring)."""
    return write_columns({"time": log.time, "v_a": log.v_a, "i_a": log.i_a}, LOG_COLUMNS, path)


def write_columns(values: dict[str, np.ndarray], spec: dict, path) -> Path:
    """Write the columns ``values`` of a log whose columns ``spec`` declares as CSV, Parquet or
    .mat (by the suffix of ``path``) with their units; times and values in full precision
    (``repr`` in a CSV, float64 otherwise), so reading it back gives the same numbers."""
    path = Path(path)
    if path.suffix not in FORMATS:
        raise InputError("path", f"must end in {', '.join(FORMATS)}")
    headers = [f"{name} [{unit}]" for name, (unit, _) in spec.items()]
    data = [np.asarray(values[name], dtype=float) for name in spec]
    if path.suffix == ".mat":
        from scipy.io import savemat

        contents = dict(zip(spec, data, strict=True))
        contents[MAT_UNITS] = {name: unit for name, (unit, _) in spec.items()}
        savemat(path, contents)
    elif path.suffix == ".csv":
        with open(path, "w", encoding="utf-8") as handle:
            handle.write(",".join(headers) + "\n")
            handle.writelines(",".join(repr(float(x)) for x in row) + "\n"
                              for row in zip(*data, strict=True))  # fmt: skip
    else:
        import pyarrow as pa
        import pyarrow.parquet as pq

        fields = [
            pa.field(name, pa.float64(), metadata={"unit": unit, "description": doc})
            for name, (unit, doc) in spec.items()
        ]
        pq.write_table(pa.table(data, schema=pa.schema(fields)), path)
    return path
