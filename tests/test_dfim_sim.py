"""The compiled sampled-data engine: accuracy, slow path, closed-loop physics, robustness."""

import dataclasses
import math

import numpy as np
import pytest

from acdrive.control._speed import speed_pi
from acdrive.core import Profile
from acdrive.drives.dfim import DFIMDrive, simulate, simulate_slow
from acdrive.machines._dfim import N_P, rotor_voltage_for, stator_current_command, torque_window
from acdrive.scenarios import build_setup, load_scenario


def short_ramp(duration=0.1, **overrides):
    setup = load_scenario("bodson-ramp")
    return dataclasses.replace(setup, duration=duration, **overrides)


def relative_error(a, b):
    return np.max(np.abs(a - b)) / np.max(np.abs(b))


@pytest.mark.slow
def test_engine_matches_radau_reference():
    """RK4 between samples agrees with solve_ivp(Radau, rtol 1e-10) to 1e-6 relative."""
    setup = dataclasses.replace(load_scenario("bodson-ramp"), duration=0.12)
    setup = dataclasses.replace(
        setup,
        motors=(
            dataclasses.replace(setup.motors[0], speed_reference=Profile([0.0, 0.12], [0.0, 40.0])),
        ),
    )
    fast = simulate(setup)
    reference = simulate_slow(setup, method="Radau")
    for name in ("w", "i_s_mag", "i_r_mag", "i_rx", "i_ry"):
        assert relative_error(fast.signal(name), reference.signal(name)) < 1e-6, name


class PlainPythonController:
    """A user-written voltage-command controller built from acdrive's public physics functions
    (Bodson (20), (22), (25), limits (30)-(37)), with its own speed estimate and the nominal
    supply frequency, run in place of the compiled ``SpeedController`` part: same inputs and
    outputs, read and written through that part's declarations."""

    def __init__(self, params, gains, i_max, T_s, w_e):
        from acdrive.machines import machine_vector

        self.p, self.g, self.i_max, self.T_s, self.w_e = (
            machine_vector(params),
            gains,
            i_max,
            T_s,
            w_e,
        )
        self.e_int, self.theta_prev, self.w, self.started = 0.0, None, 0.0, False

    def step(self, t, T_s, u, p, s, y):
        from acdrive.control import SpeedController

        inputs = SpeedController.INPUTS.unpack(u)
        theta_meas, v_s, w_ref = inputs["theta"], inputs["v_s"], inputs["w_ref"]
        v_r_slot = SpeedController.OUTPUTS.slot("v_r")
        if not self.started:  # the loop's first sample: hold the converter's initial voltage
            self.started, self.theta_prev = True, theta_meas
            y[v_r_slot : v_r_slot + 2] = s[SpeedController.STATES.slot("v_r") :][:2]
            return 0
        self.w = (theta_meas - self.theta_prev) / self.T_s
        self.theta_prev = theta_meas
        v = abs(v_s)
        lo, hi, _ = torque_window(self.p, self.w_e, v, self.i_max, self.i_max)
        tau, self.e_int, _ = speed_pi(
            self.g.K_P, self.g.K_I, self.g.K_F, self.e_int, w_ref, self.w, lo, hi, self.T_s
        )
        i_s, _ = stator_current_command(self.p, self.w_e, v, tau, 0.0)
        v_r = rotor_voltage_for(self.p, self.w_e, self.w, v, i_s)
        v_r = v_r * (v_s / v) * np.exp(-1j * self.p[N_P] * theta_meas)
        y[v_r_slot], y[v_r_slot + 1] = v_r.real, v_r.imag
        y[SpeedController.OUTPUTS.slot("tau_com")] = tau
        return 0


def test_plain_python_controller_gives_the_compiled_result():
    setup = short_ramp(0.1)
    motor = setup.motors[0]
    ctrl = PlainPythonController(
        motor.machine,
        motor.controller.gains,
        math.sqrt(1.5) * 6.0,
        setup.sample_time,
        2 * math.pi * 60,
    )
    slow = simulate_slow(setup, python_steps={"controller0": ctrl.step})
    fast = simulate(setup)
    for name in ("w", "i_s_mag", "i_r_mag", "i_rx", "tau_com"):
        assert np.allclose(slow.signal(name), fast.signal(name), rtol=1e-7, atol=1e-9), name


def test_slow_path_with_the_compiled_parts_is_the_fast_loop():
    """The slow path runs the same compiled pieces: with the loop's own RK4 it gives the fast
    loop's numbers to rounding (the fast loop's borrowed arrays are a second specialisation of
    the fast-math plant code, whose contractions may differ in the last bit)."""
    setup = short_ramp(0.05)
    slow, fast = simulate_slow(setup, method="RK4"), simulate(setup)
    scale = np.maximum(np.max(np.abs(fast.signals), axis=(0, 1)), 1e-300)
    assert np.all(np.max(np.abs(slow.signals - fast.signals), axis=(0, 1)) <= 1e-12 * scale)


