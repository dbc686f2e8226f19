"""Every reference quantity the reproduction reports show, computed through public names only
(``acdrive.machines``, ``.control``, ``.analysis``, ``.sim``, ``.plant``, ``.scenarios``) and
checked against the paper's printed value (to half a unit of its last printed digit, or the
report's stated tolerance) or against the analytic value.

Where the paper misprints, the check is against what the equations give and the misprint is
asserted as such (the printed value is *not* reached)."""

from __future__ import annotations

import cmath
import math

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

from acdrive.analysis import (
    PAPER_PERTURBATION,
    PAPER_SPECS,
    Perturbation,
    analyse,
    check_controller,
    compare_design_models,
    complex_hurwitz,
    evaluate_ss,
    gm_min,
    hold_delay,
    icad_coupling,
    icad_coupling_peak,
    icad_quantities,
    im_dgamma_re_im,
    im_msf_at_rotor_speed,
    im_msf_closed_form,
    im_msf_magnitude_at_rotor_speed,
    im_msf_positive_crossing,
    msf_positive_real_crossing,
    pi_gain_for_crossover,
    plant_from_params,
    pmsg_msf,
    structure_conditions,
)
from acdrive.control import (
    FIG17_K_I,
    FIG17_K_P,
    FIG17_PI_FAMILY,
    FIG18_PI,
    PAPER_20,
    PAPER_PI,
    PI_OF_22,
    current_loop_gains,
)
from acdrive.machines import (
    BODSON_DFIM,
    DELORENZO_IM,
    DELORENZO_IM_13,
    PMSG_2MW,
    UGALDE_IM_300W,
    abc_to_complex,
    complex_power,
    complex_to_abc,
    delta_z_coefficients,
    electrical_poles,
    electromagnetic_torque,
    lossless_law_torque,
    machine_vector,
    params_from_stationary_matrix,
    rotor_current_for,
    rotor_voltage_for,
    shifted_delta_z_coefficients,
    stator_current_lossless,
    stator_current_ss,
    steady_state_currents,
    torque_limits_case1,
)


def printed(value: float, text: str) -> bool:
    """``value`` rounds to the number printed as ``text`` (half a unit of its last digit)."""
    mantissa = text.lower().split("e")[0]
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    exponent = int(text.lower().split("e")[1]) if "e" in text.lower() else 0
    return abs(value - float(text)) <= 0.5 * 10.0 ** (exponent - decimals) * (1 + 1e-12)


def entries(p, w_r=1.0):
    A, B, C, _ = stator_current_ss(p, w_r)
    return {
        "a11": A[0, 0],
        "a13": A[0, 2],
        "a14": A[0, 3] / w_r,
        "a31": A[2, 0],
        "a33": A[2, 2],
        "b": B[0, 0],
        "C": C,
    }


# --- Ugalde-Loo et al. ---------------------------------------------------------------------


def test_pmsg_matrices_and_gamma_of_ugalde_loo_sec_3():
    p = PMSG_2MW
    plant = plant_from_params(p, 0.0)
    assert printed(plant.A[0, 0], "-14.0466")  # -R_s / L_d
    assert printed(plant.B[0, 0], "3105.59")  # 1 / L_d
    # (35): d(s) = s^2 + 28.0932 s + 197.31 at w_gen = 0
    den = np.poly(plant.A)
    assert printed(den[1], "28.0932") and printed(den[2], "197.31")
    # (18) against the state space at w_gen = 157 rad/s (electrical 314)
    w_e = 2 * 157.0
    plant = plant_from_params(p, w_e)
    s = 1j * np.array([1.0, 30.0, 1e3])
    G = evaluate_ss(plant.A, plant.B, plant.C, plant.D, s)
    gamma = G[:, 0, 1] * G[:, 1, 0] / (G[:, 0, 0] * G[:, 1, 1])
    assert np.allclose(pmsg_msf(p, w_e, s), gamma, rtol=1e-9)
    # double pole of gamma at -R_s/L_d = -14.05 (sec. 3.5)
    assert printed(-p.R_s / p.L_d, "-14.05")
    assert structure_conditions(plant).iv


