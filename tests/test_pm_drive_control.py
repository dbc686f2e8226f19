"""The PM drive's sampled controller parts (``drives/pm/_control.py``), one sample at a time.

* rotor-frame current controller: with zero error and the integrals at R_s i, the command is the
  machine's steady-state voltage v = R_s i + j w_e psi_dq (decoupling and back-EMF exact), turned
  to the stationary frame at theta_e + advance w_e T_s; at the voltage limit the command is
  limited along its direction and the integrals take the realisable error (back-calculation);
* torque reference: the part's output is the design's operating point, events from its flags;
* speed PI: its limit is min(tau_max, available torque) and the integral freezes while limited.
"""

import math

import numpy as np
import pytest

from acdrive.drives.pm import PMSpeedPI, PMTorqueReference, RotorFrameCurrentController
from acdrive.drives.pm import _design as d
from acdrive.errors import InputError

MACHINE = {"R_s": 0.2, "L_d": 1.2e-3, "L_q": 3.0e-3, "psi_m": 0.08, "n_p": 4}
LIMITS = {"i_max": 60.0, "V_dc": 300.0, "margin": 0.9}
PSI_F = math.sqrt(1.5) * MACHINE["psi_m"]
T_S = 1e-4


def step(part, u, s=None, t=0.0):
    """One sample of a part's kernel: (outputs, new state, events)."""
    y = np.zeros(part.OUTPUTS.size())
    s = part.initial_state() if s is None else s
    events = type(part).step(t, T_S, np.asarray(u, float), part.p, s, y)
    return part.OUTPUTS.unpack(y), s, events


def current_controller(**changes):
    gains = d.CurrentPIGains.design(MACHINE["R_s"], MACHINE["L_d"], MACHINE["L_q"], 2000.0)
    return RotorFrameCurrentController("current", K_P_d=gains.K_P_d, K_P_q=gains.K_P_q,
                                       K_I_d=gains.K_I_d, K_I_q=gains.K_I_q, V_dc=300.0,
                                       **{**MACHINE, **changes})  # fmt: skip


def test_decoupled_command_is_the_steady_state_voltage():
    part = current_controller()
    i_dq, w, theta = complex(-20.0, 35.0), 150.0, 0.7
    theta_e, w_e = MACHINE["n_p"] * theta, MACHINE["n_p"] * w
    i_s = i_dq * np.exp(1j * theta_e)
    s = part.initial_state(x=MACHINE["R_s"] * i_dq)  # the integrals of a settled loop
    y, s_next, events = step(part, [i_dq.real, i_dq.imag, i_s.real, i_s.imag, theta, w], s)
    psi_dq = complex(MACHINE["L_d"] * i_dq.real + PSI_F, MACHINE["L_q"] * i_dq.imag)
    v_steady = MACHINE["R_s"] * i_dq + 1j * w_e * psi_dq  # v = R i + j w_e psi in dq
    assert events == 0
    assert y["v_dq_ref"] == pytest.approx(v_steady, rel=1e-13)
    assert y["i_dq"] == pytest.approx(i_dq, rel=1e-13)
    advance = 0.5 * w_e * T_S
    assert y["v_ref"] == pytest.approx(v_steady * np.exp(1j * (theta_e + advance)), rel=1e-13)
    assert s_next == pytest.approx(s, rel=1e-15)  # zero error: the integrals stay


