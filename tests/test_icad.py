"""ICAD: frequency responses, MSF, channels, exact Nyquist counts, margins, closed forms."""

import math

import numpy as np
import pytest
import scipy.linalg
import scipy.signal
from hypothesis import given, settings
from hypothesis import strategies as st

from acdrive.analysis import (
    Plant2x2,
    gm_min,
    icad_quantities,
    icad_response,
    im_msf_at_rotor_speed,
    im_msf_closed_form,
    im_msf_magnitude_at_rotor_speed,
    im_msf_positive_crossing,
    plant_for,
    plant_from_params,
    plants_for,
    pmsg_msf,
    structure_conditions,
)
from acdrive.analysis._freqresp import LTI, evaluate_ss, freqresp_ss
from acdrive.analysis._icad import analyse, controller_for, imc_pi, worst
from acdrive.errors import InputError
from acdrive.machines import (
    DELORENZO_IM,
    DELORENZO_IM_13,
    PMSG_2MW,
    UGALDE_IM_300W,
    IMParams,
    PMSGParams,
)

control = pytest.importorskip("control")

K20 = LTI.paper_20()
W = np.logspace(0, 5, 600)


def plant_from_elements(g11: LTI, g12: LTI, g21: LTI, g22: LTI) -> Plant2x2:
    """Block realisation of [[g11, g12], [g21, g22]] from four SISO systems."""
    parts = [g11, g12, g21, g22]
    A = scipy.linalg.block_diag(*[g.A for g in parts])
    sizes = [g.order for g in parts]
    off = np.concatenate([[0], np.cumsum(sizes)])
    n = off[-1]
    B, C = np.zeros((n, 2)), np.zeros((2, n))
    for idx, (i, j) in enumerate([(0, 0), (0, 1), (1, 0), (1, 1)]):
        sl = slice(off[idx], off[idx + 1])
        B[sl, j] = parts[idx].B[:, 0]
        C[i, sl] = parts[idx].C[0, :]
    D = np.array([[g11.D[0, 0], g12.D[0, 0]], [g21.D[0, 0], g22.D[0, 0]]])
    return Plant2x2(A, B, C, D)


def rhp(values) -> int:
    values = np.asarray(values)
    return int(np.sum(values.real > 1e-9 * np.maximum(1, np.abs(values))))


def closed_loop_poles_control(plant: Plant2x2, k1: LTI, k2: LTI) -> np.ndarray:
    """Poles of the MIMO loop built by python-control (independent interconnection)."""
    G = control.ss(plant.A, plant.B, plant.C, plant.D)
    K = control.append(control.ss(k1.A, k1.B, k1.C, k1.D), control.ss(k2.A, k2.B, k2.C, k2.D))
    return control.feedback(G * K, np.eye(2)).poles()


# --- frequency responses ---------------------------------------------------------------------


@pytest.mark.filterwarnings("ignore::scipy.signal.BadCoefficients")  # scipy's ss -> tf step
def test_batched_freqresp_matches_python_control_and_scipy():
    plants = plants_for("delorenzo-im", [0.0, 100.0, 375.0])
    A = np.stack([p.A for p in plants])
    B = np.stack([p.B for p in plants])
    C = np.stack([p.C for p in plants])
    D = np.stack([p.D for p in plants])
    G = freqresp_ss(A, B, C, D, W)
    for b, p in enumerate(plants):
        ref = control.ss(p.A, p.B, p.C, p.D).frequency_response(W)
        np.testing.assert_allclose(G[b], np.moveaxis(ref.complex, -1, 0), rtol=1e-9, atol=1e-15)
        _, h = scipy.signal.freqresp(
            scipy.signal.StateSpace(p.A, p.B[:, :1], p.C[:1], p.D[:1, :1]), W
        )
        np.testing.assert_allclose(G[b, :, 0, 0], h, rtol=1e-9)


