"""Speed and parameter-perturbation sweeps (Amezquita-Brooks et al. sec. V-E, VIII), checked
against independent eigenvalue and frequency-response computations."""

from __future__ import annotations

import math

import numpy as np
import pytest

from acdrive.analysis import (
    NOMINAL,
    PAPER_PERTURBATION,
    Perturbation,
    analyse,
    gm_min,
    perturbation_sweep,
    plant_from_params,
    random_perturbations,
    speed_sweep,
)
from acdrive.analysis._freqresp import LTI
from acdrive.errors import InputError
from acdrive.machines import DELORENZO_IM, DELORENZO_IM_13

SPEEDS = np.array([0.0, 187.5, 375.0])


def _gamma(plant, w):
    n = plant.A.shape[0]
    G = np.array([plant.C @ np.linalg.solve(1j * x * np.eye(n) - plant.A, plant.B) for x in w])
    return G[:, 0, 1] * G[:, 1, 0] / (G[:, 0, 0] * G[:, 1, 1])


def test_perturbation_scales_the_parameters():
    p = PAPER_PERTURBATION.apply(DELORENZO_IM)
    assert p.R_s == pytest.approx(2 * DELORENZO_IM.R_s)
    assert p.R_r == pytest.approx(2 * DELORENZO_IM.R_r)
    assert p.L_s == pytest.approx(0.6 * DELORENZO_IM.L_s)
    assert p.L_r == pytest.approx(0.6 * DELORENZO_IM.L_r)
    assert p.L_m == pytest.approx(0.59 * DELORENZO_IM.L_m)
    # L_m falls slightly more than L_s, L_r: the leakage factor grows
    assert p.sigma > DELORENZO_IM.sigma


@pytest.mark.parametrize("field", ["R_s", "R_r", "L_s", "L_r", "L_m"])
def test_bad_perturbation_factors_raise(field):
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(InputError):
            Perturbation(**{field: bad})


def test_perturbation_that_kills_sigma_raises():
    with pytest.raises(InputError):
        Perturbation(L_m=1.2).apply(DELORENZO_IM)  # L_m^2 > L_s L_r


@pytest.mark.slow
def test_perturbed_plant_keeps_conditions_i_to_iv():
    # Independent of the ICAD module: eigenvalues, gamma poles and real-axis crossings.
    p = PAPER_PERTURBATION.apply(DELORENZO_IM_13)
    res = perturbation_sweep(DELORENZO_IM_13, LTI.paper_20(), LTI.paper_20(), SPEEDS)
    assert res.all_conditions and res.all_stable and res.all_b2 and not res.failures
    w = np.logspace(-1, 5, 40000)
    for s in SPEEDS:
        plant = plant_from_params(p, s)
        assert np.all(np.linalg.eigvals(plant.A).real < 0)  # i
        g = _gamma(plant, w)
        assert abs(g[-1]) < 1e-6  # iii (relative degree 4)
        cross = np.flatnonzero(np.sign(g.imag[:-1]) != np.sign(g.imag[1:]))
        right = [g.real[i] for i in cross if g.real[i] > 0]
        assert all(x < 1.0 for x in right)  # iv: every positive-axis crossing left of (1, 0)
        if s > 0:
            # the reported structural margin is that crossing, and it respects G_M,min (19)
            case = next(
                r for r in res.results if r.case == PAPER_PERTURBATION.label and r.speed == s
            )
            assert case.structural_gm_db == pytest.approx(-20 * math.log10(max(right)), abs=0.05)
            assert max(right) < gm_min(p)


def test_paper_perturbation_figures_match_fig_22_structure():
    # sec. VIII: with the perturbed plant the design still meets the specs at 375 rad/s
    res = perturbation_sweep(
        DELORENZO_IM_13, LTI.paper_20(), LTI.paper_20(), [375.0], [PAPER_PERTURBATION]
    )
    (case,) = res.results
    assert case.crossover_rad_s > 3300.0
    assert case.pm_deg > 50.0 and case.gm_db > 12.0
    assert case.kg_pm_deg > 50.0 and case.kg_gm_db > 12.0
    assert case.coupling_peak_db < -15.0


