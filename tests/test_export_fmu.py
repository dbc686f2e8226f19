"""FMI 2.0 co-simulation FMUs (issue 22, item 4): the controller chains and the plant (cage IM,
shaft, averaged converter fed from the DC link) of a scenario as FMUs built from the generated C,
checked with fmpy: ``validate_fmu`` clean; ``simulate_fmu`` of the controller with acdrive's
logged plant outputs gives acdrive's commands exactly; the plant with acdrive's logged commands
gives acdrive's plant outputs within 1e-9 of each signal's peak; both FMUs stepped by a small
master equal acdrive's closed loop within the same bound. The comparisons run in a child process
with ACDRIVE_STRICT_MATH=1, as the software-in-the-loop tests do (numba without fast-math, the C
with -ffp-contract=off): the bound then holds with room (the agreement is to the bit here)."""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import pytest

from acdrive.scenarios._files import builtin_text

fmpy = pytest.importorskip("fmpy", reason="fmpy is not installed (pip install 'acdrive[fmu]')")
pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc is not installed")

#: im-foc-speed on the averaged inverter, shortened: the speed step at 5 ms, the brake at 50 ms
_CHANGES = {
    'model = "switching"': 'model = "averaged"',
    "dead_time_s = 2e-6\n": "",
    "device_drop_v = 1.5\n": "",
    "duration = 1.2": "duration = 0.1",
    "brake_profile = [[0.0, 0.0], [0.6, 0.0], [0.6, 2.77e-3]]": (
        "brake_profile = [[0.0, 0.0], [0.05, 0.0], [0.05, 2.77e-3]]"
    ),
    "speed_rad_s_profile = [[0.0, 0.0], [0.05, 0.0], [0.05, 150.0]]": (
        "speed_rad_s_profile = [[0.0, 0.0], [0.005, 0.0], [0.005, 150.0]]"
    ),
}


@pytest.fixture(scope="module")
def scenario(tmp_path_factory):
    text = builtin_text("im-foc-speed")
    for old, new in _CHANGES.items():
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    path = tmp_path_factory.mktemp("scenario") / "im-averaged.toml"
    path.write_text(text)
    return str(path)


@pytest.fixture(scope="module")
def fmus(scenario, tmp_path_factory):
    from acdrive.export._fmu_check import PARTS, scenario_fmus
    from acdrive.scenarios._loader import load_scenario

    return scenario_fmus(load_scenario(scenario), PARTS, tmp_path_factory.mktemp("fmus"))


