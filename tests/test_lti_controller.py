"""LTI controllers in the time domain: discretisation (ZOH, Tustin, pre-warping) against analytic
results, the stationary-frame current controller part in a System against its difference
equation, the identity of the simulated and the ICAD-analysed controller, anti-windup, and
InputErrors naming the field (Amezquita-Brooks et al. (20), (22), secs. VI-D, VII)."""

import math

import numpy as np
import pytest
import scipy.linalg
import scipy.signal

from acdrive.analysis import plant_from_params
from acdrive.analysis._freqresp import LTI as ANALYSIS_LTI
from acdrive.analysis._icad import analyse, controller_for
from acdrive.control import LTIMatrix
from acdrive.control._current import (
    EVENT_PERIOD_MISMATCH,
    EVENT_SATURATED,
    CurrentProgram,
    StationaryCurrentController,
    current_controller_step,
)
from acdrive.control._discretise import discretise, tustin_constant
from acdrive.control._lti import (
    BUILTIN,
    FIG17_K_I,
    FIG17_K_P,
    FIG17_PI_FAMILY,
    FIG18_PI,
    LTI,
    PAPER_20,
    PAPER_PI,
    PI_OF_22,
    builtin,
)
from acdrive.core import Profile
from acdrive.errors import InputError
from acdrive.machines import DELORENZO_IM_13, CageInductionMachine
from acdrive.plant import PrescribedSpeed
from acdrive.plant._converter import AveragedConverter, max_voltage_magnitude
from acdrive.sim import System

#: The paper's DC source (sec. VI): 310 V, so |v| <= 310 / sqrt(2) V (linear SVPWM).
V_DC = 310.0
V_MAX = 310.0 / math.sqrt(2.0)
W_R = 375.0


def tf_of_20():
    """Numerator and denominator of (20), from the printed factors (not from its realisation)."""
    num = 326.5 * np.polymul(np.polymul([1.0, 400.0], [1.0, 400.0]), [1.0, 1000.0])
    den = np.polymul([1.0, 0.0], [1.0, 100.0, 42500.0])
    return num, den


def bilinear_polynomials(num, den, c):
    """Coefficients in z (highest first) of num/den with s = c (z - 1)/(z + 1), by expanding
    sum a_i c^i (z - 1)^i (z + 1)^(n - i) (independent of the state-space formulas)."""
    n = len(den) - 1
    num = np.concatenate([np.zeros(n + 1 - len(num)), num])

    def expand(coeffs):
        out = np.zeros(n + 1)
        for power, a in enumerate(coeffs[::-1]):  # a multiplies s^power
            term = np.array([a * c**power])
            for _ in range(power):
                term = np.convolve(term, [1.0, -1.0])
            for _ in range(n - power):
                term = np.convolve(term, [1.0, 1.0])
            out += term
        return out

    b, a = expand(num), expand(den)
    return b / a[0], a / a[0]


def run_state_space(d, e):
    """u_k = C_d x_k + D_d e_k, x_{k+1} = A_d x_k + B_d e_k for e of shape (N, m)."""
    x = np.zeros(d.order)
    out = np.empty((e.shape[0], d.shape[0]))
    for k in range(e.shape[0]):
        out[k] = d.Cd @ x + d.Dd @ e[k]
        x = d.Ad @ x + d.Bd @ e[k]
    return out


# --- discretisation against analytic results ------------------------------------------------


def test_tustin_pi_is_the_textbook_difference_equation():
    T, kp, ki = 1e-4, PAPER_PI.D[0, 0], PAPER_PI.C[0, 0]
    d = discretise(PAPER_PI, T, "tustin")
    Ad, Bd, Cd, Dd = d
    np.testing.assert_allclose(Ad, [[1.0]], rtol=0, atol=0)
    np.testing.assert_allclose(Bd, [[T]], rtol=1e-15)
    np.testing.assert_allclose(Cd, [[ki]], rtol=1e-15)
    np.testing.assert_allclose(Dd, [[kp + ki * T / 2]], rtol=1e-15)
    e = np.random.default_rng(1).normal(size=400)
    u = run_state_space(d, e[:, None])[:, 0]
    # u_k = u_{k-1} + K_P (e_k - e_{k-1}) + K_I T/2 (e_k + e_{k-1}), u_0 = (K_P + K_I T/2) e_0
    ref = np.empty_like(e)
    ref[0] = (kp + ki * T / 2) * e[0]
    for k in range(1, e.size):
        ref[k] = ref[k - 1] + kp * (e[k] - e[k - 1]) + ki * T / 2 * (e[k] + e[k - 1])
    np.testing.assert_allclose(u, ref, rtol=0, atol=1e-12 * np.abs(ref).max())


