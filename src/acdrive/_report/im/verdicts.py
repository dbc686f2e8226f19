"""The verdicts of the IM time-domain report: ``compute_verdicts`` judges the numbers of
``_report.im.numbers`` against the tolerances of ``_report.im.settings``; the helpers build the
sentences that explain a verdict (overshoot order, the hold's delay, the Fig. 16 steady state).
"""

from __future__ import annotations

from acdrive._report import icad_targets as targets
from acdrive._report.im.settings import PRINTED, TOLERANCES, pct
from acdrive._report.markdown import fmt
from acdrive._verdicts import (
    Verdict,
    at_most,
    error_within,
    judge_settling,
    printed_digits,
    ratio_at_least,
    transcription,
    when_settled,
    within_abs,
    within_rel,
)
from acdrive.analysis._coupling import VOLTAGE_LIMIT


def compute_verdicts(n: dict, tol: dict | None = None) -> dict[str, Verdict]:
    """Every verdict of the report from the numbers ``n`` and the tolerances ``tol`` (default
    ``TOLERANCES``)."""
    t = dict(TOLERANCES if tol is None else tol)
    P = PRINTED
    v: dict[str, Verdict] = {}

    def setting(key, value):
        """An input check: a setting taken from the paper against the printed number."""
        return transcription(within_rel(value, P[key].value, t["setting_rel"]))

    def speed_settled(drift, window):
        return judge_settling(drift, window, t["settled_speed_abs"])

    v["dc_link"] = setting("dc_link", n["dc_link_v"])
    v["pwm"] = setting("pwm", n["pwm_khz"])
    v["sampling"] = setting("sampling", n["sampling_khz"])
    v["pi_kp"] = transcription(printed_digits(P["pi_kp"].text, n["pi_kp"]))
    v["pi_ki"] = transcription(printed_digits(P["pi_ki"].text, n["pi_ki"]))
    v["controller_20"] = transcription(error_within(n["controller_20_max_rel_diff"], 1e-12))
    # Fig. 11
    v["fig11_frequency"] = setting("fig11_frequency", n["fig11_frequency_rad_s"])
    v["fig11_tracking"] = at_most(
        n["fig11_rms_error_icad_rel"], t["tracking_rel"], yes="low error", no="not low"
    )
    v["fig11_pi_worse"] = ratio_at_least(
        n["fig11_rms_error_pi_a"],
        n["fig11_rms_error_icad_a"],
        t["better_ratio"],
        yes="(20) tracks better",
        no="(20) not clearly better",
    )
    # Fig. 13
    v["fig13_reference"] = setting("fig13_speed", n["fig13_speed_reference_rad_s"])
    fig13_settled = {
        "the speed": speed_settled(n["fig13_speed_drift_rad_s"], n["fig13_steady_window_s"])
    }
    v["fig13_final"] = when_settled(
        within_abs(n["fig13_speed_final_rad_s"], P["fig13_speed"].value, t["speed_abs"], " rad/s"),
        fig13_settled,
        " rad/s",
    )
    v["fig13_dip"] = at_most(
        abs(n["fig13_load_dip_rad_s"]) / P["fig13_speed"].value,
        t["load_dip_rel"],
        yes="rejected",
        no="large dip",
    )
    v["fig13_balance"] = when_settled(
        within_abs(n["fig13_torque_residual_n_m"], 0.0, t["torque_balance_abs"], " N m"),
        fig13_settled,
        " rad/s",
    )
    v["fig13_tracking"] = at_most(
        n["fig13_rms_error_rel"], t["tracking_rel"], yes="low error", no="not low"
    )
    v["fig13_amplitude"] = amplitude_change_verdict(n, t)
    v["fig13_modulation"] = at_most(
        n["fig13_peak_modulation"],
        1.0 - t["modulation_margin"],
        yes="clearly within the limits",
        no="not clearly within the limits",
    )
    # Fig. 14
    v["fig14_reference"] = setting("fig14_position", n["fig14_position_reference_rad"])
    v["fig14_final"] = when_settled(
        within_abs(
            n["fig14_position_final_rad"], P["fig14_position"].value, t["position_abs"], " rad"
        ),
        {
            "the position": judge_settling(
                n["fig14_position_drift_rad"],
                n["fig14_steady_window_s"],
                t["settled_position_abs"],
            )
        },
        " rad",
    )
    v["fig14_settled_before_load"] = when_settled(
        within_abs(
            n["fig14_preload_position_rad"],
            P["fig14_position"].value,
            t["position_abs"],
            " rad",
            yes="settled at the reference",
            no="away from the reference",
        ),
        {
            "the position": judge_settling(
                n["fig14_preload_drift_rad"],
                n["fig14_preload_window_s"],
                t["settled_position_abs"],
            )
        },
        " rad",
    )
    v["fig14_dip"] = at_most(
        abs(n["fig14_load_dip_rad"]) / P["fig14_position"].value,
        t["position_dip_rel"],
        yes="slight",
        no="not slight",
    )
    v["fig14_load_time"] = transcription(
        within_abs(
            n["fig14_load_time_s"], P["fig14_load_time"].value, 0.0, " s", no="differs (assumed)"
        )
    )
    v["fig14_tracking"] = at_most(
        n["fig14_rms_error_rel"], t["tracking_rel"], yes="low error", no="not low"
    )
    # Fig. 16
    v["fig16_reference"] = setting("fig16_speed", n["fig16_speed_reference_rad_s"])
    v["fig16_slope_icad"] = within_rel(
        n["fig16_slope_icad_rad_s2"], n["fig16_ideal_slope_rad_s2"], t["ramp_slope_rel"]
    )
    rel_pi = (n["fig16_slope_pi_rad_s2"] - n["fig16_ideal_slope_rad_s2"]) / abs(
        n["fig16_ideal_slope_rad_s2"]
    )
    rel_icad = (n["fig16_slope_icad_rad_s2"] - n["fig16_ideal_slope_rad_s2"]) / abs(
        n["fig16_ideal_slope_rad_s2"]
    )
    further = abs(rel_pi) > t["ramp_slope_rel"] and abs(rel_pi) > abs(rel_icad)
    v["fig16_slope_pi"] = Verdict(
        further,
        ("agrees: the PI's ramp is further from the ideal" if further else "differs: the PI's "
         "ramp is not further from the ideal")
        + f" (relative difference {fmt(100 * rel_pi, 2)} %, tolerance {pct(t['ramp_slope_rel'])};"
        f" (20): {fmt(100 * rel_icad, 2)} %)",
    )  # fmt: skip
    v["fig16_closer"] = ratio_at_least(
        n["fig16_ramp_error_pi_rad_s"],
        n["fig16_ramp_error_icad_rad_s"],
        t["better_ratio"],
        yes="(20) significantly closer to the ideal",
        no="(20) not significantly closer",
    )
    v["fig16_current"] = ratio_at_least(
        n["fig16_rms_error_pi_a"],
        n["fig16_rms_error_icad_a"],
        t["better_ratio"],
        yes="PI has greater error",
        no="PI error not clearly greater",
    )
    v["fig16_pi_steady"] = fig16_steady_verdict(n, t)
    # Figs. 18, 20
    v["steps_speed"] = setting("w_r_steps", n["steps_speed_rad_s"])
    v["fig18_overshoot"] = overshoot_order(
        n["step_overshoot_high_ki_pi"],
        n["step_overshoot_icad"],
        t["overshoot_order_abs"],
        "the high-K_I PI overshoots more than (20)",
        "the high-K_I PI does not overshoot clearly more than (20)",
    )
    v["fig20_overshoot"] = overshoot_order(
        n["step_overshoot_icad"],
        n["step_overshoot_inner_pi"],
        t["overshoot_order_abs"],
        "(20) overshoots more than its inner PI",
        "(20) does not overshoot clearly more than its inner PI",
    )
    v["fig20_ringing"] = ratio_at_least(
        n["step_ringing_inner_pi"],
        n["step_ringing_icad"],
        t["ringing_ratio"],
        yes="the inner PI rings more",
        no="the inner PI does not ring clearly more",
    )
    v["fig18_ringing"] = ringing_eliminated_verdict(n, t)
    for label in ("icad", "inner_pi", "high_ki_pi"):
        v[f"step_linear_{label}"] = within_abs(
            n[f"step_overshoot_{label}"], n[f"step_overshoot_linear_{label}"], t["overshoot_abs"]
        )
        v[f"step_linear_delayed_{label}"] = within_abs(
            n[f"step_overshoot_{label}"],
            n[f"step_overshoot_linear_delayed_{label}"],
            t["overshoot_abs"],
        )
    # Fig. 23
    for k, f in targets.PERTURBATION_FACTORS.items():
        v[f"fig23_factor_{k}"] = transcription(
            within_rel(n[f"fig23_factor_{k}"], f, t["setting_rel"])
        )
    v["fig23_frequency"] = setting("fig23_frequency", n["fig23_frequency_rad_s"])
    v["fig23_tracking"] = at_most(
        n["fig23_rms_error_rel"], t["tracking_rel"], yes="closely follow", no="not close"
    )
    # coupling
    for key in ("im", "pmsg"):
        if f"coupling_{key}_max_rel_error" in n:
            v[f"coupling_{key}"] = error_within(
                n[f"coupling_{key}_max_rel_error"],
                t["coupling_rel"],
                f"largest relative difference up to {fmt(t['coupling_w_max'])} rad/s",
            )
    if "coupling_im_5khz_max_rel_error_delayed" in n:
        v["coupling_im_5khz_delayed"] = error_within(
            n["coupling_im_5khz_max_rel_error_delayed"],
            t["coupling_rel"],
            f"largest relative difference to (10) with the hold's delay, up to "
            f"{fmt(t['coupling_w_max'])} rad/s",
        )
        v["coupling_im_5khz"] = error_within(
            n["coupling_im_5khz_max_rel_error"],
            t["coupling_rel"],
            f"largest relative difference to (10) without delay, up to "
            f"{fmt(t['coupling_w_max'])} rad/s",
        )
    if "coupling_im_peak_db" in n:
        v["coupling_printed_peak"] = at_most(
            n["coupling_im_peak_db"],
            targets.NOMINAL_20["coupling_peak"].value,
            " dB",
            yes="within it",
            no="above it",
        )
        v["coupling_spec"] = at_most(n["coupling_im_peak_db"], targets.SPEC_COUPLING.value, " dB")
        v["coupling_linear_range"] = at_most(
            n["coupling_im_peak_voltage_v"], VOLTAGE_LIMIT, " V", yes="linear", no="limited"
        )
    if "coupling_hold_change_db" in n:
        amp = [
            w
            for w, d in zip(
                n["coupling_hold_frequencies_rad_s"], n["coupling_hold_change_db"], strict=True
            )
            if d > t["coupling_change_db"]
        ]
        v["coupling_hold_amplifies"] = Verdict(
            bool(amp),
            (
                f"agrees: the 5 kHz hold raises the coupling by more than "
                f"{fmt(t['coupling_change_db'])} dB at {', '.join(fmt(w) for w in amp)} rad/s"
                if amp
                else f"differs: the 5 kHz hold raises the coupling by more than "
                f"{fmt(t['coupling_change_db'])} dB at no measured frequency"
            ),
        )
    return v