def _fmu_check(*args: str) -> dict:
    """``acdrive export fmu-check ... --json`` in a child process under strict math."""
    env = dict(os.environ, ACDRIVE_STRICT_MATH="1")
    code = "import sys; from acdrive.cli import main; raise SystemExit(main(sys.argv[1:]))"
    done = subprocess.run(
        [sys.executable, "-c", code, "export", "fmu-check", *args, "--json"],
        check=False, capture_output=True, text=True, env=env, timeout=1200,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


@pytest.fixture(scope="module")
def report(scenario):
    return _fmu_check(scenario)


def test_both_fmus_validate_clean(fmus):
    from fmpy.validation import validate_fmu

    for path in fmus.values():
        assert validate_fmu(str(path)) == [], path.name


def test_model_description_from_the_declarations(fmus):
    """Causalities, units with their SI exponents, start values and descriptions as declared;
    the two FMUs connect by equal names; the C sources travel inside."""
    import zipfile

    from fmpy import read_model_description

    controller = read_model_description(str(fmus["controller"]))
    plant = read_model_description(str(fmus["plant"]))
    c_vars = {v.name: v for v in controller.modelVariables}
    p_vars = {v.name: v for v in plant.modelVariables}
    c_in = {n for n, v in c_vars.items() if v.causality == "input"}
    p_out = {n for n, v in p_vars.items() if v.causality == "output"}
    assert c_in == {"machine.i_s.re", "machine.i_s.im", "shaft.theta", "dc.v_dc"} <= p_out | c_in
    assert c_in <= p_out
    p_in = {n for n, v in p_vars.items() if v.causality == "input"}
    assert p_in == {"latch.v_ref.re", "latch.v_ref.im"}
    assert p_in <= {n for n, v in c_vars.items() if v.causality == "output"}
    i_s = p_vars["machine.i_s.re"]
    assert i_s.unit == "A" and "stator current" in i_s.description
    units = {u.name: u.baseUnit for u in plant.unitDefinitions}
    brake = units["N m s/rad"]  # N m s / rad = kg m^2 s^-1 rad^-1
    assert (brake.kg, brake.m, brake.s, brake.rad) == (1, 2, -1, -1)
    assert (units["V"].kg, units["V"].m, units["V"].s, units["V"].A) == (1, 2, -3, -1)
    J = p_vars["shaft.J"]
    assert J.causality == "parameter" and float(J.start) == 0.000711 and J.unit == "kg m^2"
    assert plant.defaultExperiment.stepSize == "2e-05" or float(
        plant.defaultExperiment.stepSize
    ) == pytest.approx(2e-5, rel=0)
    for path in fmus.values():
        names = zipfile.ZipFile(path).namelist()
        stem = path.stem
        assert f"binaries/linux64/{stem}.so" in names
        assert {f"sources/{stem}.c", f"sources/{stem}.h", f"sources/{stem}_fmi2.c"} <= set(names)


def test_controller_fmu_gives_acdrives_commands_exactly(report):
    assert report["strict_math"] is True
    controller = report["controller"]["signals"]
    assert set(controller) == {"latch.v_ref.re", "latch.v_ref.im"}
    for column, row in controller.items():
        assert row["max_difference"] == 0.0, (column, row)
        assert row["peak"] > 100.0  # the speed step drives the voltage command (V)


def test_dfim_voltage_mode_fmus_equal_acdrive(tmp_path):
    """Bodson's DFIM drive as two FMUs over bodson-ramp with its ramp compressed into 0.3 s: the
    controller (voltage command (20), synchroniser (28)) gives acdrive's commands exactly; the
    plant (grid, supply bus, DFIM (9), stator relay, shaft, averaged rotor converter) with
    acdrive's logged commands, and the two in closed loop, within 1e-9 of each signal's peak."""
    text = builtin_text("bodson-ramp")
    for old, new in {
        "duration = 14.0": "duration = 0.3",
        "speed_reference_rpm = [[0.0, 0.0], [0.5, 0.0], [9.5, 2700.0], [11.0, 2700.0], "
        "[11.0, 0.0], [14.0, 0.0]]": "speed_reference_rpm = [[0.0, 0.0], [0.02, 0.0], "
        "[0.3, 1500.0]]",
    }.items():
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    path = tmp_path / "bodson-ramp.toml"
    path.write_text(text)
    from fmpy.validation import validate_fmu

    from acdrive.export._fmu_check import PARTS, scenario_fmus
    from acdrive.scenarios._loader import load_scenario

    (tmp_path / "fmus").mkdir()
    built = scenario_fmus(load_scenario(str(path)), PARTS, tmp_path / "fmus")
    for fmu in built.values():
        assert validate_fmu(str(fmu)) == [], fmu.name
    report = _fmu_check(str(path))
    assert report["strict_math"] is True and report["samples"] == 1500
    signals = report["controller"]["signals"]
    assert {"controller0.v_r.re", "controller0.v_r.im", "sync0.closed"} <= set(signals)
    for column, row in signals.items():
        assert row["max_difference"] == 0.0, (column, row)
    assert signals["controller0.v_r.re"]["peak"] > 1.0  # the rotor voltage command moved (V)
    for check in ("plant", "closed_loop"):
        run = report[check]
        assert run["worst_ratio"] <= report["plant_tolerance"] == 1e-9, (check, run["worst_signal"])
        assert run["signals"]["shaft0.w"]["peak"] > 100.0  # the ramp ran the shaft up (rad/s)
        assert run["signals"]["dfim0.i_s.re"]["peak"] > 1.0  # stator current flowed (A)
        assert run["signals"]["bus.v.re"]["peak"] > 10.0  # the grid's 11.1 V peak x sqrt(3/2)


def test_dfim_relay_closing_inside_the_run_fmus_equal_acdrive():
    """bodson-sync over 0.5 s: the stator starts open and the synchroniser closes the relay
    (Bodson (28)). The plant's direct outputs (the relay's voltage, the DFIM's currents) read
    the command held from the previous sample, as acdrive's loop does, so the closing sample
    matches too: plant and closed loop within 1e-9 of each signal's peak."""
    report = _fmu_check("bodson-sync", "--duration", "0.5")
    assert report["samples"] == 2500
    for check in ("plant", "closed_loop"):
        run = report[check]
        assert run["worst_ratio"] <= report["plant_tolerance"], (check, run["worst_signal"])
        assert run["signals"]["relay0.closed"]["peak"] == 1.0  # it closed
        assert run["signals"]["dfim0.v_open.re"]["peak"] > 1.0  # it was open before (V)
    assert report["closed_loop"]["signals"]["sync0.closed"]["peak"] == 1.0


def test_plant_fmu_open_loop_within_1e_9_of_peak(report):
    plant = report["plant"]
    assert report["plant_tolerance"] == 1e-9
    assert plant["worst_ratio"] <= 1e-9, (plant["worst_signal"], plant["worst_ratio"])
    signals = plant["signals"]
    assert signals["shaft.w"]["peak"] > 50.0  # the shaft ran up (rad/s)
    assert signals["machine.tau_e"]["peak"] > 0.5  # near the 0.83 N m torque limit and above
    assert report["samples"] == 5000


def test_closed_loop_within_the_plant_bound(report):
    """The master's order is acdrive's within a sample, so the bound is the plant's."""
    closed = report["closed_loop"]
    assert closed["worst_ratio"] <= report["plant_tolerance"], closed["worst_signal"]
    assert {"shaft.w", "latch.v_ref.re", "machine.i_s.im"} <= set(closed["signals"])


def test_switching_inverter_plant_fmu_equals_acdrive(tmp_path):
    """The switching SVPWM inverter (5 kHz carrier, 50 kHz control, 2 us dead time, 1.5 V
    device drops) inside the plant FMU, its segments integrated within each communication step:
    im-foc-speed as built in (speed step moved to 5 ms, brake to 50 ms, 0.06 s). Controller
    exact; plant and closed loop within 1e-9 of each signal's peak. The inverter's own outputs
    change within a period (acdrive logs the first segment, the FMU shows the last) and are
    reported as not compared; the machine and shaft, driven by every segment, are compared."""
    text = builtin_text("im-foc-speed")
    for old, new in _CHANGES.items():
        if "model" in old or "dead_time" in old or "device_drop" in old:
            continue
        text = text.replace(old, new.replace("duration = 0.1", "duration = 0.06"))
    path = tmp_path / "im-switching.toml"
    path.write_text(text)
    report = _fmu_check(str(path))
    assert "inverter.v.re" in report["not_compared"]
    for column, row in report["controller"]["signals"].items():
        assert row["max_difference"] == 0.0, (column, row)
    for check in ("plant", "closed_loop"):
        assert report[check]["worst_ratio"] <= 1e-9, (check, report[check]["worst_signal"])
        assert "inverter.v.re" not in report[check]["signals"]
    signals = report["plant"]["signals"]
    assert signals["shaft.w"]["peak"] > 50.0 and signals["machine.i_s.re"]["peak"] > 0.5


def test_rk6_plant_fmu_equals_acdrive(tmp_path):
    """The plant FMU integrates with the scenario's method: rk6 (Butcher's seven stages), one
    step per switching segment, on the switching-inverter drive over 0.02 s."""
    text = builtin_text("im-foc-speed").replace(
        "log_every = 5", 'log_every = 5\nintegrator = "rk6"\nsubsteps = 1', 1
    )
    for old, new in _CHANGES.items():
        if "model" in old or "dead_time" in old or "device_drop" in old:
            continue
        text = text.replace(old, new.replace("duration = 0.1", "duration = 0.02"))
    path = tmp_path / "im-rk6.toml"
    path.write_text(text)
    assert 'integrator = "rk6"' in text
    report = _fmu_check(str(path))
    for check in ("plant", "closed_loop"):
        assert report[check]["worst_ratio"] <= 1e-9, (check, report[check]["worst_signal"])
    assert report["plant"]["signals"]["shaft.w"]["peak"] > 1.0  # the step at 5 ms moved it


def test_pm_drive_fmus_equal_acdrive():
    """The PM drive (Ugalde-Loo (7)-(8) machine with its rotor phasor re-normalised at each
    sample, shaft with the load step at 0.1 s, averaged converter; FOC with MTPA, speed PI):
    controller exact, plant and closed loop within 1e-9 of each signal's peak, over 0.15 s."""
    report = _fmu_check("pm-bly171d-speed", "--duration", "0.15")
    assert report["strict_math"] is True
    for column, row in report["controller"]["signals"].items():
        assert row["max_difference"] == 0.0, (column, row)
    for check in ("plant", "closed_loop"):
        assert report[check]["worst_ratio"] <= 1e-9, (check, report[check]["worst_signal"])
    signals = report["plant"]["signals"]
    assert signals["shaft.w"]["peak"] > 250.0  # the speed step to 300 rad/s
    assert signals["machine.theta"]["peak"] > 2 * 3.14159  # more than a turn: e_r re-normalised


def _slave(path, messages: list | None = None):
    """An instance of the FMU at ``path`` in initialisation; with ``messages``, its logger
    appends (status, message) there."""
    from ctypes import byref

    from fmpy import calloc, extract, free, read_model_description
    from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                           fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)  # fmt: skip
    from fmpy.logging import addLoggerProxy

    md = read_model_description(str(path))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path)),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="t")  # fmt: skip
    callbacks = None
    if messages is not None:

        def logger(component, instance, status, category, message):
            messages.append((status, message.decode()))

        callbacks = fmi2CallbackFunctions()
        callbacks.logger = fmi2CallbackLoggerTYPE(logger)
        callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        addLoggerProxy(byref(callbacks))
    slave.instantiate(callbacks=callbacks)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    return slave, {v.name: v.valueReference for v in md.modelVariables}