def test_defective_matrix_uses_solve_path():
    A = np.array([[-2.0, 1.0], [0.0, -2.0]])  # Jordan block
    G = evaluate_ss(A, np.eye(2), np.eye(2), np.zeros((2, 2)), np.array([1j, 3.0 + 2j]))
    expected = np.linalg.inv(np.array([1j, 3.0 + 2j])[:, None, None] * np.eye(2) - A)
    np.testing.assert_allclose(G, expected, rtol=1e-12)


def test_lti_constructors_match_transfer_functions():
    s = 1j * W
    k = LTI.paper_20()
    expected = 326.5 * (s + 400) ** 2 * (s + 1000) / (s * (s**2 + 100 * s + 42500))
    np.testing.assert_allclose(k.freqresp(W), expected, rtol=1e-10)
    np.testing.assert_allclose(LTI.pi(360, 9000).freqresp(W), 360 + 9000 / s, rtol=1e-12)
    assert not LTI.paper_20().is_stable  # integrator
    assert LTI.zpk([], [-1.0], 1.0).is_stable
    with pytest.raises(InputError, match="improper"):
        LTI.zpk([-1.0, -2.0], [-3.0], 1.0)
    tf = control.tf([2.0, 3.0], [1.0, 4.0, 0.0])
    np.testing.assert_allclose(LTI.from_control(tf).freqresp(W), (2 * s + 3) / (s**2 + 4 * s))


def test_worst_case_never_skips_undefined_figures():
    assert worst([3.0, 1.0, 2.0]) == 1.0 and worst([3.0, 1.0], max) == 3.0
    assert math.isnan(worst([1.0, math.nan, 0.5]))


@settings(max_examples=30, deadline=None)
@given(
    st.lists(st.floats(-50, 50), max_size=3),
    st.lists(st.tuples(st.floats(-50, -0.1), st.floats(0.1, 80)), max_size=2),
    st.lists(st.floats(-60, -0.1), min_size=1, max_size=3),
    st.floats(0.1, 100),
)
def test_zpk_realisation(real_zeros, pole_pairs, real_poles, gain):
    poles = list(real_poles) + [complex(a, b) for a, b in pole_pairs]
    poles += [complex(a, -b) for a, b in pole_pairs]
    zeros = real_zeros[: len(poles)]
    k = LTI.zpk(zeros, poles, gain)
    s = np.array([0.7j, 3.0 + 11j, 150j])
    expected = (
        gain * np.prod([s - z for z in zeros], axis=0) / np.prod([s - p for p in poles], axis=0)
    )
    np.testing.assert_allclose(
        k.evaluate(s), expected, rtol=1e-6
    )  # state-space realisation: cancellation near repeated zeros


# --- MSF, channels, coupling ------------------------------------------------------------------


def test_gamma_batched_equals_independent_evaluation():
    plants = plants_for("ugalde-im-300w", np.linspace(0, 400, 5))
    resp = icad_response(plants, K20, K20, W)
    for b, p in enumerate(plants):
        g = control.ss(p.A, p.B, p.C, p.D).frequency_response(W).complex  # (2, 2, nw)
        gamma = g[0, 1] * g[1, 0] / (g[0, 0] * g[1, 1])
        np.testing.assert_allclose(resp.gamma[b], gamma, rtol=1e-8, atol=1e-14)