def test_zoh_of_an_integrator_and_of_a_lag_is_exact_sampling():
    T, ki = 2e-4, 9000.0
    Ad, Bd, Cd, Dd = discretise(LTI.pi(0.0, ki), T, "zoh")
    # the integral of a staircase: u_{k+1} = u_k + K_I T e_k, no feedthrough
    assert Ad[0, 0] == 1.0 and Dd[0, 0] == 0.0
    assert Cd[0, 0] * Bd[0, 0] == pytest.approx(ki * T, rel=1e-15)
    a = 700.0
    lag = LTI.tf([a], [1.0, a])
    d = discretise(lag, T, "zoh")
    assert d.Ad[0, 0] == pytest.approx(math.exp(-a * T), rel=1e-14)
    assert (d.Cd @ d.Bd)[0, 0] == pytest.approx(1.0 - math.exp(-a * T), rel=1e-13)
    # (20) fed by a unit step: the samples of the continuous step response, exactly
    k = np.arange(60)
    t = k * T
    _, y = scipy.signal.step(scipy.signal.lti(*tf_of_20()), T=t)
    u = run_state_space(discretise(PAPER_20, T, "zoh"), np.ones((k.size, 1)))[:, 0]
    np.testing.assert_allclose(u, y, rtol=1e-9, atol=1e-9 * np.abs(y).max())


def test_tustin_is_the_bilinear_substitution_with_and_without_prewarping():
    num, den = tf_of_20()
    z = np.exp(1j * np.array([0.01, 0.3, 1.0, 2.5])) * np.array([1.0, 0.9, 1.1, 0.5])
    for T, w0 in ((1e-4, None), (1e-3, 300.0), (5e-5, 3343.7)):
        c = tustin_constant(T, w0)
        b, a = bilinear_polynomials(num, den, c)
        expected = np.polyval(b, z) / np.polyval(a, z)
        got = discretise(PAPER_20, T, "tustin", w0).evaluate(z)[:, 0, 0]
        # (the expanded polynomials lose ~1e-10 near the integrator's z = 1)
        np.testing.assert_allclose(got, expected, rtol=1e-9)
        s = c * (z - 1) / (z + 1)
        np.testing.assert_allclose(got, PAPER_20.evaluate(s), rtol=1e-10)


def test_prewarping_preserves_the_response_at_the_warping_frequency():
    T = 1e-3  # coarse on purpose: 300 rad/s is 1/10 of the Nyquist frequency
    for k in (PAPER_20, PAPER_PI, FIG18_PI, PI_OF_22):
        for w0 in (300.0, 375.0, 2500.0):
            exact = k.freqresp([w0])[0]
            warped = discretise(k, T, "tustin", prewarp=w0).freqresp([w0])[0]
            plain = discretise(k, T, "tustin").freqresp([w0])[0]
            assert abs(warped - exact) <= 1e-12 * abs(exact)
            assert abs(plain - exact) > 1e-4 * abs(exact)  # without pre-warping it misses


def test_discrete_response_of_20_converges_with_the_order_of_the_method():
    w = np.geomspace(10.0, 3000.0, 200)
    exact = PAPER_20.freqresp(w)
    periods = [2e-4, 1e-4, 5e-5, 2.5e-5, 1.25e-5]
    orders = {}
    for method in ("tustin", "zoh"):
        err = [
            np.max(np.abs(discretise(PAPER_20, T, method).freqresp(w) - exact) / np.abs(exact))
            for T in periods
        ]
        orders[method] = np.log2(np.array(err[:-1]) / np.array(err[1:]))
        assert err[-1] < (2e-4 if method == "tustin" else 3e-2)
    assert np.all(np.abs(orders["tustin"] - 2.0) < 0.05), orders
    assert np.all(np.abs(orders["zoh"] - 1.0) < 0.1), orders


