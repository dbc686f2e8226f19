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

import numpy as np
import pytest

from acdrive.cli import main
from acdrive.drives import for_setup
from acdrive.drives._period import speed_loop_radius
from acdrive.drives.cage_im._period import im_control_period_warnings
from acdrive.drives.dfim._period import control_period_warnings, current_loop_radius
from acdrive.drives.dfim._schema import fastest_mode
from acdrive.drives.dfim._setup import RK4_STEP_LIMIT, ConverterLosses, fastest_electrical_rate
from acdrive.errors import InputError, Notice
from acdrive.plant._converter import max_voltage_magnitude
from acdrive.scenarios._loader import build_setup, builtin_names, builtin_text, load_scenario
from acdrive.sim._compiled import MAX_SUBSTEPS

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

#: 5 ms samples of a machine with an 8-ohm rotor: the rotor flux mode R_r / (sigma L_r) is about
#: 3,100 1/s, and 4 substeps (1.25 ms) exceed RK4's limit; the estimate (3,433 1/s) asks for 7.
#: The speed loop is slowed to a_D,VEL = 50 rad/s so the controller works at that period
#: (a_D,VEL T_s = 0.25, 3.3 samples per supply period: drives.dfim._period) and only the plant's
#: integration is at stake here.
COARSE = "duration = 0.5\nsample_time = 0.005"


def _coarse(tmp_path, simulation=COARSE, R_r=8.0):
    data = tomllib.loads(_scenario(tmp_path, simulation=simulation).read_text())
    motor = data["motor"][0]
    del motor["machine"]
    motor["params"] = {"R_s": 0.66, "R_r": R_r, "L_s": 13.1e-3, "L_r": 9.8e-3, "M": 9.7e-3,
                       "n_p": 2, "J": 3.5e-4}  # fmt: skip
    motor["controller"]["speed_bandwidth"] = 50.0
    path = tmp_path / "coarse.toml"
    path.write_text(_toml(data))
    assert tomllib.loads(path.read_text()) == data
    return path


def _toml(data: dict) -> str:
    """The few tables of a DFIM scenario as TOML (scalars, lists, nested tables)."""
    lines, tables = [], []
    for key, value in data.items():
        if isinstance(value, dict):
            tables.append((key, value))
        elif isinstance(value, list) and value and isinstance(value[0], dict):
            for item in value:
                lines.append(f"[[{key}]]")
                lines.append(_toml_body(item, key))
        else:
            lines.insert(0, f"{key} = {json.dumps(value)}")
    for key, value in tables:
        lines.append(f"[{key}]")
        lines.append(_toml_body(value, key))
    return "\n".join(lines) + "\n"


def _toml_body(table: dict, prefix: str) -> str:
    lines, nested = [], []
    for key, value in table.items():
        if isinstance(value, dict):
            nested.append((key, value))
        else:
            lines.append(f"{key} = {json.dumps(value)}")
    for key, value in nested:
        lines.append(f"[{prefix}.{key}]")
        lines.append(_toml_body(value, f"{prefix}.{key}"))
    return "\n".join(lines)


def test_too_few_default_substeps_are_raised_and_the_run_ends(capsys, tmp_path):
    err = _accepted(capsys, tmp_path, _coarse(tmp_path))
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(
        "acdrive: note: simulation.substeps = 7 chosen (default 4 too few)"
    ), err
    import pandas as pd

    data = pd.read_parquet(tmp_path / "out" / "bodson-ramp-ideal" / "data.parquet")
    assert len(data) == 100  # every sample of the 0.5 s logged


def test_the_default_would_have_diverged(capsys, tmp_path):
    """The same scenario with substeps = 4 written out: kept as given, it diverges (exit 3)."""
    path = _coarse(tmp_path, simulation=COARSE + "\nsubsteps = 4")
    code, err = _run(capsys, tmp_path, path)
    assert code == 3, err
    assert "diverged" in err and "at least 7" in err and "note" not in err