def scenario(**motor_extra):
    data = {
        "name": "test",
        "simulation": {"duration": 3.0},
        "motor": [
            {
                "speed_reference_rpm": [[0, 0], [0.2, 0], [1.2, 600], [3.0, 600]],
                "controller": {"speed_bandwidth": 60.0},
                **motor_extra,
            }
        ],
    }
    return build_setup(data)


def test_tracks_reference_and_torque_balances_load():
    """At constant speed the electromagnetic torque equals the load plus friction (26)."""
    load, B = 0.05, 1e-4
    result = simulate(scenario(load_torque=load, viscous_friction=B))
    late = result.t > 2.5
    w = result.signal("w")[late]
    assert np.max(np.abs(result.speed_rpm()[late] - 600)) < 1.0
    assert np.mean(result.signal("tau_e")[late]) == pytest.approx(load + B * np.mean(w), rel=2e-3)
    # rotor current frequency equals the slip frequency w_e - n_p w (Bodson IV-B)
    i_x = result.signal("i_rx")[late]
    crossings = np.count_nonzero(np.diff(np.sign(i_x)) > 0)
    slip_hz = 60.0 - 2 * 600 / 60.0
    assert crossings == pytest.approx(slip_hz * 0.5, abs=1.5)


def test_rotor_sequence_reverses_above_synchronous_speed():
    """Below synchronous speed the rotor currents are in forward sequence, above it in reverse."""

    def sequence(rpm):
        data = {
            "simulation": {"duration": 1.5},
            "motor": [
                {
                    "speed_reference_rpm": [[0, rpm], [1.5, rpm]],
                    "initial_speed_rpm": rpm,
                    "controller": {"speed_bandwidth": 60.0},
                }
            ],
        }
        r = simulate(build_setup(data))
        i_x, i_y = r.signal("i_rx")[-2000:], r.signal("i_ry")[-2000:]
        vector = i_x + 1j * (i_x + 2 * i_y) / np.sqrt(3)  # (3) with theta_e = 0, scaled
        return np.sign(np.mean(np.diff(np.unwrap(np.angle(vector)))))

    assert sequence(1500) > 0 and sequence(2100) < 0


def test_supply_collapse_holds_output_and_records_event():
    data = {
        "simulation": {"duration": 0.3},
        "supply": {"voltage_pk_profile": [[0, 11.1], [0.1, 11.1], [0.12, 0.0], [0.3, 0.0]]},
        "motor": [{"speed_reference_rpm": [[0, 0], [0.3, 0]]}],
    }
    result = simulate(build_setup(data))
    assert np.all(np.isfinite(result.signals))
    assert result.events()["supply_lost"] > 0
    assert result.first_event_time("supply_lost") > 0.1


def test_step_beyond_limits_records_limit_events_without_nan():
    data = {
        "simulation": {"duration": 0.5},
        "motor": [{"speed_reference_rpm": [[0, 0], [0.05, 0], [0.05, 1500], [0.5, 1500]]}],
    }
    result = simulate(build_setup(data))
    assert np.all(np.isfinite(result.signals))
    assert result.events()["torque_limit"] > 0
    tau = result.signal("tau_com")
    assert np.max(tau) <= 0.2741 + 1e-9  # the on-line case-1 limit (37)


def test_batch_axis_runs_variants_in_parallel():
    """Variants of one drive (load torques) in the compiled batch loop equal single runs."""
    loads = (0.0, 0.03, 0.06)
    setups = [scenario(load_torque=tl) for tl in loads]
    drive = DFIMDrive(setups[0])
    initial, held = drive.initial()
    batch = drive.compile().run_batch(
        [{"shaft0": {"load": tl}} for tl in loads], setups[0].duration, setups[0].sample_time,
        setups[0].substeps, initial=initial, held=held, log=drive.log_ports(),
    )  # fmt: skip
    for result, s in zip(batch, setups, strict=True):
        assert np.array_equal(drive.drive_result(result).signals, simulate(s).signals)
    assert not np.array_equal(batch[0].data, batch[2].data)


