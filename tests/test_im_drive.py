"""The cage induction motor drive (``sim.im_drive``) and its built-in scenarios (Amezquita-Brooks
et al., sections VI-VIII), checked against physics and the linear models, not against numbers
copied from runs: the tracking error against the ICAD model's sensitivity, switching against
averaged inverter over carrier periods, torque balance, the saturated ramp of (21), the P-PI
position cascade, the step responses against the linear closed loops; the summary against the
logged data; the loader's rules; the command's outputs and one-line errors.

The runs reuse the built-in scenarios' topologies (one compiled loop each, cached on disk)."""

from __future__ import annotations

import dataclasses
import json
import math
import subprocess
import sys
from typing import ClassVar

import numpy as np
import pytest
from scipy.signal import lsim, lti

from acdrive._frames import complex_to_abc
from acdrive.analysis import plant_from_params
from acdrive.cli import main
from acdrive.core import Profile
from acdrive.drives.cage_im import IMDrive, IMDriveResult, IMDriveSetup, run_im_scenario
from acdrive.drives.cage_im._outputs import closed_loop_reference_ss, linear_step_response
from acdrive.drives.cage_im._physics import foc_voltage, modulation_signals
from acdrive.drives.cage_im._schema import build_im_setup
from acdrive.errors import InputError, SimulationDiverged
from acdrive.scenarios._loader import builtin_names, builtin_text, load_scenario

IM_SCENARIOS = (
    "im-locked-rotor",
    "im-foc-speed",
    "im-foc-position",
    "im-icad-vs-pi",
    "im-step-responses",
    "im-perturbed",
)


def _ideal_inverter(setup: IMDriveSetup, **changes) -> IMDriveSetup:
    inverter = dataclasses.replace(setup.inverter, dead_time=0.0, device_drop=0.0, **changes)
    return dataclasses.replace(setup, inverter=inverter)


def _with_controller(setup: IMDriveSetup, name: str) -> IMDriveSetup:
    cc = dataclasses.replace(setup.current_control, controller=name)
    return dataclasses.replace(setup, current_control=cc, compare_controllers=())


def _finite(result: IMDriveResult) -> None:
    for name, values in result.signals.items():
        assert np.all(np.isfinite(values)), name


@pytest.fixture(scope="module")
def outcomes():
    """Every built-in scenario run once (the figures are not drawn here)."""
    return {name: run_im_scenario(load_scenario(name)) for name in IM_SCENARIOS}


# --- the built-ins ------------------------------------------------------------------------------


def test_the_builtins_are_listed_short_and_state_their_assumptions(capsys):
    assert main(["scenarios"]) == 0
    listing = capsys.readouterr().out
    for name in IM_SCENARIOS:
        assert name in builtin_names()
        setup = load_scenario(name)
        assert isinstance(setup, IMDriveSetup)
        assert setup.duration <= 2.0 and setup.sample_time == 2e-5  # the paper's 50 kHz
        assert "Assumed" in setup.note or "linear" in setup.note
        line = next(row for row in listing.splitlines() if row.startswith(name))
        assert "Amezquita-Brooks Fig" in line
        assert 'drive = "cage-im"' in builtin_text(name)


@pytest.mark.slow
def test_no_run_returns_nan(outcomes):
    for outcome in outcomes.values():
        for result in outcome.results.values():
            _finite(result)
    # a logged non-finite value is refused, never returned
    result = outcomes["im-step-responses"].main
    drive = IMDrive(result.setup)

    class Raw:  # a SystemResult whose stator current went non-finite
        t = result.t
        events: ClassVar[dict] = {"current": {"saturated": 0}, "inverter": {"overmodulation": 0}}
        event_log = np.zeros((result.t.size, 10), dtype=np.int64)
        wall_time, steps = 0.0, 1

        @staticmethod
        def signal(port):
            values = np.ones(result.t.size, dtype=complex if port.var.kind == "complex" else float)
            if port.path == "machine.i_s":
                values[7] = np.nan
            return values

    with pytest.raises(SimulationDiverged, match=r"logged signal i_s is not finite"):
        ports = drive.log_ports()
        events, flags = drive.event_counts(Raw), drive.event_flags(Raw)
        IMDriveResult.from_system(drive.setup, Raw, ports, events, flags)