def _free(*slaves):
    for slave in slaves:
        slave.terminate()
        slave.freeInstance()


def test_do_step_takes_whole_periods_only(fmus):
    """A step of 3 periods runs 3 periods (the plant's state moves as three single steps do); a
    step of 1.5 periods and a communication point that is not the FMU's time are refused."""
    T_s = 2e-5
    a, vr = _slave(fmus["plant"])
    b, _ = _slave(fmus["plant"])
    for s in (a, b):
        s.exitInitializationMode()
    a.doStep(0.0, 3 * T_s)
    for k in range(3):
        b.doStep(k * T_s, T_s)
    refs = [vr["machine.i_s.re"], vr["machine.psi_r.re"], vr["shaft.w"]]
    assert a.getReal(refs) == b.getReal(refs)
    with pytest.raises(Exception, match=r"status 3 \(error\)"):
        a.doStep(3 * T_s, 1.5 * T_s)
    with pytest.raises(Exception, match=r"status 3 \(error\)"):
        a.doStep(5 * T_s, T_s)
    for s in (a, b):
        s.terminate()
        s.freeInstance()


def test_a_parameter_set_before_the_start_is_used(fmus):
    """The plant's fixed parameters are settable in initialisation: with a rotor resistance of
    1e-9 ohm the rotor flux at standstill hardly moves (dpsi_r/dt = (L_m R_r / L_r) i_s -
    (R_r / L_r - j w_r) psi_r scales with R_r: over 2 ms under 1e-9 of it; R_r = 0 itself breaks
    the declared rule R_r > 0 and is refused), while the exported R_r lets it move."""
    T_s = 2e-5
    fluxes = []
    for R_r in (None, 1e-9):
        slave, vr = _slave(fmus["plant"])
        if R_r is not None:
            slave.setReal([vr["machine.R_r"]], [R_r])
        slave.setReal([vr["latch.v_ref.re"], vr["latch.v_ref.im"]], [0.0, 0.0])
        slave.exitInitializationMode()
        start = slave.getReal([vr["machine.psi_r.re"]])[0]
        slave.doStep(0.0, 100 * T_s)
        fluxes.append((start, slave.getReal([vr["machine.psi_r.re"]])[0]))
        with pytest.raises(Exception, match=r"status 3 \(error\)"):  # fixed: not settable any more
            slave.setReal([vr["machine.R_r"]], [1.0])
        slave.terminate()
        slave.freeInstance()
    (start, moved), (start0, held) = fluxes
    assert start == start0 == pytest.approx(0.964)
    assert abs(held - start0) <= 1e-9 * start0
    assert abs(moved - start) > 1e-4 * start


