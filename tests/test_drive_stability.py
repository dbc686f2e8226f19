"""Whole-drive linearisation (acdrive.drives.dfim._linearisation._stability): analytic limits of Bodson's
equations, consistency of the continuous and sampled-data models, and nonlinear simulation."""

import dataclasses
import json
import math

import numpy as np
import pytest

from acdrive.cli import main
from acdrive.drives.dfim import simulate
from acdrive.drives.dfim._linearisation._stability import (
    RAD_S_PER_RPM,
    DriveModel,
    OperatingPoint,
    linearize,
    simulate_from_equilibrium,
)
from acdrive.drives.dfim._linearisation._studies import max_stable_bandwidth, stability_map
from acdrive.errors import InputError
from acdrive.machines import (
    BODSON_DFIM,
    electrical_poles,
    shifted_delta_z_coefficients,
)
from acdrive.scenarios import build_setup

W_E = 2 * math.pi * 60.0


def sort_eigs(values):
    values = np.asarray(values, dtype=complex)
    return values[np.lexsort((values.imag, values.real))]


def assert_same_eigs(actual, expected, rtol):
    a, e = sort_eigs(actual), sort_eigs(expected)
    assert a.shape == e.shape
    scale = np.max(np.abs(e))
    assert np.max(np.abs(a - e)) < rtol * scale, (a, e)


@pytest.mark.parametrize("speed_rpm", [0.0, 700.0, 1800.0, 2600.0, -900.0])
@pytest.mark.parametrize("load", [0.0, 0.15, -0.2])
def test_torque_law_at_frozen_speed_has_the_poles_of_delta_z(speed_rpm, load):
    """Open-loop law (20)+(22), speed held: the electrical eigenvalues are the roots of Delta Z(s)
    (13) and their conjugates (real 4 x 4 model), i.e. the roots of Delta Z(s - j w_e) (15)-(16)
    moved by -j w_e (if Delta Z(s - j w_e) vanishes at r, Delta Z vanishes at r - j w_e); the law
    does not move the poles of the machine."""
    w = speed_rpm * RAD_S_PER_RPM
    r = linearize(DriveModel(speed_loop="frozen"), OperatingPoint(w, load))
    roots = electrical_poles(BODSON_DFIM, W_E, w)
    assert_same_eigs(r.eigenvalues, np.concatenate([roots, roots.conj()]), 1e-7)
    shifted = np.roots(shifted_delta_z_coefficients(BODSON_DFIM, w)) - 1j * W_E
    assert_same_eigs(shifted, roots, 1e-10)
    assert r.torque_command == pytest.approx(load, abs=1e-12)


@pytest.mark.parametrize("inertia_ratio", [1.0, 2.0])
def test_slow_speed_loop_has_the_poles_of_27(inertia_ratio):
    """With a_D,VEL far below the electrical poles the two slow poles are the roots of
    J_true s^2 + K_P s + K_I (27) (gains designed with J): a double root at -a_D,VEL when the
    true inertia is the design one."""
    a = 1.0
    machine = dataclasses.replace(BODSON_DFIM, J=inertia_ratio * BODSON_DFIM.J)
    model = DriveModel(speed_bandwidth=a, machine=machine, design_inertia=BODSON_DFIM.J)
    r = linearize(model, OperatingPoint(1000 * RAD_S_PER_RPM, 0.05))
    slow = r.eigenvalues[np.argsort(np.abs(r.eigenvalues))][:2]
    g = model.gains
    expected = np.roots([machine.J, g.K_P, g.K_I])
    # a double root splits like sqrt(perturbation); its sum and product are analytic
    assert np.sum(slow).real == pytest.approx(np.sum(expected).real, rel=1e-2)
    assert np.prod(slow).real == pytest.approx(np.prod(expected).real, rel=1e-2)
    assert np.all(np.abs(r.eigenvalues[np.abs(r.eigenvalues) > 10 * a]) > 40.0)