# --- locked rotor (Fig. 11) -----------------------------------------------------------------


def predicted_rms_error(params, k, w_ref: float, amplitude: float, w_shaft: float = 0.0):
    """RMS phase error of the linear closed loop (plant (1) at w_r, diag(k, k)) in steady state
    for the balanced reference i_alpha = A cos(w t), i_beta = A sin(w t): the error vector is
    (I - T(jw)) [1, -j] A (phasors), its mean square over the two axes /2 per axis."""
    plant = plant_from_params(params, params.n_p * w_shaft)
    A, B, C = closed_loop_reference_ss(plant, k)
    T = C @ np.linalg.solve(1j * w_ref * np.eye(A.shape[0]) - A, B)
    E = (np.eye(2) - T) @ np.array([1.0, -1j]) * amplitude
    return math.sqrt((abs(E[0]) ** 2 + abs(E[1]) ** 2) / 4.0)


def test_locked_rotor_summary_is_the_logged_data_and_20_beats_the_pi(outcomes):
    outcome = outcomes["im-locked-rotor"]
    summary, setup = outcome.summary, outcome.setup
    errors = {}
    for label, result in outcome.results.items():
        late = result.t >= setup.metrics_from
        e = result.signal("i_ref")[late] - result.signal("i_s")[late]
        a, b, c = complex_to_abc(e)  # the three phase errors (Bodson (2))
        rms = math.sqrt(np.mean(np.concatenate([a, b, c]) ** 2))
        assert summary[f"current_rms_error_{label}_a"] == pytest.approx(rms, rel=1e-10)
        assert summary["runs"][label]["current_rms_error_a"] == pytest.approx(rms, rel=1e-10)
        # the reference is a balanced 1 A phase peak set: an RMS phase current of 1/sqrt(2) A
        ref = np.concatenate(complex_to_abc(result.signal("i_ref")[late]))
        assert math.sqrt(np.mean(ref**2)) == pytest.approx(1.0 / math.sqrt(2.0), rel=1e-12)
        assert result.summary["current_rms_reference_a"] == pytest.approx(1.0 / math.sqrt(2.0))
        errors[label] = rms
        assert result.setup.current_control.controller == dict(setup.compare_controllers)[label]
        assert np.all(result.signal("w") == 0.0)  # locked rotor
    # the first run at the top level (two formulas of the same RMS: equal to rounding)
    assert summary["current_rms_error_a"] == summary["runs"]["icad"]["current_rms_error_a"]
    assert summary["current_rms_error_a"] == pytest.approx(errors["icad"], rel=1e-12)
    # (20)'s high loop gain around the rotor frequency (sec. V-C) against the PI's (sec. VI-D)
    assert errors["icad"] < errors["pi"] / 4


@pytest.mark.slow
@pytest.mark.parametrize("controller", ["paper-20", "paper-pi"])
def test_steady_tracking_error_is_the_icad_models_sensitivity(controller):
    """With the averaged inverter (ideal devices, 5 kHz latch) the steady RMS error of the
    simulated drive equals the linear closed loop's |(I - T(j 300)) r| within 1 %: the plant
    part, the discretised controller and the hold add nothing at 300 rad/s that the ICAD model
    misses."""
    setup = _with_controller(load_scenario("im-locked-rotor"), controller)
    setup = _ideal_inverter(setup, model="averaged")
    result = IMDrive(setup).run()
    ref = setup.current_reference
    expected = predicted_rms_error(
        setup.plant, setup.current_control.lti, ref.frequency, ref.amplitude_pk
    )
    assert result.current_rms_error() == pytest.approx(expected, rel=0.01)