def test_a_master_adding_its_step_to_its_time_runs_to_the_end(fmus):
    """A master that keeps its time as t += h (fmpy's SSP master does) is off from k T_s by the
    rounding of k sums: 60,000 periods of the controller (1.2 s at 20 us, im-foc-speed's full
    run) stepped that way are all accepted, while the accumulated time really does drift from
    k T_s by more than the 1e-9 of a period a fixed tolerance would allow. Wrong steps stay
    refused that late in the run (the tolerance never passes a quarter period): a point 0.3
    periods off, a step of 1.5 periods, a point one period early, each with a message; the
    right point is accepted after them."""
    T_s = 2e-5
    messages: list = []
    slave, _ = _slave(fmus["controller"], messages)
    slave.exitInitializationMode()
    t, drift = 0.0, 0.0
    for k in range(60_000):
        drift = max(drift, abs(t - k * T_s))
        slave.doStep(t, T_s)
        t += T_s
    assert drift > 1e-9 * T_s  # what the master's sums really do
    assert messages == []
    for point, step in ((t + 0.3 * T_s, T_s), (t, 1.5 * T_s), (t - T_s, T_s)):
        with pytest.raises(Exception, match=r"status 3 \(error\)"):
            slave.doStep(point, step)
    assert [status for status, _ in messages] == [3, 3, 3]
    assert "is not the FMU's time" in messages[0][1] and "is not a whole number" in messages[1][1]
    assert "is not the FMU's time" in messages[2][1]
    slave.doStep(t, T_s)
    _free(slave)


def _status(call) -> int:
    """The fmi2Status of an fmpy call (0 if it returned, the status it raised otherwise)."""
    try:
        call()
    except Exception as error:  # fmpy raises FMICallException with .status
        return int(error.status)
    return 0


def test_derived_numbers_are_calculated_parameters(fmus, scenario):
    """The discretised current controller's matrices, its order, T_s and anti-windup gain are
    fixed when the FMU is built (acdrive's part refuses them as arguments: they come from the
    controller, T_s and the method): calculatedParameter without start, readable, refused by
    fmi2SetReal/fmi2SetInteger with a message; the order is an Integer equal to the order of
    the discrete controller acdrive built."""
    from fmpy import read_model_description

    from acdrive.export._scenario import built
    from acdrive.scenarios._loader import load_scenario

    drive, _, _ = built(load_scenario(scenario))
    part = next(p for p in drive.system.sampled if p.name == "current")
    md = read_model_description(str(fmus["controller"]))
    variables = {v.name: v for v in md.modelVariables}
    calculated = {n for n, v in variables.items() if v.causality == "calculatedParameter"}
    n = part.discrete.order
    matrices = {f"current.{name}_{i}_{j}" for name, rows, cols in
                (("Ad", n, n), ("Bd", n, 2), ("Cd", 2, n), ("Dd", 2, 2), ("Kaw", n, 2))
                for i in range(rows) for j in range(cols)}  # fmt: skip
    assert {"current.order", "current.T_s", "current.v_dc_input", "current.aw_gain"} | matrices \
        == calculated
    assert all(variables[c].start is None for c in calculated)
    assert variables["current.order"].type == "Integer"
    assert variables["current.v_max"].causality == "parameter"  # a free number stays settable
    messages: list = []
    slave, vr = _slave(fmus["controller"], messages)
    assert slave.getInteger([vr["current.order"]]) == [n] and n > 0
    assert slave.getReal([vr["current.T_s"]]) == [part.discrete.T_s]
    assert slave.getReal([vr["current.Ad_0_0"]]) == [float(part.discrete.Ad[0, 0])]
    assert _status(lambda: slave.setInteger([vr["current.order"]], [8])) == 3
    assert _status(lambda: slave.setReal([vr["current.Ad_0_0"]], [0.5])) == 3
    assert slave.getInteger([vr["current.order"]]) == [n]
    assert [m for _, m in messages] == [
        "fmi2SetInteger: current.order is a calculated parameter (derived when the FMU was built "
        "from the scenario): not settable",
        "fmi2SetReal: current.Ad_0_0 is a calculated parameter (derived when the FMU was built "
        "from the scenario): not settable",
    ]
    _free(slave)


