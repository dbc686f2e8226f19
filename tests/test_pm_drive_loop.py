"""The PM speed drive in the compiled loop (``drives/pm/_build.py``), checked against physics.

Three machines:

* the Anaheim BLY171D surface PMSM (``drives.pm._machines``, published parameters), rated current,
  24 V link: a speed step and a load step. The load step is rejected (integral action) and the
  speed dip matches the ideal-torque loop J s^2 + K_P s + K_I with its double root at -a:
  dw(t) = -(dT / J) t e^{-a t}, a dip of dT / (J a e) at t = 1 / a;
* an interior (salient) machine with TEST values (L_q / L_d = 2.33; not a published machine,
  kept beside the published one below for its different ratios), at half base speed under load
  (the MTPA check) and at 2.2 times base speed (field weakening: the voltage limit held, i_d
  below its MTPA value);
* motulator's 2.2-kW interior PMSM (published parameters) in the built-in scenarios:

  - ``pm-ipmsm-speed``: below base speed, MTPA; the settled current angle is the closed-form MTPA
    angle, the torque formula with the plant's currents carries the nominal 14 N m load;
  - ``pm-ipmsm-field-weakening``: at more than 2x the base speed (``_design.base_speed``, the
    steady-state voltage equation, at the scenario's current limit and link) with a load the drive can carry there
    (``_design.available_torque``); the voltage command stays within margin V_dc / sqrt(2) (1 %
    for the loops' residual ripple), i_d < 0 and below its MTPA value, the plant's flux on the
    limit (V), the torque formula against the shaft balance.

All: the shaft's torque balance equals the torque formula with the currents the controller
measured (encoder angle, stationary currents), and the energy balance closes:
int Re(v conj i) dt = int R_s |i|^2 dt + dW_mag + dE_kin + int (tau_L + B w) w dt.
"""

import dataclasses
import math

import numpy as np
import pytest

from acdrive._frames import K_PEAK
from acdrive.core import table_at
from acdrive.core._signals import pack_table
from acdrive.drives.pm import PMDriveSetup, builtin, run, signals
from acdrive.drives.pm import _design as d
from acdrive.drives.pm._machines import (
    BLY171D,
    BLY171D_B,
    BLY171D_I_RATED_PEAK,
    BLY171D_V_DC,
    IPMSM_2KW2,
    IPMSM_2KW2_I_NOM,
    IPMSM_2KW2_T_NOM,
    IPMSM_2KW2_V_DC,
)
from acdrive.machines import PMSGParams

#: interior machine with test values (see the module docstring)
SALIENT = PMSGParams(R_s=0.1, L_d=1.5e-3, L_q=3.5e-3, psi_m=0.08, n_p=4, J=0.01)


def window(t, start, end):
    return (t >= start) & (t < end)


def torque_of(setup, i_dq):
    m = setup.machine
    return d.torque(m.n_p, d.magnet_flux(m.psi_m), m.L_d, m.L_q, i_dq.real, i_dq.imag)


def energy_residual(setup, result, s):
    """(input energy, residual of the balance) over the run, trapezoid rule on the samples; the
    converter's voltage is constant over each sample (averaged converter)."""
    T = setup.sample_time
    m = setup.machine
    v, i = s["v_s"][:-1], s["i_s"]
    i_mid = 0.5 * (i[:-1] + i[1:])
    e_in = float(np.sum(T * np.real(v * np.conj(i_mid))))
    trap = lambda f: float(np.sum(0.5 * T * (f[:-1] + f[1:])))
    copper = trap(m.R_s * np.abs(i) ** 2)
    i_dq = s["i_dq"]
    w_mag = 0.5 * (m.L_d * i_dq.real**2 + m.L_q * i_dq.imag**2)
    kinetic = 0.5 * setup.J * s["w"] ** 2
    load = np.array([table_at(pack_table("load", setup.load), 0, tk) for tk in result.t])
    mech = trap((load + setup.B * s["w"]) * s["w"])
    stored = (w_mag[-1] - w_mag[0]) + (kinetic[-1] - kinetic[0])
    return e_in, e_in - copper - stored - mech