def test_matrix_80_and_the_closed_forms_of_ugalde_loo_sec_4():
    p = UGALDE_IM_300W
    e = entries(p)
    # (80) as printed: a_14, a_31, a_33 agree to the digits, a_11, a_13, b_11 do not (the report
    # shows both; the rounding of sec. 4.5 reaches all six)
    assert printed(e["a14"], "9") and printed(e["a31"], "22.3") and printed(e["a33"], "-15.4")
    assert not printed(e["a11"], "-359.2") and not printed(e["b"], "9.7")
    assert np.array_equal(e["C"], np.eye(2, 4))  # C = [I_2 0] of (41)
    w_r = 300.0
    # F(2) of (73): root of re d_gamma, printed closed form sqrt(Om (R_r^2 + w_r^2 L_r^2) R_s)/Om
    Rs, Rr, Ls, Lr, Lm, sg = p.R_s, p.R_r, p.L_s, p.L_r, p.L_m, p.sigma
    om = 2 * sg * Ls * Lr * Rr + Lr**2 * Rs + Lm**2 * Rr
    f2 = brentq(lambda x: im_dgamma_re_im(p, w_r, x)[0], 1e-6, 1e6)
    assert f2 == pytest.approx(math.sqrt(om * (Rr**2 + w_r**2 * Lr**2) * Rs) / om, rel=1e-7)
    assert printed(f2, "190.9421")
    # F(3): the crossing of the positive real axis; the consistent closed form, not the printed
    psi = sg * Ls * Lr
    f3_consistent = math.sqrt(
        (psi * (w_r**2 * Lr**2 + Rr**2) + 2 * Lr**2 * Rs * Rr + Lm**2 * Rr**2) / (psi * Lr**2)
    )
    w3, g3 = im_msf_positive_crossing(p, w_r)
    assert w3 == pytest.approx(f3_consistent, rel=1e-9)
    assert printed(w3, "313.4149") and printed(float(np.real(g3)), "0.6204")
    ups = 2 * Lr * Rs * Rr + Lm**2 * Rr**2
    f3_as_printed = math.sqrt(psi * (psi * (w_r**2 * Lr**2 + Rr**2) + ups)) / psi**2
    assert abs(f3_as_printed / w3 - 1) > 1.0  # the misprint (the report: 3037.961 vs 313.4)
    # gamma of (60)-(61) against the state space
    plant = plant_from_params(p, w_r)
    w = np.array([50.0, 313.0, 2000.0])
    G = evaluate_ss(plant.A, plant.B, plant.C, plant.D, 1j * w)
    gamma = G[:, 0, 1] * G[:, 1, 0] / (G[:, 0, 0] * G[:, 1, 1])
    assert np.allclose(im_msf_closed_form(p, w_r, w), gamma, rtol=1e-8)
    # (45): d_w1 = 753.0583 (coefficient of s^3 of the characteristic polynomial)
    assert printed(np.poly(plant.A)[1], "753.0583")


# --- Amezquita-Brooks et al. ---------------------------------------------------------------


def test_matrix_13_its_parameters_and_gm_min():
    e = entries(DELORENZO_IM_13)
    for key, text in (("a11", "-359.2"), ("a14", "9.2"), ("a31", "21.9"), ("a33", "-15.4")):
        assert printed(e[key], text), key
    assert printed(e["b"], "9.7")
    back = params_from_stationary_matrix(
        a11=-359.2, a13=141.8, a14_per_wr=9.2, a31=21.9, a33=-15.4, b11=9.7, n_p=1
    ).params
    assert back.L_s == pytest.approx(DELORENZO_IM_13.L_s, rel=1e-12)
    # with the Appendix parameters b_11 is 10.45, not 9.7 (the report's rows)
    assert entries(DELORENZO_IM)["b"] == pytest.approx(10.446, abs=5e-4)
    # (19): G_M,min = 0.75 (-2.47 dB) with the parameters of (13)
    g = gm_min(DELORENZO_IM_13)
    assert printed(g, "0.75") and printed(20 * math.log10(g), "-2.47")
    # (14) and (18) against the state space at w_r = 375
    w_r = 375.0
    plant = plant_from_params(DELORENZO_IM_13, w_r)
    G = evaluate_ss(plant.A, plant.B, plant.C, plant.D, np.array([1j * w_r]))[0]
    gamma = G[0, 1] * G[1, 0] / (G[0, 0] * G[1, 1])
    assert im_msf_at_rotor_speed(DELORENZO_IM_13, w_r) == pytest.approx(gamma, rel=1e-8)
    assert im_msf_magnitude_at_rotor_speed(DELORENZO_IM_13, w_r) == pytest.approx(
        abs(gamma), rel=1e-8
    )