def test_switching_and_averaged_agree_over_carrier_periods():
    """The averaged model is the switching inverter's carrier-period average: with ideal
    devices the stator current and the latched command averaged over each carrier period agree
    to 0.1 % of their peaks (the ripple's effect); the logged modulation signal of the switching
    inverter is its latched command's, as the averaged model computes it."""
    base = _with_controller(load_scenario("im-locked-rotor"), "paper-20")
    runs = {m: IMDrive(_ideal_inverter(base, model=m)).run() for m in ("switching", "averaged")}
    n = base.carrier_samples
    for name in ("i_s", "v_pwm"):
        means = []
        for result in runs.values():
            x = result.signal(name)[result.t >= base.metrics_from]
            means.append(x[: x.size // n * n].reshape(-1, n).mean(axis=1))
        scale = np.max(np.abs(means[1]))
        assert np.max(np.abs(means[0] - means[1])) < 1e-3 * scale, name
    sw = runs["switching"]
    # the switching pattern differs from the averaged voltage sample by sample
    assert np.max(np.abs(sw.signal("v") - sw.signal("v_pwm"))) > 0.3 * 310.0
    m_a = modulation_signals(sw.signal("v_pwm"), sw.signal("v_dc"))[0]
    np.testing.assert_allclose(sw.signal("m_a"), m_a, atol=1e-12)


# --- FOC speed (Fig. 13) --------------------------------------------------------------------


def test_speed_step_reaches_the_reference_and_rejects_the_brake(outcomes):
    outcome = outcomes["im-foc-speed"]
    result, s = outcome.main, outcome.setup
    t, w, tau_e = result.t, result.signal("w"), result.signal("tau_e")
    (t_load,) = result.load_changes()
    # magnetised start: the currents stay on their references (within the transient of the
    # inverter's dead time and drops, which the bumpless controller state does not know) and
    # the shaft stays still
    before_step = t < 0.05
    i_d = s.foc.psi_ref[1][0] / s.machine.L_m
    error = np.abs(result.signal("i_s") - result.signal("i_ref"))
    assert np.max(error[before_step]) < 0.03 * i_d
    assert np.max(error[(t > 0.04) & before_step]) < 1e-3 * i_d
    assert np.max(np.abs(w[before_step])) < 1e-6
    # acceleration at the torque limit: (tau_max - friction) / J
    ramp = (t > 0.05) & (w > 15.0) & (w < 100.0)
    slope = np.polyfit(t[ramp], w[ramp], 1)[0]
    friction = float(s.mechanics.friction_torque(np.array([57.5]))[0])
    assert slope == pytest.approx((s.speed_pi.tau_max - friction) / s.mechanics.J, rel=0.02)
    # the reference is reached before the brake and held after it
    w_ref = 150.0
    settled = (t > t_load - 0.1) & (t < t_load)
    assert np.max(np.abs(w[settled] - w_ref)) < 1e-3 * w_ref
    end = t > t[-1] - 0.1
    assert np.max(np.abs(w[end] - w_ref)) < 1e-3 * w_ref
    # the dip: the speed PI's load response with an ideal torque, -(tau_L / J) t e^{-a t}
    # (double root at -a), is a dip of tau_L / (e a J); the brake adds a little damping
    tau_l = s.mechanics.brake[1][-1] * w_ref
    a = math.sqrt(s.speed_pi.K_I / s.mechanics.J)
    dip = result.summary["load_changes"][0]["max_deviation_rad_s"]
    assert -dip == pytest.approx(tau_l / (math.e * a * s.mechanics.J), rel=0.1)
    # steady torque balance tau_e = load + brake + friction, against the logged shaft speed
    # (logged twice per carrier period, always at the same points of the PWM ripple: the mean
    # of those samples is off the true mean by a fraction of a percent)
    load = s.mechanics.external_torque(t[end], w[end])
    fr = s.mechanics.friction_torque(w[end])
    assert np.mean(tau_e[end]) == pytest.approx(np.mean(load + fr), rel=1e-2)
    balance = outcome.summary["torque_balance"]
    assert abs(balance["residual_n_m"]) < 1e-2 * balance["load_n_m"]
    assert balance["load_n_m"] == pytest.approx(np.mean(load), rel=1e-4)
    # Fig. 13(d): the modulation signal stays within the linear range
    assert np.max(np.abs(result.signal("m_a")[t > 0.1])) < 1.0
    # the DC link holds the rated flux at 150 rad/s (foc_voltage): no voltage warning
    check = outcome.summary["voltage_check"]
    assert check["needed_at_torque_limit_v"] < check["limit_v"]


def test_a_dc_link_too_low_for_the_flux_is_reported_not_refused():
    """100 V cannot hold the rated flux at 150 rad/s (foc_voltage: 147 V at no load against
    71 V, space vectors): the run goes ahead, the current controller saturates, and the summary says so with
    the numbers."""
    setup = load_scenario("im-foc-speed")
    inverter = dataclasses.replace(setup.inverter, dc_link=Profile.constant(100.0))
    setup = dataclasses.replace(setup, inverter=inverter, duration=0.3)
    outcome = run_im_scenario(setup)
    check = outcome.summary["voltage_check"]
    # phase peak volts: the space-vector magnitudes over sqrt(3/2) (Bodson (8))
    assert check["limit_v"] == pytest.approx(100.0 / math.sqrt(3))
    assert check["needed_no_load_v"] == pytest.approx(
        abs(foc_voltage(setup.plant, 0.964, 0.0, 150.0)) / math.sqrt(1.5)
    )
    assert check["needed_no_load_v"] > check["limit_v"]
    assert outcome.summary["events"]["current_controller_saturation"] > 0
    warning = outcome.summary["warnings"][0]
    assert f"{check['needed_no_load_v']:.0f} V (no load)" in warning
    assert f"{check['limit_v']:.0f} V the DC link gives" in warning
    _finite(outcome.main)


# --- the saturated ramp of (21) (Fig. 16) ----------------------------------------------------


def test_saturated_ramp_slope_is_tau_max_over_J_and_the_pi_falls_behind(outcomes):
    outcome = outcomes["im-icad-vs-pi"]
    s, summary = outcome.setup, outcome.summary
    J, tau_max, k_p = s.mechanics.J, s.speed_p.tau_max, s.speed_p.k_p
    t_step = 0.05
    t_sat = t_step + J * (376.0 - tau_max / k_p) / tau_max
    for label, result in outcome.results.items():
        t, w = result.t, result.signal("w")
        window = (t >= t_step) & (t <= t_sat)
        ideal = w[np.searchsorted(t, t_step)] + tau_max / J * (t[window] - t_step)
        rms = math.sqrt(np.mean((w[window] - ideal) ** 2))
        assert summary[f"speed_ramp_error_{label}"] == pytest.approx(rms, rel=1e-9)
        assert result.events["torque_limit"] > 0
    ramp = summary["runs"]["icad"]["ramp"]
    # friction (B w + tau_c) over the ramp's fitted middle is at most that at the top speed
    most = float(s.mechanics.friction_torque(np.array([376.0]))[0])
    assert (tau_max - most) / J * 0.99 <= ramp["ramp_slope_rad_s2"] <= tau_max / J * 1.01
    assert ramp["ideal_slope_rad_s2"] == pytest.approx(tau_max / J)
    # with the PI the torque falls short (sec. VI-D): slower ramp, larger ramp error
    assert summary["ramp_slope_pi_rad_s2"] < 0.9 * ramp["ramp_slope_rad_s2"]
    assert summary["speed_ramp_error_pi"] > 5 * summary["speed_ramp_error_icad"]
    # (21) has no integral: it settles below the reference, where the torque it commands
    # holds the friction (the steady torque balance)
    balance = summary["runs"]["icad"]["torque_balance"]
    assert 0.0 < 376.0 - summary["runs"]["icad"]["speed_final_rad_s"] < 1.0
    assert balance["tau_e_n_m"] == pytest.approx(balance["friction_n_m"], rel=0.02)


# --- position (Fig. 14) ---------------------------------------------------------------------


def test_position_settles_and_rejects_the_active_load_as_the_cascade_predicts(outcomes):
    outcome = outcomes["im-foc-position"]
    result, s = outcome.main, outcome.setup
    t, theta = result.t, result.signal("theta")
    (t_load,) = result.load_changes()
    target = float(s.position_reference[1][-1])
    assert abs(theta[np.searchsorted(t, t_load) - 1] - target) < 2e-3
    assert abs(outcome.summary["position_final_error_rad"]) < 1e-3  # the speed PI's integral
    assert abs(theta[-1] - target) < 1e-3
    # the load deviation: the linear P-PI cascade with an ideal torque, J s^2 theta =
    # (K_P + K_I / s)(K_th (r - theta) - s theta) - tau_L (viscous friction added to J s)
    J, B = s.mechanics.J, s.mechanics.B
    K_P, K_I, K_th = s.speed_pi.K_P, s.speed_pi.K_I, s.position.K_theta
    tau_l = float(s.mechanics.load[1][-1])
    after = t >= t_load
    _, lin, _ = lsim(
        lti([-tau_l, 0.0], [J, K_P + B, K_I + K_th * K_P, K_th * K_I]),
        np.ones(after.sum()),
        t[after] - t_load,
    )
    dev = outcome.summary["load_changes"][0]["max_deviation_rad"]
    assert dev == pytest.approx(lin.min(), rel=0.1)


# --- step responses (Figs. 18, 20) ----------------------------------------------------------


def test_step_responses_match_the_linear_loops_without_the_pwm_hold():
    """A command updated every sample (f_pwm = 1 / T_s, averaged) gives the continuous linear
    closed loop's alpha step response to within 0.05 of the step (sampling at 50 kHz); the
    5 kHz hold of the built-in scenario adds delay, and with it overshoot, most to the PI of
    lowest phase margin (Fig. 18's)."""
    base = load_scenario("im-step-responses")
    fast = dataclasses.replace(base.inverter, model="averaged", f_pwm=1.0 / base.sample_time)
    ref = base.current_reference
    for label, name in base.compare_controllers:
        setup = dataclasses.replace(_with_controller(base, name), inverter=fast)
        result = IMDrive(setup).run()
        after = result.t >= ref.start
        t = result.t[after] - ref.start
        sim = result.phase_peak("i_s")[after] / ref.amplitude_pk
        lin = linear_step_response(setup.plant, 375.0, setup.current_control.lti, t)
        assert np.max(np.abs(sim.real - lin[:, 0])) < 0.05, label
        assert np.max(np.abs(sim.imag - lin[:, 1])) < 0.005, label


def test_step_summary_and_the_papers_ordering(tmp_path, outcomes):
    from acdrive.drives.cage_im._outputs import write_im_outcome

    outcome = outcomes["im-step-responses"]
    summary = write_im_outcome(outcome, tmp_path, figures=False)
    over = {label: summary[f"step_overshoot_{label}"] for label in outcome.results}
    linear = {label: summary[f"linear_step_overshoot_{label}"] for label in outcome.results}
    # sec. VII: the inner PI of (22) overshoots least, the high-integral-gain PI most
    for values in (over, linear):
        assert values["inner_pi"] < values["icad"] < values["high_ki_pi"]
    for label, result in outcome.results.items():
        after = result.t >= outcome.setup.current_reference.start
        sim = result.phase_peak("i_s")[after].real / outcome.setup.current_reference.amplitude_pk
        assert over[label] == pytest.approx(sim.max() - 1.0, rel=1e-12)
        assert result.events["current_controller_saturation"] == 0  # linear throughout
    # the hold delay adds overshoot to the loop of least phase margin
    assert over["high_ki_pi"] > linear["high_ki_pi"] + 0.05


# --- perturbed plant (Fig. 23) ---------------------------------------------------------------


def test_perturbed_plant_is_tracked_by_the_nominal_20(outcomes):
    outcome = outcomes["im-perturbed"]
    s, result = outcome.setup, outcome.main
    n = s.machine
    assert (s.plant.R_s, s.plant.R_r) == (2 * n.R_s, 2 * n.R_r)
    assert (s.plant.L_s, s.plant.L_r, s.plant.L_m) == pytest.approx(
        (0.6 * n.L_s, 0.6 * n.L_r, 0.59 * n.L_m)
    )
    assert s.current_control.controller == "paper-20"
    assert outcome.summary["current_rms_error_relative"] < 0.05
    w = result.signal("w")
    assert 0.0 < w[-1] < 300.0 and np.all(np.diff(w) > -1e-3)  # runs up under the currents
    assert result.events["current_controller_saturation"] < 100  # only the start


# --- the loader's rules ------------------------------------------------------------------------

BASE = """
drive = "cage-im"
name = "bad"
[simulation]
duration = 0.01
{simulation}
[machine]
prescribed_speed_rad_s = 0.0
{machine}
[inverter]
model = "switching"
{inverter}
[current_control]
{control}
[reference]
mode = "current"
{reference}
{extra}
"""


#: case -> (template fields, or "raw" = another template; the message the error starts with)
BAD = {
    "sample time longer than the PWM period": (
        {"simulation": "sample_time = 4e-4"},
        "simulation.sample_time: must not be longer than the PWM period",
    ),
    "sample time not a fraction of the PWM period": (
        {"simulation": "sample_time = 3e-5"},
        (
            "simulation.sample_time: must be the PWM period 1 / inverter.pwm_frequency_hz = "
            "0.0002 s divided by an integer"
        ),
    ),
    "dead time too long": (
        {"inverter": "dead_time_s = 1e-4"},
        "inverter.dead_time_s: must be shorter than half the switching period",
    ),
    "dead time on the averaged model": (
        {
            "inverter": "dead_time_s = 1e-6",
            "raw": BASE.replace('model = "switching"', 'model = "averaged"'),
        },
        'inverter.dead_time_s: applies to model = "switching" only',
    ),
    "unstable sampled loop": (
        {"simulation": "sample_time = 1e-3", "inverter": "pwm_frequency_hz = 1000"},
        "simulation.sample_time: the sampled current loop with controller paper-20",
    ),
    "hold too long for the loop": (
        {"inverter": "pwm_frequency_hz = 1000"},
        "inverter.pwm_frequency_hz: the sampled current loop with controller paper-20",
    ),
    "prewarp beyond nyquist": (
        {"control": "prewarp_rad_s = 2e5"},
        "current_control.prewarp_rad_s: controller paper-20: must lie in (0, pi/T_s)",
    ),
    "unknown controller": (
        {"control": 'controller = "pid"'},
        "current_control.controller: must be one of",
    ),
    "unknown key": ({"machine": "colour = 1"}, "machine.colour: unknown key"),
    "unknown integrator": (
        {"simulation": 'integrator = "euler"'},
        "simulation.integrator: must be one of rk4, rk6",
    ),
    "speed loop on a held shaft": (
        {"raw": BASE.replace('mode = "current"', 'mode = "speed-pi"\nspeed_rad_s = 10.0')},
        "machine.prescribed_speed_rad_s: mode speed-pi controls the shaft: it must be free",
    ),
    "foc in current mode": (
        {"extra": "[foc]\nflux_reference_wb = 0.5"},
        "foc: is not used in mode current",
    ),
    "perturbation without leakage": (
        {"machine": "[machine.perturbation]\nL_m = 1.2"},
        "machine.perturbation.L_m: the perturbed plant: leakage factor",
    ),
    "amplitude of the wrong type": (
        {"reference": 'amplitude_pk_a = "big"'},
        "reference.amplitude_pk_a: must be a number",
    ),
}
FIELDS = ("simulation", "machine", "inverter", "control", "reference", "extra")


def _text(case: str) -> tuple[str, str]:
    parts, message = BAD[case]
    parts = dict(parts)
    raw = parts.pop("raw", None)
    fields = dict.fromkeys(FIELDS, "")
    fields.update(parts)
    return (raw or BASE).format(**fields), message


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_input_names_the_field_and_the_rule(case, tmp_path):
    import tomllib

    text, message = _text(case)
    with pytest.raises(InputError) as info:
        build_im_setup(tomllib.loads(text))
    assert str(info.value).startswith(message), str(info.value)
    assert "\n" not in str(info.value)


def test_other_rules(tmp_path):
    import tomllib

    text, _ = _text("unknown key")
    data = tomllib.loads(text.replace("colour = 1", ""))
    assert isinstance(build_im_setup(data), IMDriveSetup)
    path = tmp_path / "drive.toml"
    path.write_text(text.replace('drive = "cage-im"', 'drive = "pmsm"'))
    with pytest.raises(InputError, match=r'^drive: must be one of "dfim", "cage-im"'):
        load_scenario(path)
    both = dict(data, compare_controllers={"a": "paper-20"})
    both["current_control"] = {"controller": "paper-pi"}
    with pytest.raises(InputError, match=r"^current_control.controller: give either"):
        build_im_setup(both)
    with pytest.raises(InputError, match=r"^compare_controllers.x: must be one of"):
        build_im_setup(dict(data, compare_controllers={"x": "nope"}))


@pytest.mark.parametrize(
    "case",
    [
        "sample time not a fraction of the PWM period",
        "hold too long for the loop",
        "dead time too long",
    ],
)
def test_bad_input_from_the_command_is_one_line_with_exit_code_2(case, tmp_path):
    text, message = _text(case)
    path = tmp_path / "bad.toml"
    path.write_text(text)
    out = subprocess.run(
        [sys.executable, "-m", "acdrive.cli", "run", str(path), "--out", str(tmp_path / "out")],
        check=False,
        capture_output=True,
        text=True,
    )
    assert out.returncode == 2
    assert out.stderr.count("\n") == 1 and message in out.stderr
    assert "Traceback" not in out.stderr
    assert not (tmp_path / "out").exists()


# --- the command ----------------------------------------------------------------------------


@pytest.mark.slow
def test_run_writes_data_figures_and_a_strict_summary(tmp_path):
    out = subprocess.run(
        [sys.executable, "-m", "acdrive.cli", "run", "im-step-responses", "--out", str(tmp_path)],
        check=False,
        capture_output=True,
        text=True,
    )
    assert out.returncode == 0, out.stderr
    folder = tmp_path / "im-step-responses"
    text = (folder / "summary.json").read_text()
    summary = json.loads(text, parse_constant=lambda c: pytest.fail(f"non-strict JSON {c}"))
    assert summary["drive"] == "cage-im" and set(summary["runs"]) == {
        "icad",
        "inner_pi",
        "high_ki_pi",
    }
    assert summary["units"]["i_s_alpha_sv"] == "A" and summary["units"]["tau_e"] == "N m"
    assert (folder / "step_responses.png").exists()
    import pandas as pd

    for label in summary["runs"]:
        assert (folder / label / "currents.png").exists()
        assert (folder / label / "modulation_a.png").exists()
        frame = pd.read_parquet(folder / label / "data.parquet")
        assert len(frame) == 2000
        assert {"t", "i_s_alpha_sv", "i_ref_beta_sv", "m_a", "w"} <= set(frame)
        from acdrive.columns import read_units

        meta = read_units(folder / label / "data.parquet")
        assert list(meta) == list(frame) and meta["i_s_alpha_sv"]["unit"] == "A"
        assert "power-invariant" in meta["i_s_alpha_sv"]["description"]
        notes = (folder / label / "columns.md").read_text()
        assert all(f"| `{name}` |" in notes for name in frame)
    # the printed rows are the summary's numbers
    over = summary["step_overshoot_icad"]
    assert f"{over:.1%}" in out.stdout and "linear ICAD model" in out.stdout