#: a 5 ms sample (the controller works at it, as in COARSE) of rotors so resistive that their
#: flux mode needs about 1,530 (2,000 ohm) and 956 (1,250 ohm) substeps: past and just under
#: MAX_SUBSTEPS; the usual 200 us sample would need only 61 and 38, so the sample time is named
LONG = "duration = 10.0\nsample_time = 0.005"


def test_a_step_that_no_allowed_substeps_can_integrate_is_refused(capsys, tmp_path):
    path = _coarse(tmp_path, simulation=LONG, R_r=2000.0)
    line = _refused(capsys, tmp_path, path, "simulation.sample_time")
    assert f"(limit {MAX_SUBSTEPS})" in line and "shorten simulation.sample_time" in line


def test_a_step_needing_just_under_max_substeps_is_accepted(tmp_path):
    with pytest.warns(Notice, match=r"simulation.substeps = \d+ chosen"):
        setup = load_scenario(_coarse(tmp_path, simulation=LONG, R_r=1250.0))
    rate = fastest_mode(setup)[0]
    assert setup.substeps == math.ceil(0.005 * rate / RK4_STEP_LIMIT) <= MAX_SUBSTEPS
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


#: the drives whose loaders choose the integration substeps and check the control period
#: (this file's subject), with their control-period warnings
PERIOD_CHECKED = {"dfim": control_period_warnings, "cage-im": im_control_period_warnings}


def _period_checked_builtins():
    for name in builtin_names():
        setup = load_scenario(name)
        kind = for_setup(setup).kind
        if kind in PERIOD_CHECKED:
            yield name, setup, PERIOD_CHECKED[kind]


def test_the_builtins_keep_their_substeps():
    with warnings.catch_warnings():
        warnings.simplefilter("error", Notice)
        for name, setup, _ in _period_checked_builtins():
            assert setup.substeps == 4, name


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


# ---------------------------------------------------------------------------------------------
# (e) the control period (drives.dfim._period): supply aliasing, sampled speed and current loops, PWM
# ---------------------------------------------------------------------------------------------


def _speed_loop_polynomial(aT: float) -> np.ndarray:
    """Characteristic polynomial of the sampled speed loop with the design (27) (K_P = 2 a J,
    K_I = a^2 J), no filter, derived by hand in z: the backward difference (1 + z^-1)/2 W, the
    forward-Euler integral -T (1 + z^-1)/(2 (z - 1)) W and the shaft (z - 1) W = (T/J) U give
    2 z (z - 1)^2 + aT (z + 1) (2 (z - 1) + aT) = 0."""
    shaft = 2.0 * np.polymul([1.0, 0.0], np.polymul([1.0, -1.0], [1.0, -1.0]))
    return np.polyadd(shaft, aT * np.polymul([1.0, 1.0], [2.0, -2.0 + aT]))


@pytest.mark.parametrize("aT", [0.01, 0.1, 0.5, 0.8, 0.9, 2.0])
def test_the_sampled_speed_loop_radius_is_that_of_its_characteristic_polynomial(aT):
    J, T = 3.5e-4, 2e-4
    a = aT / T
    rho = speed_loop_radius(2 * a * J, a * a * J, J, T, 0.0)
    assert rho == pytest.approx(max(abs(np.roots(_speed_loop_polynomial(aT)))), rel=1e-9)


def test_the_sampled_speed_loop_tends_to_its_continuous_design():
    """Both continuous poles at s = -a map to z = exp(-a T): the sampled loop's slowest pole
    approaches it as aT -> 0 (within (aT)^1.5: a perturbation of order (aT)^3 of a double root
    moves it by the square root of that), and it is unstable at aT = 1 (the 10 ms DFIM case
    has aT = 3.1)."""
    J = 3.5e-4
    for aT in (1e-3, 1e-2):
        T = 2e-4
        a = aT / T
        assert abs(speed_loop_radius(2 * a * J, a * a * J, J, T, 0.0) - math.exp(-aT)) < aT**1.5
    assert speed_loop_radius(2 * 5000 * J, 5000**2 * J, J, 2e-4, 0.0) > 1.0