@pytest.mark.slow
def test_controller_20_results_of_sec_v_c_and_vii():
    w_r = 375.0
    a = analyse(plant_from_params(DELORENZO_IM_13, w_r), PAPER_20, PAPER_20)
    ch = a.channels[0]
    assert ch.margins.crossover_rad_s == pytest.approx(3350.0, rel=0.01)  # 'bandwidth' 3350
    assert ch.margins.pm_deg == pytest.approx(67.0, abs=1.0)  # PM 67 deg (Fig. 19)
    assert -ch.margins.gm_reduction_db > PAPER_SPECS.gm_db  # GM > 12 dB
    assert ch.structural.gm_db == pytest.approx(3.4, abs=0.1)  # GM of gamma h_j 3.4 dB
    assert a.b1 and a.b2 and a.closed_loop_stable
    c375 = icad_quantities(
        evaluate_ss(a.plant.A, a.plant.B, a.plant.C, a.plant.D, np.array([1j * w_r])),
        PAPER_20.freqresp(np.array([w_r])),
        PAPER_20.freqresp(np.array([w_r])),
    )["c"][0, 0]
    assert 20 * math.log10(abs(c375)) == pytest.approx(20.0, abs=2.0)  # 'approx 20 dB'
    inner = analyse(plant_from_params(DELORENZO_IM_13, w_r), PI_OF_22, PI_OF_22)
    assert inner.channels[0].margins.pm_deg == pytest.approx(80.0, abs=1.0)  # PM 80 deg
    assert not check_controller(DELORENZO_IM_13, PAPER_20, PAPER_20, PAPER_SPECS).unmet


def test_controller_20_on_the_perturbed_plant_of_sec_viii():
    p = PAPER_PERTURBATION.apply(DELORENZO_IM_13)
    for name, factor in (("R_s", 2.0), ("R_r", 2.0), ("L_s", 0.6), ("L_r", 0.6), ("L_m", 0.59)):
        assert getattr(p, name) == pytest.approx(factor * getattr(DELORENZO_IM_13, name))
    ch = analyse(plant_from_params(p, 375.0), PAPER_20, PAPER_20).channels[0]
    # the printed 'bandwidth' 3700 is not reached to the 1 % of the nominal 3350 (3770, +1.9 %);
    # the factor L_m x 0.59 as printed stands for 0.585 ... 0.595, over which the crossover
    # spans 3700 (the report's explanation)
    assert abs(ch.margins.crossover_rad_s / 3700.0 - 1) > 0.01
    ends = [
        analyse(
            plant_from_params(
                Perturbation(R_s=2.0, R_r=2.0, L_s=0.6, L_r=0.6, L_m=f).apply(DELORENZO_IM_13),
                375.0,
            ),
            PAPER_20,
            PAPER_20,
        )
        .channels[0]
        .margins.crossover_rad_s
        for f in (0.585, 0.595)
    ]
    assert ends[0] < 3700.0 < ends[1]
    assert ch.margins.pm_deg == pytest.approx(77.0, abs=1.0)
    assert -ch.margins.gm_reduction_db == pytest.approx(20.0, abs=1.0)
    assert ch.kg_margins.pm_deg == pytest.approx(77.0, abs=1.0)
    assert -ch.kg_margins.gm_reduction_db == pytest.approx(27.0, abs=1.0)


def test_controllers_and_design_models_as_printed():
    w = np.array([10.0, 375.0, 3000.0])
    s = 1j * w
    k20 = 326.5 * (s + 1000) / s * (s + 400) ** 2 / (s**2 + 100 * s + 42500)
    assert np.allclose(PAPER_20.freqresp(w), k20, rtol=1e-12)
    assert np.allclose(PAPER_PI.freqresp(w), 360.0 + 9000.0 / s, rtol=1e-12)
    assert np.allclose(PI_OF_22.freqresp(w), 326.5 * (s + 1000) / s, rtol=1e-12)
    assert FIG18_PI is FIG17_PI_FAMILY[-1] and FIG17_K_I[-1] == 9e5 and len(FIG17_K_P) == 7
    cmp = compare_design_models(DELORENZO_IM_13, 375.0, np.logspace(0, 5, 2000))
    # model D = 1/(L_s s + R_s) against A: at 1e5 rad/s the gain ratio is sigma (D uses L_s,
    # not sigma L_s), 20 log10 sigma = -23 dB
    top = np.argmin(np.abs(cmp.w - 1e5))
    ratio = abs(cmp.responses["D"][top] / cmp.responses["A"][top])
    assert 20 * math.log10(ratio) == pytest.approx(20 * math.log10(DELORENZO_IM_13.sigma), abs=0.5)
    assert cmp.errors["D"].max_gain_error_db > 3.0  # 'insufficient' (the report's tolerance)