def test_mimo_grids_and_state_space():
    w = np.array([30.0, 375.0, 3000.0])
    K = LTIMatrix.diagonal(PAPER_20, PAPER_PI)
    assert K.shape == (2, 2) and K.order == 4 and K.is_diagonal
    assert K[0, 0] is PAPER_20 and K[1, 1] is PAPER_PI and K[0, 1] is None
    assert K.diagonal_entries() == (PAPER_20, PAPER_PI)
    G = K.freqresp(w)
    np.testing.assert_allclose(G[:, 0, 0], PAPER_20.freqresp(w), rtol=1e-12)
    np.testing.assert_allclose(G[:, 1, 1], PAPER_PI.freqresp(w), rtol=1e-12)
    assert np.all(G[:, 0, 1] == 0) and np.all(G[:, 1, 0] == 0)
    full = LTIMatrix.grid([[PAPER_20, 2.0], [PI_OF_22, PAPER_PI]])
    Gf = full.freqresp(w)
    np.testing.assert_allclose(Gf[:, 0, 1], 2.0, rtol=1e-14)
    np.testing.assert_allclose(Gf[:, 1, 0], PI_OF_22.freqresp(w), rtol=1e-12)
    assert not full.is_diagonal
    ss = LTIMatrix.ss(full.A, full.B, full.C, full.D)
    np.testing.assert_allclose(ss.freqresp(w), Gf, rtol=1e-12)
    # the discretisation of a grid is the grid of the discretisations
    for method in ("zoh", "tustin"):
        Dg = discretise(full, 1e-4, method).freqresp(w)
        np.testing.assert_allclose(
            Dg[:, 1, 0], discretise(PI_OF_22, 1e-4, method).freqresp(w), rtol=1e-10
        )
        np.testing.assert_allclose(
            Dg[:, 0, 0], discretise(PAPER_20, 1e-4, method).freqresp(w), rtol=1e-10
        )


def test_transfer_function_constructor():
    num, den = tf_of_20()
    w = np.geomspace(1.0, 1e5, 50)
    np.testing.assert_allclose(LTI.tf(num, den).freqresp(w), PAPER_20.freqresp(w), rtol=1e-10)
    np.testing.assert_allclose(
        LTI.tf([360.0, 9000.0], [1.0, 0.0]).freqresp(w), PAPER_PI.freqresp(w), rtol=1e-12
    )
    assert LTI.tf([0.0, 0.0, 5.0], [2.0]).order == 0  # leading zeros; a static gain of 2.5
    assert LTI.tf([5.0], [2.0]).D[0, 0] == 2.5
    assert LTI.tf([2.0, 1.0], [4.0, 2.0, 1.0]).evaluate([1j])[0] == pytest.approx(
        (2j + 1) / (4 * 1j**2 + 2j + 1)
    )
    # the analysis name is the same class (moved, re-exported)
    assert ANALYSIS_LTI is LTI


# --- the built-in controllers: one definition ------------------------------------------------


def test_builtin_controllers_are_the_papers_and_the_icad_ones():
    from acdrive._report import icad_targets as targets

    w = np.geomspace(1.0, 1e5, 40)
    num, den = tf_of_20()
    s = 1j * w
    np.testing.assert_allclose(PAPER_20.freqresp(w), np.polyval(num, s) / np.polyval(den, s))
    np.testing.assert_allclose(PAPER_PI.freqresp(w), targets.PI_KP + targets.PI_KI / s)
    c20 = targets.CONTROLLER_20
    inner = c20["gain"] * (s - c20["pi_zero"]) / s
    np.testing.assert_allclose(PI_OF_22.freqresp(w), inner, rtol=1e-13)
    lag = np.polyval(np.poly(c20["lag_zeros"]), s) / np.polyval(c20["lag_den"], s)
    np.testing.assert_allclose(PAPER_20.freqresp(w), inner * lag, rtol=1e-10)  # (22) = (20)
    # the analysis and the report take these very objects
    assert LTI.paper_20() is PAPER_20 and controller_for("paper-20") is PAPER_20
    assert controller_for("paper-pi") is PAPER_PI and builtin("paper-pi") is PAPER_PI
    assert builtin("fig18-pi") is FIG18_PI is FIG17_PI_FAMILY[-1]
    assert [k.C[0, 0] for k in FIG17_PI_FAMILY] == list(FIG17_K_I)
    assert BUILTIN["paper-22-pi"] is PI_OF_22
    with pytest.raises(InputError, match=r"^controller: unknown built-in 'nope'"):
        builtin("nope")


@pytest.mark.slow
def test_fig17_family_gains_solve_the_crossover_of_20():
    """The stored K_P give c_i the crossover of (20) at w_r = 375 (sec. VII), as re-solved."""
    from acdrive.analysis import pi_gain_for_crossover

    plant = plant_from_params(DELORENZO_IM_13, W_R)
    wc20 = analyse(plant, PAPER_20, PAPER_20, verify=False).channels[0].margins.crossover_rad_s
    for ki, kp, k in zip(FIG17_K_I, FIG17_K_P, FIG17_PI_FAMILY, strict=True):
        assert k.D[0, 0] == kp
        assert pi_gain_for_crossover(plant, ki, wc20) == pytest.approx(kp, rel=1e-9)
    pm = [analyse(plant, k, k, verify=False).channels[0].margins.pm_deg for k in FIG17_PI_FAMILY]
    assert pm[-1] < pm[0] - 40.0  # the high-integral-gain PI of Fig. 18 loses its margin