def test_channels_and_coupling_equal_mimo_closed_loop():
    """y_i/r_i = c_i/(1+c_i) and y_i/r_j = (10), from (I + G K)^-1 G K; c_i = (3) directly."""
    plant = plant_for("delorenzo-im", 300.0)
    k1, k2 = LTI.paper_20(), LTI.pi(360.0, 9000.0)
    resp = icad_response(plant, k1, k2, W)
    G = resp.G[0]
    K = np.zeros_like(G)
    K[:, 0, 0], K[:, 1, 1] = resp.k
    T = np.linalg.solve(np.eye(2) + G @ K, G @ K)
    np.testing.assert_allclose(resp.T[0, :, 0], T[:, 0, 0], rtol=1e-8)
    np.testing.assert_allclose(resp.T[0, :, 1], T[:, 1, 1], rtol=1e-8)
    np.testing.assert_allclose(resp.coupling[0, :, 0], T[:, 0, 1], rtol=1e-7, atol=1e-14)
    np.testing.assert_allclose(resp.coupling[0, :, 1], T[:, 1, 0], rtol=1e-7, atol=1e-14)
    # the papers' form (3): c_1 = k_1 g_11 (1 - gamma h_2)
    c1 = resp.k[0] * G[:, 0, 0] * (1 - resp.gamma[0] * resp.h[0, :, 1])
    np.testing.assert_allclose(resp.c[0, :, 0], c1, rtol=1e-8)
    # (10): S_i g_ij / g_jj h_j
    cpl = resp.S[0, :, 0] * G[:, 0, 1] / G[:, 1, 1] * resp.h[0, :, 1]
    np.testing.assert_allclose(resp.coupling[0, :, 0], cpl, rtol=1e-8)


def test_icad_quantities_scalar_identity():
    """1 - gamma = det G / (g11 g22) (Amezquita-Brooks, list after (10))."""
    G = evaluate_ss(*[getattr(plant_for("delorenzo-im", 200.0), m) for m in "ABCD"], 1j * W)
    q = icad_quantities(G, K20.freqresp(W), K20.freqresp(W))
    det = np.linalg.det(G)
    np.testing.assert_allclose(1 - q["gamma"], det / (G[:, 0, 0] * G[:, 1, 1]), rtol=1e-8)
    # plant and controller values broadcast together (e.g. several controllers at once)
    ks = np.stack([K20.freqresp(W), LTI.pi(360.0, 9000.0).freqresp(W)])[:, None, :]
    qb = icad_quantities(G[None, None], ks, ks)
    assert qb["c"].shape == (2, 1, W.size, 2)
    np.testing.assert_allclose(qb["c"][0, 0], q["c"], rtol=1e-12)


def test_icad_quantities_match_the_definitions_on_random_data():
    """The kernel's division-safe forms and reciprocals against numpy's direct evaluation of
    (3)-(6) on random plant and controller values: controller values shared by every row (one
    frequency grid), one set per row, and broadcast along the frequency axis; rows scaled by
    1e80 and 1e-80 make |g11 g22|^2 overflow or underflow (the complex-division branch)."""
    rng = np.random.default_rng(7)

    def values(shape, decades):
        size = 10.0 ** rng.uniform(-decades, decades, shape)
        return size * np.exp(1j * rng.uniform(-np.pi, np.pi, shape))

    G = values((3, 5, 2, 2), 3.0)
    G[0, :2] *= 1e80
    G[1, :2] *= 1e-80
    shared, per_row, per_freq = values((5,), 2.0), values((3, 5), 2.0), values((3, 1), 2.0)
    g11, g12, g21, g22 = G[..., 0, 0], G[..., 0, 1], G[..., 1, 0], G[..., 1, 1]
    for k1, k2 in ((shared, shared), (shared, per_row), (per_row, per_freq)):
        q = icad_quantities(G, k1, k2)
        gamma = g12 * g21 / (g11 * g22)
        kg1, kg2 = k1 * g11, k2 * g22
        h1, h2 = kg1 / (1 + kg1), kg2 / (1 + kg2)
        c1, c2 = kg1 * (1 - gamma * h2), kg2 * (1 - gamma * h1)
        coupling = (g12 / g22 * h2 / (1 + c1), g21 / g11 * h1 / (1 + c2))
        np.testing.assert_allclose(q["gamma"], gamma, rtol=1e-12)
        np.testing.assert_allclose(q["h"], np.stack([h1, h2], axis=-1), rtol=1e-12)
        np.testing.assert_allclose(q["c"], np.stack([c1, c2], axis=-1), rtol=1e-10)
        np.testing.assert_allclose(q["coupling"], np.stack(coupling, axis=-1), rtol=1e-10)
        np.testing.assert_allclose(q["S"], 1 / (1 + np.stack([c1, c2], axis=-1)), rtol=1e-10)


