"""Physical pre-checks of the scenario loader, made before any simulation: converter losses the DC
link cannot supply, a dead time without or beyond the switching period, an integration step the
plant's fastest mode does not allow (more substeps are chosen, or the scenario is refused), and a
log interval longer than the run. Each refusal is one line naming the field, exit code 2; a
scenario just inside each bound is accepted.

Scenarios are the built-ins with a few fields changed (``_scenario``).
"""

from __future__ import annotations

import json
import math
import re
import tomllib
import warnings

import pytest

from acdrive.cli import main
from acdrive.errors import InputError, Notice
from acdrive.plant._converter import max_voltage_magnitude
from acdrive.scenarios._loader import (
    build_setup,
    builtin_names,
    builtin_text,
    fastest_mode,
    load_scenario,
)
from acdrive.sim._setup import RK4_STEP_LIMIT, ConverterLosses, fastest_electrical_rate
from acdrive.sim._system import MAX_SUBSTEPS

V_DC = 30.0  # the built-ins' DC link
#: the largest phase loss V_dc t_d f_sw + V_drop whose fundamental the 30 V link can supply
LOSS_BOUND = float(max_voltage_magnitude(V_DC)) / ConverterLosses(device_drop=1.0).fundamental_loss(
    V_DC
)


def _scenario(tmp_path, base="bodson-ramp-ideal", simulation="duration = 0.02", motor="",
              drop=()):  # fmt: skip
    """The built-in ``base`` with its [simulation] table replaced, ``motor`` lines added to its
    first [[motor]] and the keys in ``drop`` removed."""
    text = builtin_text(base)
    text = re.sub(r"\[simulation\]\n(?:[^\n]+\n)*", f"[simulation]\n{simulation}\n", text, count=1)
    for key in drop:
        text = re.sub(rf"^{key} = [^\n]*\n", "", text, flags=re.MULTILINE)
    text = text.replace('machine = "bodson-dfim"\n', f'machine = "bodson-dfim"\n{motor}\n', 1)
    path = tmp_path / "scenario.toml"
    path.write_text(text)
    return path


def _run(capsys, tmp_path, path):
    out = tmp_path / "out"
    try:
        code = main(["run", str(path), "--out", str(out), "--no-figures"])
    except SystemExit as exc:
        code = exc.code
    _, err = capsys.readouterr()
    # the one-time compile notice depends on the numba cache, not on the scenario under test
    kept = [line for line in err.splitlines(True) if "compiling the simulation loop" not in line]
    return code, "".join(kept)


def _refused(capsys, tmp_path, path, field) -> str:
    code, err = _run(capsys, tmp_path, path)
    assert code == 2, err
    lines = err.splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"acdrive: error: {field}: "), err
    assert not (tmp_path / "out").exists()
    return lines[0]


def _accepted(capsys, tmp_path, path) -> str:
    code, err = _run(capsys, tmp_path, path)
    assert code == 0, err
    summary = json.loads(next((tmp_path / "out").iterdir()).joinpath("summary.json").read_text())
    assert math.isfinite(summary["peak_rotor_current_a"])
    return err


# ---------------------------------------------------------------------------------------------
# (a) converter losses the DC link cannot supply
# ---------------------------------------------------------------------------------------------


def test_a_device_drop_beyond_the_dc_link_is_refused_with_the_numbers(capsys, tmp_path):
    drop = 1.01 * LOSS_BOUND
    line = _refused(
        capsys,
        tmp_path,
        _scenario(tmp_path, motor=f"converter_device_drop = {drop!r}"),
        "motor[0].converter_device_drop",
    )
    loss = ConverterLosses(device_drop=drop).fundamental_loss(V_DC)
    assert f"= {loss:.4g} V must be smaller than" in line
    assert f"V_dc / sqrt(2) = {max_voltage_magnitude(V_DC):.4g} V" in line