def test_speed_oscillation_metric_recovers_a_known_sinusoid():
    from acdrive.drives.dfim._result import LOG_NAMES, DriveResult

    t = np.arange(20000) * 200e-6
    signals = np.zeros((t.size, 1, len(LOG_NAMES)))
    amplitude_rpm, f = 12.0, 47.0
    signals[:, 0, LOG_NAMES.index("w")] = (
        (500 + amplitude_rpm * np.sin(2 * np.pi * f * t)) * np.pi / 30
    )
    signals[:, 0, LOG_NAMES.index("w_ref")] = 500 * np.pi / 30 + 0.01 * t  # slow drift: out of band
    r = DriveResult(
        name="synthetic", t=t, signals=signals, sample_time=200e-6, final_state=np.zeros(1)
    )
    rms, hz = r.speed_oscillation()
    assert rms == pytest.approx(amplitude_rpm / np.sqrt(2), rel=0.02)
    assert hz == pytest.approx(f, abs=0.5)


@pytest.mark.slow
def test_paper_gains_limit_cycle_in_voltage_mode_only():
    """The finding stated in docs/stability.md: at a_D,VEL = 314 rad/s voltage command oscillates
    near the supply frequency, current command does not, and voltage command at 100 rad/s does
    not."""

    def oscillation(mode, bandwidth, **converter):
        data = {
            "simulation": {"duration": 1.5},
            "motor": [
                {
                    "speed_reference_rpm": [[0, 0], [0.1, 0], [1.1, 900], [1.5, 900]],
                    "controller": {"mode": mode, "speed_bandwidth": bandwidth},
                    **converter,
                }
            ],
        }
        return simulate(build_setup(data)).speed_oscillation()

    rms, hz = oscillation("voltage", 314.0)
    assert rms > 2.0 and 35 < hz < 65
    # a bench converter's dead time and device drops (1.6 V of fundamental) damp it
    bench = {
        "converter_dead_time": 1e-6,
        "converter_switching_frequency": 1e4,
        "converter_device_drop": 0.7,
    }
    assert oscillation("voltage", 314.0, **bench)[0] < 0.5
    assert oscillation("current", 314.0)[0] < 0.5
    assert oscillation("voltage", 100.0)[0] < 0.5


def test_converter_loss_opposes_rotor_current():
    """First-harmonic dead-time / drop model: the applied rotor voltage differs from the command by
    sqrt(3/2) (4/pi) (V_dc t_d f_sw + V_drop) along -i_R / |i_R|."""
    from acdrive.drives.dfim._setup import ConverterLosses

    losses = ConverterLosses(dead_time=2e-6, switching_frequency=1e4, device_drop=0.5)
    expected = np.sqrt(1.5) * 4 / np.pi * (30.0 * 2e-6 * 1e4 + 0.5)
    assert losses.fundamental_loss(30.0) == pytest.approx(expected)
    ideal = short_ramp(0.01)
    ideal = dataclasses.replace(
        ideal, motors=(dataclasses.replace(ideal.motors[0], converter=ConverterLosses()),)
    )
    lossy = dataclasses.replace(
        ideal, motors=(dataclasses.replace(ideal.motors[0], converter=losses),)
    )
    derivatives = []
    for setup in (ideal, lossy):
        drive = DFIMDrive(setup)
        compiled, (initial, held) = drive.compile(), drive.initial()
        X, _ = drive.system.pack_initial(initial)
        Y = drive.system.pack_held(held)
        a = drive.system.slots["converter0"].y[0]
        Y[a], Y[a + 1] = 3.0, 1.0  # held rotor voltage 3 + 1j (rotor coordinates)
        dX = compiled.derivatives(0.0, X, Y)
        o = drive.system.slots["dfim0"].x[0] + drive.motors[0]["dfim"].STATES.slot("psi_r")
        derivatives.append(complex(dX[o], dX[o + 1]))  # d psi_r / dt
        i_r = complex(X[o], X[o + 1]) / setup.motors[0].machine.L_r  # i_s = 0 at t = 0
    direction = i_r / abs(i_r)
    assert derivatives[1] - derivatives[0] == pytest.approx(-expected * direction, rel=1e-3)


def test_numerical_blow_up_is_an_error_not_nan():
    """An integration step beyond the stability limit of RK4 (h |lambda| > 2.8 for the fast electrical
    pole, here h = 2 ms on a rotor of 8 ohm: about 3,400 1/s) makes the state blow up; the engine
    stops and says so instead of returning NaN. (A 10 ms control period is refused before it
    runs: drives.dfim._period.)"""
    params = {"R_s": 0.66, "R_r": 8.0, "L_s": 13.1e-3, "L_r": 9.8e-3, "M": 9.7e-3, "n_p": 2,
              "J": 3.5e-4}  # fmt: skip
    data = {
        "simulation": {"duration": 2.0, "sample_time": 2e-3, "substeps": 1},
        "motor": [
            {"speed_reference_rpm": [[0, 0], [2, 0]], "controller": {"speed_bandwidth": 10.0},
             "params": params}
        ],
    }  # fmt: skip
    with pytest.raises(RuntimeError, match="diverged"):
        simulate(build_setup(data))