@pytest.mark.parametrize("a_cur,R_T", [(3142.0, 1.0), (1500.0, 2.5)])
def test_current_mode_rotor_loop_poles_are_those_of_50(a_cur, R_T):
    """Current command, speed held: the loop (45)-(47) with gains (49) places the rotor-current
    poles at -a_D,CUR and at the cancelled -R_T / (sigma L_r) (48)-(50); the stator flux keeps its
    own pole -R_s/L_s - j w_e (from (44) with i_R fixed)."""
    m = BODSON_DFIM
    model = DriveModel(mode="current", speed_loop="frozen", current_bandwidth=a_cur, R_T=R_T)
    r = linearize(model, OperatingPoint(1200 * RAD_S_PER_RPM, 0.1))
    stator = -m.R_s / m.L_s - 1j * W_E
    expected = [-a_cur, -a_cur, -R_T / (m.sigma * m.L_r), -R_T / (m.sigma * m.L_r)]
    assert_same_eigs(r.eigenvalues, expected + [stator, np.conj(stator)], 1e-6)


BENCH = {
    "supply_resistance": 0.3,
    "supply_inductance": 0.5e-3,
    "speed_filter_tau": 1e-3,
    "converter_loss": 1.0,
}


@pytest.mark.parametrize("mode", ["voltage", "current"])
@pytest.mark.parametrize("extras", [{}, BENCH], ids=["plain", "bench-effects"])
def test_sampled_model_converges_to_continuous_one(mode, extras):
    """The sampled-data map (the simulator's controller and RK4 plant, zero-order hold) tends to
    the continuous-time linearisation at first order in the sample time, also with a supply
    impedance (continuous model: the measured-voltage loop solved by iteration), a speed filter
    and a converter loss."""
    point = OperatingPoint(900 * RAD_S_PER_RPM, 0.05)
    cont = linearize(DriveModel(mode=mode, **extras), point).dominant
    gaps = [
        abs(
            linearize(DriveModel(mode=mode, sample_time=T, **extras), point, "sampled").dominant
            - cont
        )
        for T in (40e-6, 20e-6)
    ]
    assert gaps[1] < 1e-2 * abs(cont)
    assert gaps[0] / gaps[1] == pytest.approx(2.0, rel=0.1)


def test_paper_gains_voltage_mode_unstable_current_mode_stable():
    point = OperatingPoint(900 * RAD_S_PER_RPM, 0.0)
    voltage = linearize(DriveModel(), point)
    current = linearize(DriveModel(mode="current"), point)
    assert not voltage.stable and voltage.max_real_part > 0
    assert abs(voltage.dominant.imag) == pytest.approx(W_E, rel=0.2)  # near the supply frequency
    assert current.stable and current.max_real_part < 0
    low = linearize(DriveModel(speed_bandwidth=100.0), point)
    assert low.stable


@pytest.mark.parametrize(
    "mode,bandwidth,delay",
    [("voltage", 314.0, 0), ("voltage", 100.0, 0), ("current", 314.0, 0),
     ("voltage", 100.0, 1), ("current", 314.0, 1)],
)  # fmt: skip
def test_engine_follows_the_linear_prediction(mode, bandwidth, delay):
    """The compiled engine, started at the sampled equilibrium plus a small perturbation along
    the dominant mode, grows or decays as the eigenvalues of the one-sample map say; with one
    sample of computation delay the run is the drive with its ``ComputationDelay`` part."""
    model = DriveModel(mode=mode, speed_bandwidth=bandwidth, delay_samples=delay)
    r = linearize(model, OperatingPoint(900 * RAD_S_PER_RPM, 0.0), "sampled")
    # at rest at the fixed point
    _, w0 = simulate_from_equilibrium(r, np.zeros_like(r.state), 200)
    assert np.max(np.abs(w0 - r.state[4])) < 1e-9
    vals, vecs = np.linalg.eig(r.jacobian)
    k = np.argmax(np.abs(vals))
    dz = 1e-6 * np.real(vecs[:, k]) / np.max(np.abs(vecs[:5, k]))
    n = 500
    t, w = simulate_from_equilibrium(r, dz, n)
    # linear prediction of the speed deviation, sample by sample
    pred, z = [], dz.copy()
    for _ in range(n):
        pred.append(z[4])
        z = r.jacobian @ z
    deviation = w - r.state[4]
    assert np.max(np.abs(deviation - np.array(pred))) < 2e-3 * np.max(np.abs(pred))
    first, last = np.max(np.abs(deviation[:100])), np.max(np.abs(deviation[-100:]))
    growth = math.log(last / first) / (t[-50] - t[50])
    assert (last > first) == (not r.stable)
    assert growth == pytest.approx(r.max_real_part, abs=0.15 * abs(r.max_real_part) + 2.0)