def amplitude_change_verdict(n: dict, t: dict) -> Verdict:
    """Fig. 13(c): the load change "reflects as an amplitude change in the references". Holds
    when the reference amplitude after the load differs from the one before by at least
    ``t["amplitude_change_rel"]`` of it, and equals the field-oriented prediction from the
    electromagnetic torques (``numbers.reference_amplitude_change``) within
    ``t["amplitude_prediction_rel"]``: the change is the load's."""
    before, after = n["fig13_ref_amplitude_before_a"], n["fig13_ref_amplitude_after_a"]
    predicted = n["fig13_ref_amplitude_predicted_a"]
    change = (after - before) / before
    off = (after - predicted) / predicted
    changes = abs(change) >= t["amplitude_change_rel"]
    predicted_ok = abs(off) <= t["amplitude_prediction_rel"]
    return Verdict(
        changes and predicted_ok,
        f"{'agrees' if changes and predicted_ok else 'differs'}: the reference amplitude "
        f"{'changes' if changes else 'does not change clearly'} at the load change, "
        f"{fmt(before, 4)} A -> {fmt(after, 4)} A ({fmt(100 * change, 3)} %, tolerance: at least "
        f"{pct(t['amplitude_change_rel'])}); field orientation predicts {fmt(predicted, 4)} A "
        f"from the torque (relative difference {fmt(100 * off, 2)} %, tolerance "
        f"{pct(t['amplitude_prediction_rel'])}): "
        + ("the change is the load's" if predicted_ok else "the change is not the predicted one"),
    )


