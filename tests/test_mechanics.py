"""The shaft (``plant/_mechanics.py``): the eddy-current brake, friction, and the cage IM on it.

The runs use the cage-IM wiring of ``tests/test_system.py`` (same part names, same generated
loop, compiled once). A de-energised cage motor (no voltage, no flux) exerts exactly zero torque,
so its shaft coasts freely: J dw/dt = -(B + k_b) w, w = w(0) exp(-(B + k_b) t / J).
"""

import numpy as np
import pytest

from acdrive.control import VoltageProgram
from acdrive.errors import InputError
from acdrive.machines import UGALDE_IM_300W, CageInductionMachine, IMParams, PermanentMagnetMachine
from acdrive.machines import _registry as registry
from acdrive.plant import AveragedConverter, Shaft
from acdrive.sim import System
from acdrive.sim._reference import simulate_reference


def cage_drive(machine, shaft, V_pk=100.0, f=50.0, V_dc=310.0, method="rk4"):
    """The cage motor fed open loop through the averaged converter, on ``shaft``."""
    im = CageInductionMachine.from_params("im", machine)
    program = VoltageProgram("program", V_pk=V_pk, f=f)
    inverter = AveragedConverter("inverter", V_dc=V_dc)
    wires = [
        (program.out.v_ref, inverter.inp.v_ref),
        (inverter.out.v, im.inp.v_s),
        (shaft.out.w, im.inp.w),
        (im.out.tau_e, shaft.inp.tau_e),
    ]
    return im, System([im, shaft, program, inverter], wires, method=method)


# --- parameters ---------------------------------------------------------------------------------
def test_the_brake_is_appended_to_the_parameter_layout():
    assert [v.name for v in Shaft.PARAMS] == ["J", "B", "tau_c", "load", "brake"]
    shaft = Shaft("shaft", J=2.0, B=0.1, tau_c=0.3, load=[[0.0, 1.0], [1.0, 2.0]])
    # J, B, tau_c, the load table [n, times, values], then the default brake table (zero)
    np.testing.assert_array_equal(shaft.p, [2.0, 0.1, 0.3, 2, 0.0, 1.0, 1.0, 2.0, 1, 0.0, 0.0])


def test_the_brake_is_passive_and_validated():
    with pytest.raises(
        InputError, match=r"shaft.brake: a passive brake's coefficient must be >= 0"
    ):
        Shaft("shaft", J=1.0, brake=[[0.0, 0.0], [1.0, -0.1]])
    with pytest.raises(InputError, match=r"shaft.brake: times must be >= 0 and non-decreasing"):
        Shaft("shaft", J=1.0, brake=[[1.0, 0.0], [0.5, 0.1]])
    assert Shaft("shaft", J=1.0, brake=0.2).values["brake"] == 0.2


# --- the free shaft with the brake ------------------------------------------------------------
J, B, K_BRAKE, W0 = 0.02, 1e-3, 0.03, 100.0  # kg m^2, N m s/rad, N m s/rad, rad/s
T_S, SUBSTEPS = 1e-3, 4


def coast(shaft, duration):
    """(t, w) of ``shaft`` coasting from W0 behind a de-energised cage motor."""
    im, system = cage_drive(UGALDE_IM_300W, shaft, V_pk=0.0)
    result = system.compile().run(duration, T_S, SUBSTEPS, initial={"shaft": {"w": W0}},
                                  log=[shaft.out.w, im.out.tau_e])  # fmt: skip
    assert not np.any(result.signal(im.out.tau_e))  # exactly zero torque
    return result.t, result.signal(shaft.out.w)


def decay_time_constant(t, w, a, b):
    """-(t_b - t_a) / ln(w_b / w_a) between samples a and b."""
    return -(t[b] - t[a]) / np.log(w[b] / w[a])


@pytest.mark.slow
def test_free_shaft_with_a_brake_decays_with_time_constant_J_over_B_plus_k():
    t, w = coast(Shaft("shaft", J=J, B=B, brake=K_BRAKE), 2.0)
    tau = J / (B + K_BRAKE)  # 0.645 s
    np.testing.assert_allclose(w, W0 * np.exp(-t / tau), rtol=1e-11, atol=0)
    assert decay_time_constant(t, w, 100, -1) == pytest.approx(tau, rel=1e-10)
    # without the brake: the viscous friction alone, J / B = 20 s
    t, w = coast(Shaft("shaft", J=J, B=B), 2.0)
    np.testing.assert_allclose(w, W0 * np.exp(-t * B / J), rtol=1e-11, atol=0)


