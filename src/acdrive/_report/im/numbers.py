"""The computation of the IM time-domain report: the experiments run as built-in scenarios, the
coupling measurements (``analysis._coupling``), and ``compute_numbers``, the flat dict of every
number the report prints.
"""

from __future__ import annotations

import math

import numpy as np

from acdrive._report import icad_targets as targets
from acdrive._report.im.settings import (
    EXPERIMENTS,
    IM_FREQUENCIES,
    PMSG_AMPLITUDE,
    PMSG_BANDWIDTH,
    PMSG_FREQUENCIES,
    PMSG_SPEED,
    PRELOAD_WINDOW,
    FIG13_BEFORE_LOAD_WINDOW,
    TOLERANCES,
)
from acdrive._verdicts import window_drift
from acdrive.analysis._coupling import (
    CouplingResult,
    CouplingSetup,
    hold_delay,
    icad_coupling_peak,
    measure_coupling,
    pmsg_pi,
)
from acdrive.control._lti import PAPER_20, PAPER_PI
from acdrive.drives.cage_im._outcome import IMOutcome, run_im_scenario
from acdrive.drives.cage_im._outputs import delayed_linear_step_response, step_comparison
from acdrive.drives.cage_im._physics import foc_voltage
from acdrive.drives.cage_im._result import IMDriveResult, _steady_mask
from acdrive.machines._induction import DELORENZO_IM
from acdrive.machines._pmsm import PMSG_2MW
from acdrive.scenarios._loader import load_scenario

# --- computation ---------------------------------------------------------------------------


def run_experiments() -> dict[str, IMOutcome]:
    """Every built-in scenario of ``EXPERIMENTS``, run as built (``run_im_scenario``)."""
    return {key: run_im_scenario(load_scenario(name)) for key, name in EXPERIMENTS.items()}


def icad_peak_frequency(params, w_e: float, k, lo: float = 100.0, hi: float = 3000.0) -> float:
    """Frequency [rad/s, rounded to 0.1] of the largest |(10)| (``analysis.icad_coupling_peak``):
    one injection frequency is put there so that the measured peak is the peak of (10)."""
    return round(icad_coupling_peak(params, w_e, k, lo, hi)[0], 1)


def coupling_setups() -> dict[str, CouplingSetup]:
    """The three coupling measurements: the DeLorenzo IM with (20) at w_r = 375 rad/s with an
    ideal voltage (hold of one 50 kHz sample) and with the paper's 5 kHz carrier hold, and the
    2 MW PMSG at rated speed with the dq PI ``pmsg_pi``; the IM's frequencies include the peak
    of (10)."""
    w_r = targets.W_R_MAX
    peak = icad_peak_frequency(DELORENZO_IM, w_r, PAPER_20)
    im_w = tuple(sorted(set(IM_FREQUENCIES) | {peak}))
    return {
        "im": CouplingSetup(DELORENZO_IM, PAPER_20, w_r, im_w, name="im"),
        "im_5khz": CouplingSetup(
            DELORENZO_IM, PAPER_20, w_r, im_w, hold_samples=10, name="im_5khz"
        ),
        "pmsg": CouplingSetup(
            PMSG_2MW,
            pmsg_pi(PMSG_2MW, PMSG_BANDWIDTH),
            PMSG_SPEED,
            PMSG_FREQUENCIES,
            amplitude=PMSG_AMPLITUDE,
            name="pmsg",
        ),
    }


def measure_couplings() -> dict[str, CouplingResult]:
    return {key: measure_coupling(s) for key, s in coupling_setups().items()}