# --- closed forms ------------------------------------------------------------------------------


@pytest.mark.parametrize("params", [UGALDE_IM_300W, DELORENZO_IM])
@pytest.mark.parametrize("w_r", [37.0, 375.0, 3000.0])
def test_im_msf_closed_forms(params, w_r):
    """Ugalde-Loo (60)-(61) at any w; Amezquita-Brooks (14) and (18) at w = w_r."""
    resp = icad_response(plant_from_params(params, w_r), K20, K20, W)
    np.testing.assert_allclose(resp.gamma[0], im_msf_closed_form(params, w_r, W), rtol=1e-8)
    g_wr = icad_response(plant_from_params(params, w_r), K20, K20, [w_r]).gamma[0, 0]
    assert im_msf_at_rotor_speed(params, w_r) == pytest.approx(g_wr, rel=1e-9)
    assert im_msf_magnitude_at_rotor_speed(params, w_r) == pytest.approx(abs(g_wr), rel=1e-9)


@pytest.mark.parametrize("params", [UGALDE_IM_300W, DELORENZO_IM, DELORENZO_IM_13])
def test_gm_min_is_the_high_speed_limit_of_18(params):
    """(19) = lim |gamma(j w_r)| as w_r -> infinity, evaluated numerically at high speed."""
    w_r = 1e6
    g = icad_response(plant_from_params(params, w_r), K20, K20, [w_r]).gamma[0, 0]
    assert abs(g) == pytest.approx(gm_min(params), rel=1e-6)
    assert gm_min(params) < 1.0
    # (19) is the square of L_m^2 / (L_m^2 + 2 sigma L_s L_r)
    expected = (params.L_m**2 / (params.L_m**2 + 2 * params.sigma * params.L_s * params.L_r)) ** 2
    assert gm_min(params) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("w_r", [50.0, 375.0, -900.0, 1e4])
def test_structural_crossing_matches_corrected_ugalde_73(w_r):
    """The positive-real-axis crossing of gamma is at the (corrected) F(3) of Ugalde-Loo (73)."""
    a = analyse(plant_from_params(DELORENZO_IM_13, w_r), K20, K20, verify=False)
    w, x = im_msf_positive_crossing(DELORENZO_IM_13, w_r)
    assert a.structural.crossing_rad_s == pytest.approx(w, rel=1e-8)
    assert a.structural.crossing == pytest.approx(x, rel=1e-8)
    assert 0 < x < gm_min(DELORENZO_IM_13)  # (19) bounds the crossing at every speed


def test_gm_min_of_matrix_13_is_the_printed_075():
    """The printed 0.75 (-2.47 dB) follows from (13); the Appendix parameters give more."""
    assert 20 * math.log10(gm_min(DELORENZO_IM_13)) == pytest.approx(-2.47, abs=0.01)
    assert gm_min(DELORENZO_IM) > gm_min(DELORENZO_IM_13) + 0.01


def test_pmsg_msf_closed_form_and_structure():
    """Ugalde-Loo (18): gamma is real negative at DC and never crosses the positive real axis."""
    w_r = 2 * 157.0
    plant = plant_from_params(PMSG_2MW, w_r)
    resp = icad_response(plant, K20, K20, W)
    np.testing.assert_allclose(resp.gamma[0], pmsg_msf(PMSG_2MW, w_r, 1j * W), rtol=1e-9)
    cond = structure_conditions(plant)
    assert (cond.i, cond.ii, cond.iii, cond.iv) == (True, True, True, True)
    np.testing.assert_allclose(cond.gamma_poles, -PMSG_2MW.R_s / PMSG_2MW.L_d, rtol=1e-6)
    a = analyse(plant, imc_pi(PMSG_2MW), imc_pi(PMSG_2MW))
    assert a.structural.gm_db == math.inf