def test_hold_delay_is_half_the_hold():
    assert hold_delay(10, 2e-5) == pytest.approx(1e-4)


# --- Bodson ----------------------------------------------------------------------------------


def test_transforms_power_and_torque_of_bodson():
    theta = 0.3
    a, b, c = (math.cos(theta - k * 2 * math.pi / 3) for k in range(3))
    x = abc_to_complex(a, b, c)
    assert x == pytest.approx(math.sqrt(1.5) * cmath.exp(1j * theta), rel=1e-12)  # (1)
    assert np.allclose(complex_to_abc(x), (a, b, c), atol=1e-12)  # (2)
    i = abc_to_complex(*(math.cos(theta - 0.2 - k * 2 * math.pi / 3) for k in range(3)))
    s_ = complex_power(x, i)
    assert s_.real == pytest.approx(1.5 * math.cos(0.2), rel=1e-12)  # (5): P = sum v_k i_k
    p = BODSON_DFIM
    i_s, i_r = 2.0 + 1.0j, -1.5 + 0.5j
    tau = electromagnetic_torque(machine_vector(p), i_s, i_r)
    assert tau == pytest.approx(p.n_p * p.M * (i_s * np.conj(i_r)).imag, rel=1e-12)  # (9)


def test_steady_state_relations_of_bodson_19_20_43():
    p = machine_vector(BODSON_DFIM)
    w_e, w_m, v_s, i_s = 2 * math.pi * 60, 150.0, 100.0 + 0j, 3.0 - 2.0j
    v_r = rotor_voltage_for(p, w_e, w_m, v_s, i_s)  # (20)
    i_s2, i_r2 = steady_state_currents(p, w_e, w_m, v_s, v_r)  # (19)
    assert i_s2 == pytest.approx(i_s, rel=1e-10)
    assert rotor_current_for(p, w_e, v_s, i_s) == pytest.approx(i_r2, rel=1e-10)  # (43)


def test_electrical_stability_of_bodson_13_to_18():
    p = BODSON_DFIM
    w_e, w_m = 2 * math.pi * 60, 150.0
    poles = electrical_poles(p, w_e, w_m)
    assert np.allclose(np.polyval(delta_z_coefficients(p, w_e, w_m), poles), 0, atol=1e-6)
    # (15)-(17): the shifted polynomial is Hurwitz (the machine is electrically stable), and
    # Delta_2 of (18) is positive
    assert complex_hurwitz(shifted_delta_z_coefficients(p, w_m)).stable
    Ls, Lr, Rs, Rr, M = p.L_s, p.L_r, p.R_s, p.R_r, p.M
    sg = 1 - M**2 / (Ls * Lr)
    d2 = (Ls * Rr + Lr * Rs) ** 2 * Rs * Rr + Ls * Lr * Rs * Rr * (p.n_p * w_m) ** 2 * sg * Ls * Lr
    assert d2 > 0


def test_rotor_current_loop_gains_of_bodson_49():
    p = BODSON_DFIM
    a, r_t = 500.0, p.R_r + 0.1
    sg = 1 - p.M**2 / (p.L_s * p.L_r)
    k_p, k_i = current_loop_gains(sg, p.L_r, r_t, a)
    # with the plant 1/(sigma L_r s + R_T) the PI K_P + K_I/s gives the loop a/s: (50)
    s = 1j * 37.0
    loop = (k_p + k_i / s) / (sg * p.L_r * s + r_t)
    assert loop == pytest.approx(a / s, rel=1e-12)


# --- quantities the reports compute with helpers of their own, reached through public names --------