def test_worst_case_is_the_extreme_over_cases_and_speeds():
    k = LTI.paper_20()
    perts = [NOMINAL, PAPER_PERTURBATION]
    res = perturbation_sweep(DELORENZO_IM, k, k, SPEEDS, perts)
    assert len(res.results) == len(perts) * SPEEDS.size
    pms = [r.pm_deg for r in res.results]
    cps = [r.coupling_peak_db for r in res.results]
    assert res.worst["pm_deg"].value == min(pms)
    assert res.worst["coupling_peak_db"].value == max(cps)
    worst = res.worst["coupling_peak_db"]
    # recompute the worst coupling case independently with a plain analysis
    pert = next(p for p in perts if p.label == worst.case)
    a = analyse(plant_from_params(pert.apply(DELORENZO_IM), worst.speed), k, k, verify=False)
    assert a.coupling_peak_db == pytest.approx(worst.value, abs=0.05)  # grid peak


def test_speed_sweep_matches_the_perturbation_sweep_of_the_nominal_case():
    k = LTI.pi(360.0, 9000.0)
    a = speed_sweep(DELORENZO_IM, k, k, SPEEDS)
    b = perturbation_sweep(DELORENZO_IM, k, k, SPEEDS, [NOMINAL])
    for name, wc in a.worst.items():
        assert b.worst[name].value == pytest.approx(wc.value, rel=1e-12, abs=1e-12)
    by_name = speed_sweep("delorenzo-im", k, k, SPEEDS)
    assert by_name.worst["pm_deg"].value == pytest.approx(a.worst["pm_deg"].value)


def test_random_perturbations_are_seeded_and_in_range():
    a = random_perturbations(20, seed=7, params=DELORENZO_IM)
    b = random_perturbations(20, seed=7, params=DELORENZO_IM)
    c = random_perturbations(20, seed=8, params=DELORENZO_IM)
    assert a == b and a != c
    for p in a:
        assert 0.8 <= p.R_s <= 2.0 and 0.8 <= p.R_r <= 2.0
        for f in (p.L_s, p.L_r, p.L_m):
            assert 0.6 * 0.99 <= f <= 1.1 * 1.01
        assert p.apply(DELORENZO_IM).sigma > 0


def test_random_perturbation_sweep_keeps_structure():
    k = LTI.paper_20()
    perts = random_perturbations(4, seed=3, params=DELORENZO_IM)
    res = perturbation_sweep(DELORENZO_IM, k, k, [375.0], perts)
    assert res.all_conditions  # the IM structure theorem (Ugalde-Loo et al. sec. 4.4)
    for r in res.results:
        p = next(q for q in perts if q.label == r.case).apply(DELORENZO_IM)
        assert r.gm_min == pytest.approx(gm_min(p))
        assert r.msf_at_wr < 1.0


@pytest.mark.parametrize(
    "call",
    [
        lambda: random_perturbations(0),
        lambda: random_perturbations(3, r_range=(2.0, 1.0)),
        lambda: random_perturbations(3, l_spread=1.5),
        lambda: random_perturbations(3, l_spread=0.5, params=DELORENZO_IM, max_draws=1),
        lambda: speed_sweep(DELORENZO_IM, LTI.paper_20(), LTI.paper_20(), [float("nan")]),
        lambda: speed_sweep(DELORENZO_IM, LTI.paper_20(), LTI.paper_20(), []),
        lambda: perturbation_sweep(DELORENZO_IM, LTI.paper_20(), LTI.paper_20(), [1.0], []),
        lambda: perturbation_sweep("delorenzo-im", LTI.paper_20(), LTI.paper_20(), [1.0]),
    ],
)
def test_bad_sweep_input_raises(call):
    with pytest.raises(InputError):
        call()


@pytest.mark.parametrize("params", [DELORENZO_IM_13, PAPER_PERTURBATION.apply(DELORENZO_IM_13)])
def test_gm_min_bounds_the_gamma_crossing_and_is_approached(params):
    # Amezquita-Brooks (19): the positive-real-axis crossing of gamma stays below G_M,min and
    # tends to it as w_r grows (the crossing is near w = w_r, at F(3) of Ugalde-Loo (73)).
    bound = gm_min(params)
    crossings = []
    for w_r in (100.0, 375.0, 1000.0, 5000.0):
        w = np.logspace(math.log10(0.3 * w_r), math.log10(3.0 * w_r), 20000)
        g = _gamma(plant_from_params(params, w_r), w)
        idx = np.flatnonzero((np.sign(g.imag[:-1]) != np.sign(g.imag[1:])) & (g.real[:-1] > 0))
        crossings.append(max(g.real[idx]))
    assert all(x < bound for x in crossings)
    assert np.all(np.diff(crossings) > 0)
    assert crossings[-1] > 0.99 * bound