def ringing_eliminated_verdict(n: dict, t: dict) -> Verdict:
    """Fig. 18: the high-K_I PI "eliminates the ringing associated with lower gains around 300
    rad/s". The lower-gain PI run beside it is the inner PI of (22) (K_I = 3.265e5 < 9e5).
    Holds when the lower-gain PI rings at least ``t["ringing_ratio"]`` times as much as the
    high-K_I PI (the rule of Fig. 20's ringing) and the high-K_I PI rings no more than (20),
    which Fig. 20 calls "without the ringing"."""
    high, low, icad = (
        n["step_ringing_high_ki_pi"],
        n["step_ringing_inner_pi"],
        n["step_ringing_icad"],
    )
    ratio = low / high if high > 0 else float("inf")
    less = ratio >= t["ringing_ratio"]
    as_icad = high <= icad
    ok = less and as_icad
    return Verdict(
        ok,
        f"{'agrees' if ok else 'differs'}: the high-K_I PI rings "
        f"{'less' if less else 'not clearly less'} than the lower-gain inner PI of (22) (ringing "
        f"{fmt(high)} vs {fmt(low)}: ratio {fmt(ratio, 3)}, threshold {fmt(t['ringing_ratio'])}) "
        f"and {'no more' if as_icad else 'more'} than (20), 'without the ringing' in Fig. 20 "
        f"({fmt(icad)})",
    )