def test_the_part_runs_the_object_the_icad_analysis_takes():
    k = controller_for("paper-20")
    part = StationaryCurrentController("cc", k, 1e-4, v_max=V_MAX)
    k1, k2 = part.controller.diagonal_entries()
    assert k1 is PAPER_20 and k2 is PAPER_20 and part.controller[0, 0] is LTI.paper_20()
    assert part.discrete.source is part.controller
    a = analyse(plant_from_params(DELORENZO_IM_13, W_R), k1, k2)
    assert a.closed_loop_stable
    # the part's parameters are the discretisation of that object, nothing else
    d = discretise(part.controller, 1e-4, "tustin")
    values = part.PARAMS.unpack(part.p)
    for name, M in (("Ad", d.Ad), ("Bd", d.Bd), ("Cd", d.Cd), ("Dd", d.Dd)):
        got = np.array(
            [[values[f"{name}_{i}_{j}"] for j in range(M.shape[1])] for i in range(M.shape[0])]
        )
        np.testing.assert_array_equal(got, M)
    # a re-parametrised copy (same order) re-discretises the object it is given
    lag = LTI.pi_lag(300.0, 900.0, [-400.0] * 2, [-50 + 200j, -50 - 200j])
    other = part.with_params(controller=lag)
    assert other.discrete.order == part.discrete.order
    assert part.with_params(v_max=10.0).controller is part.controller
    # a DiscreteLTI of the object: its period and method, the same object inside
    zoh = StationaryCurrentController("cc", discretise(PAPER_20, 1e-4, "zoh"))
    assert zoh.discrete.method == "zoh" and zoh.controller[1, 1] is PAPER_20
    warped = StationaryCurrentController("cc", PAPER_20, 1e-4, prewarp=300.0)
    assert warped.discrete.prewarp == 300.0


def test_full_mimo_controller_couples_the_axes():
    """A 2 x 2 controller with off-diagonal entries: the kernel runs its state-space recursion."""
    K = LTIMatrix.grid([[PAPER_20, 2.0], [PI_OF_22, PAPER_PI]])
    part = StationaryCurrentController("cc", K, 1e-4)
    e = np.random.default_rng(3).normal(size=(200, 2))
    s, y, out = part.initial_state(), np.zeros(2), np.empty((200, 2))
    for k in range(200):
        u = np.array([e[k, 0], e[k, 1], 0.0, 0.0])
        assert current_controller_step(k * 1e-4, 1e-4, u, part.p, s, y) == 0
        out[k] = y
    ref = run_state_space(part.discrete, e)
    np.testing.assert_allclose(out, ref, rtol=0, atol=1e-12 * np.abs(ref).max())
    only_beta = run_state_space(part.discrete, np.stack([0 * e[:, 0], e[:, 1]], axis=1))
    assert np.abs(only_beta[:, 0]).max() > 0  # beta error reaches the alpha voltage (K[0, 1])


# --- the sampled part in a System --------------------------------------------------------------