# --- surface machine: step and load rejection -------------------------------------------------

LOAD = 0.04  # N m, 70 % of the rated 0.0566 N m


@pytest.fixture(scope="module")
def surface():
    setup = builtin("pm-bly171d-speed")  # speed step to 300 rad/s, LOAD from 0.1 s
    assert setup.load[-1][1] == LOAD
    assert (setup.machine, setup.B, setup.V_dc) == (BLY171D, BLY171D_B, BLY171D_V_DC)
    result, summary = run(setup)
    return setup, result, summary, signals(setup, result)


def test_surface_speed_step_is_tracked_and_load_rejected(surface):
    setup, result, summary, s = surface
    t, w = result.t, s["w"]
    before, after = window(t, 0.09, 0.1), window(t, 0.19, 0.2)
    assert abs(np.mean(300.0 - w[before])) < 0.05  # rad/s, settled before the load step
    assert abs(np.mean(300.0 - w[after])) < 0.05  # and again after it: integral action
    # the dip after the load step is the ideal-torque loop's dT / (J a e)
    a = setup.speed_bandwidth
    expected = LOAD / (setup.J * a * math.e)
    dip = 300.0 - np.min(w[window(t, 0.1, 0.19)])
    assert dip == pytest.approx(expected, rel=0.15)  # sampling and the current loop's lag
    assert summary["current_peak_a"] <= BLY171D_I_RATED_PEAK * (1 + 1e-3)
    assert summary["voltage_limited_fraction"] == 0.0


def test_surface_torque_balance_uses_the_formula_with_measured_currents(surface):
    setup, result, _, s = surface
    final = window(result.t, 0.19, 0.2)
    measured = s["i_dq"][final]  # plant currents in rotor coordinates
    formula = torque_of(setup, measured)
    shaft_needs = LOAD + setup.B * s["w"][final]  # dw/dt = 0 in the settled window
    assert np.mean(formula) == pytest.approx(np.mean(shaft_needs), rel=2e-3)
    assert np.mean(formula) == pytest.approx(np.mean(s["tau_e"][final]), rel=1e-12)


def test_surface_encoder_offset_turns_the_current_by_its_electrical_angle(surface):
    """An encoder mounted delta off turns the controller's dq frame by n_p delta: the plant's
    current is the reference turned by e^{j n_p delta}, and only its cosine makes torque, so the
    speed loop asks 1 / cos(n_p delta) times the aligned q current."""
    setup = dataclasses.replace(surface[0], encoder_offset=0.075)  # n_p delta = 0.3 rad
    result, _ = run(setup)
    s = signals(setup, result)
    final = window(result.t, 0.19, 0.2)
    turn = np.exp(1j * setup.machine.n_p * setup.encoder_offset)
    i_ref, i_plant = np.mean(s["i_dq_ref"][final]), np.mean(s["i_dq"][final])
    assert i_plant == pytest.approx(i_ref * turn, rel=2e-3)
    psi_f = d.magnet_flux(setup.machine.psi_m)
    aligned_q = (LOAD + setup.B * 300.0) / (
        setup.machine.n_p * psi_f
    )  # surface: tau = n_p psi_f i_q
    assert i_ref.imag == pytest.approx(aligned_q / turn.real, rel=2e-3)


def test_surface_energy_balance(surface):
    setup, result, _, s = surface
    e_in, residual = energy_residual(setup, result, s)
    # trapezoid error ~ (w_e T_s)^2 / 12 = (4 * 300 * 50e-6)^2 / 12 = 3e-4 of the input
    assert abs(residual) < 2e-3 * e_in


# --- interior machine: MTPA and field weakening -----------------------------------------------

LIMITS = {"V_dc": 300.0, "i_max_peak": 60.0}
MARGIN = 0.9
BASE = d.base_speed(SALIENT.R_s, SALIENT.L_d, SALIENT.L_q, d.magnet_flux(SALIENT.psi_m),
                    SALIENT.n_p, K_PEAK * 60.0, 300.0 / math.sqrt(2), MARGIN)  # fmt: skip