def reference_amplitude_change(result: IMDriveResult, t_load: float) -> dict:
    """Fig. 13(c): the current reference's amplitude (phase peak) before the load change (mean
    over the ``FIG13_BEFORE_LOAD_WINDOW`` before ``t_load``) and after it (the summary's steady
    window at the end), and the amplitude after it that field orientation predicts from the
    torque: the d reference is held (constant flux) and the q reference scales with the
    electromagnetic torque (tau = n_P (L_m / L_r) psi_r i_q), so i_q after = i_q before x
    tau_E after / tau_E before."""
    before = (result.t >= t_load - FIG13_BEFORE_LOAD_WINDOW) & (result.t < t_load)
    after = _steady_mask(result.t)
    i_dq = result.signal("i_dq_ref") / math.sqrt(1.5)  # phase peak (Bodson (8))
    tau = result.signal("tau_e")
    d_before, q_before = float(np.mean(i_dq[before].real)), float(np.mean(i_dq[before].imag))
    q_predicted = q_before * float(np.mean(tau[after])) / float(np.mean(tau[before]))
    return {
        "fig13_ref_amplitude_before_a": float(np.mean(np.abs(i_dq[before]))),
        "fig13_ref_amplitude_after_a": float(np.mean(np.abs(i_dq[after]))),
        "fig13_ref_amplitude_predicted_a": math.hypot(d_before, q_predicted),
        "fig13_tau_e_before_n_m": float(np.mean(tau[before])),
        "fig13_before_window_s": FIG13_BEFORE_LOAD_WINDOW,
    }


def _peak_modulation(outcome: IMOutcome) -> float:
    return float(np.max(np.abs(outcome.main.signal("m_a"))))


def _steady_drift(result: IMDriveResult, signal: str) -> tuple[float, float, float]:
    """(mean, drift, window [s]) of a logged signal over the summary's steady window
    (``drives.cage_im._result._steady_mask``, the window of its final values): the numbers of the
    settling test (``acdrive._verdicts.window_drift``)."""
    mask = _steady_mask(result.t)
    return window_drift(result.t[mask], result.signal(signal)[mask])