def test_integer_parameters_are_integers(fmus):
    """The pole pairs (declared rule "count") are an Integer with min 1 in both FMUs, read and
    set with fmi2GetInteger/fmi2SetInteger; a value set in initialisation is the one used."""
    from fmpy import read_model_description

    for part, name in (("plant", "machine.n_p"), ("controller", "ifoc.n_p")):
        variables = {v.name: v for v in read_model_description(str(fmus[part])).modelVariables}
        assert variables[name].type == "Integer" and variables[name].min == "1", name
        slave, vr = _slave(fmus[part])
        assert slave.getInteger([vr[name]]) == [1]
        slave.setInteger([vr[name]], [2])
        assert slave.getInteger([vr[name]]) == [2]
        _free(slave)


def test_parameter_values_against_their_rules_are_refused(fmus):
    """A value that breaks the rule its part declares (core._signals.RULES) is fmi2Error with
    one message naming the variable, the value and the rule, and the value is not taken:
    ifoc.n_p = 0 (acdrive's run gave NaN commands with fmi2OK), a negative resistance, a NaN
    inertia, a flux limit of inf. A value within the rule is taken."""
    cases = (
        ("controller", "ifoc.n_p", 0, "must be a positive integer"),
        ("plant", "machine.R_s", -1.0, "must be > 0"),
        ("plant", "shaft.J", math.nan, "must be finite (not NaN or infinite)"),
        ("controller", "ifoc.psi_min", math.inf, "must be finite (not NaN or infinite)"),
        ("controller", "speed_controller.K_F", 1.5, "must be between 0 and 1"),
    )
    for part, name, value, rule in cases:
        messages: list = []
        slave, vr = _slave(fmus[part], messages)
        integer = isinstance(value, int)
        get = slave.getInteger if integer else slave.getReal
        before = get([vr[name]])
        setter = slave.setInteger if integer else slave.setReal
        assert _status(lambda: setter([vr[name]], [value])) == 3, name
        assert get([vr[name]]) == before
        function = "fmi2SetInteger" if integer else "fmi2SetReal"
        shown = {0: "0", -1.0: "-1", 1.5: "1.5"}.get(value, "nan" if value != value else "inf")
        assert messages == [(3, f"{function}: {name} = {shown} refused: {rule}")], messages
        _free(slave)
    slave, vr = _slave(fmus["plant"])
    slave.setReal([vr["machine.R_s"]], [10.0])
    assert slave.getReal([vr["machine.R_s"]]) == [10.0]
    _free(slave)


def test_a_broken_relation_is_refused_when_initialisation_ends(fmus):
    """Rules over several parameters (core._signals.Relation) are judged when initialisation
    ends: L_m = 2 H is a valid inductance alone, but with L_s = 1.44 H and L_r = 1.5 H the
    leakage factor 1 - L_m^2/(L_s L_r) is negative; fmi2ExitInitializationMode is fmi2Error,
    its message the rule and the three values. The same for the IFOC's estimates, L_m = 1.6 H
    above L_r = 1.5 H."""
    messages: list = []
    slave, vr = _slave(fmus["plant"], messages)
    slave.setReal([vr["machine.L_m"]], [2.0])
    assert _status(slave.exitInitializationMode) == 3
    assert messages == [(3, "fmi2ExitInitializationMode: machine.L_m: leakage factor sigma = 1 - "
                            "L_m^2/(L_s L_r) must be > 0 (machine.L_s = 1.4399999999999999, "
                            "machine.L_r = 1.5, machine.L_m = 2)")]  # fmt: skip
    messages.clear()
    controller, vr = _slave(fmus["controller"], messages)
    controller.setReal([vr["ifoc.L_m"]], [1.6])  # the IFOC's estimate: L_m <= L_r = 1.5 H
    assert _status(controller.exitInitializationMode) == 3
    assert messages == [(3, "fmi2ExitInitializationMode: ifoc.L_m: must not exceed L_r (L_r = "
                            "L_m + rotor leakage) (ifoc.L_r = 1.5, ifoc.L_m = 1.6000000000000001)")]
    _free(slave, controller)