def test_a_brake_applied_at_a_time():
    """A vertical step of the brake profile at t_b: the time constant is J / B before and
    J / (B + k) after. The integration splits at t_b and no stage before it sees the brake
    (``sim._loop_source.advance_lines``), so both exponentials hold to the integrator's error."""
    t_b = 0.5
    shaft = Shaft("shaft", J=J, B=B, brake=[[0.0, 0.0], [t_b, 0.0], [t_b, K_BRAKE]])
    t, w = coast(shaft, 1.5)
    k_b = round(t_b / T_S)
    assert t[k_b] == pytest.approx(t_b, abs=1e-12)
    assert decay_time_constant(t, w, 0, k_b - 1) == pytest.approx(J / B, rel=1e-10)
    assert decay_time_constant(t, w, k_b, -1) == pytest.approx(J / (B + K_BRAKE), rel=1e-10)
    before, after = np.arange(t.size) < k_b, np.arange(t.size) >= k_b
    np.testing.assert_allclose(w[before], W0 * np.exp(-t[before] * B / J), rtol=1e-11, atol=0)
    expected = W0 * np.exp(-t_b * B / J - (t[after] - t_b) * (B + K_BRAKE) / J)
    np.testing.assert_allclose(w[after], expected, rtol=1e-11, atol=0)


# --- the cage IM with viscous and Coulomb friction and the brake -----------------------------
@pytest.mark.slow
def test_cage_start_with_friction_and_brake_matches_radau():
    """Direct start of the 300 W motor against a load ramp, viscous and Coulomb friction and a
    brake ramped on (continuous profiles): the fast loop against Radau (rtol 1e-10) on the same
    equations, and the brake visibly slows the shaft."""
    brake = [[0.0, 0.0], [0.02, 0.0], [0.03, 3e-4]]
    shaft = Shaft("shaft", J=UGALDE_IM_300W.J, B=1e-5, tau_c=0.01,
                  load=[[0.0, 0.0], [0.02, 0.05]], brake=brake)  # fmt: skip
    im, system = cage_drive(UGALDE_IM_300W, shaft, V_pk=300.0)
    compiled = system.compile()
    log = [im.out.i_s, shaft.out.w]
    fast = compiled.run(0.04, 1e-4, 4, log=log)
    ref = simulate_reference(compiled, 0.04, 1e-4, log=log, rtol=1e-10, atol=1e-12)
    i_ref, w_ref = ref.signal(im.out.i_s), ref.signal(shaft.out.w)
    assert np.max(np.abs(fast.signal(im.out.i_s) - i_ref)) < 1e-6 * np.max(np.abs(i_ref))
    assert np.max(np.abs(fast.signal(shaft.out.w) - w_ref)) < 1e-6 * np.max(np.abs(w_ref))
    unbraked = compiled.run(0.04, 1e-4, 4, log=log, parts=[shaft.with_params(brake=0.0)])
    w_free = unbraked.signal(shaft.out.w)
    assert w_free[-1] - w_ref[-1] > 1e-3 * w_free[-1] and w_ref[-1] > 10.0


# --- the built-in machines as parts -----------------------------------------------------------
@pytest.mark.parametrize("name", registry.names(IMParams))
def test_every_builtin_induction_machine_is_a_cage_part(name):
    params = registry.machine_params(name, IMParams)
    part = registry.machine_part(name, "im")
    assert isinstance(part, CageInductionMachine)
    assert part.values == {"R_s": params.R_s, "R_r": params.R_r, "L_s": params.L_s,
                           "L_r": params.L_r, "L_m": params.L_m, "n_p": params.n_p}  # fmt: skip


def test_machine_part_follows_the_parameter_class():
    assert isinstance(registry.machine_part("pmsg-2mw", "pm"), PermanentMagnetMachine)
    assert registry.machine_part("bodson-dfim", "dfim", V_loss=1.5).values["V_loss"] == 1.5
    with pytest.raises(InputError, match=r"motor.machine: unknown 'nothing'"):
        registry.machine_part("nothing", "m", field="motor.machine")