def test_the_sampled_current_loop_without_integral_is_one_minus_a_t():
    """R_T = 0 in (49): K_I,C = 0 and the loop sigma L_r di/dt = -K_P,C i has the single sampled
    pole 1 - a T (forward step of the held voltage): stable up to aT = 2."""
    sigma_L = 2.6e-3
    for aT in (0.3, 1.5, 2.5):
        T = 2e-4
        a = aT / T
        assert current_loop_radius(sigma_L, 0.0, sigma_L * a, 0.0, T) == pytest.approx(abs(1 - aT))


def test_a_control_period_that_aliases_the_supply_is_refused(capsys, tmp_path):
    """The issue's case: at 10 ms the DFIM drive never left standstill and the run ended with
    exit 0 and a reassuring note. 60 Hz x 10 ms = 0.6 >= 1/2: the frequency estimator aliases."""
    path = _scenario(tmp_path, simulation="duration = 0.5\nsample_time = 0.01")
    line = _refused(capsys, tmp_path, path, "simulation.sample_time")
    assert "f T_s >= 0.5 (here 0.6)" in line and "1 / (2 f) = 0.00833 s" in line


def test_a_control_period_that_makes_the_speed_loop_unstable_is_refused(capsys, tmp_path):
    # 5 ms: 60 Hz is sampled 3.3 times a period (no aliasing), but a_D,VEL T_s = 1.57
    path = _scenario(tmp_path, simulation="duration = 0.5\nsample_time = 0.005")
    line = _refused(capsys, tmp_path, path, "simulation.sample_time")
    assert "sampled speed loop of motor[0]" in line and "a_D,VEL T_s = 1.57" in line
    J = 3.5e-4
    rho = speed_loop_radius(2 * 314 * J, 314**2 * J, J, 0.005, 0.0)
    assert f"spectral radius {rho:.4g} >= 1" in line


def test_a_bandwidth_too_high_for_the_usual_period_names_the_bandwidth(tmp_path):
    text = _scenario(tmp_path).read_text()
    assert "speed_bandwidth = 314.0" in text
    data = tomllib.loads(text.replace("speed_bandwidth = 314.0", "speed_bandwidth = 5000.0"))
    with pytest.raises(InputError) as info:  # a_D,VEL T_s = 1.0 at the usual 200 us
        build_setup(data)
    assert info.value.field == "motor[0].controller.speed_bandwidth"


def test_an_unstable_current_loop_is_refused_in_current_mode(tmp_path):
    # a_D,CUR T_s = 12000 x 200 us = 2.4 with R_T = 0: the sampled pole 1 - 2.4 is outside
    data = tomllib.loads(_scenario(tmp_path).read_text())
    controller = data["motor"][0]["controller"]
    controller.update(mode="current", current_bandwidth=12e3, R_T=0.0)
    with pytest.raises(InputError) as info:
        build_setup(data)
    assert info.value.field == "motor[0].controller.current_bandwidth"
    assert "rotor current loop" in info.value.rule and "a_D,CUR T_s = 2.4" in info.value.rule
    controller["mode"] = "voltage"  # no current loop: accepted
    build_setup(data)


def test_a_coarse_but_stable_control_period_runs_with_the_warnings_in_the_summary(capsys, tmp_path):
    """2 ms: 8.3 samples per supply period (< 20) and a_D,VEL T_s = 0.628 (> 0.5), a stable
    sampled speed loop: the run goes ahead and summary.json says both, with their numbers."""
    path = _scenario(tmp_path, simulation="duration = 0.1\nsample_time = 0.002")
    code, err = _run(capsys, tmp_path, path)
    assert code == 0, err
    summary = json.loads((tmp_path / "out" / "bodson-ramp-ideal" / "summary.json").read_text())
    period = [w for w in summary["warnings"] if w.startswith("control period:")]
    J = 3.5e-4
    rho = speed_loop_radius(2 * 314 * J, 314**2 * J, J, 0.002, 0.0)
    assert len(period) == 2, summary["warnings"]
    assert "8.33 samples per period of the 60 Hz supply (fewer than 20" in period[0]
    assert "a_D,VEL T_s = 0.628" in period[1] and f"spectral radius {rho:.3g}" in period[1]
    assert 0.0 < rho < 1.0


