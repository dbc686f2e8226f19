"""Current-subsystem models of the IM, PMSG and DFIM against the papers' closed forms."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from acdrive.analysis import evaluate_ss
from acdrive.analysis._plants import (
    MACHINES,
    Plant2x2,
    as_plant,
    dfim_rotor_current_ss,
    plant_for,
    plant_from_params,
    plants_for,
)
from acdrive.errors import InputError
from acdrive.machines import (
    BODSON_DFIM,
    DELORENZO_IM,
    DELORENZO_IM_13,
    UGALDE_IM_300W,
    DFIMParams,
    IMParams,
    params_from_stationary_matrix,
    stator_current_ss,
)
from acdrive.machines._pmsm import PMSG_2MW, PMSGParams, dq_current_ss

S_POINTS = np.array([0.3j, 7.0 + 40j, 120j, -3.0 + 900j, 5000j, 20.0 - 300j])


def real_from_complex_siso(h_plus: np.ndarray, h_minus: np.ndarray) -> np.ndarray:
    """Real 2x2 transfer of y = H u for complex signals, from H(s) and conj(H(conj s))."""
    a = (h_plus + h_minus) / 2
    b = (h_plus - h_minus) / 2j
    return np.stack([np.stack([a, -b], -1), np.stack([b, a], -1)], -2)


def im_params():
    """Physically valid IM parameters: L_s = L_ls + L_m, L_r = L_lr + L_m."""
    pos = st.floats(0.05, 50.0)
    return st.builds(
        lambda Rs, Rr, Lm, ls, lr: IMParams(Rs, Rr, Lm + ls, Lm + lr, Lm),
        pos,
        pos,
        st.floats(0.01, 2.0),
        st.floats(1e-3, 0.5),
        st.floats(1e-3, 0.5),
    )


# --- induction motor -------------------------------------------------------------------------


@pytest.mark.parametrize("params", [UGALDE_IM_300W, DELORENZO_IM, DELORENZO_IM_13])
@pytest.mark.parametrize("w_r", [0.0, 150.0, -375.0])
def test_im_matrix_equals_complex_vector_model(params, w_r):
    """(41) equals the complex space-vector IM model: i_s/v_s = 1/(sigma L_s (s - a11 - K(s)))."""
    p = params
    G = evaluate_ss(*stator_current_ss(p, w_r), S_POINTS)
    sLs = p.sigma * p.L_s
    a11 = -(p.L_r**2 * p.R_s + p.L_m**2 * p.R_r) / (sLs * p.L_r**2)

    def h(s, wr):
        flux = (p.L_m * p.R_r / p.L_r) / (s + p.R_r / p.L_r - 1j * wr)
        back = p.L_m / (sLs * p.L_r) * (p.R_r / p.L_r - 1j * wr)
        return 1.0 / (sLs * (s - a11 - back * flux))

    expected = real_from_complex_siso(h(S_POINTS, w_r), np.conj(h(np.conj(S_POINTS), w_r)))
    np.testing.assert_allclose(G, expected, rtol=1e-10, atol=1e-14)


def test_im_transfer_matrix_matches_ugalde_44_45():
    """g11 = n11/d and g12 = n12/d of Ugalde-Loo (44)-(45), (52)-(53); n12 = -n21."""
    p, w_r = UGALDE_IM_300W, 200.0
    sig, Ls, Lr, Lm, Rs, Rr = p.sigma, p.L_s, p.L_r, p.L_m, p.R_s, p.R_r
    kap = 1 / (sig**2 * Ls**2 * Lr**4)
    d = [
        1.0,
        kap * 2 * sig * Ls * Lr**2 * (Lm**2 * Rr + sig * Ls * Lr * Rr + Lr**2 * Rs),
        kap * (Lm**4 * Rr**2 + Lr**4 * Rs**2 + sig**2 * Ls**2 * Lr**2 * (Rr**2 + Lr**2 * w_r**2))
        + kap
        * (2 * Lr**2 * Lm**2 * Rs * Rr + 2 * sig * Ls * Lr * Rr * (2 * Lr**2 * Rs + Lm**2 * Rr)),
        2 * kap * Lr * Rs * Rr * (Lr**2 * Rs + Lm**2 * Rr)
        + 2 * kap * sig * Ls * Lr**2 * Rs * (Rr**2 + Lr**2 * w_r**2),
        kap * (Lr**4 * Rs**2 * w_r**2 + Lr**2 * Rs**2 * Rr**2),
    ]
    q = sig**2 * Ls**2 * Lr**3
    eta = [
        1 / (sig * Ls),
        (2 * sig * Ls * Lr**2 * Rr + Lm**2 * Rr * Lr + Lr**3 * Rs) / q,
        (sig * Ls * Lr**3 * w_r**2 + 2 * Lr**2 * Rs * Rr + sig * Ls * Lr * Rr**2 + Lm**2 * Rr**2)
        / q,
        (Lr**3 * Rs * w_r**2 + Lr * Rs * Rr**2) / q,
    ]
    n12 = Lm**2 * Rr * w_r / (sig**2 * Ls**2 * Lr**2)
    G = evaluate_ss(*stator_current_ss(p, w_r), S_POINTS)
    den = np.polyval(d, S_POINTS)
    np.testing.assert_allclose(G[:, 0, 0], np.polyval(eta, S_POINTS) / den, rtol=1e-9)
    np.testing.assert_allclose(G[:, 1, 1], G[:, 0, 0], rtol=1e-12)
    # (44) prints n12 = -n21 = -(...) s; the model (41) gives the opposite sign (gamma unaffected)
    np.testing.assert_allclose(G[:, 0, 1], n12 * S_POINTS / den, rtol=1e-9)
    np.testing.assert_allclose(G[:, 1, 0], -G[:, 0, 1], rtol=1e-12)


@settings(max_examples=40, deadline=None)
@given(im_params(), st.floats(-2000.0, 2000.0))
def test_im_open_loop_stable_for_any_parameters(p, w_r):
    """Ugalde-Loo (47)-(49): every IM current subsystem is open-loop stable at any speed."""
    A = stator_current_ss(p, w_r)[0]
    assert np.all(np.linalg.eigvals(A).real < 0)


@settings(max_examples=40, deadline=None)
@given(im_params())
def test_params_from_stationary_matrix_round_trip(p):
    A, B, _, _ = stator_current_ss(p, 1.0)
    fit = params_from_stationary_matrix(A[0, 0], A[0, 2], A[0, 3], A[2, 0], A[2, 2], B[0, 0])
    for name in ("R_s", "R_r", "L_s", "L_r", "L_m"):
        assert getattr(fit.params, name) == pytest.approx(getattr(p, name), rel=1e-9)
    assert fit.a13_implied == pytest.approx(fit.a13_printed, rel=1e-12)


def test_delorenzo_matrix_13_reconciliation():
    """(13) of Amezquita-Brooks is the Appendix machine with L_s ~ 1.45 H instead of 1.44 H."""
    A13, B13, _, _ = stator_current_ss(DELORENZO_IM_13, 1.0)
    printed = {(0, 0): -359.2, (0, 3): 9.2, (2, 0): 21.9, (2, 2): -15.4}
    for (i, j), v in printed.items():
        assert A13[i, j] == pytest.approx(v, rel=1e-12)
    assert B13[0, 0] == pytest.approx(9.7, rel=1e-12)
    assert A13[0, 2] == pytest.approx(141.8, rel=2e-3)  # the redundant entry, rounding only
    for name in ("R_s", "R_r", "L_r", "L_m"):
        assert getattr(DELORENZO_IM_13, name) == pytest.approx(
            getattr(DELORENZO_IM, name), rel=0.01
        )
    assert 1.445 < DELORENZO_IM_13.L_s < 1.46  # the claim: about 1.45 H, not the Appendix 1.44 H
    A_app = stator_current_ss(DELORENZO_IM, 1.0)[0]
    assert abs(A_app[0, 0] - A13[0, 0]) / abs(A13[0, 0]) > 0.05  # the two do not agree


@pytest.mark.parametrize(
    "field, value",
    [("R_s", 0.0), ("R_r", -1.0), ("L_s", float("nan")), ("n_p", 1.5), ("J", -1.0)],
)
def test_im_params_validation(field, value):
    kwargs = {"R_s": 1.0, "R_r": 1.0, "L_s": 0.1, "L_r": 0.1, "L_m": 0.09, "n_p": 1}
    kwargs[field] = value
    with pytest.raises(InputError, match=field):
        IMParams(**kwargs)


def test_im_params_sigma_must_be_positive():
    with pytest.raises(InputError, match="sigma"):
        IMParams(R_s=1.0, R_r=1.0, L_s=0.1, L_r=0.1, L_m=0.1)


# --- PMSG -------------------------------------------------------------------------------------


def test_pmsg_matrix_and_transfer_matrix():
    """(11) and the transfer matrix (13)-(14) of Ugalde-Loo, at w_r = n_P w_gen."""
    p, w_gen = PMSGParams(R_s=0.02, L_d=1.1e-3, L_q=1.7e-3, psi_m=0.5, n_p=3), 40.0
    w_r = p.n_p * w_gen
    A, B, C, D = dq_current_ss(p, w_r)
    assert A[0, 1] == pytest.approx(p.L_q / p.L_d * p.n_p * w_gen)
    s = S_POINTS
    d = p.L_d * p.L_q * s**2 + (p.L_d + p.L_q) * p.R_s * s + p.R_s**2 + p.L_d * p.L_q * w_r**2
    G = evaluate_ss(A, B, C, D, s)
    np.testing.assert_allclose(G[:, 0, 0], (p.L_q * s + p.R_s) / d, rtol=1e-10)
    np.testing.assert_allclose(G[:, 0, 1], p.L_q * w_r / d, rtol=1e-10)
    np.testing.assert_allclose(G[:, 1, 0], -p.L_d * w_r / d, rtol=1e-10)
    np.testing.assert_allclose(G[:, 1, 1], (p.L_d * s + p.R_s) / d, rtol=1e-10)


def test_pmsg_2mw_printed_matrix_entries():
    """Section 3.5: -R_s/L_d = -14.0466, 1/L_d = 3105.59, off-diagonal 2 w_gen."""
    A, B, _, _ = dq_current_ss(PMSG_2MW, 2 * 10.0)  # w_gen = 10 rad/s
    assert A[0, 0] == pytest.approx(-14.0466, abs=1e-4)
    assert B[0, 0] == pytest.approx(3105.59, abs=1e-2)
    assert A[0, 1] == pytest.approx(2 * 10.0)


def test_pmsg_params_validation():
    with pytest.raises(InputError, match="L_q"):
        PMSGParams(R_s=1.0, L_d=1e-3, L_q=0.0, psi_m=1.0, n_p=2)
    with pytest.raises(InputError, match="n_p"):
        PMSGParams(R_s=1.0, L_d=1e-3, L_q=1e-3, psi_m=1.0, n_p=0)


# --- DFIM -------------------------------------------------------------------------------------


@pytest.mark.parametrize("w_r", [0.0, 188.5, 377.0, 600.0])
def test_dfim_rotor_subsystem_matches_bodson_12_13(w_r):
    """i_R / v_R = (s L_S + Z_S)/Delta Z(s) of Bodson (12)-(13); poles = roots of Delta Z."""
    p, w_e = BODSON_DFIM, 2 * math.pi * 60
    A, B, C, D = dfim_rotor_current_ss(p, w_r, w_e)
    w_slip = w_e - w_r
    Z_S, Z_MS = p.R_s + 1j * w_e * p.L_s, 1j * w_e * p.M
    Z_R, Z_MR = p.R_r + 1j * w_slip * p.L_r, 1j * w_slip * p.M

    def h(s):
        dz = (s * p.L_s + Z_S) * (s * p.L_r + Z_R) - (s * p.M + Z_MR) * (s * p.M + Z_MS)
        return (s * p.L_s + Z_S) / dz

    def h_conj(s):
        return np.conj(h(np.conj(s)))

    expected = real_from_complex_siso(h(S_POINTS), h_conj(S_POINTS))
    np.testing.assert_allclose(evaluate_ss(A, B, C, D, S_POINTS), expected, rtol=1e-10)
    # poles: the roots of Delta Z and their conjugates (Bodson, after (14))
    dz_coeffs = [
        p.L_s * p.L_r - p.M**2,
        p.L_s * Z_R + p.L_r * Z_S - p.M * (Z_MR + Z_MS),
        Z_S * Z_R - Z_MR * Z_MS,
    ]
    roots = np.roots(dz_coeffs)
    expected_poles = np.sort_complex(np.concatenate([roots, np.conj(roots)]))
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(A)), expected_poles, rtol=1e-9)


@settings(max_examples=40, deadline=None)
@given(
    st.floats(0.05, 5.0),
    st.floats(0.05, 5.0),
    st.floats(1e-3, 0.1),
    st.floats(1e-4, 0.02),
    st.floats(1e-4, 0.02),
    st.floats(-2000.0, 2000.0),
)
def test_dfim_electrically_stable_for_any_parameters(Rs, Rr, M, ls, lr, w_r):
    """Bodson's Fact (15)-(18): the DFIM electrical model is stable at any constant speed."""
    p = DFIMParams(R_s=Rs, R_r=Rr, L_s=M + ls, L_r=M + lr, M=M, n_p=2, J=1e-3)
    A = dfim_rotor_current_ss(p, w_r)[0]
    assert np.all(np.linalg.eigvals(A).real < 0)