LOW, HIGH = 0.5 * BASE, 2.2 * BASE
STEADY_LOAD = 10.0  # N m


@pytest.fixture(scope="module")
def interior():
    setup = PMDriveSetup(
        machine=SALIENT, **LIMITS, voltage_margin=MARGIN, B=0.025,
        speed_reference=[[0, 0], [0.1, LOW], [0.3, LOW], [0.65, HIGH], [1.0, HIGH]],
        load=STEADY_LOAD, duration=1.0, sample_time=50e-6,
        current_bandwidth=2 * math.pi * 300, speed_bandwidth=50.0,
    )  # fmt: skip
    result, summary = run(setup)
    return setup, result, summary, signals(setup, result)


def _assert_mtpa(setup, i_dq: complex) -> None:
    """The settled current ``i_dq`` sits at the closed-form MTPA angle (1e-3 rad), and no
    current angle of its magnitude gives more torque (brute force over the quarter plane)."""
    m = setup.machine
    psi_f = d.magnet_flux(m.psi_m)
    beta = math.atan2(-i_dq.real, i_dq.imag)
    assert beta == pytest.approx(d.mtpa_angle(psi_f, m.L_d, m.L_q, abs(i_dq)), abs=1e-3)
    angles = np.linspace(0.0, math.pi / 2, 100001)
    best = np.max(d.torque(m.n_p, psi_f, m.L_d, m.L_q, -abs(i_dq) * np.sin(angles),
                           abs(i_dq) * np.cos(angles)))  # fmt: skip
    assert torque_of(setup, i_dq) == pytest.approx(best, rel=1e-5)


def test_interior_mtpa_angle_is_the_closed_form_optimum(interior):
    setup, result, _, s = interior
    _assert_mtpa(setup, np.mean(s["i_dq"][window(result.t, 0.25, 0.3)]))


def test_interior_field_weakening_holds_the_voltage_limit(interior):
    setup, result, _, s = interior
    assert HIGH >= 2.0 * BASE
    settled = window(result.t, 0.9, 1.0)
    w = s["w"][settled]
    assert np.mean(w) == pytest.approx(HIGH, rel=1e-3)
    v_max = setup.V_dc / math.sqrt(2)
    v = np.abs(s["v_dq_wanted"][settled])
    # the references keep |v| <= margin v_max in steady state; 1 % for the loops' residual ripple
    assert np.max(v) <= MARGIN * v_max * 1.01
    assert np.min(v) >= MARGIN * v_max * 0.9  # and the drive runs on the limit, not below it
    i_dq = s["i_dq"][settled]
    m = setup.machine
    psi_f = d.magnet_flux(m.psi_m)
    tau = np.mean(torque_of(setup, i_dq))
    i_s_mtpa = d.mtpa_current(m.n_p, psi_f, m.L_d, m.L_q, tau, 1e6)
    i_d_mtpa, _ = d.mtpa_point(psi_f, m.L_d, m.L_q, i_s_mtpa)
    assert np.max(i_dq.real) < 0.0
    assert np.mean(i_dq.real) < i_d_mtpa - 1.0  # weakened: well below the MTPA d current
    assert tau == pytest.approx(STEADY_LOAD + setup.B * np.mean(w), rel=2e-3)


def test_interior_voltage_never_beyond_the_converter(interior):
    _, result, summary, _ = interior
    assert summary["voltage_limited_fraction"] == 0.0
    assert result.events["converter"]["saturated"] == 0
    assert summary["converter_limited_samples"] == 0
    assert summary["voltage_limited_samples"] > 0  # the references did meet the voltage limit
    assert summary["beyond_reach_samples"] == 0


def test_interior_energy_balance(interior):
    setup, result, _, s = interior
    e_in, residual = energy_residual(setup, result, s)
    # trapezoid error ~ (w_e T_s)^2 / 12 at the top speed 4 * 467 rad/s: 7e-4 of the input
    assert abs(residual) < 3e-3 * e_in


# --- the same surface drive on the switching SVPWM inverter -----------------------------------


