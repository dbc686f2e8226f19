"""Standstill logs as files: CSV and Parquet round trips, and every bad log refused with one line
naming the column and the rule (identify._log)."""

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from acdrive.errors import InputError
from acdrive.identify import StandstillLog, read_log, write_log

T = np.arange(100) * 2e-4
LOG = StandstillLog(T, 10.0 * np.sin(2 * np.pi * 50 * T), 0.1 * np.cos(2 * np.pi * 50 * T), "x")


@pytest.mark.parametrize("suffix", [".csv", ".parquet", ".mat"])
def test_a_written_log_reads_back_the_same_numbers(tmp_path, suffix):
    path = write_log(LOG, tmp_path / f"log{suffix}")
    back = read_log(path)
    for name in ("time", "v_a", "i_a"):
        np.testing.assert_array_equal(getattr(back, name), getattr(LOG, name))


def test_parquet_units_may_sit_in_the_field_metadata(tmp_path):
    fields = [pa.field(n, pa.float64(), metadata={"unit": u})
              for n, u in (("time", "s"), ("v_a", "V"), ("i_a", "A"))]  # fmt: skip
    path = tmp_path / "log.parquet"
    pq.write_table(pa.table([LOG.time, LOG.v_a, LOG.i_a], schema=pa.schema(fields)), path)
    np.testing.assert_array_equal(read_log(path).i_a, LOG.i_a)


def write_csv(path, header, rows):
    path.write_text(header + "\n" + "\n".join(",".join(repr(float(x)) for x in r) for r in rows))
    return path


ROWS = list(zip(LOG.time, LOG.v_a, LOG.i_a, strict=True))


@pytest.mark.parametrize(
    ("header", "rows", "message"),
    [
        ("time [s],v_a [V]", [r[:2] for r in ROWS], r"column 'i_a': is missing"),
        ("time [s],v_a [V],i_a [A],w [rad/s]", [(*r, 0.0) for r in ROWS],
         r"column 'w': unknown; a standstill log has time \[s\], v_a \[V\], i_a \[A\]"),
        ("time [s],v_a [V],i_a [mA]", ROWS, r"column 'i_a': must be in A, got 'mA'"),
        ("time [ms],v_a [V],i_a [A]", ROWS, r"column 'time': must be in s, got 'ms'"),
        ("time [s],v_a,i_a [A]", ROWS, r"column 'v_a': has no unit"),
        ("time [s],v_a [V],i_a [A]", ROWS[:10], r"column 'time': too short: at least 16 rows"),
        ("time [s],v_a [V],i_a [A]", [(t * (1 + 0.01 * (k % 2)), v, i) for k, (t, v, i) in
                                      enumerate(ROWS)], r"column 'time': samples must be uniformly"),
        ("time [s],v_a [V],i_a [A]", ROWS[::-1], r"column 'time': must increase strictly"),
        ("time [s],v_a [V],i_a [A]", [*ROWS[:50], (ROWS[50][0], float("nan"), 0.0), *ROWS[51:]],
         r"column 'v_a': row 51 is not a finite number"),
    ],
)  # fmt: skip
def test_a_bad_log_is_refused_naming_the_column_and_the_rule(tmp_path, header, rows, message):
    path = write_csv(tmp_path / "log.csv", header, rows)
    with pytest.raises(InputError, match=r"^path: " + message):
        read_log(path)


def test_a_file_of_another_kind_or_missing_is_refused(tmp_path):
    with pytest.raises(InputError, match=r"^path: must be a .csv, .parquet, .mat file"):
        read_log(tmp_path / "log.txt")
    (tmp_path / "junk.mat").write_text("not a MATLAB file")
    with pytest.raises(InputError, match=r"^path: '.*junk.mat' is not a readable .mat file"):
        read_log(tmp_path / "junk.mat")
    with pytest.raises(InputError, match=r"^path: '.*nothing.csv' is not a readable file"):
        read_log(tmp_path / "nothing.csv")


def write_mat(path, units, **columns):
    from scipy.io import savemat

    savemat(path, {**columns, **({} if units is None else {"units": units})})
    return path


@pytest.mark.parametrize(
    ("units", "columns", "message"),
    [
        ({"time": "s", "v_a": "V", "i_a": "mA"}, {}, r"column 'i_a': must be in A, got 'mA'"),
        (None, {}, r"column 'time': has no unit; give it in the struct variable 'units'"),
        ({"time": "s", "v_a": "V"}, {"i_a": None}, r"column 'i_a': is missing"),
        ({"time": "s", "v_a": "V", "i_a": "A", "w": "rad/s"}, {"w": T},
         r"column 'w': unknown; a standstill log has time \[s\], v_a \[V\], i_a \[A\]"),
    ],
)  # fmt: skip
def test_a_mat_log_carries_its_units_in_a_struct_and_is_checked_like_the_others(
    tmp_path, units, columns, message
):
    data = {"time": LOG.time, "v_a": LOG.v_a, "i_a": LOG.i_a, **columns}
    data = {k: v for k, v in data.items() if v is not None}
    path = write_mat(tmp_path / "log.mat", units, **data)
    with pytest.raises(InputError, match=r"^path: " + message):
        read_log(path)