def overshoot_order(larger: float, smaller: float, tol: float, yes: str, no: str) -> Verdict:
    """Figs. 18, 20: one simulated step overshoot exceeds another by at least ``tol`` (fractions
    of the step), both printed in % of the step."""
    ok = larger - smaller >= tol
    return Verdict(
        ok,
        f"{'agrees' if ok else 'differs'}: {yes if ok else no} ({pct(larger)} vs "
        f"{pct(smaller)}: difference {fmt(100 * (larger - smaller), 3)} % of the step, "
        f"tolerance: at least {pct(tol)})",
    )


def hold_explanation(n: dict, t: dict, names: dict[str, str]) -> str:
    """The sentence under Figs. 18/20 on the gap between the simulated and the continuous linear
    overshoot: printed as explained by the modelled hold only for a controller where the linear
    loop with the hold's delay agrees with the simulation while the continuous one does not;
    otherwise the cause is stated as open."""
    tol = t["overshoot_abs"]
    gaps = [
        label
        for label in names
        if abs(n[f"step_overshoot_{label}"] - n[f"step_overshoot_linear_{label}"]) > tol
    ]
    if not gaps:
        return (
            "Every simulated overshoot agrees with the continuous linear one (tolerance "
            f"{pct(tol)} of the step): no gap to explain."
        )
    delay_us = fmt(1e6 * n["steps_hold_delay_s"])
    closed = [
        g
        for g in gaps
        if abs(n[f"step_overshoot_{g}"] - n[f"step_overshoot_linear_delayed_{g}"]) <= tol
    ]
    spoiled = [
        label
        for label in names
        if label not in gaps
        and abs(n[f"step_overshoot_{label}"] - n[f"step_overshoot_linear_delayed_{label}"]) > tol
    ]
    head = (
        "The simulated overshoot differs from the continuous linear one beyond "
        f"{pct(tol)} of the step for {_names(names, gaps)}. A single loop delay of {delay_us} us "
        "(the average delay N T_s / 2 of the 5 kHz carrier hold) in the linear loop gives the "
        "'linear with the hold's delay' overshoots above. "
    )
    open_ = [g for g in gaps if g not in closed]
    if not open_ and not spoiled:
        return head + (
            "It closes the gap for each of them and keeps the others within the tolerance: the "
            "hold's delay accounts for the difference."
        )
    findings = []
    if closed:
        findings.append(f"it closes the gap for {_names(names, closed)}")
    if open_:
        findings.append(f"it does not close the gap for {_names(names, open_)}")
    if spoiled:
        findings.append(
            f"it moves {_names(names, spoiled)} beyond the tolerance, which the continuous loop met"
        )
    return head + (
        f"Computed: {'; '.join(findings)}. This single-delay model does not reproduce the "
        "simulated overshoots, so the cause of the gap is open (the sampling, the carrier latch "
        "and the SVPWM are not in the linear model)."
    )


