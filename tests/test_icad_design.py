"""Design models A-D (Amezquita-Brooks et al. sec. V-A), specifications, controller checks and
the loop-shaping helper, checked against independent computations (numpy solves, scipy.signal,
python-control closed loops)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.signal
from hypothesis import given, settings
from hypothesis import strategies as st

from acdrive.analysis import (
    PAPER_SPECS,
    Specifications,
    check_controller,
    plant_from_params,
    propose_controller,
)
from acdrive.analysis._design_models import compare_design_models, design_models, ideal_other_loop
from acdrive.analysis._freqresp import LTI
from acdrive.errors import InputError
from acdrive.machines import DELORENZO_IM, DELORENZO_IM_13, IMParams

control = pytest.importorskip("control")


def _G(plant, w):
    """G(jw) by direct linear solves (independent of the library's eigen-decomposition path)."""
    n = plant.A.shape[0]
    return np.array([plant.C @ np.linalg.solve(1j * x * np.eye(n) - plant.A, plant.B) for x in w])


# ---------------------------------------------------------------------------------------------
# design models


def test_model_a_is_the_channel_with_ideal_other_loop():
    w = np.logspace(0, 5, 300)
    plant = plant_from_params(DELORENZO_IM, 375.0)
    G = _G(plant, w)
    expected = G[:, 0, 0] * (1.0 - G[:, 0, 1] * G[:, 1, 0] / (G[:, 0, 0] * G[:, 1, 1]))
    got = ideal_other_loop(plant).freqresp(w)
    assert np.max(np.abs(got - expected) / np.abs(expected)) < 1e-9


@pytest.mark.filterwarnings("ignore::scipy.signal.BadCoefficients")
@settings(max_examples=25, deadline=None)
@given(
    R_s=st.floats(0.01, 50.0),
    R_r=st.floats(0.01, 50.0),
    L_s=st.floats(0.01, 2.0),
    leak=st.floats(0.01, 0.2),
    ratio=st.floats(0.9, 1.1),
    w_r=st.floats(-2000.0, 2000.0),
)
def test_model_a_zeros_are_the_im_transmission_zeros(R_s, R_r, L_s, leak, ratio, w_r):
    # det G of the IM vanishes where the rotor circuit is resonant: s = -R_r/L_r + j w_r
    L_r = L_s * ratio
    L_m = math.sqrt(L_s * L_r) * (1.0 - leak)
    p = IMParams(R_s=R_s, R_r=R_r, L_s=L_s, L_r=L_r, L_m=L_m)
    m = design_models(p, w_r)["A"].model
    z, poles, _ = scipy.signal.ss2zpk(m.A, m.B, m.C, m.D)
    expected = np.array([-R_r / L_r + 1j * w_r, -R_r / L_r - 1j * w_r])
    assert len(z) == 2
    scale = max(1.0, abs(w_r), R_r / L_r)
    assert np.allclose(np.sort_complex(z), np.sort_complex(expected), atol=1e-6 * scale)
    # its poles are the zeros of g_22 (stable: Ugalde-Loo et al. (55)-(57))
    plant = plant_from_params(p, w_r)
    A, b, c, d = plant.siso(1, 1)
    z22, _, _ = scipy.signal.ss2zpk(A, b, c, d)
    assert np.allclose(np.sort_complex(poles), np.sort_complex(z22), atol=1e-6 * scale)
    assert np.all(poles.real < 0)


def test_models_coincide_at_standstill_and_agree_where_the_paper_says():
    # w_r = 0: gamma = 0 (n_12 is proportional to w_r), so A = B = C exactly
    cmp0 = compare_design_models(DELORENZO_IM, 0.0, np.logspace(0, 5, 200))
    assert cmp0.errors["B"].max_rel_error < 1e-9
    assert cmp0.errors["C"].max_rel_error < 1e-9
    # D = 1/(L_s s + R_s) has the right DC gain 1/R_s at standstill ...
    low = compare_design_models(DELORENZO_IM, 0.0, np.logspace(-4, -2, 5))
    assert low.errors["D"].max_rel_error < 1e-3
    # ... but not the high-frequency gain 1/(sigma L_s s): relative error -> 1 - sigma
    high = compare_design_models(DELORENZO_IM, 375.0, np.logspace(6, 7, 5))
    sigma = DELORENZO_IM.sigma
    assert high.errors["D"].max_rel_error == pytest.approx(1.0 - sigma, rel=1e-3)
    # A, B, C share the asymptote 1/(sigma L_s s) (gamma has relative degree 4)
    assert high.errors["B"].max_rel_error < 1e-6
    assert high.errors["C"].max_rel_error < 1e-3
    # at 375 rad/s model B misses the resonance dip at w = w_r (sec. V-A, Fig. 4)
    mid = compare_design_models(DELORENZO_IM, 375.0, np.logspace(1, 5, 400))
    assert mid.errors["B"].max_rel_error > 1.0
    assert 300.0 < mid.errors["B"].at_rad_s < 450.0


def test_design_models_reject_bad_input():
    with pytest.raises(InputError):
        design_models(DELORENZO_IM, float("nan"))
    with pytest.raises(InputError):
        compare_design_models(DELORENZO_IM, 100.0, np.array([]))
    with pytest.raises(InputError):
        compare_design_models(DELORENZO_IM, 100.0, np.array([-1.0, 2.0]))


# ---------------------------------------------------------------------------------------------
# specifications


@pytest.mark.parametrize(
    "kwargs",
    [
        {"bandwidth_rad_s": 0.0},
        {"bandwidth_rad_s": float("nan")},
        {"gm_db": -1.0},
        {"pm_deg": 180.0},
        {"pm_deg": -5.0},
        {"coupling_db": float("inf")},
        {"w_r_min": 100.0, "w_r_max": 50.0},
        {"w_r_max": float("nan")},
        {"n_speeds": 0},
        {"n_speeds": 2.5},
        {"n_speeds": 1, "w_r_min": 0.0, "w_r_max": 10.0},
        {"structural_gm_db": -3.0},
        {"bandwidth_measure": "median"},
    ],
)
def test_bad_specifications_raise(kwargs):
    with pytest.raises(InputError):
        Specifications(**kwargs)


def test_specification_speeds_cover_the_range():
    s = Specifications(w_r_min=-100.0, w_r_max=300.0, n_speeds=5)
    assert s.speeds()[0] == -100.0 and s.speeds()[-1] == 300.0 and s.speeds().size == 5


# ---------------------------------------------------------------------------------------------
# independent verification of a controller with python-control


def _independent(plant, k: LTI, w):
    """Closed-loop poles, channel-1 loop c_1 (frequency response) and coupling y_1/r_2 from
    python-control interconnections (no ICAD formulas)."""
    P = control.ss(plant.A, plant.B, plant.C, plant.D)
    kc = control.ss(k.A, k.B, k.C, k.D)
    zero = control.ss([], [], [], [[0.0]])
    K = control.append(kc, kc)
    cl = control.feedback(P * K, np.eye(2))  # r -> y
    poles = cl.poles()
    loop2 = control.feedback(P, control.append(zero, kc))  # loop 2 closed: u -> y
    c1 = kc * control.ss(loop2.A, loop2.B[:, :1], loop2.C[:1, :], loop2.D[:1, :1])
    c1_w = control.frequency_response(c1, w).complex.ravel()
    coupling = control.frequency_response(cl, w).complex[0, 1].ravel()
    return poles, c1_w, coupling


def _margins_from_response(L, w):
    """(highest crossover, PM there, smallest |GM| over the phase crossovers) on a dense grid."""
    mag = np.abs(L)
    above = np.flatnonzero(mag >= 1.0)
    k = above[-1]
    pm = 180.0 - abs(math.degrees(np.angle(L[k])))
    cross = np.flatnonzero((np.sign(L.imag[:-1]) != np.sign(L.imag[1:])) & (L.real[:-1] < 0))
    gm = min((abs(20 * math.log10(abs(L.real[i]))) for i in cross), default=math.inf)
    return w[k], pm, gm


@pytest.mark.slow
def test_check_controller_paper_20_against_python_control():
    specs = Specifications(n_speeds=3)
    k = LTI.paper_20()
    chk = check_controller("delorenzo-im-13", k, k, specs)
    assert chk.conditions_hold and chk.closed_loop_stable and chk.met_all
    w = np.logspace(0, 5.5, 20000)
    for speed in specs.speeds():
        poles, c1, coupling = _independent(plant_from_params(DELORENZO_IM_13, speed), k, w)
        assert np.all(poles.real < 0)
        wc, pm, gm = _margins_from_response(c1, w)
        assert wc >= chk.get("bandwidth (crossover of c_i)").worst * (1 - 2e-3)
        assert pm >= chk.get("phase margin of c_i").worst - 0.2
        assert gm >= chk.get("gain margin of c_i").worst - 0.2
        if speed != 0.0:  # at standstill g_12 = 0: no coupling at all
            peak = 20 * math.log10(np.max(np.abs(coupling)))
            assert peak <= chk.get("coupling peak").worst + 0.05
        else:
            assert np.max(np.abs(coupling)) < 1e-12


def test_check_controller_flags_the_pi_coupling():
    # the PI (K_P = 360, K_I = 9000) has too little gain near w_r (sec. VI-D): coupling fails
    specs = Specifications(n_speeds=2, w_r_min=187.5)
    k = LTI.pi(360.0, 9000.0)
    chk = check_controller("delorenzo-im-13", k, k, specs)
    cp = chk.get("coupling peak")
    assert not cp.met and cp.worst > specs.coupling_db
    w = np.logspace(1, 5, 8000)
    _, _, coupling = _independent(plant_from_params(DELORENZO_IM_13, cp.worst_speed), k, w)
    assert 20 * math.log10(np.max(np.abs(coupling))) == pytest.approx(cp.worst, abs=0.1)


def test_check_controller_rejects_bad_input():
    k = LTI.paper_20()
    with pytest.raises(InputError):
        check_controller("delorenzo-im", k, k, {"bandwidth": 1.0})
    with pytest.raises(InputError):
        check_controller("delorenzo-im", k, k, PAPER_SPECS, speeds=[float("nan")])
    unstable = LTI.zpk([], [5.0], 1.0)
    with pytest.raises(InputError):
        check_controller("delorenzo-im", unstable, unstable, Specifications(n_speeds=2))


def _assert_stable_minimum_phase(k: LTI):
    poles = k.poles()
    assert np.all(poles.real <= 1e-9)  # integrator on the axis allowed
    assert np.sum(np.abs(poles) < 1e-9) <= 1
    z, _, _ = scipy.signal.ss2zpk(k.A, k.B, k.C, k.D)
    assert np.all(np.real(z) < 0)


@pytest.mark.slow
def test_proposed_controller_meets_what_it_claims():
    specs = Specifications(n_speeds=3)
    prop = propose_controller("delorenzo-im-13", None, specs)
    k = prop.controller
    _assert_stable_minimum_phase(k)
    assert k.order <= 3
    assert prop.check.met_all, prop.check.unmet
    w = np.logspace(0, 5.5, 20000)
    for speed in specs.speeds():
        poles, c1, coupling = _independent(plant_from_params(DELORENZO_IM_13, speed), k, w)
        assert np.all(poles.real < 0)
        wc, pm, gm = _margins_from_response(c1, w)
        assert wc >= specs.bandwidth_rad_s
        assert pm >= specs.pm_deg
        assert gm >= specs.gm_db
        assert np.max(np.abs(coupling)) <= 10 ** (specs.coupling_db / 20)


def test_low_speed_range_gives_a_pi():
    # far below 375 rad/s the resonance dip at w = w_r is shallow: a PI meets every spec
    specs = Specifications(bandwidth_rad_s=2000.0, w_r_max=100.0, n_speeds=2)
    prop = propose_controller("delorenzo-im-13", None, specs)
    assert prop.candidate.structure == "PI"
    assert prop.controller.order == 1
    assert prop.check.met_all
    w = np.logspace(0, 5.5, 20000)
    poles, c1, _ = _independent(plant_from_params(DELORENZO_IM_13, 100.0), prop.controller, w)
    assert np.all(poles.real < 0)
    assert _margins_from_response(c1, w)[0] >= 2000.0


def test_impossible_specs_are_reported_unmet():
    specs = Specifications(bandwidth_rad_s=3300.0, pm_deg=89.0, coupling_db=-60.0, n_speeds=2)
    prop = propose_controller("delorenzo-im-13", None, specs, max_verify=1)
    assert not prop.check.met_all
    assert "coupling peak" in prop.unmet


# ---------------------------------------------------------------------------------------------
# the reproduce command (dispatch only; the full report is regenerated by `acdrive reproduce`)


def test_reproduce_dispatches_to_the_report_module(monkeypatch, tmp_path, capsys):
    import importlib

    # output safety: acdrive replaces only a report that carries its stamp
    REPORT = "# report\n\nGenerated by `acdrive reproduce icad`.\n"

    from acdrive.cli import main

    module = importlib.import_module("acdrive._report.icad_reproduction")
    calls = []

    def fake(out_dir):  # writes the report's two items into the staging folder it is given
        calls.append(Path(out_dir))
        (Path(out_dir) / "icad.md").write_text(REPORT)
        (Path(out_dir) / "icad").mkdir()
        return Path(out_dir) / "icad.md"

    monkeypatch.setattr(module, "write_report", fake)
    assert main(["reproduce", "icad", "--out", str(tmp_path)]) == 0
    assert len(calls) == 1 and calls[0].parent == tmp_path  # a staging folder inside --out
    assert (tmp_path / "icad.md").read_text() == REPORT and (tmp_path / "icad").is_dir()
    assert str(tmp_path / "icad.md") in capsys.readouterr().out


def test_reproduce_missing_report_is_exit_2(monkeypatch, capsys):
    from acdrive._commands import reproduce
    from acdrive.cli import main

    monkeypatch.setitem(reproduce.REPORTS, "bodson", "acdrive._report.no_such_report_module")
    assert main(["reproduce", "bodson"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bodson" in err[0]
    with pytest.raises(SystemExit) as exc:
        main(["reproduce", "nonsense"])
    assert exc.value.code == 2