def test_limited_command_and_back_calculation():
    part = current_controller()
    v_max = 300.0 / math.sqrt(2.0)
    i_ref, w = complex(0.0, 60.0), 300.0  # a large step at speed: the command saturates
    u = [i_ref.real, i_ref.imag, 0.0, 0.0, 0.0, w]
    y, s, events = step(part, u)
    wanted, applied = y["v_dq_wanted"], y["v_dq_ref"]
    assert events == 1
    assert abs(applied) == pytest.approx(v_max, rel=1e-14)
    assert applied / abs(applied) == pytest.approx(wanted / abs(wanted), rel=1e-14)
    # the integrals advanced by T_s K_I times the realisable error e + (v - v_wanted) / K_P
    v = part.values
    e_r = complex(i_ref.real + (applied.real - wanted.real) / v["K_P_d"],
                  i_ref.imag + (applied.imag - wanted.imag) / v["K_P_q"])  # fmt: skip
    assert complex(s[0], s[1]) == pytest.approx(
        complex(T_S * v["K_I_d"] * e_r.real, T_S * v["K_I_q"] * e_r.imag), rel=1e-12
    )
    # with that error the unlimited PI would have given the applied command (no windup)
    ff = complex(0.0, MACHINE["n_p"] * w * PSI_F)
    assert complex(v["K_P_d"] * e_r.real, v["K_P_q"] * e_r.imag) + ff == pytest.approx(
        applied, rel=1e-12
    )


def test_without_decoupling_the_command_is_the_plain_pi():
    part = current_controller(decouple=0.0)
    y, _, _ = step(part, [1.0, 2.0, 0.0, 0.0, 0.3, 200.0])
    v = part.values
    assert y["v_dq_ref"] == pytest.approx(complex(v["K_P_d"] * 1.0, v["K_P_q"] * 2.0), rel=1e-14)


@pytest.mark.parametrize("tau, w", [(5.0, 10.0), (-5.0, 10.0), (30.0, 10.0), (8.0, 900.0),
                                    (50.0, 900.0), (5.0, 5000.0)])  # fmt: skip
def test_torque_reference_is_the_design_operating_point(tau, w):
    part = PMTorqueReference("ref", **MACHINE, **LIMITS)
    y, _, events = step(part, [tau, w])
    psi_max = d.flux_limit(MACHINE["R_s"], 300.0 / math.sqrt(2), 0.9, 60.0, MACHINE["n_p"] * w)
    i_d, i_q, flags = d.operating_point(4, PSI_F, 1.2e-3, 3.0e-3, tau, 60.0, psi_max)
    assert y["i_dq_ref"] == complex(i_d, i_q)
    assert y["tau_lim"] == pytest.approx(d.torque(4, PSI_F, 1.2e-3, 3.0e-3, i_d, i_q), rel=1e-14)
    assert events == flags  # same bit order: current, voltage, beyond reach


def test_speed_pi_limit_is_the_available_torque():
    part = PMSpeedPI("spi", K_P=1.0, K_I=10.0, tau_max=100.0, **MACHINE, **LIMITS)
    w = 900.0  # field weakening: less torque than tau_max is available
    psi_max = d.flux_limit(MACHINE["R_s"], 300.0 / math.sqrt(2), 0.9, 60.0, MACHINE["n_p"] * w)
    avail = d.available_torque(4, PSI_F, 1.2e-3, 3.0e-3, 60.0, psi_max)
    assert 0.0 < avail < 100.0
    s = part.initial_state(e_int=0.5)
    y, s, events = step(part, [w + 500.0, w], s)
    assert events == 1 and y["tau_ref"] == pytest.approx(avail, rel=1e-14)
    assert y["tau_avail"] == y["tau_ref"]
    assert s[0] == 0.5  # clamped: the integral did not move
    y, s, events = step(part, [w + 1e-3, w], s)  # a small error: inside the limit
    assert events == 0 and s[0] == pytest.approx(0.5 + T_S * 1e-3, rel=1e-12)


def test_parts_refuse_an_impossible_voltage_budget_and_a_reversed_saliency():
    with pytest.raises(InputError, match=r"^ref\.margin"):
        PMTorqueReference("ref", **MACHINE, i_max=1000.0, V_dc=300.0, margin=0.9)
    with pytest.raises(InputError, match=r"^ref\.L_q"):
        PMTorqueReference("ref", **{**MACHINE, "L_q": 1e-3}, **LIMITS)