def test_the_usual_control_period_warns_of_nothing():
    for name, setup, period_warnings in _period_checked_builtins():
        assert period_warnings(setup) == [], name


def test_a_pwm_period_longer_than_the_control_period_is_warned(tmp_path):
    motor = "converter_dead_time = 1e-6\nconverter_switching_frequency = 2e3"
    setup = load_scenario(_scenario(tmp_path, motor=motor))  # T_s = 200 us, f_sw T_s = 0.4
    (line,) = control_period_warnings(setup)
    assert "switches at 2000 Hz" in line and "0.0005 s longer than T_s = 0.0002 s" in line


# ---------------------------------------------------------------------------------------------
# (f) inputs far beyond what the machine allows name themselves, not a consequence
# ---------------------------------------------------------------------------------------------


def test_a_megavolt_supply_names_the_supply_voltage(capsys, tmp_path):
    text = _scenario(tmp_path).read_text().replace("voltage_pk = 11.1", "voltage_pk = 1e6")
    path = tmp_path / "scenario.toml"
    path.write_text(text)
    line = _refused(capsys, tmp_path, path, "supply.voltage_pk")
    magnetising = 1e6 / (2 * math.pi * 60.0 * 9.7e-3)  # v / (w_e M), Bodson (33)
    assert f"= {magnetising:.4g} A peak" in line and "(rotor 6 A, stator 6 A)" in line


def test_a_meganewton_metre_load_names_the_load(capsys, tmp_path):
    from acdrive.drives.dfim._setup import peak_torque_window

    path = _scenario(tmp_path, motor="load_torque = 1e6")
    line = _refused(capsys, tmp_path, path, "motor[0].load_torque")
    setup = load_scenario(_scenario(tmp_path, motor="load_torque = 0.5"))  # above the window: runs
    lo, hi = peak_torque_window(setup.motors[0], setup.supply)
    assert 0.0 < hi < 0.5 < 10 * hi
    assert f"largest torque the drive can produce, {max(hi, -lo):.4g} N m" in line


def test_the_im_current_loop_bandwidth_is_that_of_its_closed_loop_and_warned_when_coarse():
    """The cage-IM drive: the current loop's -3 dB bandwidth as designed (paper-20 on the nominal
    machine at standstill) is where |L / (1 + L)| crosses 1/sqrt(2), checked against the loop
    evaluated there independently; 250 us samples (4 per 4 kHz carrier period, a stable
    latched loop) give a_C T_s > 1 and a warning, the paper's 20 us none."""
    from acdrive.drives.cage_im._period import im_current_bandwidth
    from acdrive.drives.cage_im._schema import build_im_setup
    from acdrive.machines import stator_current_ss

    data = tomllib.loads(builtin_text("im-locked-rotor"))
    paper = build_im_setup(data)
    a = im_current_bandwidth(paper)
    A, B, C, D = stator_current_ss(paper.machine, 0.0)

    def closed(w):
        g = (C @ np.linalg.solve(1j * w * np.eye(4) - A, B) + D)[0, 0]
        loop = g * paper.current_control.lti.freqresp(np.array([w]))[0]
        return abs(loop / (1 + loop))

    step = 10 ** (7 / 1400)  # the grid's ratio (1401 points over 1 to 1e7 rad/s)
    assert closed(a / step) >= 1 / math.sqrt(2) > closed(a)
    assert im_control_period_warnings(paper) == []
    data["simulation"]["sample_time"] = 2.5e-4
    data["inverter"]["pwm_frequency_hz"] = 4000.0
    (line,) = im_control_period_warnings(build_im_setup(data))
    assert f"a_C T_s = {a * 2.5e-4:.3g}" in line and a * 2.5e-4 > 1.0