# --- plants and registry --------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(MACHINES))
def test_registry_builds_2x2_plants(name):
    plant = plant_for(name, 100.0)
    assert plant.B.shape[1] == 2 and plant.C.shape[0] == 2 and plant.speed == 100.0
    assert plant.name == name


def test_plant_from_params_dispatches_on_type():
    assert plant_from_params(PMSG_2MW, 3.0).inputs == ("v_d", "v_q")
    assert plant_from_params(BODSON_DFIM, 3.0).outputs == ("i_Rd", "i_Rq")
    with pytest.raises(InputError, match="params"):
        plant_from_params(object(), 1.0)


def test_plant_validation_errors():
    A = -np.eye(3)
    with pytest.raises(InputError, match="plant"):
        Plant2x2(A, np.ones((3, 3)), np.ones((2, 3)), np.zeros((2, 3)))  # 2x3 plant
    with pytest.raises(InputError, match="plant"):
        Plant2x2(A, np.ones((3, 2)), np.ones((3, 3)), np.zeros((3, 2)))  # 3x2 plant
    with pytest.raises(InputError, match="A"):
        Plant2x2(-np.eye(2), np.ones((3, 2)), np.ones((2, 3)), np.zeros((2, 2)))
    with pytest.raises(InputError, match="A"):
        Plant2x2(A * np.nan, np.ones((3, 2)), np.ones((2, 3)), np.zeros((2, 2)))
    with pytest.raises(InputError, match="speed"):
        plant_for("delorenzo-im", float("nan"))
    with pytest.raises(InputError, match="speeds"):
        plants_for("delorenzo-im", [1.0, float("nan")])
    with pytest.raises(InputError, match="machine"):
        plant_for("no-such-machine", 1.0)
    with pytest.raises(InputError, match="plant"):
        as_plant("not a plant")


def test_as_plant_accepts_python_control():
    control = pytest.importorskip("control")
    plant = plant_for("delorenzo-im", 50.0)
    again = as_plant(control.ss(plant.A, plant.B, plant.C, plant.D))
    np.testing.assert_array_equal(again.A, plant.A)
    with pytest.raises(InputError, match="plant"):
        as_plant(control.ss(-np.eye(2), np.ones((2, 3)), np.eye(2), np.zeros((2, 3))))
