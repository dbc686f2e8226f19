"""python-control interoperability: acdrive's controllers and plants convert to and from
``StateSpace`` / ``TransferFunction`` without changing their frequency response, and the ICAD
functions take python-control controllers and plants as they take acdrive's own."""

from __future__ import annotations

import numpy as np
import pytest

control = pytest.importorskip("control")

from acdrive.analysis import analyse, icad_response, plant_for
from acdrive.control import FIG18_PI, LTI, PAPER_20, LTIMatrix, as_lti, discretise
from acdrive.errors import InputError

W = np.logspace(0, 4, 60)


def _response(sys, w):
    """Frequency response of a python-control system at w, computed from its own matrices."""
    ss = control.ss(sys)
    A, B, C, D = (np.asarray(m, dtype=float) for m in (ss.A, ss.B, ss.C, ss.D))
    n = A.shape[0]
    s = 1j * w if ss.dt in (0, None) else np.exp(1j * w * ss.dt)
    return np.array([C @ np.linalg.solve(z * np.eye(n) - A, B) + D for z in s])


@pytest.mark.parametrize("k", [PAPER_20, FIG18_PI, LTI.pi(2.0, 30.0), LTI.gain(3.5)])
def test_siso_controllers_round_trip_with_the_same_response(k):
    sys = k.to_control()
    assert isinstance(sys, control.StateSpace) and sys.dt == 0
    np.testing.assert_allclose(_response(sys, W)[:, 0, 0], k.freqresp(W), rtol=1e-10)
    back = LTI.from_control(control.tf(sys))
    np.testing.assert_allclose(back.freqresp(W), k.freqresp(W), rtol=1e-8)


def test_mimo_matrix_and_discrete_controllers_convert():
    K = LTIMatrix.grid([[PAPER_20, LTI.gain(0.5)], [None, LTI.pi(1.0, 10.0)]])
    sys = K.to_control()
    assert (sys.noutputs, sys.ninputs) == (2, 2)
    np.testing.assert_allclose(_response(sys, W), K.freqresp(W), rtol=1e-10, atol=1e-12)
    back = LTIMatrix.from_control(sys)
    np.testing.assert_allclose(back.freqresp(W), K.freqresp(W), rtol=1e-10, atol=1e-12)
    kd = discretise(PAPER_20, 2e-5, "tustin")
    sysd = kd.to_control()
    assert sysd.dt == pytest.approx(2e-5)
    w = np.logspace(1, 4, 20)
    np.testing.assert_allclose(_response(sysd, w)[:, 0, 0], kd.freqresp(w), rtol=1e-9)


def test_icad_takes_python_control_objects_as_its_own():
    plant = plant_for("delorenzo-im", 150.0)
    k_tf = control.tf(PAPER_20.to_control())
    ours = icad_response(plant, PAPER_20, PAPER_20, W)
    theirs = icad_response(plant.to_control(), k_tf, k_tf, W)
    np.testing.assert_allclose(theirs.gamma, ours.gamma, rtol=1e-8)
    np.testing.assert_allclose(theirs.coupling, ours.coupling, rtol=1e-8)
    a = analyse(plant.to_control(), k_tf, k_tf)
    b = analyse(plant, PAPER_20, PAPER_20)
    assert (a.b1, a.b2, a.closed_loop_stable) == (b.b1, b.b2, b.closed_loop_stable)
    assert a.coupling_peak_db == pytest.approx(b.coupling_peak_db, abs=1e-6)
    np.testing.assert_allclose(
        np.sort_complex(a.closed_loop_poles), np.sort_complex(b.closed_loop_poles), rtol=1e-6
    )


def test_not_a_controller_and_mimo_where_siso_is_needed_are_named():
    with pytest.raises(InputError, match=r"^k1: must be an LTI controller or a python-control"):
        as_lti("360 + 9000/s", "k1")
    mimo = control.ss(-np.eye(2), np.eye(2), np.eye(2), np.zeros((2, 2)))
    with pytest.raises(InputError, match=r"^k2: must be SISO"):
        as_lti(mimo, "k2")