def test_every_rule_has_its_c_and_they_agree():
    """The C condition of each declared rule (the FMU's check) holds for exactly the values
    the Python rule (core._signals) accepts, compiled and run on values around each bound."""
    from acdrive.core._signals import _RULE_HOLDS, RULES
    from acdrive.export._fmu import RULE_C

    assert set(RULE_C) == set(RULES) - {""}
    values = (-2.0, -1.0, -0.5, -1e-300, 0.0, 1e-300, 0.5, 1.0, 1.5, 2.0, 3.0, 1e300)
    program = ["#include <math.h>", "#include <stdio.h>", "int main(void)", "{",
               f"    static const double values[] = {{{', '.join(map(repr, values))}}};",
               "    int i;", f"    for (i = 0; i < {len(values)}; ++i) {{",
               "        double value = values[i];",
               *(f'        printf("%d ", ({c}) ? 1 : 0);' for c in RULE_C.values()),
               '        printf("\\n");', "    }", "    return 0;", "}"]  # fmt: skip
    folder = Path(tempfile.mkdtemp(prefix="acdrive-rules-"))
    (folder / "rules.c").write_text("\n".join(program) + "\n")
    subprocess.run(["gcc", "-std=c99", "-o", str(folder / "rules"), str(folder / "rules.c"), "-lm"],
                   check=True)  # fmt: skip
    rows = subprocess.run([str(folder / "rules")], check=True, capture_output=True, text=True)
    shutil.rmtree(folder)
    for value, row in zip(values, rows.stdout.split("\n"), strict=False):
        for (rule, _), bit in zip(RULE_C.items(), row.split(), strict=True):
            assert bool(int(bit)) == _RULE_HOLDS[rule](value), (rule, value)


def test_a_non_finite_output_is_an_error(fmus):
    """A NaN command makes the plant's state NaN: the step is fmi2Error with a message naming
    the first output that is not finite and the time, the instance refuses further steps, and
    fmi2Reset starts it again. The same for the controller given a NaN current."""
    T_s = 2e-5
    messages: list = []
    plant, vr = _slave(fmus["plant"], messages)
    plant.exitInitializationMode()
    plant.doStep(0.0, T_s)
    plant.setReal([vr["latch.v_ref.re"]], [math.nan])
    assert _status(lambda: plant.doStep(T_s, T_s)) == 3
    assert _status(lambda: plant.doStep(2 * T_s, T_s)) == 3
    first = messages[0][1]
    assert first.startswith("fmi2DoStep: output ")
    assert " is NaN at 4.0000000000000003e-05 s" in first
    assert messages[1][1].startswith("fmi2DoStep: the FMU stopped at an error")
    plant.reset()
    plant.setupExperiment(startTime=0.0)
    plant.enterInitializationMode()
    plant.exitInitializationMode()
    plant.doStep(0.0, T_s)  # the command is its start value again
    assert all(math.isfinite(x) for x in plant.getReal([vr["machine.i_s.re"], vr["shaft.w"]]))
    messages.clear()
    controller, vr = _slave(fmus["controller"], messages)
    controller.exitInitializationMode()
    controller.setReal([vr["machine.i_s.re"]], [math.nan])
    assert _status(lambda: controller.doStep(0.0, 20 * T_s)) == 3
    assert messages[0][1].startswith("fmi2DoStep: output latch.v_ref.")
    _free(plant, controller)