@pytest.mark.slow
def test_part_in_a_system_reproduces_the_difference_equation():
    """Open loop: reference and 'measured' current from tables (known signals), the diagonal
    controller (20) on alpha, the PI 360/9000 on beta; the logged command equals the state-space
    recursion bit for bit and the transfer-function difference equations to rounding."""
    T, N = 1e-4, 400
    t = np.arange(N) * T
    rng = np.random.default_rng(7)
    ref = rng.normal(size=N) + 1j * rng.normal(size=N)
    meas = 0.5 * np.sin(300.0 * t) + 1j * rng.normal(scale=0.2, size=N)
    ref_part = CurrentProgram("ref", re=Profile(t, ref.real), im=Profile(t, ref.imag))
    meas_part = CurrentProgram("meas", re=Profile(t, meas.real), im=Profile(t, meas.imag))
    cc = StationaryCurrentController("cc", LTIMatrix.diagonal(PAPER_20, PAPER_PI), T)
    system = System(
        [ref_part, meas_part, cc],
        [(ref_part.out.i, cc.inp.i_ref), (meas_part.out.i, cc.inp.i_meas)],
    )
    res = system.compile().run(N * T, T, log=[cc.out.v_ref])
    v = res.signal(cc.out.v_ref)
    assert v.size == N and res.events["cc"] == {"saturated": 0, "period_mismatch": 0}
    e = np.stack([(ref - meas).real, (ref - meas).imag], axis=1)
    # the kernel's recursion in the kernel's order of operations, in Python
    d = cc.discrete
    x, expected = np.zeros(d.order), np.empty(N, dtype=complex)
    for k in range(N):
        v0 = d.Dd[0, 0] * e[k, 0] + d.Dd[0, 1] * e[k, 1]
        v1 = d.Dd[1, 0] * e[k, 0] + d.Dd[1, 1] * e[k, 1]
        for j in range(d.order):
            v0 += d.Cd[0, j] * x[j]
            v1 += d.Cd[1, j] * x[j]
        nxt = np.empty(d.order)
        for i in range(d.order):
            acc = d.Bd[i, 0] * e[k, 0] + d.Bd[i, 1] * e[k, 1]
            for j in range(d.order):
                acc += d.Ad[i, j] * x[j]
            nxt[i] = acc
        x = nxt
        expected[k] = complex(v0, v1)
    np.testing.assert_array_equal(v, expected)
    # the difference equations of the transfer functions (bilinear substitution)
    b, a = bilinear_polynomials(*tf_of_20(), 2.0 / T)
    alpha = scipy.signal.lfilter(b, a, e[:, 0])
    # (the polynomial form's own rounding, integrated by its pole at z = 1: ~1e-10 of the peak)
    np.testing.assert_allclose(v.real, alpha, rtol=0, atol=1e-9 * np.abs(alpha).max())
    kp, ki = 360.0, 9000.0
    beta = np.empty(N)
    beta[0] = (kp + ki * T / 2) * e[0, 1]
    for k in range(1, N):
        beta[k] = beta[k - 1] + kp * (e[k, 1] - e[k - 1, 1]) + ki * T / 2 * (e[k, 1] + e[k - 1, 1])
    np.testing.assert_allclose(v.imag, beta, rtol=0, atol=1e-12 * np.abs(beta).max())
    # a run at another sample time than the matrices' is refused before it starts
    with pytest.raises(InputError, match=r"cc\.T_s: the controller was discretised for"):
        system.compile().run(10 * 2e-4, 2e-4, log=[cc.out.v_ref])


def plant_zoh(w_r, T):
    """ZOH-exact discrete model of the DeLorenzo IM (13) stator currents at speed w_r."""
    pl = plant_from_params(DELORENZO_IM_13, w_r)
    n, m = pl.B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = pl.A * T, pl.B * T
    E = scipy.linalg.expm(M)
    return E[:n, :n], E[:n, n:], pl.C


def closed_loop(part, w_r, ref, N, T, v_dc=None):
    """The part's kernel against the exact discrete IM: (currents, controller states, commands,
    events) per sample, the plant input held over each sample as the averaged converter does."""
    Ap, Bp, Cp = plant_zoh(w_r, T)
    n = part.discrete.order
    xp, s, y = np.zeros(Ap.shape[0]), part.initial_state(), np.zeros(2)
    u = np.zeros(part.INPUTS.size())
    out_i, out_x = np.zeros((N, 2)), np.zeros((N, n))
    out_v, out_e = np.zeros((N, 2)), np.zeros(N, dtype=np.int64)
    for k in range(N):
        i = Cp @ xp
        out_i[k] = i
        r = ref(k) if callable(ref) else ref
        u[0], u[1], u[2], u[3] = r.real, r.imag, i[0], i[1]
        if v_dc is not None:
            u[4] = v_dc(k)
        out_e[k] = current_controller_step(k * T, T, u, part.p, s, y)
        out_x[k], out_v[k] = s[:n], y
        xp = Ap @ xp + Bp @ y
    return out_i, out_x, out_v, out_e


@pytest.mark.slow
def test_closed_loop_with_the_cage_motor_matches_the_discrete_loop():
    """(20) on both axes drives the DeLorenzo IM (13) at w_r = 375 rad/s through the averaged
    converter (310 V): a 5 A step saturates the command for a few samples; the simulated
    currents follow the exact discrete loop (ZOH plant, the same kernel) to integration error."""
    T, N = 1e-4, 400
    im = CageInductionMachine.from_params("im", DELORENZO_IM_13)
    shaft = PrescribedSpeed("shaft", w=W_R / DELORENZO_IM_13.n_p)
    ref = CurrentProgram("ref", re=5.0)
    cc = StationaryCurrentController("cc", PAPER_20, T, v_max=max_voltage_magnitude(V_DC))
    conv = AveragedConverter("conv", V_dc=V_DC)
    system = System(
        [im, shaft, ref, cc, conv],
        [
            (ref.out.i, cc.inp.i_ref),
            (im.out.i_s, cc.inp.i_meas),
            (cc.out.v_ref, conv.inp.v_ref),
            (conv.out.v, im.inp.v_s),
            (shaft.out.w, im.inp.w),
        ],
    )
    res = system.compile().run(N * T, T, substeps=4, log=[im.out.i_s, cc.out.v_ref])
    i_sim = res.signal(im.out.i_s)
    i_ref, _, _, events = closed_loop(cc, W_R, 5.0 + 0j, N, T)
    n_sat = int(np.sum(events & EVENT_SATURATED))
    assert 10 < n_sat < 100 and res.events["cc"]["saturated"] == n_sat
    assert res.events["conv"]["saturated"] <= n_sat  # at most rounding at the same limit
    np.testing.assert_allclose(i_sim.real, i_ref[:, 0], atol=1e-8 * 5.0)
    np.testing.assert_allclose(i_sim.imag, i_ref[:, 1], atol=1e-8 * 5.0)
    assert abs(i_sim[-1] - 5.0) < 0.05