@pytest.mark.slow  # a second topology to compile (about 30 s of CPU on a cold cache)
def test_surface_drive_on_the_svpwm_inverter():
    setup = builtin("pm-bly171d-svpwm")  # the surface drive above on a 20 kHz SVPWM inverter
    result, summary = run(setup)
    s = signals(setup, result)
    final = window(result.t, 0.19, 0.2)
    assert abs(np.mean(300.0 - s["w"][final])) < 0.1  # rad/s: tracked, load rejected
    # the mean torque carries the load (the ripple averages out over the window)
    formula = np.mean(torque_of(setup, s["i_dq"][final]))
    assert formula == pytest.approx(LOAD + setup.B * 300.0, rel=0.01)
    # within a carrier period the applied vector is at most sqrt(2/3) V_dc away from its mean, so
    # the current leaves its controlled value by at most sqrt(2/3) V_dc T_pwm / L (space vector)
    ripple = math.sqrt(2 / 3) * setup.V_dc / setup.f_pwm / BLY171D.L_d / K_PEAK
    assert summary["current_peak_a"] <= BLY171D_I_RATED_PEAK + ripple


# --- motulator's 2.2-kW interior PMSM: the built-in scenarios ---------------------------------


def load_at_end(setup):
    return setup.load[-1][1]


def speed_at_end(setup):
    return setup.speed_reference[-1][1]


@pytest.fixture(scope="module")
def speed_drive():
    setup = builtin("pm-ipmsm-speed")
    result, summary = run(setup)
    return setup, result, summary, signals(setup, result)


@pytest.fixture(scope="module")
def field_weakening():
    setup = builtin("pm-ipmsm-field-weakening")
    result, summary = run(setup)
    return setup, result, summary, signals(setup, result)


def test_scenarios_use_the_published_machine_at_1_5_times_nominal_current(
    speed_drive, field_weakening
):
    for setup in (speed_drive[0], field_weakening[0]):
        assert (setup.machine, setup.J, setup.V_dc) == (IPMSM_2KW2, IPMSM_2KW2.J, IPMSM_2KW2_V_DC)
        assert setup.i_max_peak == pytest.approx(1.5 * math.sqrt(2) * IPMSM_2KW2_I_NOM, rel=1e-15)
    assert load_at_end(speed_drive[0]) == IPMSM_2KW2_T_NOM


# --- below base speed: MTPA at the nominal torque ---------------------------------------------


def test_speed_drive_tracks_below_base_speed_and_rejects_the_nominal_load(speed_drive):
    setup, result, summary, s = speed_drive
    w_ref = speed_at_end(setup)
    assert w_ref < setup.base_speed  # MTPA region
    before, after = window(result.t, 0.25, 0.3), window(result.t, 0.55, 0.6)
    for win in (before, after):
        assert abs(np.mean(w_ref - s["w"][win])) < 0.01 * w_ref * 0.01  # 0.01 % of the speed
    assert summary["speed_final_to_base_ratio"] < 1.0
    assert summary["voltage_limited_samples"] == 0  # the references never met the voltage limit
    assert summary["current_peak_a"] <= setup.i_max_peak * (1 + 1e-3)


def test_speed_drive_voltage_limit_acts_only_at_the_speed_step(speed_drive):
    """The current PIs (K_P = a L) ask for more than the link's V_dc / sqrt(2) when the current
    reference jumps to the limit at the speed step; the anti-windup holds them there for a few
    samples only (the summary's negative least voltage margin comes from there)."""
    setup, result, summary, s = speed_drive
    over = np.abs(s["v_dq_wanted"]) > setup.V_dc / math.sqrt(2)
    assert summary["current_controller_limited_samples"] == over.sum() > 0
    step_at = setup.speed_reference[1][0]
    assert np.all((result.t[over] >= step_at) & (result.t[over] < step_at + 0.002))


def test_speed_drive_mtpa_angle_is_the_closed_form_optimum(speed_drive):
    setup, result, _, s = speed_drive
    i_dq = np.mean(s["i_dq"][window(result.t, 0.55, 0.6)])
    assert i_dq.real < 0.0  # the reluctance torque is used
    _assert_mtpa(setup, i_dq)