def coupling_delay_text(n: dict, t: dict) -> str:
    """The paragraph under the coupling tables: whether the differences to (10) grow with the
    frequency (largest at the highest measured frequency, smallest at the lowest) and how well
    (10) with the hold's delay matches; for the PMSG, whether the difference stays at low
    frequencies (above ``coupling_rel`` at the lowest one) and whether the delayed prediction,
    which also turns the dq voltage back by w_e N T_s / 2, removes it there."""
    parts = []
    for key, name in (("im", "IM, ideal"), ("im_5khz", "IM, 5 kHz"), ("pmsg", "PMSG")):
        rows = n.get(f"coupling_{key}_rows")
        if not rows:
            continue
        err = [r["relative_error"] for r in rows]
        grows = err[-1] == max(err) and err[0] == min(err)
        parts.append(
            f"{name}: the difference to (10) is {'largest' if grows else 'not largest'} at the "
            f"highest measured frequency and {'smallest' if grows else 'not smallest'} at the "
            f"lowest ({pct(err[0])} ... {pct(err[-1])}); with the hold's delay in k, (10) "
            f"matches to {pct(n[f'coupling_{key}_max_rel_error_delayed_all'])} over all "
            "frequencies"
        )
    text = "; ".join(parts) + (
        ". The delay model (phase w N T_s / 2) is a first-order picture of the hold, exact only "
        f"as w N T_s -> 0. The IM's injection frequencies include "
        f"{fmt(n['coupling_im_peak_at_rad_s'], 5)} rad/s, where |(10)| peaks."
    )
    rows = n.get("coupling_pmsg_rows")
    if rows and rows[0]["relative_error"] > t["coupling_rel"]:
        removed = rows[0]["relative_error_delayed"] <= t["coupling_rel"]
        text += (
            f" For the PMSG the difference at the lowest frequency, {fmt(rows[0]['frequency_rad_s'])} "
            f"rad/s, is {pct(rows[0]['relative_error'])}, above {pct(t['coupling_rel'])}; the "
            "delayed prediction, which also turns the dq voltage back by w_e N T_s / 2 (the frame "
            "turns during the hold; `analysis._coupling`), "
            + (
                f"brings it to {pct(rows[0]['relative_error_delayed'])}."
                if removed
                else f"leaves {pct(rows[0]['relative_error_delayed'])}: the cause is open."
            )
        )
    return text


def _names(names: dict[str, str], labels: list[str]) -> str:
    return ", ".join(names[label] for label in labels)


def fig16_steady_verdict(n: dict, t: dict) -> Verdict:
    """Sec. VII: the PI gives "a slow response with a large steady-state error" near 370 rad/s
    (Fig. 16). Judged on the steady window only if both speeds are settled there (else "not
    settled"); the steady-state error is "large" from ``t["large_steady_rel"]`` of the
    reference. The verdict holds when the large error is reproduced; its sentence also says
    whether the slow response is: the magnitude of the PI's ramp slope is more than
    ``t["ramp_slope_rel"]`` below the ideal tau_max / J and below (20)'s."""
    ref = abs(n["fig16_speed_reference_rad_s"])
    ideal = abs(n["fig16_ideal_slope_rad_s2"])
    slope_rel_pi = abs(n["fig16_slope_pi_rad_s2"]) / ideal - 1.0
    slope_rel_icad = abs(n["fig16_slope_icad_rad_s2"]) / ideal - 1.0
    slow = slope_rel_pi < -t["ramp_slope_rel"] and slope_rel_pi < slope_rel_icad
    err_pi, err_icad = n["fig16_steady_error_pi_rad_s"], n["fig16_steady_error_icad_rad_s"]
    large = abs(err_pi) >= t["large_steady_rel"] * ref
    text = (
        f"the PI's settled steady-state speed error is {fmt(err_pi, 3)} rad/s "
        f"({fmt(100 * err_pi / ref, 2)} % of the reference) against {fmt(err_icad, 3)} for (20) "
        f'— the paper\'s "large" steady-state error is {"" if large else "not "}reproduced '
        f"(large: at least {pct(t['large_steady_rel'])} of the reference); its slow response "
        f"is{'' if slow else ' not'} (ramp slope {fmt(100 * slope_rel_pi, 2)} % from the ideal, "
        f"(20) {fmt(100 * slope_rel_icad, 2)} %, tolerance {pct(t['ramp_slope_rel'])})"
    )
    window = n["fig16_steady_window_s"]
    settled = {
        f"{name}'s speed": judge_settling(
            n[f"fig16_speed_drift_{label}_rad_s"], window, t["settled_speed_abs"]
        )
        for label, name in (("pi", "the PI"), ("icad", "(20)"))
    }
    return when_settled(Verdict(large, text), settled, " rad/s")