def test_a_dead_time_loss_beyond_the_dc_link_names_the_dead_time(capsys, tmp_path):
    t_d = 1.01 * LOSS_BOUND / V_DC / 10e3  # t_d f_sw = 0.46: within the switching period
    motor = f"converter_dead_time = {t_d!r}\nconverter_switching_frequency = 10e3"
    line = _refused(
        capsys, tmp_path, _scenario(tmp_path, motor=motor), "motor[0].converter_dead_time"
    )
    assert "fundamental loss" in line and "the DC link cannot supply it" in line


def test_a_loss_just_below_the_dc_link_runs(capsys, tmp_path):
    # bodson-ramp: 1 us at 10 kHz (0.3 V) plus a drop bringing the loss to 99.9 % of V_dc/sqrt(2)
    drop = 0.999 * LOSS_BOUND - V_DC * 1e-6 * 10e3
    path = _scenario(
        tmp_path,
        "bodson-ramp",
        motor=f"converter_device_drop = {drop!r}",
        drop=["converter_device_drop"],
    )
    err = _accepted(capsys, tmp_path, path)
    # the loss acts near zero rotor current as a large resistance: more substeps, said in one line
    assert err.startswith("acdrive: note: simulation.substeps = ") and err.count("\n") == 1


# ---------------------------------------------------------------------------------------------
# (b) dead time and switching frequency
# ---------------------------------------------------------------------------------------------


def test_a_dead_time_without_switching_frequency_is_refused(capsys, tmp_path):
    line = _refused(
        capsys,
        tmp_path,
        _scenario(tmp_path, motor="converter_dead_time = 1e-6"),
        "motor[0].converter_switching_frequency",
    )
    assert "must be given (> 0 Hz) with converter_dead_time = 1e-06 s" in line


def test_a_dead_time_of_a_whole_switching_period_is_refused(capsys, tmp_path):
    motor = "converter_dead_time = 1e-4\nconverter_switching_frequency = 1e4"
    line = _refused(
        capsys, tmp_path, _scenario(tmp_path, motor=motor), "motor[0].converter_dead_time"
    )
    assert "must be shorter than the switching period" in line and ">= 1" in line


def test_a_dead_time_just_inside_the_period_meets_the_loss_rule_instead(capsys, tmp_path):
    """t_d f_sw = 0.999 passes the period rule; its loss (1.56 x 0.999 V_dc) is then refused by
    the DC-link rule, which binds first for every t_d f_sw above 0.45."""
    motor = "converter_dead_time = 0.999e-4\nconverter_switching_frequency = 1e4"
    line = _refused(
        capsys, tmp_path, _scenario(tmp_path, motor=motor), "motor[0].converter_dead_time"
    )
    assert "switching period" not in line and "the DC link cannot supply it" in line


def test_a_dead_time_within_both_bounds_runs(capsys, tmp_path):
    t_d = 0.99 * LOSS_BOUND / V_DC / 10e3  # t_d f_sw = 0.45
    motor = f"converter_dead_time = {t_d!r}\nconverter_switching_frequency = 10e3"
    _accepted(capsys, tmp_path, _scenario(tmp_path, motor=motor))


# ---------------------------------------------------------------------------------------------
# (c) the integration step against the fastest mode
# ---------------------------------------------------------------------------------------------

#: 25 ms samples: 4 substeps (6.25 ms) exceed RK4's limit for the 513 1/s flux mode of the
#: Bodson machine; the estimate (736 1/s) asks for 8
COARSE = "duration = 0.5\nsample_time = 0.025"


def test_too_few_default_substeps_are_raised_and_the_run_ends(capsys, tmp_path):
    err = _accepted(capsys, tmp_path, _scenario(tmp_path, simulation=COARSE))
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(
        "acdrive: note: simulation.substeps = 8 chosen (default 4 too few)"
    ), err
    import pandas as pd

    data = pd.read_parquet(tmp_path / "out" / "bodson-ramp-ideal" / "data.parquet")
    assert len(data) == 20  # every sample of the 0.5 s logged


