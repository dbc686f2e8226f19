"""Systems from parts: wiring validation, the cage IM and the DFIM open loop against analytic
steady states and a Radau reference of the same equations, batch equal to single runs."""

import math

import numpy as np
import pytest

from acdrive.control import ComplexProgram, VoltageProgram
from acdrive.core import Layout, Var, real
from acdrive.errors import InputError
from acdrive.machines import (
    BODSON_DFIM,
    DELORENZO_IM,
    UGALDE_IM_300W,
    CageInductionMachine,
    DoublyFedMachine,
    machine_vector,
    steady_state_currents,
)
from acdrive.plant import AveragedConverter, PrescribedSpeed, RelayCommand, Shaft, ThreePhaseSource
from acdrive.sim import System
from acdrive.sim._reference import simulate_reference

SQRT_3_2 = math.sqrt(1.5)


def cage_drive(machine, shaft, V_pk=100.0, f=50.0, V_dc=310.0):
    im = CageInductionMachine.from_params("im", machine)
    program = VoltageProgram("program", V_pk=V_pk, f=f)
    inverter = AveragedConverter("inverter", V_dc=V_dc)
    wires = [
        (program.out.v_ref, inverter.inp.v_ref),
        (inverter.out.v, im.inp.v_s),
        (shaft.out.w, im.inp.w),
    ]
    if "tau_e" in shaft.INPUTS:
        wires.append((im.out.tau_e, shaft.inp.tau_e))
    return im, System([im, shaft, program, inverter], wires)


# --- wiring -------------------------------------------------------------------------------------
def test_wiring_mistakes_name_both_ends():
    im = CageInductionMachine.from_params("im", DELORENZO_IM)
    shaft = PrescribedSpeed("shaft", w=0.0)
    source = ThreePhaseSource("grid", V_pk=100.0)
    with pytest.raises(InputError, match=r"wire grid.v -> im.w: kind mismatch"):
        System([im, shaft, source], [(source.out.v, im.inp.w)])
    with pytest.raises(
        InputError, match=r"wire shaft.theta -> im.w: unit mismatch \(rad -> rad/s\)"
    ):
        System([im, shaft, source], [(shaft.out.theta, im.inp.w)])
    with pytest.raises(InputError, match=r"im.v_s: input is not wired"):
        System([im, shaft, source], [(shaft.out.w, im.inp.w)])
    with pytest.raises(InputError, match=r"already wired from shaft.w"):
        System([im, shaft, source], [(shaft.out.w, im.inp.w), (shaft.out.w, im.inp.w)])
    with pytest.raises(InputError, match=r"must go from an output to an input"):
        System([im, shaft, source], [(im.inp.v_s, source.out.v)])
    with pytest.raises(InputError, match=r"im.nothing: im has no input nothing"):
        _ = im.inp.nothing
    other = ThreePhaseSource("elsewhere", V_pk=1.0)
    with pytest.raises(InputError, match=r"part elsewhere is not in the system"):
        System([im, shaft], [(other.out.v, im.inp.v_s), (shaft.out.w, im.inp.w)])
    with pytest.raises(InputError, match=r"im: two parts have this name"):
        System([im, CageInductionMachine.from_params("im", DELORENZO_IM)], [])


def test_parameters_are_validated_with_the_part_name():
    with pytest.raises(InputError, match=r"im.R_s: must be > 0"):
        CageInductionMachine("im", R_s=-1.0, R_r=1.0, L_s=1.0, L_r=1.0, L_m=0.9)
    with pytest.raises(InputError, match=r"im.L_m: leakage factor"):
        CageInductionMachine("im", R_s=1.0, R_r=1.0, L_s=1.0, L_r=1.0, L_m=1.0)
    with pytest.raises(InputError, match=r"shaft.J: must be finite"):
        Shaft("shaft", J=float("nan"))