def scenario_at(speed_rpm, bandwidth, duration=0.6):
    """Constant speed reference from that speed; K_F = 1 so the drive starts at its equilibrium
    (zero torque command) up to the sampled ripple: a small perturbation."""
    return build_setup(
        {
            "simulation": {"duration": duration},
            "motor": [
                {
                    "speed_reference_rpm": [[0.0, speed_rpm]],
                    "initial_speed_rpm": speed_rpm,
                    "controller": {"speed_bandwidth": bandwidth, "K_F": 1.0},
                }
            ],
        }
    )


def test_scenario_simulation_oscillates_only_where_linearisation_says():
    """Nonlinear simulation through the scenario loader: at the paper's a_D,VEL = 314 rad/s the
    voltage-command drive at 900 rpm breaks into an oscillation near the frequency of the unstable
    pair (bounded by the torque limits); at 100 rad/s it stays at rest."""
    point = OperatingPoint(900 * RAD_S_PER_RPM, 0.0)
    for bandwidth in (314.0, 100.0):
        res = simulate(scenario_at(900.0, bandwidth))
        dev = res.signal("w") - 900 * RAD_S_PER_RPM
        late = res.t > 0.4
        r = linearize(DriveModel(speed_bandwidth=bandwidth), point, "sampled")
        if r.stable:
            assert np.max(np.abs(dev[late])) < 1e-3
        else:
            assert np.max(np.abs(dev[late])) > 20 * np.max(np.abs(dev[res.t < 0.01]))
            spectrum = np.abs(np.fft.rfft(dev[late] - dev[late].mean()))
            freq = np.fft.rfftfreq(dev[late].size, res.sample_time)
            f_peak = freq[np.argmax(spectrum)]
            assert f_peak == pytest.approx(abs(r.dominant.imag) / (2 * math.pi), rel=0.25)


def test_max_stable_bandwidth_is_the_stability_boundary():
    speeds, loads = np.array([900.0]), np.array([0.0])
    a = max_stable_bandwidth("voltage", speeds, loads, tol=0.5)
    point = OperatingPoint(900 * RAD_S_PER_RPM, 0.0)
    assert linearize(DriveModel(speed_bandwidth=a), point).stable
    assert not linearize(DriveModel(speed_bandwidth=a + 1.0), point).stable
    assert max_stable_bandwidth("current", speeds, loads, upper=400.0) == 400.0


def test_map_marks_points_without_equilibrium():
    model = DriveModel(supply_resistance=0.5)
    m = stability_map(model, [900.0], [0.0, 0.26])
    assert m.feasible.tolist() == [[True, False]]
    assert not m.stable[0, 1]


def test_invalid_points_and_models_raise_input_error():
    with pytest.raises(InputError, match="speed"):
        linearize(DriveModel(), OperatingPoint(1e4, 0.0))
    with pytest.raises(InputError, match="load_torque"):
        linearize(DriveModel(), OperatingPoint(0.0, 0.5))
    with pytest.raises(InputError, match="speed_bandwidth"):
        DriveModel(speed_bandwidth=-1.0)
    with pytest.raises(InputError, match="speed_bandwidth"):
        DriveModel(speed_bandwidth=float("nan"))
    with pytest.raises(InputError, match="kind"):
        linearize(DriveModel(), OperatingPoint(0.0, 0.0), "discrete")