# --- anti-windup ---------------------------------------------------------------------------


@pytest.mark.parametrize("k", [PAPER_20, PAPER_PI, FIG18_PI, PI_OF_22], ids=lambda k: k.name)
@pytest.mark.parametrize("w_r", [0.0, W_R])
def test_anti_windup_recovers_without_overshoot_beyond_the_unsaturated_loop(k, w_r):
    """A 5 A step with |v| <= 310/sqrt(2) V: with anti-windup the peak stays within the peak of
    the unsaturated loop; and after a DC-link sag that makes 5 A unreachable for 150 ms the
    current recovers without exceeding it either. Without anti-windup both overshoot more."""
    T, N = 1e-4, 4000
    unlimited = StationaryCurrentController("cc", k, T)
    i_free, _, _, ev = closed_loop(unlimited, w_r, 5.0 + 0j, N, T)
    assert not np.any(ev & EVENT_SATURATED)
    peak_free = np.abs(i_free).max()
    limited = StationaryCurrentController("cc", k, T, v_max=V_MAX)
    i_aw, _, v_aw, ev = closed_loop(limited, w_r, 5.0 + 0j, N, T)
    assert np.any(ev & EVENT_SATURATED) and np.all(
        np.abs(v_aw[:, 0] + 1j * v_aw[:, 1]) <= V_MAX * (1 + 1e-15)
    )
    assert np.abs(i_aw).max() <= peak_free + 1e-9
    assert np.abs(i_aw[-1] - [5.0, 0.0]).max() < 0.02
    wound = limited.with_params(aw_gain=0.0)
    i_w, *_ = closed_loop(wound, w_r, 5.0 + 0j, N, T)
    assert np.abs(i_w).max() > np.abs(i_aw).max() + 0.005
    # DC-link sag: v_dc = 85 V (|v| <= 60 V) for 1500 samples, then 310 V again
    sag = StationaryCurrentController("cc", k, T, v_dc_input=True)
    v_dc = lambda j: 85.0 if j < 1500 else V_DC
    i_s, _, v_s, ev = closed_loop(sag, w_r, 5.0 + 0j, N, T, v_dc)
    assert np.all(ev[:1500] & EVENT_SATURATED)
    assert np.all(np.abs(v_s[:1500, 0] + 1j * v_s[:1500, 1]) <= 85.0 / math.sqrt(2) * (1 + 1e-15))
    assert np.abs(i_s[1500:]).max() <= peak_free + 1e-9
    assert np.abs(i_s[-1] - [5.0, 0.0]).max() < 0.02
    i_sw, *_ = closed_loop(sag.with_params(aw_gain=0.0), w_r, 5.0 + 0j, N, T, v_dc)
    assert np.abs(i_sw[1500:]).max() > peak_free + 1.0