def compute_numbers(outcomes: dict[str, IMOutcome], couplings: dict[str, CouplingResult]) -> dict:
    """Every number the report prints, by key (plain floats; units in the keys)."""
    n: dict = {}
    o11 = outcomes["fig11"]
    s11 = o11.setup
    n["dc_link_v"] = float(s11.inverter.dc_link_min)
    n["pwm_khz"] = s11.inverter.f_pwm / 1e3
    n["sampling_khz"] = 1e-3 / s11.sample_time
    n["pi_kp"] = float(PAPER_PI.D[0, 0])
    n["pi_ki"] = float(PAPER_PI.C[0, 0] * PAPER_PI.B[0, 0])
    w = np.array([10.0, 375.0, 3000.0])
    s = 1j * w
    printed20 = (
        targets.CONTROLLER_20["gain"]
        * (s - targets.CONTROLLER_20["pi_zero"])
        / s
        * np.prod([s - z for z in targets.CONTROLLER_20["lag_zeros"]], axis=0)
        / np.polyval(targets.CONTROLLER_20["lag_den"], s)
    )
    n["controller_20_max_rel_diff"] = float(
        np.max(np.abs(PAPER_20.freqresp(w) - printed20) / np.abs(printed20))
    )
    # Fig. 11
    sm = o11.summary
    n["fig11_frequency_rad_s"] = float(s11.current_reference.frequency)
    n["fig11_amplitude_a"] = float(s11.current_reference.amplitude_pk)
    for label in ("icad", "pi"):
        run = sm["runs"][label]
        n[f"fig11_rms_error_{label}_a"] = run["current_rms_error_a"]
        n[f"fig11_rms_error_{label}_rel"] = run["current_rms_error_relative"]
    n["fig11_saturated_samples"] = sm["runs"]["icad"]["events"]["current_controller_saturation"]
    # Fig. 13
    sm = outcomes["fig13"].summary
    n["fig13_speed_reference_rad_s"] = sm["speed_reference_final_rad_s"]
    n["fig13_speed_final_rad_s"] = sm["speed_final_rad_s"]
    n["fig13_overshoot_rad_s"] = sm["speed_overshoot_rad_s"]
    lc = sm["load_changes"][0]
    n["fig13_load_time_s"] = lc["time_s"]
    n["fig13_load_dip_rad_s"] = lc["max_deviation_rad_s"]
    n["fig13_load_n_m"] = sm["torque_balance"]["load_n_m"]
    n["fig13_tau_e_n_m"] = sm["torque_balance"]["tau_e_n_m"]
    n["fig13_friction_n_m"] = sm["torque_balance"]["friction_n_m"]
    n["fig13_torque_residual_n_m"] = sm["torque_balance"]["residual_n_m"]
    n["fig13_rms_error_rel"] = sm["current_rms_error_relative"]
    n["fig13_peak_modulation"] = _peak_modulation(outcomes["fig13"])
    n["fig13_inertia_kg_m2"] = float(outcomes["fig13"].setup.mechanics.J)
    n["fig13_flux_wb"] = float(np.max(outcomes["fig13"].setup.foc.psi_ref[1]))
    n["fig13_overmodulation_samples"] = sm["events"]["overmodulation"]
    n["fig13_saturated_samples"] = sm["events"]["current_controller_saturation"]
    n["fig13_duration_s"] = sm["duration_s"]
    _, n["fig13_speed_drift_rad_s"], n["fig13_steady_window_s"] = _steady_drift(
        outcomes["fig13"].main, "w"
    )
    n.update(reference_amplitude_change(outcomes["fig13"].main, n["fig13_load_time_s"]))
    # Fig. 14
    sm = outcomes["fig14"].summary
    n["fig14_position_reference_rad"] = sm["position_reference_final_rad"]
    n["fig14_position_final_rad"] = sm["position_final_rad"]
    n["fig14_overshoot_rad"] = sm["position_overshoot_rad"]
    lc = sm["load_changes"][0]
    n["fig14_load_time_s"] = lc["time_s"]
    n["fig14_load_dip_rad"] = lc["max_deviation_rad"]
    n["fig14_rms_error_rel"] = sm["current_rms_error_relative"]
    n["fig14_top_speed_rad_s"] = float(np.max(np.abs(outcomes["fig14"].main.signal("w"))))
    n["fig14_duration_s"] = sm["duration_s"]
    _, n["fig14_position_drift_rad"], n["fig14_steady_window_s"] = _steady_drift(
        outcomes["fig14"].main, "theta"
    )
    n["fig14_load_n_m"] = float(np.max(np.abs(outcomes["fig14"].setup.mechanics.load[1])))
    main14 = outcomes["fig14"].main
    before = main14.t < n["fig14_load_time_s"]
    (
        n["fig14_preload_position_rad"],
        n["fig14_preload_drift_rad"],
        n["fig14_preload_window_s"],
    ) = window_drift(main14.t[before], main14.signal("theta")[before], PRELOAD_WINDOW)
    # Fig. 16
    sm = outcomes["fig16"].summary
    n["fig16_speed_reference_rad_s"] = sm["speed_reference_final_rad_s"]
    ramp = sm["runs"]["icad"]["ramp"]
    n["fig16_ideal_slope_rad_s2"] = ramp["ideal_slope_rad_s2"]
    n["fig16_ideal_slope_friction_rad_s2"] = ramp["ideal_slope_with_friction_rad_s2"]
    for label in ("icad", "pi"):
        run = sm["runs"][label]
        n[f"fig16_slope_{label}_rad_s2"] = run["ramp"]["ramp_slope_rad_s2"]
        n[f"fig16_ramp_error_{label}_rad_s"] = run["ramp"]["speed_ramp_error_rad_s"]
        n[f"fig16_rms_error_{label}_a"] = run["current_rms_error_a"]
        n[f"fig16_final_speed_{label}_rad_s"] = run["speed_final_rad_s"]
        n[f"fig16_steady_error_{label}_rad_s"] = run["speed_steady_error_rad_s"]
        _, n[f"fig16_speed_drift_{label}_rad_s"], n["fig16_steady_window_s"] = _steady_drift(
            outcomes["fig16"].results[label], "w"
        )
    n["fig16_duration_s"] = sm["duration_s"]
    n["fig16_k_p"] = float(outcomes["fig16"].setup.speed_p.k_p)
    n["fig16_tau_max_n_m"] = float(outcomes["fig16"].setup.speed_p.tau_max)
    check16 = outcomes["fig16"].summary["voltage_check"]
    n["fig16_flux_wb"] = check16["flux_wb"]
    n["fig16_link_limit_v"] = check16["limit_v"]
    # the rated flux of Fig. 13's run, at Fig. 16's top speed with no torque (phase peak volts)
    n["fig16_rated_flux_wb"] = n["fig13_flux_wb"]
    n["fig16_rated_flux_needed_v"] = abs(
        foc_voltage(
            outcomes["fig16"].setup.plant, n["fig16_rated_flux_wb"], 0.0, check16["speed_rad_s"]
        )
    ) / math.sqrt(1.5)
    n["fig16_top_speed_rad_s"] = check16["speed_rad_s"]
    # Figs. 18, 20
    o = outcomes["fig18_20"]
    n["steps_speed_rad_s"] = float(o.setup.mechanics.prescribed_speed[1][0])
    n["steps_hold_delay_s"] = hold_delay(o.setup.carrier_samples, o.setup.sample_time)
    for label, result in o.results.items():
        c = step_comparison(result)
        n[f"step_overshoot_{label}"] = c["overshoot_simulated"]
        n[f"step_overshoot_linear_{label}"] = c["overshoot_linear"]
        delayed = delayed_linear_step_response(
            result.setup.plant,
            n["steps_speed_rad_s"],
            result.setup.current_control.lti,
            c["t"],
            n["steps_hold_delay_s"],
        )
        n[f"step_overshoot_linear_delayed_{label}"] = float(np.max(delayed[:, 0]) - 1.0)
        n[f"step_coupling_peak_{label}"] = c["coupling_peak_simulated"]
        n[f"step_coupling_peak_linear_{label}"] = c["coupling_peak_linear"]
        n[f"step_ringing_{label}"] = c["ringing_simulated"]
        n[f"step_ringing_linear_{label}"] = c["ringing_linear"]
    # Fig. 23
    o = outcomes["fig23"]
    for k in targets.PERTURBATION_FACTORS:
        n[f"fig23_factor_{k}"] = getattr(o.setup.plant, k) / getattr(o.setup.machine, k)
    n["fig23_frequency_rad_s"] = float(o.setup.current_reference.frequency)
    n["fig23_rms_error_rel"] = o.summary["current_rms_error_relative"]
    n["fig23_rms_error_a"] = o.summary["current_rms_error_a"]
    n["fig23_final_speed_rad_s"] = float(o.main.signal("w")[-1])
    n["fig23_duration_s"] = o.summary["duration_s"]
    # coupling
    for key, r in couplings.items():
        band = r.frequencies <= TOLERANCES["coupling_w_max"]
        n[f"coupling_{key}_rows"] = r.rows()
        n[f"coupling_{key}_max_rel_error"] = float(np.max(r.relative_error()[band]))
        n[f"coupling_{key}_max_rel_error_delayed"] = float(np.max(r.relative_error(True)[band]))
        n[f"coupling_{key}_max_rel_error_delayed_all"] = float(np.max(r.relative_error(True)))
        n[f"coupling_{key}_peak_db"] = float(np.max(r.db()))
        n[f"coupling_{key}_peak_at_rad_s"] = float(r.frequencies[int(np.argmax(r.db()))])
        n[f"coupling_{key}_icad_peak_db"] = float(np.max(r.db("icad")))
        n[f"coupling_{key}_peak_voltage_v"] = float(np.max(r.peak_voltage))
        n[f"coupling_{key}_speed_rad_s"] = r.setup.w_e
        n[f"coupling_{key}_delay_s"] = r.setup.delay
        n[f"coupling_{key}_wall_s"] = r.wall_time
    if "im" in couplings and "im_5khz" in couplings:
        ideal, hold = couplings["im"].db(), couplings["im_5khz"].db()
        n["coupling_hold_frequencies_rad_s"] = [float(w) for w in couplings["im"].frequencies]
        n["coupling_hold_change_db"] = [float(b - a) for a, b in zip(ideal, hold, strict=True)]
    return n