def test_speed_drive_torque_formula_carries_the_load(speed_drive):
    setup, result, _, s = speed_drive
    final = window(result.t, 0.55, 0.6)
    formula = np.mean(torque_of(setup, s["i_dq"][final]))
    # settled: J dw/dt = 0, so the machine torque equals the load (B = 0)
    assert setup.B == 0.0
    assert formula == pytest.approx(load_at_end(setup), rel=1e-3)


def test_speed_drive_energy_balance(speed_drive):
    setup, result, _, s = speed_drive
    e_in, residual = energy_residual(setup, result, s)
    # trapezoid error ~ (w_e T_s)^2 / 12 = (3 * 78.5 * 1e-4)^2 / 12 = 5e-5 of the input
    assert abs(residual) < 1e-3 * e_in


# --- field weakening to more than twice the base speed ----------------------------------------


def test_field_weakening_load_is_within_the_available_torque(field_weakening):
    setup = field_weakening[0]
    m = setup.machine
    w_top = speed_at_end(setup)
    assert w_top >= 2.0 * setup.base_speed
    psi_max = d.flux_limit(m.R_s, setup.V_dc / math.sqrt(2), setup.voltage_margin, setup.i_max,
                           m.n_p * w_top)  # fmt: skip
    available = d.available_torque(m.n_p, d.magnet_flux(m.psi_m), m.L_d, m.L_q, setup.i_max,
                                   psi_max)  # fmt: skip
    assert load_at_end(setup) < 0.8 * available  # 10.2 N m there: room to recover a dip


def test_field_weakening_reaches_twice_base_speed(field_weakening):
    setup, result, summary, s = field_weakening
    final = window(result.t, 1.9, 2.0)
    w = np.mean(s["w"][final])
    assert w == pytest.approx(speed_at_end(setup), rel=1e-4)
    assert w / setup.base_speed >= 2.0
    assert summary["speed_final_to_base_ratio"] == pytest.approx(w / setup.base_speed, rel=1e-3)
    assert summary["beyond_reach_samples"] == 0


def test_field_weakening_holds_the_voltage_limit_with_negative_d_current(field_weakening):
    setup, result, summary, s = field_weakening
    fw = window(result.t, 1.0, 2.0) & (s["w"] > 1.5 * setup.base_speed)
    assert fw.sum() > 5000  # the claim covers the top-speed run and the load step
    v_lim = setup.voltage_margin * setup.V_dc / math.sqrt(2)
    v = np.abs(s["v_dq_wanted"][fw])
    # the references keep |v| <= m V_max; 1 % for the loops' residual ripple and the load step
    assert np.max(v) <= v_lim * 1.01
    assert summary["converter_limited_samples"] == 0
    assert summary["current_controller_limited_samples"] == 0
    assert summary["voltage_limited_samples"] > 0  # the references did meet the limit
    i_dq = s["i_dq"][fw]
    assert np.max(i_dq.real) < 0.0
    # weakened: below the d current MTPA would use for the same torque
    m = setup.machine
    psi_f = d.magnet_flux(m.psi_m)
    final = window(result.t, 1.9, 2.0)
    i_final = np.mean(s["i_dq"][final])
    tau = torque_of(setup, i_final)
    i_d_mtpa, _ = d.mtpa_point(psi_f, m.L_d, m.L_q, d.mtpa_current(m.n_p, psi_f, m.L_d, m.L_q,
                                                                   tau, 1e6))  # fmt: skip
    assert i_final.real < i_d_mtpa - 0.5 * K_PEAK
    # on the limit in steady state: the plant's flux is the flux (V) allows at this speed,
    # psi_max = (m V_max - R_s i_max) / w_e ...
    w_e = m.n_p * np.mean(s["w"][final])
    psi = d.flux_magnitude(psi_f, m.L_d, m.L_q, i_final.real, i_final.imag)
    psi_max = (v_lim - m.R_s * setup.i_max) / w_e
    assert psi == pytest.approx(psi_max, rel=2e-3)
    assert np.mean(s["psi_max"][final]) == pytest.approx(psi_max, rel=1e-3)
    # ... and the command is the steady-state voltage R_s i + j w_e psi_dq of those currents
    psi_dq = complex(m.L_d * i_final.real + psi_f, m.L_q * i_final.imag)
    v_model = m.R_s * i_final + 1j * w_e * psi_dq
    assert np.mean(s["v_dq_wanted"][final]) == pytest.approx(v_model, rel=2e-3)