@settings(max_examples=15, deadline=None)
@given(
    st.floats(0.1, 40.0),
    st.floats(0.1, 40.0),
    st.floats(0.05, 2.0),
    st.floats(0.005, 0.3),
    st.floats(0.005, 0.3),
    st.floats(-3000.0, 3000.0),
)
def test_im_satisfies_conditions_i_to_iv(Rs, Rr, Lm, ls, lr, w_r):
    """Ugalde-Loo section 4.4: every IM satisfies i-iv at every speed."""
    plant = plant_from_params(IMParams(Rs, Rr, Lm + ls, Lm + lr, Lm), w_r)
    c = structure_conditions(plant)
    assert (c.i, c.ii, c.iii, c.iv) == (True, True, True, True)
    assert c.gamma_count.winding == 0


@settings(max_examples=15, deadline=None)
@given(
    st.floats(1e-3, 1.0), st.floats(1e-5, 1e-2), st.floats(1e-5, 1e-2), st.floats(-3000.0, 3000.0)
)
def test_pmsg_satisfies_conditions_i_to_iv(Rs, Ld, Lq, w_r):
    """Ugalde-Loo section 3.4: every PMSG satisfies i-iv at every speed."""
    plant = plant_from_params(PMSGParams(Rs, Ld, Lq, 1.0, 2), w_r)
    c = structure_conditions(plant)
    assert (c.i, c.ii, c.iii, c.iv) == (True, True, True, True)


# --- exact counts vs closed-loop eigenvalues ---------------------------------------------------


def random_plant(rng, n=3, feedthrough=False):
    A = rng.normal(size=(n, n)) - 2.5 * np.eye(n)
    while np.max(np.linalg.eigvals(A).real) > -0.1:
        A -= 0.5 * np.eye(n)
    D = 0.3 * rng.normal(size=(2, 2)) if feedthrough else np.zeros((2, 2))
    return Plant2x2(A, rng.normal(size=(n, 2)), rng.normal(size=(2, n)), D)


@pytest.mark.slow
def test_counts_agree_with_closed_loop_and_transmission_zeros():
    """Z = N + P for gamma (Z: RHP zeros of 1 - gamma) and for the channels (Z: MIMO poles)."""
    rng = np.random.default_rng(7)
    nonzero_gamma = nonzero_channel = 0
    for trial in range(16):
        plant = random_plant(rng, feedthrough=trial % 4 == 3)
        gain = 10 ** rng.uniform(-1, 1.5) * rng.choice([-1.0, 1.0])
        k1 = LTI.pi(gain, abs(gain) * rng.uniform(0.1, 3.0) * np.sign(gain))
        k2 = LTI.zpk([-rng.uniform(0.5, 5)], [0.0, -rng.uniform(5, 20)], 10 * gain)
        a = analyse(plant, k1, k2, np.logspace(-3, 4, 800))  # verify=True: winding == count
        G = control.ss(plant.A, plant.B, plant.C, plant.D)
        gc = a.conditions.gamma_count
        assert gc.winding + gc.rhp_poles == rhp(G.zeros()) + rhp(G.poles())
        nonzero_gamma += gc.encirclements != 0
        z_cl = rhp(closed_loop_poles_control(plant, k1, k2))
        assert a.closed_loop_stable == (z_cl == 0)
        for ch in a.channels:
            cc = ch.channel_count
            assert cc.winding + cc.rhp_poles == z_cl
            nonzero_channel += cc.encirclements != 0
    assert nonzero_gamma > 0 and nonzero_channel > 0  # the sample exercises nonzero counts