def test_gamma_crossing_of_the_positive_real_axis_is_the_closed_form_f3():
    """``msf_positive_real_crossing`` (the reports' crossing of gamma with the positive real axis)
    equals the closed form F(3) of Ugalde-Loo (72)-(73) for the 300 W IM, and the 2 MW PMSG's
    gamma does not cross it (Ugalde-Loo sec. 3.5: gamma(j w) real negative)."""
    w3, g3 = im_msf_positive_crossing(UGALDE_IM_300W, 300.0)
    x, wx = msf_positive_real_crossing(plant_from_params(UGALDE_IM_300W, 300.0))
    assert wx == pytest.approx(w3, rel=1e-8) and x == pytest.approx(float(np.real(g3)), rel=1e-8)
    assert printed(x, "0.6204")
    for w_gen in (0.0, 78.5, 157.0):
        x, wx = msf_positive_real_crossing(plant_from_params(PMSG_2MW, 2 * w_gen))
        assert x == 0.0 and math.isnan(wx)


def test_coupling_peak_of_10_is_the_maximum_of_10():
    """``icad_coupling_peak``: the largest |(10)| of the DeLorenzo IM with (20) at 375 rad/s (the
    IM report's injection frequency 379.3 rad/s and its (10) peak -18.85 dB) is the maximum of
    |(10)| found by a bounded optimiser around it."""
    w_peak, peak_db = icad_coupling_peak(DELORENZO_IM, 375.0, PAPER_20)
    best = minimize_scalar(lambda w: -abs(icad_coupling(DELORENZO_IM, 375.0, PAPER_20, [w])[0]),
                           bounds=(w_peak - 5, w_peak + 5), method="bounded",
                           options={"xatol": 1e-6})  # fmt: skip
    assert w_peak == pytest.approx(best.x, abs=0.1)  # the grid step is 0.1 rad/s
    # within the grid step the peak is flat to second order: 1e-3 dB
    assert peak_db == pytest.approx(20 * math.log10(-best.fun), abs=1e-3)
    assert peak_db <= 20 * math.log10(-best.fun) + 1e-12
    assert printed(w_peak, "379.3") and printed(peak_db, "-18.85")


def test_pi_family_gains_are_those_of_equal_crossover_with_20():
    """``pi_gain_for_crossover``: the K_P of each PI of Fig. 17 puts the crossover of c_i at that
    of (20) (the built-in FIG17_K_P, to the bisection's tolerance)."""
    plant = plant_from_params(DELORENZO_IM_13, 375.0)
    w_c = analyse(plant, PAPER_20, PAPER_20).channels[0].margins.crossover_rad_s
    for k_i, k_p in zip(FIG17_K_I, FIG17_K_P, strict=True):
        found = pi_gain_for_crossover(plant, k_i, w_c)
        assert found == pytest.approx(k_p, rel=1e-9)
        c = icad_quantities(
            evaluate_ss(plant.A, plant.B, plant.C, plant.D, np.array([1j * w_c])),
            (k_p + k_i / (1j * np.array([w_c]))),
            (k_p + k_i / (1j * np.array([w_c]))),
        )["c"][0, 0]
        assert abs(c) == pytest.approx(1.0, rel=1e-7)


def test_torque_of_the_rs_zero_law_is_the_steady_state_of_19():
    """``lossless_law_torque``: the torque of Bodson's R_S = 0 law (38)-(39) on the 0.66 ohm
    motor equals the steady state (19) with the rotor voltage (20) of the lossless current (38),
    at every speed; at tau_LIM the 0.274 N m command gives 0.2235 N m (the Bodson report)."""
    p = machine_vector(BODSON_DFIM)
    w_e, v_s, i_max = 2 * math.pi * 60, math.sqrt(1.5) * 11.1, math.sqrt(1.5) * 6.0
    tau_lim = torque_limits_case1(p, w_e, v_s, i_max, i_max)[2]
    assert printed(tau_lim, "0.274")
    for tau in (0.1, 0.2, tau_lim):
        closed = lossless_law_torque(BODSON_DFIM, w_e, v_s, tau)
        for w_m in (0.0, 100.0, 250.0):
            i_s = stator_current_lossless(p, w_e, v_s, tau, 0.0)
            v_r = rotor_voltage_for(p, w_e, w_m, v_s, i_s)
            i_s2, i_r2 = steady_state_currents(p, w_e, w_m, v_s, v_r)
            assert float(electromagnetic_torque(p, i_s2, i_r2)) == pytest.approx(closed, rel=1e-10)
    assert printed(lossless_law_torque(BODSON_DFIM, w_e, v_s, tau_lim), "0.2235")
