"""Faults of the DFIM drive as built-in scenarios with checked outcomes (issue "Reliability").

Every fault scenario must run to its end without a non-finite value, keep the current limits or
report every excursion in its summary, and recover its speed after the fault has cleared where
physics and the controller allow it (the summary says so where they do not). The criteria are
computed, not copied from a run:

* recovery: the linearised sampled-data drive at the post-fault operating point
  (``analysis.drive_stability``, the simulator's own loop) gives the slowest decay rate sigma of
  the closed loop; five time constants 5 / sigma after the fault clears the dominant mode has
  fallen to e^-5 (< 1 %), so the speed error must be back within the pre-fault error plus
  ``MODE_SHARE`` e^-5 times the fault's peak error;
* supply faults: the stator voltage the drive sees against the profile (a sag to exactly 50 %, a
  frequency of exactly 57 Hz by the voltage's phase advance) and, for a collapsed phase, the
  symmetrical components of Fortescue: one EMF at zero leaves a positive sequence of 2/3 and a
  negative sequence of -1/3 of the healthy voltage;
* speed ramps: the speed PI (25) with the gains (27) lags a ramp of slope a by
  (1 - K_F) K_P a / K_I in steady state; the backward-difference speed estimate lags the shaft by
  half a sample, so the shaft itself lags by a T_s / 2 less;
* synchronisation (28): the phase error phi decays as e^{-g t}; from the worst start (pi) it is
  within the tolerance after ln(pi / tol) / g, plus the hold time and five rotor time constants
  L_r / R_r for the open-stator flux to build;
* the DC link: the applied rotor voltage never exceeds v_dc(t) / sqrt(2), and the converter
  saturates during a drop exactly when the steady rotor voltage the law (20) needs exceeds it.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import tomllib

import numpy as np
import pytest

from acdrive._frames import K_PEAK, complex_to_abc
from acdrive._jit import STRICT_MATH
from acdrive._toml import constant
from acdrive.analysis import OperatingPoint, linearize
from acdrive.cli import main
from acdrive.control._dfim import EVENT_NAMES
from acdrive.drives.dfim import DFIMDrive
from acdrive.drives.dfim._outcome import OSCILLATION_FINDING_RPM, run_scenario
from acdrive.drives.dfim._result import LOG_NAMES, RPM_PER_RAD_S
from acdrive.errors import InputError
from acdrive.machines import BODSON_DFIM
from acdrive.plant._converter import max_voltage_magnitude
from acdrive.plant._sources import (
    ThreePhaseSource,
    UnbalancedSource,
    source_state_outputs,
    unbalanced_state_outputs,
)
from acdrive.scenarios._loader import build_setup, builtin_names, builtin_text

ALPHA = np.exp(2j * np.pi / 3)
#: a decaying mode is down to e^-5 (< 1 %) of its start after five of its time constants
SETTLE = 5.0
#: the dominant mode may start above the fault's observed peak error (modes of similar size
#: partly cancel at the peak): allow twice the peak for it
MODE_SHARE = 2.0
FAULTS = ("fault-supply-sag", "fault-frequency-step", "fault-phase-loss", "fault-dc-link-drop",
          "fault-forced-close", "fault-sync-at-speed")  # fmt: skip


# --- running scenarios ------------------------------------------------------------------------


def _text(name: str, replace=()) -> str:
    text = builtin_text(name)
    for old, new in replace:
        assert old in text, old
        text = text.replace(old, new)
    return text


@functools.cache
def _outcome(text: str):
    return run_scenario(build_setup(tomllib.loads(text)))


def outcome(name: str, replace=()):
    """The ``ScenarioOutcome`` of built-in ``name`` with the text replacements ``replace``."""
    return _outcome(_text(name, tuple(replace)))


@functools.cache
def _system_run(text: str):
    drive = DFIMDrive(build_setup(tomllib.loads(text)))
    return drive, drive.run()


def system_run(name: str, replace=()):
    """(drive, SystemResult) of built-in ``name``: every logged port as a complex signal."""
    return _system_run(_text(name, tuple(replace)))


def speed_error_rpm(result, motor: int = 0) -> np.ndarray:
    return np.abs(result.reference_rpm(motor) - result.speed_rpm(motor))


def window(t, start, stop=np.inf):
    return (t >= start) & (t < stop)


def assert_same_run(a, b) -> None:
    """Two runs of the same equations by two topologies: identical with strict IEEE arithmetic
    (ACDRIVE_STRICT_MATH=1); with the default fast-math build each topology's compiled loop may
    round differently in the last bit, which a long run amplifies a little (docs/speed.md
    measures up to 4e-10 of a signal's peak between two engines): 1e-9 of each signal's peak."""
    if STRICT_MATH:
        np.testing.assert_array_equal(a.signals, b.signals)
        return
    for j, name in enumerate(LOG_NAMES):
        x, y = a.signals[:, :, j], b.signals[:, :, j]
        peak = max(np.max(np.abs(x)), np.max(np.abs(y)))
        assert np.max(np.abs(x - y)) <= 1e-9 * peak, name


# --- the outcome checks every fault scenario must pass -----------------------------------------


def assert_finite_and_complete(out) -> None:
    """No NaN or inf anywhere, and the run went to its end (a diverged run raises instead)."""
    for result in out.results.values():
        assert np.all(np.isfinite(result.signals))
        assert result.t[-1] + result.sample_time == pytest.approx(out.setup.duration)


def assert_limits_hold_or_reported(out) -> None:
    """Every logged sample above a current limit is counted in ``limit_excursions``; a peak
    beyond the limit by more than OVER_LIMIT_TOLERANCE is named in a warning, none else."""
    from acdrive._reducer_parts import OVER_LIMIT_TOLERANCE

    warnings = out.summary.get("warnings", [])
    for mode, result in out.results.items():
        for k, motor in enumerate(out.setup.motors):
            c = motor.controller
            for name, what, limit in (("i_s_mag", "stator", c.stator_current_limit_pk),
                                      ("i_r_mag", "rotor", c.rotor_current_limit_pk)):  # fmt: skip
                above = int(np.count_nonzero(result.peak(name, k) > limit))
                reported = out.summary["limit_excursions"][mode][k][name]
                assert reported["samples_above"] == above
                named = [w for w in warnings if f"motor {k + 1}: {what} current above" in w]
                beyond = np.max(result.peak(name, k)) > limit * (1 + OVER_LIMIT_TOLERANCE)
                assert len(named) == (1 if beyond else 0)


def slowest_decay(setup, speed_rpm: float, load: float = 0.0, frequency_hz=None) -> float:
    """-max Re(s) [1/s] of motor 0's drive linearised at (speed, load), sampled-data model
    (``analysis.drive_stability`` on the scenario's own setup: its gains, converter loss and
    supply, at ``frequency_hz`` if given): the decay rate of the slowest mode of the speed error.
    Over a range of speeds, the smallest of them is the one to wait for (``slowest_over``)."""
    if frequency_hz is not None:
        supply = dataclasses.replace(setup.supply, frequency_hz=constant(frequency_hz))
        setup = dataclasses.replace(setup, supply=supply)
    result = linearize(setup, OperatingPoint(speed_rpm / RPM_PER_RAD_S, load), "sampled")
    assert result.stable and result.within_limits
    return -result.max_real_part


def slowest_over(setup, speeds_rpm, load: float = 0.0) -> float:
    """The smallest decay rate over the speeds a ramp passes (its ends and middle)."""
    lo, hi = min(speeds_rpm), max(speeds_rpm)
    return min(slowest_decay(setup, s, load) for s in (lo, (lo + hi) / 2, hi))


def assert_recovers(result, t_fault: float, t_clear: float, decay: float) -> tuple:
    """After ``SETTLE`` / decay past the clearing the speed error is back within the pre-fault
    error (0.1 s before the fault) plus ``MODE_SHARE`` e^-SETTLE of the fault's peak error.
    Returns (before, fault peak, after) [rpm]."""
    t, e = result.t, speed_error_rpm(result)
    settled = t_clear + SETTLE / decay
    assert settled < t[-1] - 0.1, "the run must leave time to judge the recovery"
    before = e[window(t, t_fault - 0.1, t_fault)].max()
    peak = e[window(t, t_fault, settled)].max()
    after = e[window(t, settled)].max()
    assert after <= before + MODE_SHARE * math.exp(-SETTLE) * peak, (before, peak, after)
    return before, peak, after


def _operating_point(setup) -> tuple[float, float]:
    """(speed [rpm], load [N m]) the drive holds around the fault: the reference's final value
    and the load at t = 0 (constant in the fault scenarios)."""
    m = setup.motors[0]
    return float(m.speed_reference[1][-1]) * RPM_PER_RAD_S, float(m.load_torque[1][0])


def _step_times(profile) -> tuple[float, float]:
    """(start, end) of a fault written as [[0, x], [t1, x], [t1, y], [t2, y], [t2, x], ...]."""
    times = profile[0]
    assert times[1] == times[2], "the fault starts with a jump (repeated time)"
    return float(times[1]), float(times[3])


def test_the_fault_scenarios_are_built_ins_that_keep_ci_short():
    for name in FAULTS:
        assert name in builtin_names()
        setup = build_setup(tomllib.loads(builtin_text(name)))
        assert setup.duration <= 2.0 and setup.substeps == 4
        note = tomllib.loads(builtin_text(name))["note"]  # copied into summary.json
        assert "Modelled:" in note and "Assumed:" in note


# --- 1. supply sag to 50 % for 100 ms -----------------------------------------------------------

SAG = "fault-supply-sag"


def test_sag_reaches_the_stator_at_half_its_voltage_and_back():
    out = outcome(SAG)
    r, setup = out.main, out.setup
    t_sag, t_back = _step_times(setup.supply.voltage_pk)
    nominal = float(setup.supply.voltage_pk[1][0])
    assert setup.supply.resistance == setup.supply.inductance == 0.0  # stator voltage = source
    v_s = r.peak("v_s_mag")  # peak phase value (8)
    half_sample = r.sample_time / 2
    during = window(r.t, t_sag + half_sample, t_back - half_sample)
    outside = window(r.t, 0.0, t_sag - half_sample) | window(r.t, t_back + half_sample)
    assert np.count_nonzero(during) == round((t_back - t_sag) / r.sample_time) - 1
    np.testing.assert_allclose(v_s[during], 0.5 * nominal, rtol=1e-12)
    np.testing.assert_allclose(v_s[outside], nominal, rtol=1e-12)


def test_sag_is_ridden_through_and_the_speed_recovers():
    out = outcome(SAG)
    setup = out.setup
    assert_finite_and_complete(out)
    assert_limits_hold_or_reported(out)
    t_sag, t_back = _step_times(setup.supply.voltage_pk)
    decay = slowest_decay(setup, *_operating_point(setup))
    before, peak, _ = assert_recovers(out.main, t_sag, t_back, decay)
    assert peak > 10 * before  # the sag is felt: the check above is not empty


# --- 2. supply frequency step 60 -> 57 Hz --------------------------------------------------------

STEP = "fault-frequency-step"


def test_frequency_step_reaches_the_stator_with_continuous_phase():
    drive, res = system_run(STEP)
    setup = drive.setup
    t_step = float(setup.supply.frequency_hz[0][1])
    f_before, f_after = (float(f) for f in setup.supply.frequency_hz[1][[0, -1]])
    v = res.signal(drive.motors[0]["relay"].out.v)  # the stator terminal voltage
    dt = np.diff(res.t)
    f = np.angle(v[1:] * np.conj(v[:-1])) / (2 * np.pi * dt)  # phase advance per sample
    start = res.t[:-1]
    # intervals clear of the step (its sample instant may round to either side)
    before = start + dt < t_step - setup.sample_time / 2
    after = start > t_step + setup.sample_time / 2
    np.testing.assert_allclose(f[before], f_before, rtol=1e-9)
    np.testing.assert_allclose(f[after], f_after, rtol=1e-9)
    # across the step the phase advances by no more than the higher frequency allows: no jump
    assert np.all((f >= f_after * (1 - 1e-9)) & (f <= f_before * (1 + 1e-9)))
    np.testing.assert_allclose(np.abs(v), K_PEAK * setup.supply.voltage_pk[1][0], rtol=1e-12)


def test_frequency_step_moves_the_rotor_currents_to_the_new_slip_frequency():
    """Rotor currents (rotor coordinates) turn at the slip frequency f - n_p w / 2 pi."""
    drive, res = system_run(STEP)
    setup = drive.setup
    n_p = setup.motors[0].machine.n_p
    i_r = res.signal(drive.motors[0]["dfim"].out.i_r_rotor)
    w = res.signal(drive.motors[0]["shaft"].out.w)
    f_rotor = np.angle(i_r[1:] * np.conj(i_r[:-1])) / (2 * np.pi * np.diff(res.t))
    t_step = float(setup.supply.frequency_hz[0][1])
    f_before, f_after = (float(f) for f in setup.supply.frequency_hz[1][[0, -1]])
    decay = slowest_decay(setup, *_operating_point(setup), frequency_hz=f_after)
    for start, stop, f in ((t_step - 0.2, t_step, f_before),
                           (t_step + SETTLE / decay, np.inf, f_after)):  # fmt: skip
        inside = window(res.t[:-1], start, stop)
        slip = f - n_p * w[:-1][inside] / (2 * np.pi)
        # averaged over the window: the slip to 0.1 % (what is left of the decaying transients)
        assert np.mean(f_rotor[inside]) == pytest.approx(np.mean(slip), rel=1e-3)


def test_frequency_step_keeps_the_speed():
    out = outcome(STEP)
    setup = out.setup
    assert_finite_and_complete(out)
    assert_limits_hold_or_reported(out)
    t_step = float(setup.supply.frequency_hz[0][1])
    f_after = float(setup.supply.frequency_hz[1][-1])
    decay = slowest_decay(setup, *_operating_point(setup), frequency_hz=f_after)
    before, peak, _ = assert_recovers(out.main, t_step, t_step, decay)
    assert peak > before  # the step is felt


# --- 3. loss of one supply phase (a collapsed source EMF) -----------------------------------------

PHASE_LOSS = "fault-phase-loss"


def _source_output(part, kernel, t):
    """The source's output at t, its state (theta_g, u_g) at 60 Hz from theta_g(0) = 0."""
    theta = 2 * np.pi * 60.0 * t
    x = np.array([theta, np.cos(theta), np.sin(theta)])
    y = np.zeros(2)
    kernel(t, x, part.p, y)
    return complex(y[0], y[1])


@pytest.mark.parametrize("t", [0.0, 0.0031, 0.0123, 0.4])
def test_unbalanced_source_with_healthy_phases_is_the_balanced_source(t):
    balanced = ThreePhaseSource("grid", V_pk=11.1, f=60.0)
    unbalanced = UnbalancedSource("grid", V_pk=11.1, f=60.0)
    v = _source_output(unbalanced, unbalanced_state_outputs, t)
    expected = _source_output(balanced, source_state_outputs, t)
    assert v == pytest.approx(expected, rel=1e-14, abs=1e-13)
    theta = 2 * np.pi * 60.0 * t
    assert v == pytest.approx(K_PEAK * 11.1 * np.exp(1j * theta), rel=1e-14, abs=1e-13)


@pytest.mark.parametrize("scales", [(0.0, 1.0, 1.0), (1.0, 0.3, 1.0), (0.2, 0.5, 0.9)])
def test_unbalanced_source_is_the_transform_of_its_phase_emfs(scales):
    """v = sqrt(2/3) (e_a + alpha e_b + alpha^2 e_c) (Bodson (1)); the machine's phase voltages
    (2) are the EMFs minus their mean, the voltage of the isolated star point."""
    k_a, k_b, k_c = scales
    part = UnbalancedSource("grid", V_pk=11.1, f=60.0, k_a=k_a, k_b=k_b, k_c=k_c)
    for t in (0.0, 0.0017, 0.0091):
        theta = 2 * np.pi * 60.0 * t
        e = np.array([k * 11.1 * np.cos(theta - phi) for k, phi in zip(
            scales, (0.0, 2 * np.pi / 3, 4 * np.pi / 3), strict=True)])  # fmt: skip
        v = _source_output(part, unbalanced_state_outputs, t)
        expected = math.sqrt(2 / 3) * (e[0] + ALPHA * e[1] + ALPHA**2 * e[2])
        assert v == pytest.approx(expected, rel=1e-13, abs=1e-12)
        np.testing.assert_allclose(complex_to_abc(v), e - e.mean(), rtol=1e-12, atol=1e-12)


def _sequences(t, v, f):
    """(positive, negative) sequence phasors A, B of v(t) = A e^{j w t} + B e^{-j w t}, least
    squares over the samples given."""
    w = 2 * np.pi * f
    basis = np.column_stack([np.exp(1j * w * t), np.exp(-1j * w * t)])
    (a, b), *_ = np.linalg.lstsq(basis, v, rcond=None)
    return a, b


@pytest.mark.slow
def test_phase_loss_leaves_two_thirds_positive_and_one_third_negative_sequence():
    """Fortescue with e_a = 0: positive (0 + 1 + 1)/3 = 2/3, negative (0 + alpha^2 + alpha)/3 =
    -1/3 of the healthy voltage; before and after, a balanced supply (no negative sequence)."""
    drive, res = system_run(PHASE_LOSS)
    setup = drive.setup
    t_loss, t_back = _step_times(setup.supply.phase_scales[0])
    healthy = K_PEAK * float(setup.supply.voltage_pk[1][0])
    f = float(setup.supply.frequency_hz[1][0])
    v_s = res.signal(drive.motors[0]["relay"].out.v)  # the stator terminal voltage
    np.testing.assert_array_equal(v_s, res.signal(drive.grid.out.v))  # no supply impedance
    margin = 2 * setup.sample_time
    during = window(res.t, t_loss + margin, t_back - margin)
    a, b = _sequences(res.t[during], v_s[during], f)
    assert a == pytest.approx(2 / 3 * healthy, rel=1e-9)
    assert b == pytest.approx(-1 / 3 * healthy, rel=1e-9)
    assert abs(b) / abs(a) == pytest.approx(0.5, rel=1e-9)
    for inside in (window(res.t, t_loss - 0.1, t_loss - margin), window(res.t, t_back + margin)):
        a, b = _sequences(res.t[inside], v_s[inside], f)
        assert a == pytest.approx(healthy, rel=1e-9)
        assert abs(b) < 1e-9 * healthy


def test_phase_loss_is_ridden_through_and_the_speed_recovers():
    out = outcome(PHASE_LOSS)
    setup = out.setup
    assert_finite_and_complete(out)
    assert_limits_hold_or_reported(out)
    t_loss, t_back = _step_times(setup.supply.phase_scales[0])
    decay = slowest_decay(setup, *_operating_point(setup))
    before, peak, _ = assert_recovers(out.main, t_loss, t_back, decay)
    assert peak > 10 * before  # the loss is felt


def test_balanced_scenarios_keep_the_balanced_source():
    drive = DFIMDrive(build_setup(tomllib.loads(builtin_text("bodson-step"))))
    assert type(drive.grid) is ThreePhaseSource
    assert build_setup(tomllib.loads(builtin_text("bodson-step"))).supply.phase_scales is None


# --- 4. current-sensor loss (bodson-sensor-fault) ---------------------------------------------------

SENSOR = "bodson-sensor-fault"


def test_sensor_loss_falls_back_to_voltage_command_at_the_fault_time():
    out = outcome(SENSOR)
    r, motor = out.main, out.setup.motors[0]
    t_fault = motor.current_sensor_fault_time
    first = out.summary["sensor_fallback_time_s"]
    assert first == r.first_event_time("sensor_fallback")
    assert t_fault <= first < t_fault + r.sample_time  # the first sample at or after the fault
    flags = r.signal("flags").astype(np.int64)
    fallback = (flags >> EVENT_NAMES.index("sensor_fallback")) & 1
    np.testing.assert_array_equal(fallback, (r.t >= first).astype(np.int64))  # for good
    np.testing.assert_array_equal(r.signal("mode"), np.where(r.t >= first, 0.0, 1.0))
    assert_finite_and_complete(out)
    assert_limits_hold_or_reported(out)


def test_sensor_loss_keeps_the_speed_on_its_ramp():
    """After the fallback the speed follows the ramp with the PI's steady lag, and settles to
    the reference once the ramp ends."""
    out = outcome(SENSOR)
    r, setup = out.main, out.setup
    motor = setup.motors[0]
    g = motor.controller.gains
    times, w_ref = motor.speed_reference
    start, end = float(times[-3]), float(times[-2])  # the ramp [[t0, 0], [start, 0], [end, w]]
    slope = float(w_ref[-2] - w_ref[-3]) / (end - start) * RPM_PER_RAD_S  # rpm/s
    lag = (1 - g.K_F) * g.K_P * slope / g.K_I - slope * setup.sample_time / 2
    t_fb = out.summary["sensor_fallback_time_s"]
    # voltage command from the fallback on: the slowest mode over the speeds still to come
    at_fallback = float(np.interp(t_fb, times, w_ref)) * RPM_PER_RAD_S
    decay = slowest_over(
        setup.with_mode("voltage"), (at_fallback, float(w_ref[-1]) * RPM_PER_RAD_S)
    )
    e = r.reference_rpm() - r.speed_rpm()
    on_ramp = window(r.t, t_fb + SETTLE / decay, end)
    assert np.count_nonzero(on_ramp) > 0.5 / r.sample_time
    np.testing.assert_allclose(e[on_ramp], lag, rtol=0.05)
    held = window(r.t, end + SETTLE / decay)
    assert np.max(np.abs(e[held])) <= MODE_SHARE * math.exp(-SETTLE) * lag


# --- 5. encoder offset of any value at synchronisation ---------------------------------------

SYNC = "bodson-sync"
OFFSETS = (-2.0, 2 * math.pi + 1.0, math.pi - 0.05, math.pi / 2 - 0.01, -7.0)


def _with_offset(offset: float):
    return outcome(SYNC, [("encoder_offset = 2.3", f"encoder_offset = {offset!r}")])


def _law_phase_bound(setup) -> float:
    """Largest phase error theta_adj may keep after closing: what the law (28) omits with the
    stator open, the converter loss R_loss = V_loss / |i_r| in series with Z_R at standstill
    (angle Z_R - angle (Z_R + R_loss)) and the rotor voltage held over one sample while the grid
    turns by w_e T_s, plus the synchroniser's closing tolerance."""
    m, c = setup.motors[0], setup.motors[0].controller
    w_e = 2 * np.pi * float(setup.supply.frequency_hz[1][0])
    i_r = K_PEAK * float(setup.supply.voltage_pk[1][0]) / (w_e * m.machine.M)
    z_r = m.machine.R_r + 1j * w_e * m.machine.L_r
    r_loss = m.converter.fundamental_loss(m.dc_link_voltage) / i_r
    loss_phase = abs(np.angle(z_r) - np.angle(z_r + r_loss))
    return loss_phase + w_e * setup.sample_time + c.sync.tolerance_phase


def _closing_time_bound(setup) -> float:
    """Latest closing (28): phi decays as e^{-g t} from at worst pi to the tolerance, then the
    hold time, plus five rotor time constants L_r / R_r for the open-stator flux to build."""
    sync, m = setup.motors[0].controller.sync, setup.motors[0].machine
    return math.log(math.pi / sync.tolerance_phase) / sync.gain + sync.hold_time + 5 * m.L_r / m.R_r


@pytest.mark.parametrize("offset", OFFSETS)
def test_any_encoder_offset_is_identified_and_the_relay_closes(offset):
    out = _with_offset(offset)
    setup, sync = out.setup, out.summary["synchronisation"]
    assert sync["relay_closed"] and sync["closing_time_s"] <= _closing_time_bound(setup)
    n_p = setup.motors[0].machine.n_p
    error = math.remainder(sync["theta_adj_rad"] - n_p * offset, 2 * math.pi)
    assert sync["theta_adj_error_rad"] == pytest.approx(error, abs=1e-12)
    assert abs(error) <= _law_phase_bound(setup)
    limit = setup.motors[0].controller.stator_current_limit_pk
    if sync["closing_stator_current_peak_a"] > limit:
        assert any("stator current above" in w for w in out.summary["warnings"])
    assert_finite_and_complete(out)
    assert_limits_hold_or_reported(out)


def test_the_offset_left_unidentified_is_the_same_for_every_offset():
    """What theta_adj keeps beyond the offset is the law's own phase error at standstill, the
    same whatever the offset: the closings agree within twice the closing tolerance."""
    errors = [_with_offset(o).summary["synchronisation"]["theta_adj_error_rad"] for o in OFFSETS]
    tolerance = _with_offset(OFFSETS[0]).setup.motors[0].controller.sync.tolerance_phase
    assert max(errors) - min(errors) <= 2 * tolerance


@pytest.mark.parametrize("offset", OFFSETS)
def test_after_any_offset_the_speed_follows_the_ramp(offset):
    out = _with_offset(offset)
    r, setup = out.main, out.setup
    motor = setup.motors[0]
    g = motor.controller.gains
    times, w_ref = motor.speed_reference  # [[0, 0], [start, 0], [end, w], ...]
    start, end = float(times[1]), float(times[2])
    slope = float(w_ref[2] - w_ref[1]) / (end - start) * RPM_PER_RAD_S
    lag = (1 - g.K_F) * g.K_P * slope / g.K_I - slope * setup.sample_time / 2
    decay = slowest_over(setup, (0.0, float(w_ref[2]) * RPM_PER_RAD_S))
    e = r.reference_rpm() - r.speed_rpm()
    on_ramp = window(r.t, start + SETTLE / decay, end)
    assert np.count_nonzero(on_ramp) > 0.1 / r.sample_time
    np.testing.assert_allclose(e[on_ramp], lag, rtol=0.05)


# --- 6a. the synchroniser with the shaft already turning ---------------------------------------

AT_SPEED = "fault-sync-at-speed"


def _at_speed(rpm: float, ref: float | None = None):
    """fault-sync-at-speed with the shaft at ``rpm`` and the reference there (or at ``ref``)."""
    ref = rpm if ref is None else ref
    return outcome(AT_SPEED, [("initial_speed_rpm = 1200.0", f"initial_speed_rpm = {rpm!r}"),
                              ("[[0, 1200], [1.0, 1200]]", f"[[0, {ref!r}], [1.0, {ref!r}]]")])  # fmt: skip


def test_a_reference_the_converter_can_never_hold_is_refused_before_the_run():
    """Below zero speed the slip exceeds 1: the bound is (w_e / n_p)(s_max - 1), not the
    positive one (sim.setup.speed_range)."""
    with pytest.raises(InputError, match=r"motor\[0\]\.speed_reference_rpm: must stay within -"):
        _at_speed(-1500.0)


def _open_stator_voltage(setup, rpm: float) -> float:
    """Rotor voltage magnitude that makes the open stator's voltage equal the grid's at shaft
    speed ``rpm``: i_r = v_g / (j w_e M), v_r = (Z_R + R_loss) i_r with Z_R = R_r + j s w_e L_r
    (Bodson (11), (28)) and the converter loss as a resistance V_loss / |i_r| in series."""
    m = setup.motors[0]
    w_e = 2 * np.pi * float(setup.supply.frequency_hz[1][0])
    i_r = K_PEAK * float(setup.supply.voltage_pk[1][0]) / (w_e * m.machine.M)
    slip_w = w_e - m.machine.n_p * rpm / RPM_PER_RAD_S
    z = m.machine.R_r + m.converter.fundamental_loss(m.dc_link_voltage) / i_r
    return abs(z + 1j * slip_w * m.machine.L_r) * i_r


@pytest.mark.parametrize("rpm", [-1500.0, -600.0, 600.0, 1200.0, 1800.0, 2400.0])
def test_the_relay_closes_at_speed_exactly_where_the_converter_allows(rpm):
    # at -1500 rpm the shaft turns beyond the converter's range; the reference is one it can hold
    out = _at_speed(rpm, ref=-600.0 if rpm < -1000.0 else None)
    setup, sync = out.setup, out.summary["synchronisation"]
    need = _open_stator_voltage(setup, rpm)
    have = float(max_voltage_magnitude(setup.motors[0].dc_link_voltage))
    assert abs(need / have - 1) > 0.05, "choose speeds clearly inside or outside the range"
    assert sync["relay_closed"] == (need < have)
    assert_finite_and_complete(out)
    assert_limits_hold_or_reported(out)
    r = out.main
    if not sync["relay_closed"]:
        # the summary says so, and why; the open stator carries no current, so no torque: the
        # shaft keeps its speed exactly
        (warning,) = [w for w in out.summary["warnings"] if "never closed the relay" in w]
        assert "rotor converter was saturated" in warning
        np.testing.assert_array_equal(r.speed_rpm(), r.speed_rpm()[0])
        return
    assert sync["closing_time_s"] <= _closing_time_bound(setup)
    # after closing the speed is held: tracked, or the summary reports the oscillation
    after = window(r.t, sync["closing_time_s"] + 0.1)
    if "finding" in out.summary:
        assert "the speed oscillates" in out.summary["finding"]
    else:
        assert speed_error_rpm(r)[after].max() < OSCILLATION_FINDING_RPM


def test_the_oscillation_after_closing_at_speed_comes_from_the_adjustments_found():
    """The drive of fault-sync-at-speed started connected at its speed (no synchronisation, an
    aligned encoder): with the m_adj and theta_adj error the synchroniser found it oscillates as
    after the closing; with m_adj = 1 and theta_adj = 0 it holds the speed (judged over the second
    half of the run: started connected at speed, the speed PI's integral starts from zero and
    kicks the shaft at first)."""
    found = outcome(AT_SPEED)
    sync = found.summary["synchronisation"]
    assert "the speed oscillates" in found.summary["finding"]
    text = _text(AT_SPEED, [("encoder_offset = 2.3", "encoder_offset = 0.0"),
                            ("[motor.controller.sync]\nenabled = true", "")])  # fmt: skip
    adjusted = text.replace("K_F = 0.67", f"K_F = 0.67\nm_adj = {sync['m_adj']!r}\n"
                            f"theta_adj = {sync['theta_adj_error_rad']!r}")  # fmt: skip
    assert "the speed oscillates" in _outcome(adjusted).summary["finding"]
    plain = _outcome(text)
    assert "finding" not in plain.summary
    late = plain.main.t >= plain.main.t[-1] / 2
    assert speed_error_rpm(plain.main)[late].max() < OSCILLATION_FINDING_RPM


# --- 6b. forced, unsynchronised closing (mis-operation) ---------------------------------------

FORCED = "fault-forced-close"


@pytest.mark.slow
def test_forced_closing_closes_the_relay_at_its_time_unsynchronised():
    out = outcome(FORCED)
    setup, sync = out.setup, out.summary["synchronisation"]
    motor = setup.motors[0]
    t_force = motor.relay_forced_close_time
    assert sync["relay_forced_close_time_s"] == t_force and sync["closed_by_force"]
    # the contact closes at the first sample instant at or after the forced time
    T_s = out.main.sample_time
    assert t_force - 1e-9 * T_s <= sync["closing_time_s"] < t_force + T_s
    # the synchroniser would have waited for |rho - 1| and |phi| within its tolerances
    tol = motor.controller.sync
    assert sync["voltage_mismatch_at_closing"] > tol.tolerance_magnitude + tol.tolerance_phase
    assert abs(sync["theta_adj_error_rad"]) > tol.tolerance_phase  # offset not identified
    (warning,) = [w for w in out.summary["warnings"] if "closed by force at relay_forced" in w]
    assert f"{sync['theta_adj_error_rad']:+.3f} rad" in warning
    assert_finite_and_complete(out)


def test_forced_closing_inrush_is_reported_and_bounded_by_the_leakage():
    """Closing onto a voltage difference Delta v drives the stator current through the leakage
    (transient) inductance sigma L_s: at most 2 |Delta v| / (w_e sigma L_s) with the offset of a
    suddenly applied sinusoid, a bound it must stay under; here beyond both limits, so the
    excursions must be reported from the closing on."""
    out = outcome(FORCED)
    setup, sync = out.setup, out.summary["synchronisation"]
    m = setup.motors[0]
    assert_limits_hold_or_reported(out)
    excursions = out.summary["limit_excursions"][m.controller.mode][0]
    for name in ("i_s_mag", "i_r_mag"):
        e = excursions[name]
        assert e["samples_above"] > 0
        assert m.relay_forced_close_time <= e["first_time_s"] <= sync["closing_time_s"] + 0.01
    w_e = 2 * np.pi * float(setup.supply.frequency_hz[1][0])
    delta_v = sync["voltage_mismatch_at_closing"] * K_PEAK * float(setup.supply.voltage_pk[1][0])
    bound = 2 * delta_v / (w_e * m.machine.sigma * m.machine.L_s) / K_PEAK  # peak phase value
    assert sync["closing_stator_current_peak_a"] < bound


def test_a_forced_closing_after_synchronisation_changes_nothing():
    plain = outcome(SYNC)
    late = outcome(SYNC, [("encoder_offset = 2.3", "encoder_offset = 2.3\nrelay_forced_close_time = 1.0")])  # fmt: skip
    assert plain.summary["synchronisation"]["closing_time_s"] < 1.0
    assert_same_run(late.main, plain.main)
    assert not late.summary["synchronisation"]["closed_by_force"]
    assert not any("closed by force" in w for w in late.summary.get("warnings", []))


# --- 7. DC-link drop on the rotor converter -------------------------------------------------

DC = "fault-dc-link-drop"


@pytest.mark.slow
def test_the_applied_rotor_voltage_never_exceeds_the_dc_link():
    drive, res = system_run(DC)
    parts = drive.motors[0]
    v_dc = res.signal(parts["dc"].out.v_dc)
    v_r = np.abs(res.signal(parts["converter"].out.v))
    profile = drive.setup.motors[0].dc_link_profile
    t_drop, t_back = _step_times(profile)
    inside = window(
        res.t, t_drop + drive.setup.sample_time / 2, t_back - drive.setup.sample_time / 2
    )
    np.testing.assert_array_equal(v_dc[inside], profile[1][2])
    assert np.all(v_r <= max_voltage_magnitude(v_dc) * (1 + 1e-12))


def _saturated(result) -> np.ndarray:
    flags = result.signal("flags").astype(np.int64)
    return ((flags >> EVENT_NAMES.index("converter_saturation")) & 1).astype(bool)


@pytest.mark.parametrize("low", [15.0, 22.5])
def test_the_converter_saturates_during_a_drop_exactly_when_the_law_needs_more(low):
    """Before the drop the converter applies the law's steady rotor voltage unclipped; during it
    the converter saturates from its first sample if that voltage exceeds low / sqrt(2), and
    never otherwise, nor outside the drop."""
    out = outcome(DC, [("[1.0, 15.0], [1.1, 15.0]", f"[1.0, {low!r}], [1.1, {low!r}]")])
    r = out.main
    t_drop, t_back = _step_times(out.setup.motors[0].dc_link_profile)
    need = r.signal("v_r_mag")[window(r.t, t_drop - 0.1, t_drop)].max()
    saturates = need > max_voltage_magnitude(low)
    assert abs(need / max_voltage_magnitude(low) - 1) > 0.05
    saturated = _saturated(r)
    assert not saturated[~window(r.t, t_drop, t_back)].any()
    assert saturated[np.argmax(r.t >= t_drop)] == saturates
    assert saturated.any() == saturates
    assert (out.summary["limit_events"]["converter_saturation"] > 0) == saturates
    assert_finite_and_complete(out)
    assert_limits_hold_or_reported(out)


def test_after_the_dc_link_drop_the_speed_recovers():
    out = outcome(DC)
    setup = out.setup
    t_drop, t_back = _step_times(setup.motors[0].dc_link_profile)
    decay = slowest_decay(setup, *_operating_point(setup))
    before, peak, _ = assert_recovers(out.main, t_drop, t_back, decay)
    assert peak > 10 * before


def test_a_constant_dc_link_profile_runs_as_the_fixed_dc_link():
    profile = (
        "dc_link_voltage_profile = [[0, 30.0], [1.0, 30.0], [1.0, 15.0], [1.1, 15.0], [1.1, 30.0]]"
    )
    fed = outcome(DC, [(profile, "dc_link_voltage_profile = [[0, 30.0]]")])
    fixed = outcome(DC, [(profile, "dc_link_voltage = 30.0")])
    assert_same_run(fed.main, fixed.main)


# --- the new scenario fields: one-line errors naming field and rule --------------------------

_BASE = "[[motor]]\nspeed_reference_rpm = [[0, 0], [0.02, 0]]\n"


def _load(supply="", motor="", sync=False, simulation="duration = 0.02"):
    text = f"[simulation]\n{simulation}\n[supply]\n{supply}\n{_BASE}{motor}\n"
    if sync:
        text += "[motor.controller.sync]\nenabled = true\n"
    return build_setup(tomllib.loads(text))


@pytest.mark.parametrize(
    ("supply", "motor", "sync", "message"),
    [
        ("phase_a_scale = 1.5", "", False, "supply.phase_a_scale: must be between 0 and 1, got 1.5"),
        ("phase_b_scale_profile = [[0, 1], [1, -0.1]]", "", False,
         "supply.phase_b_scale_profile[1][1]: must be between 0 and 1, got -0.1"),
        ("phase_c_scale = 1\nphase_c_scale_profile = [[0, 1]]", "", False,
         "supply.phase_c_scale: give either phase_c_scale or phase_c_scale_profile, not both"),
        ("phase_a_scale = true", "", False, "supply.phase_a_scale: must be a number, got bool"),
        ("", "dc_link_voltage_profile = [[0, 30], [1, 0]]", False,
         "motor[0].dc_link_voltage_profile[1][1]: must be > 0, got 0"),
        ("", "dc_link_voltage = 30\ndc_link_voltage_profile = [[0, 30]]", False,
         "motor[0].dc_link_voltage: give either dc_link_voltage or dc_link_voltage_profile, not both"),
        ("", "dc_link_voltage_profile = [[1, 30], [0.5, 20]]", False,
         "motor[0].dc_link_voltage_profile: times must be non-decreasing"),
        ("", "relay_forced_close_time = -1", True,
         "motor[0].relay_forced_close_time: must be >= 0, got -1"),
        ("", "relay_forced_close_time = 0.02", True,
         "motor[0].relay_forced_close_time: must be shorter than simulation.duration (0.02 s), got 0.02 s"),
        ("", "relay_forced_close_time = 0.01", False,
         "motor[0].relay_forced_close_time: needs controller.sync.enabled = true"),
    ],
)  # fmt: skip
def test_invalid_new_fields_name_the_field_and_the_rule(supply, motor, sync, message):
    with pytest.raises(InputError) as info:
        _load(supply, motor, sync)
    assert str(info.value).startswith(message)
    assert "\n" not in str(info.value)


def test_the_phase_scales_default_to_healthy_phases():
    setup = _load("phase_b_scale = 0.4")
    scales = [values.tolist() for _, values in setup.supply.phase_scales]
    assert scales == [[1.0], [0.4], [1.0]]
    assert _load().supply.phase_scales is None


def test_the_dc_link_loss_check_uses_the_lowest_voltage_and_the_speed_range_the_nominal(
    capsys, tmp_path
):
    bench = "converter_device_drop = 0.7\n"
    loss = float(_load(motor=bench).motors[0].converter.fundamental_loss(30.0))
    low = 0.99 * loss * math.sqrt(2)  # below the loss: no rotor voltage would remain
    with pytest.raises(InputError) as info:
        _load(motor=bench + f"dc_link_voltage_profile = [[0, 30], [0.01, {low!r}]]")
    assert info.value.field == "motor[0].converter_device_drop"
    assert f"lowest {low:g} V" in info.value.rule
    ok = _load(motor=bench + f"dc_link_voltage_profile = [[0, 30], [0.01, {1.02 * low!r}]]")
    assert ok.motors[0].dc_link_voltage == 30.0 and ok.motors[0].dc_link_min == 1.02 * low
    # the speed range is that of the nominal link (|slip| <= (V_dc / sqrt 2) / ((L_r/M) v_s)): a
    # drop narrows it for a while, which the run simulates and reports as converter saturation
    v_s = K_PEAK * 11.1
    slip_max = max_voltage_magnitude(30.0) / (BODSON_DFIM.L_r / BODSON_DFIM.M * v_s)
    top = 60 * 60.0 / BODSON_DFIM.n_p * (1 + slip_max)
    drop = "dc_link_voltage_profile = [[0, 30], [0.01, 10]]\n"
    inside = f"speed_reference_rpm = [[0, 0], [0.02, {0.99 * top!r}]]"
    assert build_setup(tomllib.loads(f"[simulation]\nduration = 0.02\n[[motor]]\n{inside}\n{drop}"))
    fast = f"speed_reference_rpm = [[0, 0], [0.02, {1.01 * top!r}]]"
    text = f"[simulation]\nduration = 0.02\n[[motor]]\n{fast}\n{drop}"
    path = tmp_path / "fast.toml"
    path.write_text(text)
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--no-figures"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("acdrive: error: motor[0].speed_reference_rpm:")
    assert not (tmp_path / "out").exists()