def test_imaginary_axis_zeros_of_g11_are_indented():
    """g11 with zeros at +-2j: gamma has poles on the axis; counts stay exact."""
    g11 = LTI.zpk([2j, -2j], [-1.0, -1.5, -3.0], 1.0)
    g12, g21 = LTI.zpk([], [-1.0], 1.0), LTI.zpk([], [-2.0], 0.5)
    g22 = LTI.zpk([], [-3.0], 1.0)
    plant = plant_from_elements(g11, g12, g21, g22)
    k = LTI.pi(2.0, 3.0)
    a = analyse(plant, k, k, np.logspace(-2, 3, 1000))
    c = a.conditions
    assert not c.ii  # poles of gamma on the imaginary axis
    assert any(abs(p - 2j) < 1e-6 for p in c.gamma_count.axis_poles)
    G = control.ss(plant.A, plant.B, plant.C, plant.D)
    assert c.gamma_count.winding + c.gamma_count.rhp_poles == rhp(G.zeros()) + rhp(G.poles())
    z_cl = rhp(closed_loop_poles_control(plant, k, k))
    for ch in a.channels:
        assert ch.channel_count.winding + ch.channel_count.rhp_poles == z_cl


def test_transmission_zero_on_axis_means_passing_through_one():
    """det G with zeros at +-j: gamma passes through (1, 0); reported, never counted."""
    g = LTI.zpk([], [-1.0], 1.0)
    g21 = LTI.zpk([(1 + 5**0.5) / 2, (1 - 5**0.5) / 2], [-1.0, -1.0, -2.0], -1.0)
    plant = plant_from_elements(g, LTI.gain(1.0), g21, g)
    c = structure_conditions(plant)
    assert c.gamma_count.passes_through and c.gamma_count.encirclements is None
    assert not c.iv


def test_gamma_identically_zero_at_standstill():
    c = structure_conditions(plant_for("delorenzo-im", 0.0))
    assert c.gamma_identically_zero and c.iv and c.gamma_limit == 0.0


# --- margins -----------------------------------------------------------------------------------


def _scaled(k: LTI, factor: float) -> LTI:
    return LTI(k.A, k.B, k.C * factor, k.D * factor)


def test_channel_gain_margins_agree_with_closed_loop_eigenvalues():
    """Scaling k_1 across the (reduction or upward) gain margin of c_1 changes MIMO stability."""
    plant = plant_for("delorenzo-im-13", 375.0)
    lag = LTI.zpk([], [-8000.0, -8000.0], 8000.0**2)  # adds phase lag: finite upward margin
    k1 = LTI(*_series(K20, lag))
    a = analyse(plant, k1, K20, np.logspace(0, 6, 3000))
    m = a.channels[0].margins
    assert math.isfinite(m.gm_db) and m.gm_reduction_db < 0
    for margin_db in (m.gm_db, m.gm_reduction_db):
        factor = 10 ** (margin_db / 20)
        inside = factor * (0.98 if margin_db > 0 else 1.02)
        outside = factor * (1.02 if margin_db > 0 else 0.98)
        assert rhp(closed_loop_poles_control(plant, _scaled(k1, inside), K20)) == 0
        assert rhp(closed_loop_poles_control(plant, _scaled(k1, outside), K20)) > 0


def _series(k: LTI, other: LTI):
    from acdrive.analysis._freqresp import _series as series

    return series((k.A, k.B, k.C, k.D), (other.A, other.B, other.C, other.D))


def test_imc_pi_on_pmsg_at_standstill_is_an_integrator():
    """At w_r = 0, g_ii = 1/(L s + R) and k = (L s + R) a / s: c_i = a/s exactly."""
    a_bw = 2000.0
    k = imc_pi(PMSG_2MW, a_bw)
    an = analyse(plant_from_params(PMSG_2MW, 0.0), k, k)
    for ch in an.channels:
        assert ch.margins.crossover_rad_s == pytest.approx(a_bw, rel=1e-6)
        assert ch.margins.pm_deg == pytest.approx(90.0, abs=1e-4)
        assert ch.bandwidth_rad_s == pytest.approx(a_bw, rel=1e-6)
        assert ch.coupling_peak_db == -math.inf


