"""The inverse-Gamma circuit of identify._circuit against the T-circuit written independently: the
standstill impedance, the conversions both ways, and the sampled admittance against the ZOH
discretisation of the machine's own four-state model (machines.stator_current_ss at w_r = 0)."""

import math

import numpy as np
import pytest
from scipy.signal import cont2discrete

from acdrive.errors import InputError
from acdrive.identify import (
    InverseGamma,
    inverse_gamma,
    sampled_admittance,
    standstill_impedance,
    t_circuit,
)
from acdrive.machines import DELORENZO_IM, DELORENZO_IM_13, UGALDE_IM_300W, stator_current_ss

MACHINES = [DELORENZO_IM, DELORENZO_IM_13, UGALDE_IM_300W]
W = 2.0 * math.pi * np.logspace(-1, 3, 25)


def t_circuit_impedance(m, w):
    """Z = R_s + jw L_s - (jw L_m)^2 / (R_r + jw L_r): the stator with the shorted rotor loop."""
    s = 1j * w
    return m.R_s + s * m.L_s - (s * m.L_m) ** 2 / (m.R_r + s * m.L_r)


@pytest.mark.parametrize("machine", MACHINES)
def test_the_inverse_gamma_impedance_is_the_t_circuits(machine):
    Z = standstill_impedance(inverse_gamma(machine), W)
    np.testing.assert_allclose(Z, t_circuit_impedance(machine, W), rtol=1e-12)


@pytest.mark.parametrize("machine", MACHINES)
def test_the_inverse_gamma_parameters_follow_from_the_t_circuit(machine):
    p = inverse_gamma(machine)
    assert p.L_sigma == pytest.approx(machine.sigma * machine.L_s, rel=1e-12)
    assert p.L_M == pytest.approx(machine.L_m**2 / machine.L_r, rel=1e-12)
    assert p.R_R == pytest.approx(machine.R_r * machine.L_m**2 / machine.L_r**2, rel=1e-12)
    assert p.rotor_corner == pytest.approx(machine.R_r / machine.L_r, rel=1e-12)


@pytest.mark.parametrize("machine", MACHINES)
@pytest.mark.parametrize("split", ["equal", "rotor-only"])
def test_any_assumed_split_gives_back_the_same_terminal_behaviour(machine, split):
    p = inverse_gamma(machine)
    back = t_circuit(p, machine.n_p, split)
    np.testing.assert_allclose(t_circuit_impedance(back, W), t_circuit_impedance(machine, W),
                               rtol=1e-12)  # fmt: skip
    np.testing.assert_allclose(inverse_gamma(back).as_array(), p.as_array(), rtol=1e-12)
    if split == "equal":
        assert back.L_s - back.L_m == pytest.approx(back.L_r - back.L_m, rel=1e-12)
    else:
        assert back.L_s == pytest.approx(back.L_m, rel=1e-12)
    # the split itself is not in the data: the two assumptions disagree on L_m when the
    # machine's own leakage is not split that way
    other = t_circuit(p, machine.n_p, "rotor-only" if split == "equal" else "equal")
    assert abs(other.L_m - back.L_m) > 1e-3 * back.L_m


@pytest.mark.parametrize("machine", MACHINES)
@pytest.mark.parametrize("hold", [2e-4, 1e-3])
def test_the_sampled_admittance_is_the_zoh_discretised_machine_model(machine, hold):
    A, B, C, D = stator_current_ss(machine, 0.0)
    Ad, Bd, Cd, _, _ = cont2discrete((A, B, C, D), hold, method="zoh")
    w = W[W * hold < math.pi]
    z = np.exp(1j * w * hold)
    expected = np.array([(Cd @ np.linalg.solve(zk * np.eye(4) - Ad, Bd))[0, 0] for zk in z])
    np.testing.assert_allclose(sampled_admittance(inverse_gamma(machine), w, hold), expected,
                               rtol=1e-9)  # fmt: skip
    # far below the sampling rate it is the continuous admittance delayed by half a hold, to
    # within the order (w T)(|lambda| T) of the fastest pole lambda
    A2 = np.array([[A[0, 0], A[0, 2]], [A[2, 0], A[2, 2]]])
    fastest = np.max(np.abs(np.linalg.eigvals(A2)))
    slow = w * hold < 1e-3
    bound = 1e-3 * fastest * hold
    np.testing.assert_allclose(
        sampled_admittance(inverse_gamma(machine), w[slow], hold),
        np.exp(-0.5j * w[slow] * hold) / standstill_impedance(inverse_gamma(machine), w[slow]),
        rtol=bound,
    )


def test_a_parameter_that_is_not_positive_is_refused():
    with pytest.raises(InputError, match=r"^L_M: must be > 0"):
        InverseGamma(1.0, 0.1, 1.0, 0.0)
    with pytest.raises(InputError, match=r"^split: must be one of 'equal', 'rotor-only'"):
        t_circuit(InverseGamma(1.0, 0.1, 1.0, 1.0), 1, "stator-only")