def test_the_default_would_have_diverged(capsys, tmp_path):
    """The same scenario with substeps = 4 written out: kept as given, it diverges (exit 3)."""
    path = _scenario(tmp_path, simulation=COARSE + "\nsubsteps = 4")
    code, err = _run(capsys, tmp_path, path)
    assert code == 3, err
    assert "diverged" in err and "at least 8" in err and "note" not in err


def test_a_step_that_no_allowed_substeps_can_integrate_is_refused(capsys, tmp_path):
    path = _scenario(tmp_path, simulation="duration = 10.0\nsample_time = 4.0")
    line = _refused(capsys, tmp_path, path, "simulation.sample_time")
    assert f"(limit {MAX_SUBSTEPS})" in line and "shorten simulation.sample_time" in line


def test_a_step_needing_just_under_max_substeps_is_accepted(tmp_path):
    with pytest.warns(Notice, match=r"simulation.substeps = \d+ chosen"):
        setup = load_scenario(_scenario(tmp_path, simulation="duration = 10.0\nsample_time = 3.3"))
    rate = fastest_mode(setup)[0]
    assert setup.substeps == math.ceil(3.3 * rate / RK4_STEP_LIMIT) <= MAX_SUBSTEPS
    assert setup.substeps > MAX_SUBSTEPS - 100


def test_a_parameter_no_step_can_integrate_names_that_parameter(capsys, tmp_path):
    path = _scenario(tmp_path, motor="coulomb_friction = 1e6")
    line = _refused(capsys, tmp_path, path, "motor[0].coulomb_friction")
    assert "friction" in line and "substeps" in line


def _setup(speed_rpm, **motor):
    data = tomllib.loads(builtin_text("bodson-ramp-ideal"))
    data["simulation"] = {"duration": 1.0}
    data["motor"][0]["speed_reference_rpm"] = [[0.0, 0.0], [1.0, speed_rpm]]
    data["motor"][0].update(motor)
    return build_setup(data)


def test_the_speed_range_enters_the_estimate():
    """In the stationary frame the rotor flux turns at n_p w: above synchronous speed the flux
    mode grows past the supply-frequency estimate ``fastest_electrical_rate``."""
    still, fast = _setup(0.0), _setup(4500.0)
    assert fastest_mode(still)[0] == pytest.approx(fastest_electrical_rate(still))
    assert fastest_mode(fast)[0] > 1.2 * fastest_electrical_rate(fast)
    assert "flux transient" in fastest_mode(fast)[2]


def test_the_converter_loss_enters_the_estimate():
    ideal = _setup(100.0)
    lossy = _setup(100.0, converter_device_drop=0.7)
    assert fastest_mode(lossy)[0] > 10 * fastest_mode(ideal)[0]
    assert fastest_mode(lossy)[1] == "motor[0].converter_device_drop"


def test_the_builtins_keep_their_substeps():
    with warnings.catch_warnings():
        warnings.simplefilter("error", Notice)
        for name in builtin_names():
            assert load_scenario(name).substeps == 4


# ---------------------------------------------------------------------------------------------
# (d) log_every (already checked by the loader before this work; kept under test here)
# ---------------------------------------------------------------------------------------------


def test_log_every_longer_than_the_run_is_refused(capsys, tmp_path):
    path = _scenario(tmp_path, simulation="duration = 0.02\nlog_every = 101")
    line = _refused(capsys, tmp_path, path, "simulation.log_every")
    assert "(100 = simulation.duration / simulation.sample_time)" in line


def test_log_every_equal_to_the_run_is_accepted(capsys, tmp_path):
    _accepted(capsys, tmp_path, _scenario(tmp_path, simulation="duration = 0.02\nlog_every = 100"))


def test_refusals_are_input_errors_for_library_callers(tmp_path):
    with pytest.raises(InputError) as info:
        load_scenario(_scenario(tmp_path, motor="converter_dead_time = 1e-6"))
    assert info.value.field == "motor[0].converter_switching_frequency"