def test_field_weakening_torque_formula_against_the_shaft_balance(field_weakening):
    setup, result, _, s = field_weakening
    final = window(result.t, 1.9, 2.0)
    formula = np.mean(torque_of(setup, s["i_dq"][final]))
    assert formula == pytest.approx(load_at_end(setup) + setup.B * 280.0, rel=1e-3)
    # during the ramp (before the load): J dw/dt = tau, the slope of the speed
    ramp = window(result.t, 0.5, 1.0)
    slope = np.polyfit(result.t[ramp], s["w"][ramp], 1)[0]
    assert np.mean(torque_of(setup, s["i_dq"][ramp])) == pytest.approx(setup.J * slope, rel=0.01)


def test_field_weakening_energy_balance(field_weakening):
    setup, result, _, s = field_weakening
    e_in, residual = energy_residual(setup, result, s)
    # trapezoid error ~ (w_e T_s)^2 / 12 = (3 * 280 * 1e-4)^2 / 12 = 6e-4 of the input
    assert abs(residual) < 2e-3 * e_in


def test_speed_outcome_headline_reads_the_summary(tmp_path):
    import json

    from acdrive.drives.pm import _entry

    setup = builtin("pm-ipmsm-field-weakening")
    assert _entry.runs(setup) == 1
    outcome = _entry.run_outcome(setup)
    summary = _entry.write(outcome, tmp_path, figures=True, fmt="csv")
    assert json.loads((tmp_path / "summary.json").read_text()) == summary
    assert (tmp_path / "data.csv").exists() and (tmp_path / "signals.png").exists()
    first, _ = _entry.headline(outcome, summary)
    assert f"{summary['speed_final_to_base_ratio']:.3g} x base speed" in first


def test_field_weakening_summary_gives_steady_values_beside_the_transient_extremes(
    field_weakening,
):
    """The load step at 1.3 s drives i_d and the voltage command beyond their settled values:
    the summary gives the final window's mean beside the run's extreme and its instant, and the
    headline names an extreme before the final window a transient's."""
    from acdrive.drives.pm import _entry

    setup, result, summary, s = field_weakening
    final = window(result.t, 1.8, 2.0 + 1e-9)
    assert summary["final_window_from_s"] == pytest.approx(1.8, abs=setup.sample_time)
    i_d_final = np.mean(s["i_dq"].real[final]) / K_PEAK
    assert summary["i_d_final_a"] == pytest.approx(i_d_final, rel=1e-12)
    v_lim = setup.voltage_margin * setup.V_dc / math.sqrt(2)
    use = np.abs(s["v_dq_wanted"]) / v_lim
    assert summary["voltage_use_final"] == pytest.approx(np.mean(use[final]), rel=1e-12)
    assert summary["voltage_use_max"] == pytest.approx(np.max(use), rel=1e-12)
    load_at = next(t for t, value in setup.load if value != 0.0)  # the load step (1.3 s)
    for key in ("i_d_min_time_s", "voltage_use_max_time_s"):
        assert load_at <= summary[key] < summary["final_window_from_s"]
    assert summary["i_d_min_a"] < summary["i_d_final_a"]
    assert summary["voltage_use_max"] > summary["voltage_use_final"]
    rows = dict(_entry.headline(_entry.PMOutcome(setup, {"main": result}, summary), summary)[1])
    assert "final" in rows["d current (phase peak)"]
    assert "(transient, t = " in rows["d current (phase peak)"]
    assert "(transient, t = " in rows["voltage command / m V_dc / sqrt(2)"]
    assert summary["voltage_bound_speed_rad_s"] == pytest.approx(setup.voltage_bound_speed)
    assert summary["base_speed_rad_s"] == pytest.approx(setup.base_speed)