def test_table_parameters_obey_their_declared_rule_at_construction():
    """A rule declared with a table parameter holds for every value of its profile, checked when
    the part is built (issue 19: ThreePhaseSource(V_pk=-11.1) raised nothing)."""
    from acdrive.plant import DCSource, UnbalancedSource

    with pytest.raises(InputError, match=r"^grid.V_pk: must be >= 0, got -11.1$"):
        ThreePhaseSource("grid", V_pk=-11.1)
    with pytest.raises(InputError, match=r"^grid.V_pk: must be >= 0, got -1$"):
        ThreePhaseSource("grid", V_pk=[[0.0, 11.1], [0.5, -1.0]])  # a later point
    with pytest.raises(InputError, match=r"^grid.f: must be > 0, got 0$"):
        ThreePhaseSource("grid", V_pk=11.1, f=0.0)
    with pytest.raises(InputError, match=r"^grid.k_b: must be between 0 and 1, got 1.5$"):
        UnbalancedSource("grid", V_pk=11.1, k_b=1.5)
    with pytest.raises(InputError, match=r"^link.V: must be >= 0"):
        DCSource("link", V=-30.0)
    grid = ThreePhaseSource("grid", V_pk=[[0.0, 11.1], [0.5, 0.0]], f=60.0)  # a collapse to 0
    with pytest.raises(InputError, match=r"^grid.V_pk: must be >= 0"):
        grid.with_params(V_pk=-1.0)
    with pytest.raises(ValueError, match="rule"):
        Layout(Var("z", "V", "a complex value", "complex", "positive"))
    with pytest.raises(InputError, match=r"shaft.load: times must be >= 0 and non-decreasing"):
        Shaft("shaft", J=1.0, load=[[1.0, 0.0], [0.5, 1.0]])
    with pytest.raises(InputError, match=r"inverter.V_dc: must be given"):
        AveragedConverter("inverter")
    with pytest.raises(InputError, match=r"inverter.V_ac: is not declared"):
        AveragedConverter("inverter", V_dc=1.0, V_ac=2.0)


def test_layout_slots_follow_the_declarations():
    layout = Layout(real("a", "V", "first"), real("b", "A", "second"))
    assert (layout.slot("a"), layout.slot("b"), layout.size()) == (0, 1, 2)
    im = CageInductionMachine.from_params("im", DELORENZO_IM)
    assert [c[0] for c in im.OUTPUTS.columns("im.")] == [
        "im.i_s.re",
        "im.i_s.im",
        "im.psi_r.re",
        "im.psi_r.im",
        "im.tau_e",
    ]


# --- the cage induction motor -------------------------------------------------------------------
def equivalent_circuit_torque(p, V_pk, f, w_m):
    """Torque of the per-phase T equivalent circuit (RMS phasors, leakages L_s - L_m, L_r - L_m):
    written independently of the space-vector model."""
    w_e = 2 * math.pi * f
    slip = (w_e - p.n_p * w_m) / w_e
    V = V_pk / math.sqrt(2)
    Z_m = 1j * w_e * p.L_m
    Z_r = p.R_r / slip + 1j * w_e * (p.L_r - p.L_m)
    Z = p.R_s + 1j * w_e * (p.L_s - p.L_m) + Z_m * Z_r / (Z_m + Z_r)
    I_s = V / Z
    I_r = I_s * Z_m / (Z_m + Z_r)
    air_gap_power = 3 * abs(I_r) ** 2 * p.R_r / slip
    return air_gap_power / (w_e / p.n_p)


@pytest.mark.parametrize("speed_hz", [40.0, 48.0, 49.5, 51.0])
def test_cage_im_steady_torque_matches_the_equivalent_circuit(speed_hz):
    V_pk, f = 150.0, 50.0
    shaft = PrescribedSpeed("shaft", w=2 * math.pi * speed_hz)
    im, system = cage_drive(DELORENZO_IM, shaft, V_pk=V_pk, f=f)
    result = system.compile().run(1.5, 1e-4, 4, log=[im.out.tau_e, im.out.i_s], log_every=1)
    last = result.t > 1.3  # ten periods after the transients (rotor time constant 65 ms)
    torque = float(np.mean(result.signal(im.out.tau_e)[last]))
    expected = equivalent_circuit_torque(DELORENZO_IM, V_pk, f, 2 * math.pi * speed_hz)
    # the held (ZOH) voltage differs from the sinusoid by (w T_s)^2/24 ~ 4e-5 in amplitude
    assert torque == pytest.approx(expected, rel=5e-4, abs=1e-6)
    ripple = np.ptp(result.signal(im.out.tau_e)[last])
    assert ripple < 1e-2 * max(abs(expected), 1e-3)


def test_cage_im_direct_start_matches_radau():
    shaft = Shaft("shaft", J=UGALDE_IM_300W.J, B=1e-5, load=[[0.0, 0.0], [0.02, 0.05]])
    im, system = cage_drive(UGALDE_IM_300W, shaft, V_pk=300.0)
    compiled = system.compile()
    log = [im.out.i_s, shaft.out.w]
    fast = compiled.run(0.04, 1e-4, 4, log=log)
    ref = simulate_reference(compiled, 0.04, 1e-4, log=log, rtol=1e-10, atol=1e-12)
    i_fast, i_ref = fast.signal(im.out.i_s), ref.signal(im.out.i_s)
    scale = np.max(np.abs(i_ref))
    assert scale > 0.5  # a real inrush, not a trivial zero
    assert np.max(np.abs(i_fast - i_ref)) < 1e-6 * scale
    w_ref = ref.signal(shaft.out.w)
    assert w_ref[-1] > 10.0  # the shaft accelerates
    assert np.max(np.abs(fast.signal(shaft.out.w) - w_ref)) < 1e-6 * np.max(np.abs(w_ref))