def test_structural_margin_matches_crossing_of_gamma():
    a = analyse(plant_for("delorenzo-im-13", 375.0), K20, K20)
    x = a.structural.crossing
    g = icad_response(a.plant, K20, K20, [a.structural.crossing_rad_s]).gamma[0, 0]
    assert g.imag == pytest.approx(0.0, abs=1e-9) and g.real == pytest.approx(x, rel=1e-9)
    assert a.structural.gm_db == pytest.approx(-20 * math.log10(x))
    assert 0 < x < 1


# --- bad input ---------------------------------------------------------------------------------


def test_bad_inputs_raise_input_error():
    plant = plant_for("delorenzo-im", 100.0)
    unstable = LTI.zpk([], [5.0], 1.0)
    with pytest.raises(InputError, match="k1"):
        analyse(plant, unstable, K20)
    for grid in ([], [0.0, 1.0], [-1.0, 2.0], [1.0, float("nan")], [2.0, 1.0]):
        with pytest.raises(InputError, match="w"):
            analyse(plant, K20, K20, grid)
        with pytest.raises(InputError, match="w"):
            icad_response(plant, K20, K20, grid)
    with pytest.raises(InputError, match="speed"):
        plant_for("delorenzo-im", float("nan"))
    with pytest.raises(InputError, match="plant"):
        analyse((-np.eye(2), np.eye(2), np.eye(3, 2), np.zeros((3, 2))), K20, K20)
    with pytest.raises(InputError, match="controller"):
        controller_for("nonsense")


def test_loop_margins_of_textbook_loops():
    """K/(s(s+1)): PM = 90 - atan(w_c) deg; K/(s(s+1)(s+2)): GM = 6/K at w = sqrt(2)."""
    from acdrive.analysis._margins import loop_margins

    w = np.logspace(-3, 3, 2000)
    K = 4.0
    m = loop_margins(lambda x: K / (1j * x * (1j * x + 1)), w)
    wc = math.sqrt((-1 + math.sqrt(1 + 4 * K**2)) / 2)  # wc^2 (1 + wc^2) = K^2
    assert m.crossover_rad_s == pytest.approx(wc, rel=1e-9)
    assert m.pm_deg == pytest.approx(90 - math.degrees(math.atan(wc)), rel=1e-9)
    m3 = loop_margins(lambda x: 1.5 / (1j * x * (1j * x + 1) * (1j * x + 2)), w)
    assert m3.gm_db == pytest.approx(20 * math.log10(6 / 1.5), rel=1e-9)
    assert m3.gm_rad_s == pytest.approx(math.sqrt(2), rel=1e-9)
    # a crossover with phase lead (+30 deg) is 150 deg away from -1, not -150 deg
    lead = loop_margins(lambda x: np.exp(1j * np.pi / 6) * 10 / x, w)
    assert lead.pm_deg == pytest.approx(150.0, rel=1e-9)


@pytest.mark.slow
def test_resonant_controller_poles_on_the_axis_are_indented():
    """k = 360 + K_R s/(s^2 + w0^2) (poles at +-j w0): counts agree with the closed loop."""
    w0, K_R = 300.0, 5e4
    k = LTI.zpk(np.roots([1.0, K_R / 360.0, w0**2]), [1j * w0, -1j * w0], 360.0)
    plant = plant_for("delorenzo-im-13", 300.0)
    a = analyse(plant, k, k)
    z_cl = rhp(closed_loop_poles_control(plant, k, k))
    for ch in a.channels:
        cc = ch.channel_count
        assert any(abs(p - 1j * w0) < 1e-6 * w0 for p in cc.axis_poles)
        assert cc.winding + cc.rhp_poles == z_cl
    assert a.closed_loop_stable == (z_cl == 0)