def test_cli_json_single_point(capsys):
    args = ["stability", "--mode", "voltage", "--speed-rpm", "900", "--load-nm", "0", "--json"]
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["stable"] is False and out["max_real_part"] > 0
    assert max(re for re, _ in out["eigenvalues"]) == out["max_real_part"]
    assert main(args[:-1] + ["--bandwidth", "100", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["stable"] is True


@pytest.mark.parametrize(
    "extra,field",
    [
        (["--speed-rpm", "nan"], "--speed-rpm"),
        (["--speed-rpm", "9000"], "--speed-rpm"),
        (["--speed-rpm", "100", "--bandwidth", "-5"], "--bandwidth"),
        (["--speed-rpm", "100", "--load-nm", "2"], "--load-nm"),
    ],
)
def test_cli_bad_arguments_one_line_exit_2(capsys, extra, field):
    assert main(["stability", *extra]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and field in err


def test_the_public_names_reach_a_drive_linearisation_through_the_registry(capsys):
    """``acdrive.analysis``'s names are the default drive's own linearisation
    (``Drive.linearisation()``); a setup of a drive without one is refused in one line naming
    the drive, by ``analysis.linearize`` and by ``acdrive stability --scenario`` (exit 2)."""
    from acdrive import analysis
    from acdrive.drives import for_setup, get
    from acdrive.drives._registry import DEFAULT_KIND
    from acdrive.scenarios import load_scenario

    own = get(DEFAULT_KIND).linearisation()
    assert analysis.OperatingPoint is own.OperatingPoint
    assert analysis.DriveModel is own.DriveModel
    pm = load_scenario("pm-bly171d-speed")
    kind = for_setup(pm).kind
    with pytest.raises(InputError, match=f"drive '{kind}' has no linearisation"):
        analysis.linearize(pm, analysis.OperatingPoint(100.0, 0.0))
    assert main(["stability", "--scenario", "pm-bly171d-speed"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--scenario" in err and "no linearisation" in err


def test_cli_map_writes_figure_and_bandwidths(tmp_path, capsys):
    args = ["stability", "--map", "--grid", "3", "2", "--out", str(tmp_path), "--json"]
    assert main(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert (tmp_path / out["figure"].split("/")[-1]).is_file()
    assert out["modes"]["voltage"]["stable_everywhere"] is False
    assert out["modes"]["current"]["stable_everywhere"] is True
    assert out["modes"]["voltage"]["max_stable_bandwidth_rad_s"] < 314.0


def test_stabilising_threshold_is_a_stability_boundary():
    """The smallest true inertia that stabilises the zero-load line: stable there, unstable
    0.05 J below; the same for an extra rotor resistance unknown to the controller."""
    from acdrive.drives.dfim._linearisation._studies import stabilising_thresholds

    speeds = np.linspace(0.0, 2700.0, 4)
    th = {t.name: t for t in stabilising_thresholds(n_speed=4, n_load=3)}
    m0 = BODSON_DFIM

    def zero_load_stable(machine):
        model = DriveModel(machine=machine, controller_params=m0, design_inertia=m0.J)
        return stability_map(model, speeds, [0.0]).all_stable

    ratio = th["true J / design J"].zero_load
    assert 1.0 < ratio < 10.0
    assert zero_load_stable(dataclasses.replace(m0, J=ratio * m0.J))
    assert not zero_load_stable(dataclasses.replace(m0, J=(ratio - 0.05) * m0.J))
    extra = th["extra rotor resistance"].zero_load
    assert zero_load_stable(dataclasses.replace(m0, R_r=m0.R_r + extra))
    assert not zero_load_stable(dataclasses.replace(m0, R_r=m0.R_r + extra - 0.02))
    # a viscous load large enough to help needs more torque than the drive has (B 283 >> 0.27)
    assert th["viscous friction B"].zero_load == math.inf


def test_converter_loss_damps_the_drive_in_both_models():
    """The simulator's converter loss (a voltage against the rotor current) enters both models
    through the plant; it damps the unstable pair."""
    point = OperatingPoint(900 * RAD_S_PER_RPM, 0.0)
    for kind in ("continuous", "sampled"):
        ideal = linearize(DriveModel(), point, kind).max_real_part
        lossy = linearize(DriveModel(converter_loss=1.5), point, kind).max_real_part
        assert lossy < ideal - 10.0


def test_scenario_computation_delay_is_a_part_between_controller_and_converter():
    """``controller.computation_delay_samples = 1`` puts a ``ComputationDelay`` part in the drive,
    fed by the controller's command and feeding the converter; 2 is refused naming the field."""
    from acdrive.drives import get

    motor = {"speed_reference_rpm": [[0.0, 900.0]], "initial_speed_rpm": 900.0}
    data = {"motor": [{**motor, "controller": {"computation_delay_samples": 1}}]}
    drive = get("dfim").build(build_setup(data))
    parts = drive.motors[0]
    plain = get("dfim").build(build_setup({"motor": [motor]})).motors[0]
    assert "delay" in parts and "delay" not in plain
    source = drive.system.source_of
    assert source[("delay0", "x")].path == "controller0.v_r"
    assert source[("converter0", "v_ref")].path == "delay0.x"
    bad = {"motor": [{**motor, "controller": {"computation_delay_samples": 2}}]}
    with pytest.raises(InputError, match="computation_delay_samples"):
        build_setup(bad)
