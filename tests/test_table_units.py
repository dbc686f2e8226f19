"""Batch and sweep tables carry their units: ``BatchResult.to_dataframe().attrs["units"]``, the
Parquet schema metadata (``acdrive.units``) and each field's metadata of a sweep's chunk files,
and ``read_table(...).attrs["units"]``. A metric's unit is its signal's declared unit when the
value is not rescaled, else the unit its name declares (``_rpm``, ``_a``, ...)."""

import json
import textwrap

import pyarrow.parquet as pq
import pytest

from acdrive.batch import Reducer, simulate_batch
from acdrive.columns import unit_from_name
from acdrive.plant import Shaft
from acdrive.sweep import load_sweep
from acdrive.sweep._engine import UNITS_KEY, read_table, run_sweep

SHORT = {"simulation.duration": 0.05}


@pytest.mark.parametrize(
    ("name", "unit"),
    [("peak_rotor_current_a", "A"), ("speed_rms_error_tracking_rpm", "rpm"),
     ("speed_final_rad_s", "rad/s"), ("ramp_slope_rad_s2", "rad/s^2"), ("closing_time_s", "s"),
     ("peak_torque_n_m", "N m"), ("speed_limit_cycle", ""), ("variant_id", "")],
)  # fmt: skip
def test_unit_from_name_reads_the_suffix(name, unit):
    assert unit_from_name(name) == unit


def test_batch_frame_units_come_from_the_reducers_and_the_declarations():
    w_unit = Shaft.OUTPUTS.var("w").unit
    reducers = [
        Reducer("w_peak", "peak", "shaft0.w"),  # not rescaled: the declared unit
        Reducer("w_peak_rpm", "peak", "shaft0.w", scale=60 / (2 * 3.141592653589793)),
        Reducer("w_over", "exceed", "shaft0.w", limit=1.0),
        Reducer("e", "speed_error", "shaft0.w", reference="reference0.w_ref", unit="rpm",
                scale=60 / (2 * 3.141592653589793)),
    ]  # fmt: skip
    frame = simulate_batch("bodson-ramp", [SHORT, {**SHORT, "motor[0].params.M": 1.0}],
                           reducers=reducers).to_dataframe()  # fmt: skip
    units = frame.attrs["units"]
    assert set(units) == set(frame.columns)
    assert units["w_peak"] == w_unit == "rad/s"
    assert units["w_peak_time"] == "s"
    assert units["w_peak_rpm"] == "rpm"
    assert (units["w_over"], units["w_over_first_time"]) == ("", "s")
    assert units["speed_rms_error_tracking_rpm"] == "rpm"
    assert units["speed_max_abs_error_tracking_at_s"] == "s"
    assert units["status"] == "" and all(units[c] == "" for c in units if c.startswith("events."))


def test_sweep_chunks_and_table_carry_units_in_the_parquet_metadata(tmp_path):
    text = """
    name = "units"
    base = "bodson-ramp"
    chunk = 2
    [fixed]
    "simulation.duration" = 0.05
    [[vary]]
    field = "motor[0].load_torque"
    values = [0.0, 0.05]
    [traces]
    signals = ["shaft0.w"]
    every = 10
    """
    path = tmp_path / "s.toml"
    path.write_text(textwrap.dedent(text))
    folder = run_sweep(load_sweep(str(path)), tmp_path / "o", progress=False, report=False)
    (chunk,) = sorted((folder / "table").glob("chunk-*.parquet"))
    schema = pq.read_schema(chunk)
    units = json.loads(schema.metadata[UNITS_KEY])
    assert set(units) == set(schema.names)
    rpm = [c for c in schema.names if c.endswith("_rpm")]
    assert rpm and all(units[c] == "rpm" for c in rpm)
    for name in schema.names:
        assert schema.field(name).metadata[b"unit"].decode() == units[name]
    table = read_table(folder)
    assert table.attrs["units"] == {c: units[c] for c in table.columns}
    (traces,) = sorted((folder / "traces").glob("chunk-*.parquet"))
    trace_units = json.loads(pq.read_schema(traces).metadata[UNITS_KEY])
    assert trace_units["shaft0.w"] == Shaft.OUTPUTS.var("w").unit
    assert trace_units["t"] == "s"