def test_batch_equals_single_runs():
    shaft = Shaft("shaft", J=UGALDE_IM_300W.J)
    im, system = cage_drive(UGALDE_IM_300W, shaft, V_pk=200.0)
    compiled = system.compile()
    variants = [
        {"shaft": {"J": J}, "program": {"V_pk": V}}
        for J, V in [(7e-4, 200.0), (2e-3, 250.0), (5e-4, 150.0)]
    ]
    batch = compiled.run_batch(variants, 0.05, 1e-4, log=[im.out.i_s, shaft.out.w])
    # a dict where the list of variants belongs is named, not an AttributeError
    with pytest.raises(InputError, match=r"^variants: must be a list of dicts"):
        compiled.run_batch(variants[0], 0.05, 1e-4)
    with pytest.raises(InputError, match=r"^variants\[1\]: must be a dict"):
        compiled.run_batch([variants[0], ["shaft", 1.0]], 0.05, 1e-4)
    for changes, result in zip(variants, batch):
        parts = [system.part(name).with_params(**values) for name, values in changes.items()]
        alone = compiled.run(0.05, 1e-4, log=[im.out.i_s, shaft.out.w], parts=parts)
        assert np.array_equal(result.data, alone.data)
    assert not np.array_equal(batch[0].data, batch[1].data)


# --- the DFIM, open loop ------------------------------------------------------------------------
@pytest.mark.slow
def test_dfim_shorted_rotor_inrush_settles_to_the_steady_state_of_bodson_19():
    p = BODSON_DFIM
    grid = ThreePhaseSource("grid", V_pk=11.1, f=60.0)
    dfim = DoublyFedMachine.from_params("dfim", p)
    shaft = PrescribedSpeed("shaft", w=100.0)
    rotor = ComplexProgram("rotor")  # zero: rotor shorted
    relay = RelayCommand("relay")  # closed from t = 0
    wires = [(grid.out.v, dfim.inp.v_s), (rotor.out.v_ref, dfim.inp.v_r),
             (shaft.out.w, dfim.inp.w), (relay.out.closed, dfim.inp.connected)]  # fmt: skip
    system = System([grid, dfim, shaft, rotor, relay], wires)
    result = system.compile().run(1.0, 2e-4, 4, log=[dfim.out.i_s, grid.out.v])
    i_s, v_s = result.signal(dfim.out.i_s), result.signal(grid.out.v)
    # steady state: i_s / v_s constant, equal to (19) with v_r = 0 at this slip
    expected, _ = steady_state_currents(machine_vector(p), 2 * math.pi * 60.0, 100.0, 1.0 + 0j, 0j)
    ratio = i_s[-50:] / v_s[-50:]
    assert np.max(np.abs(ratio - expected)) < 1e-3 * abs(expected)
    assert np.max(np.abs(i_s[:200])) > 1.2 * np.max(np.abs(i_s[-50:]))  # a visible inrush


def test_a_diverging_system_stops_with_the_time_and_the_state():
    from acdrive.errors import SimulationDiverged

    shaft = PrescribedSpeed("shaft", w=0.0)
    im, system = cage_drive(UGALDE_IM_300W, shaft, V_pk=300.0)
    # one explicit RK4 step of 20 ms against electrical modes near -360 1/s and faster: unstable
    with pytest.raises(SimulationDiverged, match=r"im\.(i_s|psi_r)\.(re|im)"):
        system.compile().run(20.0, 0.02, 1, log=[im.out.i_s])


# --- cache keys ---------------------------------------------------------------------------------
_USER_PART = """
from numba import njit
from acdrive.core._parts import ContinuousPart
from acdrive.core._signals import Layout, Var, real

@njit
def level_outputs(t, x, p, y):
    y[0] = {value}

@njit
def level_rhs(t, x, u, p, y, dx):
    pass

class Level(ContinuousPart):
    OUTPUTS = Layout(real("v", "V", "a constant"))
    state_outputs = level_outputs
    rhs = level_rhs
"""


def _user_system(folder, value):
    import importlib.util
    import sys

    path = folder / "user_kernels.py"
    path.write_text(_USER_PART.format(value=value))
    spec = importlib.util.spec_from_file_location("user_kernels", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules["user_kernels"] = module
    spec.loader.exec_module(module)
    return System([module.Level("level")], []).source()


def test_an_edit_of_a_kernel_outside_acdrive_gives_a_new_generated_source(tmp_path):
    """The loop inlines its kernels, so its cache entry must change when a user's kernel file
    changes although the generated calls stay the same."""
    first, same, edited = (_user_system(tmp_path, v) for v in ("1.0", "1.0", "2.0"))
    assert first == same
    assert first != edited
    acdrive_only = System([ThreePhaseSource("grid", V_pk=1.0)], []).source()
    assert "# kernels of" not in acdrive_only
