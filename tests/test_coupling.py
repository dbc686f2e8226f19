"""Coupling between the current channels measured in simulation against ICAD's (10)
(``acdrive.analysis._coupling``; Amezquita-Brooks et al. (10), Fig. 8; Ugalde-Loo et al. (6))."""

from __future__ import annotations

import math

import numpy as np
import pytest

from acdrive.analysis._coupling import (
    VOLTAGE_LIMIT,
    CouplingSetup,
    closed_loop,
    fit_sinusoid,
    icad_coupling,
    measure_coupling,
    pmsg_pi,
    stationary_equivalent,
)
from acdrive.control import LTI, PAPER_20
from acdrive.errors import InputError
from acdrive.machines import DELORENZO_IM, PMSG_2MW

#: simulated coupling against (10) at frequencies well below the 50 kHz sampling rate
#: (<= 1000 rad/s, 1/300 of 2 pi 50 kHz): relative complex difference
REL_TOL = 0.02
#: with the hold's delay N T_s / 2 in the prediction
REL_TOL_DELAYED = 0.02
W_R = 375.0
W_PMSG = 2.0 * math.pi * 50.0  # rated 50 Hz, w_gen = 157 rad/s


@pytest.fixture(scope="module")
def im_ideal():
    setup = CouplingSetup(DELORENZO_IM, PAPER_20, W_R, (300.0, 375.0, 1000.0), name="im")
    return measure_coupling(setup)


@pytest.fixture(scope="module")
def im_hold():
    setup = CouplingSetup(
        DELORENZO_IM, PAPER_20, W_R, (375.0, 1000.0), hold_samples=10, name="im-5khz"
    )
    return measure_coupling(setup)


@pytest.fixture(scope="module")
def pmsg():
    k = pmsg_pi(PMSG_2MW, 1000.0)
    setup = CouplingSetup(PMSG_2MW, k, W_PMSG, (100.0, 1000.0), amplitude=100.0, name="pmsg")
    return measure_coupling(setup)


def test_im_coupling_equals_icad(im_ideal):
    # both computed here: the simulation and (10)
    predicted = icad_coupling(DELORENZO_IM, W_R, PAPER_20, im_ideal.frequencies)
    np.testing.assert_allclose(im_ideal.icad, predicted)
    err = np.abs(im_ideal.measured - predicted) / np.abs(predicted)
    assert np.all(err <= REL_TOL), err
    # the coupling peaks at the rotor speed (Fig. 8): -19 dB there, far lower at 300 rad/s
    db = 20 * np.log10(np.abs(im_ideal.measured))
    assert db[1] == pytest.approx(20 * np.log10(abs(predicted[1])), abs=0.2)
    assert db[1] > db[0] + 10.0
    # the direct channel tracks the reference with the closed loop's gain
    direct = closed_loop(DELORENZO_IM, W_R, PAPER_20, im_ideal.frequencies, im_ideal.setup.delay)
    np.testing.assert_allclose(im_ideal.measured_direct, direct[:, 0, 0], rtol=REL_TOL)
    # the commands stay in the 310 V link's linear range: the averaged inverter is this loop
    assert np.all(im_ideal.peak_voltage < VOLTAGE_LIMIT)
    assert np.all(im_ideal.uncertainty < 0.01)


def test_im_hold_delay(im_hold):
    # the 5 kHz carrier's hold: (10) with k e^{-j w N T_s / 2} predicts the measurement; the
    # delay-free (10) is further off at 1000 rad/s
    err_delayed = im_hold.relative_error(delayed=True)
    err = im_hold.relative_error()
    assert np.all(err_delayed <= REL_TOL_DELAYED), err_delayed
    assert err[-1] > 3 * err_delayed[-1]


def test_pmsg_coupling_equals_icad(pmsg):
    predicted = icad_coupling(PMSG_2MW, W_PMSG, pmsg.setup.controller, pmsg.frequencies)
    err = np.abs(pmsg.measured - predicted) / np.abs(predicted)
    assert np.all(err <= REL_TOL), err
    # the dq coupling of a speed-proportional plant is strong: about -11 ... -16 dB here
    assert np.all(20 * np.log10(np.abs(pmsg.measured)) > -20.0)


def test_icad_form_equals_closed_loop():
    # (10) in the division-safe form of analysis.icad equals the (2, 1) entry of the full loop
    w = np.logspace(1, 4, 50)
    for params, speed, k in (
        (DELORENZO_IM, W_R, PAPER_20),
        (PMSG_2MW, W_PMSG, pmsg_pi(PMSG_2MW, 1000.0)),
    ):
        for delay in (0.0, 1e-4):
            np.testing.assert_allclose(
                icad_coupling(params, speed, k, w, delay),
                closed_loop(params, speed, k, w, delay)[:, 1, 0],
                rtol=1e-9,
            )


def test_stationary_equivalent_is_frequency_shift():
    k = LTI.pi(0.3, 5.0)
    w_e = 314.0
    K = stationary_equivalent(k, w_e)
    s = 1j * np.array([10.0, 300.0, 1000.0])
    Kv = K.evaluate(s)
    for i, si in enumerate(s):
        # the real 2 x 2 form acting on e_a = X, e_b = -j X (X = e^{s t}) gives the complex
        # output v_a + j v_b = 2 k(s - j w_e) X: the complex error e = e_a + j e_b = 2 X sees
        # k(s - j w_e), the dq controller k(s) rotated into the stationary frame
        v = Kv[i] @ np.array([1.0, -1j])
        expected = k.evaluate(np.array([si - 1j * w_e]))[0]
        np.testing.assert_allclose((v[0] + 1j * v[1]) / 2.0, expected, rtol=1e-12)


def test_fit_sinusoid():
    t = np.linspace(0.0, 0.1, 5001)
    y = 0.3 * np.cos(200.0 * t + 0.4) + 2.0
    assert fit_sinusoid(t, y, 200.0) == pytest.approx(0.3 * np.exp(0.4j), rel=1e-9)


def test_setup_checks():
    with pytest.raises(InputError):
        CouplingSetup(DELORENZO_IM, PAPER_20, W_R, ())
    with pytest.raises(InputError):
        CouplingSetup(DELORENZO_IM, PAPER_20, W_R, (100.0,), hold_samples=0)