def test_anti_windup_keeps_the_state_bounded_in_sustained_saturation():
    """5 A is unreachable with |v| <= 60 V: with anti-windup the controller state settles
    (bounded by that of the unsaturated loop), without it it grows linearly (integral action)."""
    T, N = 1e-4, 3000
    free = StationaryCurrentController("cc", PAPER_20, T)
    _, x_free, _, _ = closed_loop(free, 0.0, 5.0 + 0j, N, T)
    part = StationaryCurrentController("cc", PAPER_20, T, v_max=60.0)
    _, x, _, ev = closed_loop(part, 0.0, 5.0 + 0j, N, T)
    assert np.all(ev & EVENT_SATURATED)
    assert np.abs(x).max() <= np.abs(x_free).max()
    np.testing.assert_allclose(x[N // 2], x[-1], rtol=0, atol=1e-9 * np.abs(x).max())  # settled
    _, x_w, _, _ = closed_loop(part.with_params(aw_gain=0.0), 0.0, 5.0 + 0j, N, T)
    # winds up: the state keeps growing for as long as the error lasts (the integrator)
    size = np.abs(x_w).max(axis=1)
    assert np.all(np.diff(size[N // 10 :]) > 0) and size[-1] > 1.4 * size[N // 2]
    assert size[-1] > 1000 * np.abs(x).max()


def test_limit_from_the_dc_link_input_and_the_event_bits():
    T = 1e-4
    part = StationaryCurrentController("cc", PAPER_PI, T, v_dc_input=True)
    assert [v.name for v in part.INPUTS] == ["i_ref", "i_meas", "v_dc"]
    s, y = part.initial_state(), np.zeros(2)
    u = np.array([3.0, 4.0, 0.0, 0.0, 100.0])
    assert current_controller_step(0.0, T, u, part.p, s, y) == EVENT_SATURATED
    assert math.hypot(*y) == pytest.approx(100.0 / math.sqrt(2.0), rel=1e-15)
    assert y[1] / y[0] == pytest.approx(4.0 / 3.0, rel=1e-14)  # limited along its direction
    u[4] = 1e6
    ev = current_controller_step(T, 2 * T, u, part.p, s, y)
    assert ev == EVENT_PERIOD_MISMATCH


# --- invalid input ---------------------------------------------------------------------------


def test_invalid_input_names_the_field():
    # unstable discretisation of a stable controller (a pole far beyond Tustin's reach)
    stiff = LTI.zpk([], [-1e21], 1e21)
    with pytest.raises(InputError, match=r"^T_s: the tustin discretisation is unstable"):
        discretise(stiff, 2e-4, "tustin")
    with pytest.raises(InputError, match=r"^cc\.T_s: the tustin discretisation is unstable"):
        StationaryCurrentController("cc", stiff, 2e-4)
    discretise(stiff, 2e-4, "zoh")  # ZOH maps it to z = 0
    # the closed form fails: a controller pole at s = 2/T_s (Tustin), overflow (ZOH)
    with pytest.raises(InputError, match=r"^T_s: the Tustin closed form fails"):
        discretise(LTI.zpk([], [2000.0], 1.0), 1e-3, "tustin")
    with pytest.raises(InputError, match=r"^T_s: the ZOH closed form e\^\{A T_s\} overflows"):
        discretise(LTI.zpk([], [1e6], 1.0), 1.0, "zoh")
    # improper transfer functions
    with pytest.raises(InputError, match=r"^controller\.num: improper transfer function"):
        LTI.tf([1.0, 0.0, 1.0], [1.0, 1.0])
    with pytest.raises(InputError, match=r"^controller: improper"):
        LTI.zpk([-1.0, -2.0], [-3.0], 1.0)
    with pytest.raises(InputError, match=r"^controller\.den: must not be the zero polynomial"):
        LTI.tf([1.0], [0.0, 0.0])
    # periods, methods, pre-warping
    with pytest.raises(InputError, match=r"^T_s: must be a finite sample period > 0"):
        discretise(PAPER_20, -1e-4)
    with pytest.raises(InputError, match=r"^method: must be one of zoh, tustin"):
        discretise(PAPER_20, 1e-4, "euler")
    with pytest.raises(InputError, match=r"^prewarp: must lie in \(0, pi/T_s\)"):
        discretise(PAPER_20, 1e-3, "tustin", prewarp=4000.0)
    with pytest.raises(InputError, match=r"^prewarp: pre-warping applies to the Tustin"):
        discretise(PAPER_20, 1e-3, "zoh", prewarp=300.0)
    with pytest.raises(InputError, match=r"^controller: must be an LTI or an LTIMatrix"):
        discretise([[1.0]], 1e-3)
    # sizes
    with pytest.raises(InputError, match=r"^cc\.controller: must be 2 x 2 .* got 3 x 3"):
        StationaryCurrentController("cc", LTIMatrix.diagonal(PAPER_PI, PAPER_PI, PAPER_PI), 1e-4)
    with pytest.raises(InputError, match=r"^controller\.B: has shape 2 x 2; rows must be 1"):
        LTIMatrix.ss([[0.0]], np.eye(2), [[1.0], [1.0]], np.eye(2))
    with pytest.raises(InputError, match=r"^controller\[1\]: has 1 entries; every row must"):
        LTIMatrix.grid([[PAPER_PI, None], [PAPER_PI]])
    with pytest.raises(InputError, match=r"^controller\[0\]\[1\]: must be an LTI, a number"):
        LTIMatrix.grid([[PAPER_PI, "k"]])
    # part parameters
    with pytest.raises(InputError, match=r"^cc\.T_s: must be given"):
        StationaryCurrentController("cc", PAPER_PI)
    with pytest.raises(InputError, match=r"^cc\.v_max: must be > 0"):
        StationaryCurrentController("cc", PAPER_PI, 1e-4, v_max=0.0)
    with pytest.raises(InputError, match=r"^cc\.aw_gain: must be between 0 and 1"):
        StationaryCurrentController("cc", PAPER_PI, 1e-4, aw_gain=2.0)
    with pytest.raises(InputError, match=r"^cc\.Ad_0_0: is derived from the controller"):
        StationaryCurrentController("cc", PAPER_PI, 1e-4, Ad_0_0=1.0)
    # anti-windup by conditioning needs a biproper controller with stable zeros
    integrator = LTI.pi(0.0, 9000.0)
    with pytest.raises(InputError, match=r"^cc\.aw_gain: anti-windup by conditioning needs D_d"):
        StationaryCurrentController("cc", integrator, 1e-4, "zoh")
    StationaryCurrentController("cc", integrator, 1e-4, "zoh", aw_gain=0.0)
    nmp = LTI.zpk([100.0], [0.0], -1.0)  # a zero in the right half-plane
    with pytest.raises(InputError, match=r"^cc\.aw_gain: the conditioned controller"):
        StationaryCurrentController("cc", nmp, 1e-4)
    part = StationaryCurrentController("cc", PAPER_PI, 1e-4)
    with pytest.raises(InputError, match=r"^cc\.controller: has order 6; .* keep order 2"):
        part.with_params(controller=PAPER_20)


def test_the_serial_modal_sum_has_its_own_cache_entry_and_the_same_result():
    """The threaded and the single-model modal sums are compiled from one loop; each must cache
    under its own name (numba's cache key ignores ``parallel``), and both give the same sums."""
    from acdrive.control._ss_frequency import _modal_sum, _modal_sum_one

    assert _modal_sum_one.targetoptions.get("parallel") is None
    assert _modal_sum.targetoptions.get("parallel") is True
    assert (
        _modal_sum._cache._cache_file._index_name != _modal_sum_one._cache._cache_file._index_name
    )
    rng = np.random.default_rng(7)
    s = 1j * np.geomspace(1.0, 1e4, 40)
    lam = (-rng.uniform(1, 100, (1, 3)) + 1j * rng.uniform(-50, 50, (1, 3))).astype(complex)
    R = (rng.normal(size=(1, 3, 4)) + 1j * rng.normal(size=(1, 3, 4))).astype(complex)
    D = rng.normal(size=(1, 4)).astype(complex)
    expected = D[0][None, :] + np.sum(
        R[0][None, :, :] / (s[:, None, None] - lam[0][None, :, None]), axis=1
    )
    for kernel in (_modal_sum, _modal_sum_one):
        out = np.empty((1, s.size, 4), complex)
        lost = np.zeros((1, s.size), dtype=np.bool_)
        kernel(s, lam, R, D, 1e6, out, lost)
        np.testing.assert_allclose(out[0], expected, rtol=1e-12)


def test_a_discretisation_is_kept_on_disk_bit_for_bit(tmp_path, monkeypatch):
    """The closed form's matrices are kept on disk, keyed by every bit of the inputs: a second
    process reads exactly what the first computed (no scipy import), another period computes
    anew, and a damaged memo is computed and written again."""
    import subprocess
    import sys

    code = (
        "import sys, numpy as np\n"
        "from acdrive.control._discretise import discretise\n"
        "from acdrive.control._lti_matrix import LTIMatrix\n"
        "A = np.array([[0.0, 1.0], [-4.0e4, -30.0]]); B = np.array([[0.0], [1.0]])\n"
        "C = np.array([[9000.0, 360.0]]); D = np.array([[0.5]])\n"
        "d = discretise(LTIMatrix(A, B, C, D), float(sys.argv[1]))\n"
        "print('scipy' in sys.modules, *(m.tobytes().hex() for m in (d.Ad, d.Bd, d.Cd, d.Dd)))\n"
    )
    # a cache folder of the user's choice (acdrive's own would be keyed by its sources)
    env = {k: v for k, v in __import__("os").environ.items() if k != "ACDRIVE_NUMBA_CACHE_DIR"}
    env["NUMBA_CACHE_DIR"] = str(tmp_path)

    def run(T_s):
        done = subprocess.run([sys.executable, "-c", code, repr(T_s)], env=env, check=True,
                              capture_output=True, text=True, timeout=300)  # fmt: skip
        first, *matrices = done.stdout.split()
        return first == "True", matrices

    imported, computed = run(1e-4)
    assert imported
    imported, read = run(1e-4)
    assert not imported and read == computed
    imported, other = run(2e-4)
    assert imported and other != computed
    memos = sorted((tmp_path / "discretised").glob("*.npz"))
    assert len(memos) == 2
    for memo in memos:
        memo.write_bytes(b"damaged")
    imported, again = run(1e-4)
    assert imported and again == computed