def _gauss_seidel(paths: dict, version: int, n: int, T_s: float, messages: list) -> dict:
    """The pair of FMI ``version`` stepped n periods as the closed-loop check steps it (the
    controller first, its commands to the plant, the plant; the time summed step by step):
    every Real output after every step."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave
    from fmpy.fmi3 import FMU3Slave

    slaves, reals = {}, {}
    for part, path in paths.items():
        md = read_model_description(str(path))
        kind = FMU2Slave if version == 2 else FMU3Slave
        slave = kind(guid=md.guid, unzipDirectory=extract(str(path)),
                     modelIdentifier=md.coSimulation.modelIdentifier, instanceName=part)  # fmt: skip
        if version == 2:
            slave.instantiate()
            slave.setupExperiment(startTime=0.0)
            slave.enterInitializationMode()
        else:
            slave.instantiate(logMessage=lambda env, status, category, message:
                              messages.append((status, message.decode())))  # fmt: skip
            slave.enterInitializationMode(startTime=0.0)
        slave.exitInitializationMode()
        slaves[part] = slave
        reals[part] = {v.causality: [] for v in md.modelVariables}
        for v in md.modelVariables:
            if v.type in ("Real", "Float64") and v.causality in ("input", "output"):
                reals[part][v.causality].append(v)
    get = {p: (s.getReal if version == 2 else s.getFloat64) for p, s in slaves.items()}
    put = {p: (s.setReal if version == 2 else s.setFloat64) for p, s in slaves.items()}
    log: dict = {v.name: [] for part in reals for v in reals[part]["output"]}
    t = 0.0
    for _ in range(n):
        y = dict(zip([v.name for v in reals["plant"]["output"]],
                     get["plant"]([v.valueReference for v in reals["plant"]["output"]]),
                     strict=True))  # fmt: skip
        put["controller"]([v.valueReference for v in reals["controller"]["input"]],
                          [y[v.name] for v in reals["controller"]["input"]])  # fmt: skip
        slaves["controller"].doStep(t, T_s)
        u = dict(zip([v.name for v in reals["controller"]["output"]],
                     get["controller"]([v.valueReference for v in reals["controller"]["output"]]),
                     strict=True))  # fmt: skip
        put["plant"]([v.valueReference for v in reals["plant"]["input"]],
                     [u[v.name] for v in reals["plant"]["input"]])  # fmt: skip
        slaves["plant"].doStep(t, T_s)
        for name, value in (*y.items(), *u.items()):
            log[name].append(value)
        t += T_s
    _free(*slaves.values())
    return log


def test_fmi3_fmus_validate_and_run_as_the_fmi2_pair(scenario, fmus, tmp_path, capsys):
    """``acdrive export fmu --fmi 3`` writes FMI 3.0 co-simulation FMUs of the same C: fmpy
    validates them; stepped by the closed-loop check's master (time summed step by step) for
    3,000 periods (past the speed step at 5 ms), every output equals the FMI 2.0 pair's to the
    bit; the same rules hold (fmi3SetInt32 of ifoc.n_p = 0 refused with its message, the order
    a calculated parameter, Int32); the sources compile pedantic and warning-free."""
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    from acdrive.export._fmu import fmi_headers

    assert _cli("export", "fmu", scenario, "--out", str(tmp_path), "--fmi", "3") == 0
    folder = tmp_path / "im-foc-speed-fmu"
    paths = {"controller": folder / "im_foc_speed_controller.fmu",
             "plant": folder / "im_foc_speed_plant.fmu"}  # fmt: skip
    for path in paths.values():
        assert validate_fmu(str(path)) == [], path.name
        md = read_model_description(str(path))
        assert md.fmiVersion == "3.0" and md.coSimulation is not None
        assert f"binaries/x86_64-linux/{path.stem}.so" in zipfile.ZipFile(path).namelist()
        unzipped = tmp_path / path.stem
        zipfile.ZipFile(path).extractall(unzipped)
        done = subprocess.run(
            ["gcc", "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O2", "-fPIC",
             "-shared", f"-I{fmi_headers()}", "-o", str(unzipped / "again.so"),
             *sorted(str(p) for p in (unzipped / "sources").glob("*.c")), "-lm"],
            check=False, capture_output=True, text=True,
        )  # fmt: skip
        assert done.returncode == 0, done.stderr
    variables = {v.name: v for v in read_model_description(str(paths["controller"])).modelVariables}
    assert variables["current.order"].causality == "calculatedParameter"
    assert variables["current.order"].type == variables["ifoc.n_p"].type == "Int32"
    messages: list = []
    three = _gauss_seidel(paths, 3, 3000, 2e-5, messages)
    two = _gauss_seidel(fmus, 2, 3000, 2e-5, [])
    assert set(three) == set(two) and messages == []
    for name in two:
        assert three[name] == two[name], name
    assert max(two["shaft.w"]) > 10.0  # the speed step at 5 ms moved the shaft (rad/s)

    from fmpy import extract
    from fmpy.fmi3 import FMU3Slave

    md = read_model_description(str(paths["controller"]))
    slave = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(paths["controller"])),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="t")  # fmt: skip
    slave.instantiate(logMessage=lambda env, status, category, message:
                      messages.append((status, message.decode())))  # fmt: skip
    slave.enterInitializationMode(startTime=0.0)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    assert _status(lambda: slave.setInt32([vr["ifoc.n_p"]], [0])) == 3
    assert _status(lambda: slave.setInt32([vr["current.order"]], [8])) == 3
    order = _slave(fmus["controller"])  # the FMI 2.0 controller's order
    assert slave.getInt32([vr["current.order"]]) == order[0].getInteger([order[1]["current.order"]])
    _free(order[0])
    assert messages[0] == (3, "fmi3SetInt32: ifoc.n_p = 0 refused: must be a positive integer")
    assert messages[1][1].startswith("fmi3SetInt32: current.order is a calculated parameter")
    _free(slave)


def _cli(*args):
    from acdrive.cli import main

    return main(list(args))


def test_cli_writes_both_and_keeps_users_folder(scenario, tmp_path, capsys):
    out = tmp_path / "out"
    assert _cli("export", "fmu", scenario, "--out", str(out)) == 0
    folder = out / "im-foc-speed-fmu"
    assert sorted(p.name for p in folder.glob("*.fmu")) == [
        "im_foc_speed_controller.fmu", "im_foc_speed_plant.fmu"]  # fmt: skip
    assert _cli("export", "fmu", scenario, "--out", str(out), "--part", "plant") == 0  # replaced
    assert sorted(p.name for p in folder.glob("*.fmu")) == ["im_foc_speed_plant.fmu"]
    mine = out / "bodson-ramp-fmu"
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    capsys.readouterr()
    assert _cli("export", "fmu", "bodson-ramp", "--out", str(out), "--part", "controller") == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    assert sorted(p.name for p in mine.iterdir()) == ["notes.txt"]


def test_cli_plant_without_c_is_one_line_and_writes_nothing(tmp_path, capsys, monkeypatch):
    """A plant kind without C (here fault-phase-loss's grid, an UnbalancedSource, its entry
    taken out of the registry and its kernel marked outside the language): one line naming the
    part and the rule, exit 2."""
    from acdrive.plant._sources import UnbalancedSource
    from acdrive.sim._ccode import _kinds

    monkeypatch.delitem(_kinds._PLANT_REGISTRY, UnbalancedSource, raising=False)
    monkeypatch.setitem(_kinds._UNTRANSLATABLE, UnbalancedSource, "a construct (marked by the test)")
    assert _cli("export", "fmu", "fault-phase-loss", "--part", "plant", "--out", str(tmp_path)) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "grid:" in err[0] and "has no C implementation" in err[0]
    assert list(tmp_path.iterdir()) == []


def test_cli_missing_compiler_is_one_line(scenario, tmp_path, capsys, monkeypatch):
    from acdrive.export import _sil

    monkeypatch.setattr(_sil.shutil, "which", lambda name: None)
    assert _cli("export", "fmu", scenario, "--out", str(tmp_path / "out")) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "gcc was not found on PATH: building an FMU's binary" in err[0]
    assert not (tmp_path / "out").exists()


def test_direct_outputs_without_c_are_refused(monkeypatch):
    """A plant kind with direct outputs whose C does not write them (no ``direct_outputs``
    body) is refused, naming the part and the rule."""
    from typing import ClassVar

    from acdrive.core._parts import ContinuousPart, SampledPart
    from acdrive.core._signals import Layout, real
    from acdrive.errors import InputError
    from acdrive.sim._ccode import _kinds
    from acdrive.sim._ccode._plant_source import to_plant_c
    from acdrive.sim._system import System

    class Command(SampledPart):
        OUTPUTS = Layout(real("u", "V", "command"))
        step = None

    class Through(ContinuousPart):
        STATES = Layout(real("x", "", "state"))
        INPUTS = Layout(real("u", "V", "command"))
        OUTPUTS = Layout(real("y", "V", "the command, passed through"))
        DIRECT_FROM: ClassVar = ("u",)
        DIRECT_OUTPUTS: ClassVar = ("y",)
        state_outputs = rhs = direct_outputs = None

    monkeypatch.setitem(_kinds._PLANT_REGISTRY, Through, _kinds.PlantC(source="test", rhs=""))
    command, through = Command("command"), Through("through")
    system = System.__new__(System)  # the wiring only: the kernels are never compiled here
    system.continuous, system.modulators = [through], []
    system.source_of = {("through", "u"): command.out.u}
    with pytest.raises(InputError) as caught:
        to_plant_c(system, 1e-4, 1)
    message = str(caught.value)
    assert message.startswith("through:") and "has direct outputs, which its C does not" in message
    assert "\n" not in message


def test_fmu_sources_build_warning_free_elsewhere(fmus, tmp_path):
    """The sources inside each FMU are all another tool needs besides its FMI 2.0 headers:
    they compile pedantic and warning-free (-Werror) from the unzipped folder alone."""
    import zipfile

    from acdrive.export._fmu import fmi_headers

    for path in fmus.values():
        folder = tmp_path / path.stem
        zipfile.ZipFile(path).extractall(folder)
        sources = sorted(str(p) for p in (folder / "sources").glob("*.c"))
        done = subprocess.run(
            ["gcc", "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O2", "-fPIC",
             "-shared", f"-I{fmi_headers()}", "-o", str(folder / "again.so"), *sources, "-lm"],
            check=False, capture_output=True, text=True,
        )  # fmt: skip
        assert done.returncode == 0, done.stderr


def test_unit_exponents_obey_the_si_relations():
    """The SI exponents written into UnitDefinitions satisfy the relations between the units:
    V A = W, Wb = V s, H = Wb / A, ohm = V / A, N m = J, var has the dimension of W."""
    from acdrive.export._fmu import si_exponents

    def product(*units):
        total: dict[str, int] = {}
        for unit in units:
            for k, e in si_exponents(unit).items():
                total[k] = total.get(k, 0) + e
        return {k: e for k, e in total.items() if e}

    assert product("V", "A") == si_exponents("W")
    assert product("V", "s") == si_exponents("Wb")
    assert product("Wb", "1/A") == si_exponents("H") == si_exponents("Wb/A")
    assert si_exponents("ohm") == si_exponents("V/A") == si_exponents("Ohm")
    assert product("N", "m") == si_exponents("J") == si_exponents("N m")
    assert si_exponents("var") == si_exponents("W")
    assert product("1/(V s)", "Wb") == {}
    assert si_exponents("furlong/s") is None  # a word outside the table: no BaseUnit


def test_two_chains_reading_one_plant_output_share_one_input(tmp_path):
    """bodson-two-motors: two chains on one bus both read the grid voltage; the controller FMU
    has it once as an input (validate_fmu refuses duplicate names) and both chains get it."""
    import zipfile

    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    from acdrive.export._fmu_check import scenario_fmus
    from acdrive.scenarios._loader import load_scenario

    path = scenario_fmus(load_scenario("bodson-two-motors"), ("controller",), tmp_path)[
        "controller"
    ]
    assert validate_fmu(str(path)) == []
    names = [v.name for v in read_model_description(str(path)).modelVariables]
    assert names.count("grid.v.re") == 1
    glue = zipfile.ZipFile(path).read(f"sources/{path.stem}_fmi2.c").decode()
    assert "_controller1.grid_v = m->in_bodson_two_motors_controller0.grid_v;" in glue
