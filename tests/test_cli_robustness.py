"""Nothing a user types crashes with a traceback: diverged simulations (exit 3), size bounds of a
scenario, strict JSON, extreme and negative numeric flags, and fuzzed scenario files (exit 2).

Every failure is exactly one line ``acdrive: error: <field>: <rule>`` on stderr and leaves no
output folder behind.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
import tomllib

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from acdrive._output import finite_or_null, strict_json
from acdrive.cli import main
from acdrive.errors import SimulationDiverged

MOTOR = "[[motor]]\nspeed_reference_rpm = [[0, 0], [{d}, 100]]\n"


def _scenario(tmp_path, simulation: str = "duration = 0.01", extra: str = "", name="robust"):
    path = tmp_path / "scenario.toml"
    path.write_text(f'name = "{name}"\n[simulation]\n{simulation}\n' + MOTOR.format(d=0.01) + extra)
    return path


def _main(capsys, *argv):
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:  # argparse's own errors end the process with exit code 2
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


def _one_line(err: str, field: str | None = None) -> str:
    assert "Traceback" not in err, err
    lines = err.splitlines()
    assert len(lines) == 1 and err.endswith("\n"), err
    assert lines[0].startswith("acdrive: error: "), err
    if field is not None:
        assert lines[0].startswith(f"acdrive: error: {field}:"), err
    return lines[0]


def _strict(text: str):
    """Parse JSON refusing NaN / Infinity (which Python's json would accept)."""

    def refuse(name):
        raise ValueError(f"non-standard JSON constant {name}")

    return json.loads(text, parse_constant=refuse)


# ---------------------------------------------------------------------------------------------
# 1. a diverging simulation: exit 3, the time, what to change
# ---------------------------------------------------------------------------------------------

#: RK4 step 2 ms, far beyond the stability limit of the fastest electrical pole of a machine
#: with an 8-ohm rotor (R_r / (sigma L_r) + 2 pi f = 3,433 1/s: 6.9 per step); the controller
#: works at that period (a_D,VEL T_s = 0.63 < 0.83, 8 samples per supply period: drives.dfim._period)
LONG_STEP = "duration = 0.2\nsample_time = 2e-3\nsubsteps = 1"
RESISTIVE_ROTOR = """
[motor.params]
R_s = 0.66
R_r = 8.0
L_s = 13.1e-3
L_r = 9.8e-3
M = 9.7e-3
n_p = 2
J = 3.5e-4
"""
TINY_J = """
[motor.params]
R_s = 0.66
R_r = 0.94
L_s = 13.1e-3
L_r = 9.8e-3
M = 9.7e-3
n_p = 2
J = 1e-10
"""


def test_long_integration_step_diverges_with_exit_3_and_a_hint(tmp_path, capsys):
    path = _scenario(tmp_path, LONG_STEP, extra=RESISTIVE_ROTOR)
    out = tmp_path / "out"
    code, _, err = _main(capsys, "run", path, "--out", out, "--no-figures")
    assert code == 3
    line = _one_line(err, "simulation")
    assert "diverged" in line and "t = 0.01 s" in line
    assert "simulation.substeps" in line and "at least 3" in line
    assert not out.exists()


def test_the_hinted_substeps_make_it_run(tmp_path, capsys):
    path = _scenario(tmp_path, LONG_STEP.replace("substeps = 1", "substeps = 3"), RESISTIVE_ROTOR)
    code, _, err = _main(capsys, "run", path, "--out", tmp_path / "out", "--no-figures")
    assert code == 0, err


def test_tiny_inertia_diverges_and_the_hint_names_j(tmp_path, capsys):
    path = _scenario(tmp_path, "duration = 0.05", extra=TINY_J)
    code, _, err = _main(capsys, "run", path, "--out", tmp_path / "out", "--no-figures")
    assert code == 3
    line = _one_line(err, "simulation")
    assert "t = 0.0004 s" in line and "inertia J" in line and "simulation.sample_time" in line
    assert not (tmp_path / "out").exists()


def test_debug_shows_the_divergence_as_an_exception(tmp_path):
    path = _scenario(tmp_path, LONG_STEP, extra=RESISTIVE_ROTOR)
    with pytest.raises(SimulationDiverged) as info:
        main(["--debug", "run", str(path), "--out", str(tmp_path / "out"), "--no-figures"])
    assert info.value.time == pytest.approx(0.01) and "substeps" in info.value.hint
    assert isinstance(info.value, RuntimeError)


def test_divergence_through_the_real_command_has_no_traceback(tmp_path):
    path = _scenario(tmp_path, LONG_STEP, extra=RESISTIVE_ROTOR)
    result = subprocess.run(
        [sys.executable, "-m", "acdrive.cli", "run", str(path), "--out", str(tmp_path / "o")],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 3
    _one_line(result.stderr, "simulation")
    assert not (tmp_path / "o").exists()


# ---------------------------------------------------------------------------------------------
# 2. sizes a scenario controls
# ---------------------------------------------------------------------------------------------

SIZES = {
    "substeps 1001": ("duration = 0.01\nsubsteps = 1001", "simulation.substeps", "<= 1000"),
    "substeps int64": (
        "duration = 0.01\nsubsteps = 9223372036854775807",
        "simulation.substeps",
        "<= 1000",
    ),
    "duration 1e308": ("duration = 1e308", "simulation.duration", "GB"),
    # a log of every sample asked for (the default thins a long run's log to 100,000 rows)
    "log budget": ("duration = 3000\nlog_every = 1", "simulation.duration", "GB"),
    "sample time 1e-300": (
        "duration = 0.01\nsample_time = 1e-300",
        "simulation.sample_time",
        "control steps",
    ),
    "hours of work": (
        "duration = 1e5\nlog_every = 1000000",
        "simulation.duration",
        "integration steps",
    ),
    "log_every beyond the run": (
        "duration = 0.01\nlog_every = 51",
        "simulation.log_every",
        "(50 = ",
    ),
    "log_every int64": (
        "duration = 0.01\nlog_every = 9223372036854775807",
        "simulation.log_every",
        "must not exceed",
    ),
}


@pytest.mark.parametrize("case", sorted(SIZES))
def test_sizes_are_bounded(tmp_path, capsys, case):
    simulation, field, words = SIZES[case]
    path = _scenario(tmp_path, simulation)
    code, _, err = _main(capsys, "run", path, "--out", tmp_path / "out")
    assert code == 2
    assert words in _one_line(err, field)
    assert not (tmp_path / "out").exists()


def test_log_budget_message_gives_the_estimate(tmp_path, capsys):
    # 3000 s / 200 us = 1.5e7 rows x 23 signals x 8 bytes = 2.57 GB, every sample logged
    path = _scenario(tmp_path, "duration = 3000\nlog_every = 1")
    _, _, err = _main(capsys, "run", path, "--out", tmp_path / "out")
    assert "about 2.57 GB (limit 2 GB)" in err


def test_log_every_equal_to_the_number_of_steps_is_fine(tmp_path, capsys):
    path = _scenario(tmp_path, "duration = 0.01\nlog_every = 50\nsubsteps = 1000")
    code, _, err = _main(capsys, "run", path, "--out", tmp_path / "out", "--no-figures")
    assert code == 0, err


# ---------------------------------------------------------------------------------------------
# 3. strict JSON
# ---------------------------------------------------------------------------------------------


def test_strict_json_writes_null_for_non_finite_numbers():
    import numpy as np

    value = {"a": math.inf, "b": [1.0, -math.inf, np.float64("nan")], "c": (np.int64(3), True)}
    assert finite_or_null(value) == {"a": None, "b": [1.0, None, None], "c": [3, True]}
    assert _strict(strict_json(value)) == {"a": None, "b": [1.0, None, None], "c": [3, True]}


@pytest.mark.parametrize(
    "flag, value",
    [
        # each of these printed Infinity or NaN as "JSON" before
        ("--voltage-pk", "1e308"),
        ("--voltage-pk", "1e200"),
        ("--frequency", "1e-308"),
        ("--current-limit-pk", "1e308"),
        ("--frequency", "1e308"),
        ("--current-limit-pk", "1e-308"),
    ],
)
def test_limits_refuses_the_arguments_that_gave_nan_or_infinity(capsys, flag, value):
    code, out, err = _main(capsys, "limits", "--json", flag, value)
    assert code == 2 and out == ""
    assert "must be between 1e-06 and 1e+06" in _one_line(err, flag)


@pytest.mark.parametrize("value", ["1e-6", "1e6"])
@pytest.mark.parametrize("flag", ["--voltage-pk", "--frequency", "--current-limit-pk"])
def test_limits_json_is_strict_across_the_accepted_range(capsys, flag, value):
    code, out, err = _main(capsys, "limits", "--json", flag, value)
    assert code == 0 and err == ""
    report = _strict(out)
    assert all(v is None or math.isfinite(v) for v in report.values() if not isinstance(v, bool))


def test_stability_json_is_strict(capsys):
    code, out, err = _main(
        capsys, "stability", "--speed-rpm", "-900", "--load-nm", "-0.1", "--json"
    )
    assert code == 0, err
    report = _strict(out)
    assert report["speed_rpm"] == -900.0 and report["load_nm"] == -0.1


def test_icad_json_is_strict(capsys):
    code, out, err = _main(capsys, "icad", "pmsg-2mw", "--speed", "-100", "--json")
    assert code == 0, err
    assert _strict(out)["speed_rad_s"] == -100.0


# ---------------------------------------------------------------------------------------------
# 4. extreme numeric flags name that flag; negative numbers are values
# ---------------------------------------------------------------------------------------------

EXTREMES = ["1e308", "-1e308", "nan", "inf", "-inf"]
#: (command prefix, flag, extra values refused besides EXTREMES)
FLAGS = [
    (["limits"], "--voltage-pk", ["0", "1e-308"]),
    (["limits"], "--frequency", ["0", "1e-308"]),
    (["limits"], "--current-limit-pk", ["0", "1e-308"]),
    (["icad", "pmsg-2mw"], "--speed", ["1e-308", "-1e-300"]),
    (["icad", "pmsg-2mw", "--speed", "100"], "--bandwidth", ["0", "1e-308"]),
    (["icad", "ugalde-im-300w", "--speed", "100"], "--bandwidth", ["0"]),
    (["stability"], "--speed-rpm", []),
    (["stability", "--speed-rpm", "900"], "--load-nm", []),
    (["stability", "--speed-rpm", "900"], "--bandwidth", ["0", "1e-308"]),
    (["stability", "--speed-rpm", "900"], "--speed-filter-tau", []),
    (["stability", "--speed-rpm", "900"], "--supply-resistance", []),
    (["stability", "--speed-rpm", "900"], "--supply-inductance", []),
    (["stability", "--speed-rpm", "900"], "--viscous-friction", []),
    (["stability", "--speed-rpm", "900"], "--inertia", ["0", "1e-308"]),
    (["stability", "--speed-rpm", "900"], "--rotor-resistance", ["0", "1e-308"]),
    (["stability", "--speed-rpm", "900"], "--converter-loss", []),
    (["stability", "--bench"], "--bandwidth", ["0", "1e-308"]),
]
FLAG_CASES = [(prefix, flag, value) for prefix, flag, extra in FLAGS for value in EXTREMES + extra]


@pytest.mark.parametrize(
    "prefix, flag, value", FLAG_CASES, ids=[f"{p[0]}{f}={v}" for p, f, v in FLAG_CASES]
)
def test_extreme_flag_values_name_that_flag(tmp_path, capsys, prefix, flag, value):
    # written as two tokens: negative values must reach the flag's own check, not argparse
    code, out, err = _main(capsys, *prefix, flag, value, "--json")
    assert code == 2, (out, err)
    _one_line(err, flag)


@pytest.mark.parametrize(
    "argv, field",
    [
        (["icad", "pmsg-2mw", "--sweep", "--speeds", "0", "1e308", "5"], "--speeds"),
        (["icad", "pmsg-2mw", "--sweep", "--speeds", "-1e308", "0", "5"], "--speeds"),
        (["icad", "pmsg-2mw", "--sweep", "--speeds", "0", "100", "1e9"], "--speeds"),
        (["icad", "pmsg-2mw", "--sweep", "--speeds", "0", "100", "nan"], "--speeds"),
        (["icad", "pmsg-2mw", "--sweep", "--speeds", "0", "100", "2.5"], "--speeds"),
        (["icad", "pmsg-2mw", "--sweep", "--bandwidth", "1e308"], "--bandwidth"),
        (["stability", "--map", "--grid", "100000", "100000"], "--grid"),
        (["stability", "--map", "--grid", "0", "5"], "--grid"),
        (["stability", "--map", "--delay-samples", "7"], "--delay-samples"),
    ],
)
def test_sweeps_and_grids_are_bounded(tmp_path, capsys, argv, field):
    code, _, err = _main(capsys, *argv, "--out", tmp_path / "figs")
    assert code == 2
    _one_line(err, field)
    assert not (tmp_path / "figs").exists()


@pytest.mark.parametrize(
    "argv",
    [
        ["--delay-samples", "1e308"],  # not an int: argparse names the flag
        ["--grid", "1e308", "3"],
    ],
)
def test_integer_flags_refuse_floats(capsys, argv):
    code, _, err = _main(capsys, "stability", "--speed-rpm", "900", *argv)
    assert code == 2
    assert f"argument {argv[0]}" in _one_line(err)


@pytest.mark.parametrize("value", ["-0.1", "-1e-1", "-.1", "-1E-1"])
def test_negative_numbers_are_option_values(capsys, value):
    code, out, err = _main(capsys, "stability", "--speed-rpm", "-900", "--load-nm", value, "--json")
    assert code == 0, err
    assert _strict(out)["load_nm"] == -0.1


def test_an_unknown_option_is_still_an_option(capsys):
    code, _, err = _main(capsys, "limits", "-x")
    assert code == 2
    assert "unrecognized arguments: -x" in _one_line(err)


@pytest.mark.slow
def test_tiny_sweep_speeds_round_to_zero(tmp_path, capsys):
    code, out, err = _main(
        capsys, "icad", "pmsg-2mw", "--sweep", "--speeds", "-1e-300", "1e-300", "3",
        "--out", tmp_path / "figs", "--json", "--no-verify",
    )  # fmt: skip
    assert code == 0, err
    assert _strict(out)["speeds_rad_s"] == [0.0, 0.0, 0.0]


# ---------------------------------------------------------------------------------------------
# 5. fuzzed scenario files
# ---------------------------------------------------------------------------------------------


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(v)


def _is_table(v) -> bool:
    return isinstance(v, dict) and getattr(v, "table", True)


def to_toml(data: dict, prefix: str = "") -> str:
    """A minimal TOML writer: scalars and inline values first, then tables, arrays of tables."""
    lines = []
    for k, v in data.items():
        if not (_is_table(v) or (isinstance(v, list) and v and all(_is_table(x) for x in v))):
            lines.append(f"{k} = {_toml_value(v)}")
    for k, v in data.items():
        name = f"{prefix}{k}"
        if _is_table(v):
            lines.append(f"[{name}]")
            lines.append(to_toml(v, f"{name}."))
        elif isinstance(v, list) and v and all(_is_table(x) for x in v):
            for item in v:
                lines.append(f"[[{name}]]")
                lines.append(to_toml(item, f"{name}."))
    return "\n".join(lines) + "\n"


class Inline(dict):
    """A dict written as an inline table (a wrong-type value), not as a [table]."""

    table = False


def _base() -> dict:
    return {
        "name": "fuzz",
        "simulation": {"duration": 0.01},
        "supply": {"voltage_pk": 11.1},
        "motor": [
            {
                "speed_reference_rpm": [[0.0, 0.0], [0.01, 100.0]],
                "params": {
                    "R_s": 0.66, "R_r": 0.94, "L_s": 13.1e-3, "L_r": 9.8e-3, "M": 9.7e-3,
                    "n_p": 2, "J": 3.5e-4,
                },
                "controller": {"speed_bandwidth": 100.0, "sync": {"gain": 40.0}},
            }
        ],
    }  # fmt: skip


#: numeric fields, by the table that holds them (path from the top; motor means motor[0])
NUMERIC = {
    ("simulation",): ["duration", "sample_time", "substeps", "log_every"],
    ("supply",): ["voltage_pk", "frequency_hz", "resistance", "inductance"],
    ("motor",): [
        "viscous_friction", "coulomb_friction", "load_torque", "initial_speed_rpm",
        "dc_link_voltage", "encoder_counts_per_rev", "encoder_offset", "converter_dead_time",
        "converter_switching_frequency", "converter_device_drop", "current_sensor_fault_time",
    ],
    ("motor", "params"): ["R_s", "R_r", "L_s", "L_r", "M", "n_p", "J"],
    ("motor", "controller"): [
        "current_bandwidth", "R_T", "reactive_power_kp", "reactive_power_ki", "speed_bandwidth",
        "design_inertia", "K_F", "reactive_power", "stator_current_limit_pk",
        "rotor_current_limit_pk", "theta_adj", "m_adj", "speed_filter_tau",
        "frequency_filter_tau", "min_stator_voltage_pk",
    ],
    ("motor", "controller", "sync"): ["gain", "tolerance_magnitude", "tolerance_phase_deg",
                                      "hold_time"],
}  # fmt: skip
TABLES = [(), *NUMERIC]

#: always invalid for a numeric field
WRONG_TYPES = st.sampled_from(["fast", True, [1.0], Inline(a=1), [], ""])
NON_FINITE = st.sampled_from([math.nan, math.inf, -math.inf])
#: may be valid, may make the simulation diverge; must never crash
EXTREME = st.sampled_from(
    [1e308, -1e308, 1e-308, -1e-308, 0.0, -1.0, 0, 2**63 - 1, -(2**63), 1e30, -1e30, 1e-30]
)


def _table(data, path):
    node = data
    for key in path:
        node = node[key][0] if key == "motor" else node[key]
    return node


def _field_name(path: tuple, key: str) -> str:
    """The scenario field of ``key`` in the table at ``path``, as an error names it."""
    # the TOML writer writes keys bare: "J " is read as J
    return ".".join(["motor[0]" if part == "motor" else part for part in path] + [key.strip()])


def _named(err: str) -> str:
    """The field an ``acdrive: error: <field>: <rule>`` line names."""
    return _one_line(err).removeprefix("acdrive: error: ").split(": ", 1)[0]


def _names_one_of(named: str, fields) -> bool:
    """Whether ``named`` is one of ``fields`` or the table holding one (an error may name
    ``motor[0].params`` for a parameter that makes the machine's mode too fast)."""
    return any(f == named or f.startswith(named + ".") for f in fields)


@st.composite
def broken_scenarios(draw):
    """(scenario dict, must_fail, mutated fields): one to three mutations of a valid short
    scenario; the fields are those an error may name."""
    data = _base()
    must_fail = False  # an unknown key
    kinds = {}  # field -> the kind of its last mutation
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(["wrong type", "non-finite", "extreme", "unknown", "no motor"]))
        if kind == "unknown":
            path = draw(st.sampled_from(TABLES))
            key = draw(st.sampled_from(["colour", "Duration", "motor_", "J ", "x"]))
            _table(data, path)[key] = draw(st.sampled_from([1, "a", 1.5]))
            must_fail = True
            kinds[_field_name(path, key)] = kind
        elif kind == "no motor":
            data["motor"] = draw(st.sampled_from([[], "bodson", Inline(machine="bodson-dfim")]))
            if not data["motor"]:
                del data["motor"]
            return data, True, {**kinds, "motor": kind}
        else:
            path = draw(st.sampled_from(sorted(NUMERIC)))
            key = draw(st.sampled_from(NUMERIC[path]))
            strategy = {"wrong type": WRONG_TYPES, "non-finite": NON_FINITE, "extreme": EXTREME}
            _table(data, path)[key] = draw(strategy[kind])
            kinds[_field_name(path, key)] = kind
    return data, must_fail or any(kind != "extreme" for kind in kinds.values()), kinds


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(case=broken_scenarios())
def test_fuzzed_scenarios_fail_with_one_line_and_no_output(tmp_path_factory, capsys, case):
    """A refused scenario names a field it was broken in, never one left valid: one of the
    mutated fields or its table (``motor[0].params`` for a parameter that makes the machine's
    mode too fast); exactly a mutated field when no value is merely extreme (a wrong type, a
    non-finite number, an unknown key: named by the field's own rule)."""
    data, must_fail, kinds = case
    folder = tmp_path_factory.mktemp("fuzz")
    path = folder / "scenario.toml"
    path.write_text(to_toml(data))
    out = folder / "out"
    code = main(["run", str(path), "--out", str(out), "--no-figures"])
    _, err = capsys.readouterr()
    if must_fail:
        assert code == 2, (to_toml(data), err)
    assert code in (0, 2, 3), (to_toml(data), err)
    if code:
        _one_line(err)
        assert not out.exists(), to_toml(data)
    else:
        assert err == "" and (out / "fuzz" / "summary.json").is_file()
        _strict((out / "fuzz" / "summary.json").read_text())
    if code == 2:
        named = _named(err)
        try:
            tomllib.loads(to_toml(data))
        except tomllib.TOMLDecodeError:  # e.g. "J " written beside J: a key given twice
            assert named == "scenario", (to_toml(data), err)
            return
        assert _names_one_of(named, kinds), (to_toml(data), err)
        if "extreme" not in kinds.values():
            assert named in kinds, (to_toml(data), err)


# --- sweep files --------------------------------------------------------------------------------

#: numeric scenario fields a sweep may vary on the one-motor fuzz base
SWEEP_FIELDS = ["motor[0].load_torque", "motor[0].controller.speed_bandwidth",
                "simulation.duration", "supply.voltage_pk", "motor[0].controller.K_F"]  # fmt: skip


def _sweep_base() -> dict:
    return {"name": "fuzzsweep", "base": "base.toml",
            "vary": [{"field": "motor[0].load_torque", "values": [0.0, 0.01]}]}  # fmt: skip


@st.composite
def broken_sweeps(draw):
    """(sweep dict, the field its error must name): one mutation of a valid two-variant sweep
    of a one-motor base, each of which the sweep file's loader must refuse before anything is
    written."""
    data = _sweep_base()
    vary = data["vary"][0]
    vary["field"] = draw(st.sampled_from(SWEEP_FIELDS))
    kind = draw(st.sampled_from([
        "index", "wrong type", "mixed types", "huge grid", "huge sample", "bounds",
        "non-finite bound", "unknown key", "fixed wrong type", "fixed index", "twice",
    ]))  # fmt: skip
    if kind == "index":  # a motor the base does not have
        k = draw(st.integers(1, 9))
        vary["field"] = f"motor[{k}].load_torque"
        return data, "vary[0].field"
    if kind == "wrong type":
        vary["values"] = [draw(st.sampled_from(["heavy", True, [1.0], Inline(a=1), ""]))]
        return data, "vary[0].values[0]"
    if kind == "mixed types":
        vary["values"] = [0.01, draw(st.sampled_from(["0.02", "x"]))]
        return data, "vary[0].values[1]"
    if kind == "huge grid":
        del vary["values"]
        vary.update(low=0.0, high=0.1, points=draw(st.integers(10**6 + 1, 10**12)))
        return data, "vary[0].points"
    if kind == "huge sample":
        data["sampling"] = {"method": "random", "samples": draw(st.integers(10**6 + 1, 10**12))}
        return data, "sampling.samples"
    if kind == "bounds":
        del vary["values"]
        vary.update(low=0.1, high=draw(st.sampled_from([0.1, 0.0, -1e308])), points=2)
        return data, "vary[0].high"
    if kind == "non-finite bound":
        del vary["values"]
        vary.update(low=draw(NON_FINITE), high=0.1, points=2)
        return data, "vary[0].low"
    if kind == "unknown key":
        key = draw(st.sampled_from(["colour", "Values", "point"]))
        vary[key] = 1
        return data, f"vary[0].{key}"
    if kind == "fixed wrong type":
        field = draw(st.sampled_from(SWEEP_FIELDS))
        data["fixed"] = {field: draw(st.sampled_from(["fast", [1.0]]))}
        return data, f"fixed.{field}"
    if kind == "fixed index":
        data["fixed"] = {f"motor[{draw(st.integers(1, 9))}].load_torque": 0.01}
        return data, f"fixed.{next(iter(data['fixed']))}"
    data["vary"].append(dict(vary))  # "twice"
    return data, "vary"


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(case=broken_sweeps())
def test_fuzzed_sweeps_name_the_field_and_write_nothing(tmp_path_factory, capsys, case):
    """Each broken sweep file is refused at load with one line naming the field broken (exit 2),
    before anything is written (a refused sweep leaves no folder that would block the corrected
    one), and without materialising a grid (a huge one is refused at once)."""
    import time

    data, field = case
    folder = tmp_path_factory.mktemp("sweepfuzz")
    (folder / "base.toml").write_text(to_toml(_base()))
    path = folder / "sweep.toml"
    text = to_toml({k: v for k, v in data.items() if k != "fixed"})
    if "fixed" in data:  # dotted field names are quoted keys of [fixed]
        text += "[fixed]\n" + "".join(
            f"{json.dumps(k)} = {_toml_value(v)}\n" for k, v in data["fixed"].items()
        )
    path.write_text(text)
    out = folder / "out"
    start = time.monotonic()
    code, _, err = _main(capsys, "sweep", path, "--out", out, "--quiet", "--no-report")
    assert code == 2, (text, err)
    assert _named(err) == field, (text, err)
    assert not out.exists(), text
    assert time.monotonic() - start < 30, text


def test_the_toml_writer_round_trips():
    import tomllib

    data = _base()
    assert tomllib.loads(to_toml(data)) == data


def test_an_interrupt_inside_a_parallel_compiled_call_stays_an_interrupt():
    """A signal handled while a parallel numba function runs reaches the caller as a SystemError
    caused by the handler's exception; ``call_interruptible`` re-raises the interrupt itself,
    and leaves every other error alone."""
    from acdrive.errors import call_interruptible, interrupt_behind

    def hidden(exc):
        def fn():
            try:
                raise exc
            except BaseException as inner:
                raise SystemError("returned a result with an exception set") from inner

        return fn

    with pytest.raises(KeyboardInterrupt):
        call_interruptible(hidden(KeyboardInterrupt()))
    with pytest.raises(SystemError):
        call_interruptible(hidden(ValueError("a real error")))
    assert interrupt_behind(ValueError()) is None


# ---------------------------------------------------------------------------------------------
# 6. inputs refused before any work, named by their cause (issue 19)
# ---------------------------------------------------------------------------------------------


def _write_scenario(tmp_path, data: dict, name="scenario.toml"):
    path = tmp_path / name
    path.write_text(to_toml(data))
    return path


def _refused_run(tmp_path, capsys, path, field) -> str:
    out = tmp_path / "out"
    code, _, err = _main(capsys, "run", path, "--out", out, "--no-figures")
    assert code == 2, err
    assert not out.exists()
    return _one_line(err, field)


def test_a_utf8_byte_order_mark_is_accepted_in_scenarios_and_sweeps(tmp_path):
    """Windows editors write a UTF-8 BOM; the file means the same with or without it."""
    from acdrive.scenarios import load_scenario
    from acdrive.sweep import load_sweep

    text = to_toml(_base())
    plain, marked = tmp_path / "plain.toml", tmp_path / "marked.toml"
    plain.write_text(text, encoding="utf-8")
    marked.write_text(text, encoding="utf-8-sig")
    assert marked.read_bytes().startswith(b"\xef\xbb\xbf")
    from acdrive.scenarios import read_scenario

    assert read_scenario(marked) == read_scenario(plain) == tomllib.loads(text)
    assert load_scenario(marked).name == "fuzz"
    sweep = 'base = "marked.toml"\n[[vary]]\nfield = "motor[0].load_torque"\nvalues = [0.0, 0.01]\n'
    (tmp_path / "sweep.toml").write_text(sweep, encoding="utf-8-sig")
    spec = load_sweep(str(tmp_path / "sweep.toml"))
    assert spec.base_data == tomllib.loads(text)


def test_a_toml_file_nested_too_deeply_is_one_line_naming_the_file(tmp_path, capsys):
    deep = "x = " + "[" * 5000 + "]" * 5000 + "\n"
    path = tmp_path / "deep.toml"
    path.write_text('name = "deep"\n' + deep)
    line = _refused_run(tmp_path, capsys, path, "scenario")
    assert "nests arrays or tables too deeply" in line
    code, _, err = _main(capsys, "sweep", path, "--out", tmp_path / "s")
    assert code == 2 and _one_line(err, "sweep") and not (tmp_path / "s").exists()


def test_a_mode_compared_with_itself_is_refused(tmp_path, capsys):
    data = {"compare_modes": ["voltage", "voltage"], **_base()}
    line = _refused_run(tmp_path, capsys, _write_scenario(tmp_path, data), "compare_modes")
    assert "must name each mode once" in line


@pytest.mark.parametrize("K_F", [2.0, -0.1, 1.0000001])
def test_a_feedforward_fraction_outside_0_to_1_is_refused(tmp_path, capsys, K_F):
    from acdrive.control import SpeedPIGains
    from acdrive.errors import InputError

    data = _base()
    data["motor"][0]["controller"]["K_F"] = K_F
    line = _refused_run(
        tmp_path, capsys, _write_scenario(tmp_path, data), "motor[0].controller.K_F"
    )
    assert "Bodson (25) must be between 0 (I-P control) and 1 (a plain PI)" in line
    with pytest.raises(InputError, match="^K_F: "):
        SpeedPIGains.design(3.5e-4, 314.0, K_F)


@pytest.mark.parametrize("K_F", [0.0, 2.0 / 3.0, 1.0])
def test_the_feedforward_fractions_of_the_range_are_accepted(K_F):
    from acdrive.scenarios import build_setup

    data = _base()
    data["motor"][0]["controller"]["K_F"] = K_F
    assert build_setup(data).motors[0].controller.gains.K_F == K_F


@pytest.mark.parametrize(
    ("supply", "field"),
    [
        ({"frequency_hz": 1e6}, "supply.frequency_hz"),
        ({"frequency_hz_profile": [[0.0, 60.0], [0.005, 1001.0]]}, "supply.frequency_hz_profile[1][1]"),
    ],
)  # fmt: skip
def test_a_supply_above_a_kilohertz_is_refused(tmp_path, capsys, supply, field):
    data = _base()
    data["supply"].update(supply)
    line = _refused_run(tmp_path, capsys, _write_scenario(tmp_path, data), field)
    assert "must be at most 1000 Hz" in line


def test_more_motors_than_the_bound_are_refused_before_compiling(tmp_path, capsys):
    from acdrive.drives.dfim._schema import MAX_MOTORS
    from acdrive.scenarios import build_setup

    data = _base()
    data["motor"] = [dict(data["motor"][0]) for _ in range(MAX_MOTORS)]
    assert len(build_setup(data).motors) == MAX_MOTORS
    data["motor"] = [dict(data["motor"][0]) for _ in range(100)]
    line = _refused_run(tmp_path, capsys, _write_scenario(tmp_path, data), "motor")
    assert f"at most {MAX_MOTORS} [[motor]] tables" in line and "got 100" in line


def test_icad_speeds_without_sweep_is_refused(capsys):
    code, out, err = _main(
        capsys, "icad", "bodson-dfim", "--speed", "10", "--speeds", "0", "1", "3"
    )
    assert code == 2 and out == ""
    assert "needs --sweep" in _one_line(err, "--speeds")


def test_stability_map_names_an_unwritable_out_before_the_analysis(tmp_path, capsys):
    """As `run` does: --out is checked (a folder, or creatable) before any work, one line naming
    it, exit 2 (was an input/output failure, exit 74, after the whole map)."""
    blocker = tmp_path / "a-file"
    blocker.write_text("mine")
    code, out, err = _main(
        capsys, "stability", "--map", "--out", blocker / "maps", "--grid", "2", "2"
    )
    assert code == 2 and out == ""
    assert "Not a directory" in _one_line(err, "--out")
    assert blocker.read_text() == "mine"
    code, _, err = _main(capsys, "run", _scenario(tmp_path), "--out", blocker / "runs")
    assert code == 2 and _one_line(err, "--out")


@pytest.mark.parametrize(
    "params, field",
    [
        ({"L_r": 1e308}, "motor[0].params.L_r"),  # sigma L_r a_C of (49) overflows through L_r
    ],
)
def test_an_overflowing_design_names_the_machine_parameter_that_caused_it(
    tmp_path, capsys, params, field
):
    """Found by the fuzz suite: K_P,C = sigma L_r a_C (49) overflowing because of an absurd L_r
    was blamed on the current loop's bandwidth; the factor farther from 1 is named."""
    data = {
        "name": "fuzz",
        "simulation": {"duration": 0.01},
        "motor": [{
            "speed_reference_rpm": [[0.0, 0.0], [0.01, 100.0]],
            "params": {"R_s": 0.66, "R_r": 0.94, "L_s": 0.0131, "L_r": 0.0131, "M": 0.0097,
                       "n_p": 2, "J": 0.00035, **params},
        }],
    }  # fmt: skip
    path = tmp_path / "s.toml"
    path.write_text(to_toml(data))
    code, _, err = _main(capsys, "run", path, "--out", tmp_path / "out")
    assert code == 2, err
    assert _named(err) == field, err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("scenario", "sample_time"), [("bodson-ramp", 200e-6), ("im-foc-speed", 2e-5)]
)
def test_a_run_shorter_than_the_default_sample_time_names_the_duration_with_its_numbers(
    scenario, sample_time
):
    """Both drives' loaders share ``acdrive._toml.simulation_span``: the message carries the
    default sample time and the duration given (the duration was once printed as a template)."""
    from acdrive.errors import InputError
    from acdrive.scenarios import build_setup, read_scenario

    data = read_scenario(scenario)
    data.setdefault("simulation", {}).pop("sample_time", None)
    data["simulation"]["duration"] = sample_time / 2
    with pytest.raises(InputError) as info:
        build_setup(data)
    assert str(info.value) == (
        f"simulation.duration: must be at least one sample, simulation.sample_time = "
        f"{sample_time:g} s (the default), got {sample_time / 2:g} s"
    )
