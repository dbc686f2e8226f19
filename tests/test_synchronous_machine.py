"""The synchronous machine with flux states and a magnetic model (``machines/_synchronous_part``).

* linear magnetics: the same machine as the PM part (Ugalde-Loo et al. (7)-(8), current states),
  run for run, up to rounding (Runge-Kutta commutes with the affine change of state i -> psi);
* the algebraic saturation model of Hinkkanen et al. (2017): the published peak-valued formula
  carried to power-invariant vectors (i = K i_pk(psi / K)), the currents the gradient of the
  stated magnetic energy, and so reciprocal (d i_d / d psi_q = d i_q / d psi_d);
* the energy balance of a run with steps of voltage and a free shaft: electrical input = copper
  loss + mechanical work + change of the magnetic energy, the energy from the closed form;
* the native loop gives numba's bits for both models; parameters against their rules are refused
  by name.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import simpson

from acdrive._frames import K_PEAK
from acdrive.analysis._kernel_jacobian import kernel_jacobian
from acdrive.control import ComplexProgram
from acdrive.control._open_loop import VoltageProgram
from acdrive.errors import InputError
from acdrive.machines import (
    SYRM_6_7KW,
    PermanentMagnetMachine,
    PMSGParams,
    SynchronousMachine,
    SynchronousMachineParams,
)
from acdrive.machines._pmsm import dq_current_ss
from acdrive.machines._synchronous_part import (
    magnetic_currents,
    magnetic_energy,
    synchronous_state_outputs,
)
from acdrive.plant._mechanics import PrescribedSpeed, Shaft
from acdrive.sim import System, _native

#: a small salient PM motor (test values): magnet and saliency both make torque
SERVO = PMSGParams(R_s=0.8, L_d=4e-3, L_q=6e-3, psi_m=0.12, n_p=3)
#: the built-in SyRM with a magnet added (test value), so the algebraic model's magnet shift counts
PM_SYRM = SynchronousMachineParams(**{**vars(SYRM_6_7KW), "psi_m": 0.15})


def linear_from(params: PMSGParams) -> SynchronousMachine:
    return SynchronousMachine("sm", saturation=0, R_s=params.R_s, L_d=params.L_d,
                              L_q=params.L_q, psi_m=params.psi_m, n_p=params.n_p)  # fmt: skip


def open_loop(machine, w, v_re, v_im, method="rk4"):
    """``machine`` at a prescribed speed profile ``w``, fed by a complex voltage program."""
    speed = PrescribedSpeed("speed", w=w)
    source = ComplexProgram("source", re=v_re, im=v_im)
    wires = [(source.out.v_ref, machine.inp.v_s), (speed.out.w, machine.inp.w)]
    return System([machine, speed, source], wires, method=method)


# --- linear magnetics: the PM part's machine --------------------------------------------------
#: voltage steps (stationary frame) and a speed ramp through zero: the run moves every term of (7)
V_RE = [[0.0, 30.0], [0.01, 30.0], [0.01, -20.0], [0.03, -20.0], [0.03, 45.0]]
V_IM = [[0.0, 0.0], [0.015, 0.0], [0.015, 35.0]]
SPEED = [[0.0, -40.0], [0.05, 120.0]]


@pytest.mark.parametrize("method", ["rk4", "rk6"])
def test_linear_model_runs_as_the_pm_part(method):
    """The same voltages and speed into the PM part (current states) and into the synchronous
    machine with linear magnetics (flux states psi = L i + psi_pm): currents, fluxes and torque
    agree to 1e-10 of their largest value over the run."""
    pm = PermanentMagnetMachine.from_params("pm", SERVO)
    sm = linear_from(SERVO)
    outputs = ("i_s", "i_dq", "psi_s", "tau_e", "theta")
    runs = []
    for machine in (pm, sm):
        system = open_loop(machine, SPEED, V_RE, V_IM, method)
        result = system.compile().run(0.05, 1e-4, 4, initial={machine.name: {"theta": 0.3}},
                                      log=[getattr(machine.out, n) for n in outputs])  # fmt: skip
        runs.append({n: result.signal(getattr(machine.out, n)) for n in outputs})
    for name in outputs:
        scale = np.max(np.abs(runs[0][name]))
        assert scale > 0.1, name  # the run moved it
        assert np.max(np.abs(runs[1][name] - runs[0][name])) < 1e-10 * scale, name


# --- the algebraic model: published form, scaling, energy, reciprocity ------------------------
def published_currents(params, psi_d_pk, psi_q_pk):
    """Hinkkanen et al. (2017)'s model in its own (peak-valued) variables, psi_d measured from the
    magnet's flux (peak psi_m)."""
    a = vars(params)
    d = psi_d_pk - params.psi_m
    q = psi_q_pk
    g_d = (a["a_d0"] + a["a_dd"] * abs(d) ** a["S"]
           + a["a_dq"] / (a["V"] + 2) * abs(d) ** a["U"] * abs(q) ** (a["V"] + 2))  # fmt: skip
    g_q = (a["a_q0"] + a["a_qq"] * abs(q) ** a["T"]
           + a["a_dq"] / (a["U"] + 2) * abs(d) ** (a["U"] + 2) * abs(q) ** a["V"])  # fmt: skip
    return g_d * d, g_q * q


#: power-invariant fluxes across and beyond the 6.7-kW SyRM's range (its base flux is 0.45 Wb
#: peak, 0.56 Wb power-invariant), both signs of both axes
GRID = [(d, q) for d in np.linspace(-0.9, 1.1, 9) for q in np.linspace(-0.7, 0.7, 8)]


@pytest.mark.parametrize("params", [SYRM_6_7KW, PM_SYRM], ids=["syrm", "pm-syrm"])
def test_algebraic_currents_are_the_published_model_in_power_invariant_scaling(params):
    """i_pi = K i_pk(psi_pi / K), K = sqrt(3/2), with the published coefficients as given."""
    p = SynchronousMachine.from_params("sm", params).p
    for psi_d, psi_q in GRID:
        i_d, i_q = magnetic_currents(p, psi_d, psi_q)
        i_d_pk, i_q_pk = published_currents(params, psi_d / K_PEAK, psi_q / K_PEAK)
        assert i_d == pytest.approx(K_PEAK * i_d_pk, rel=1e-13, abs=1e-12)
        assert i_q == pytest.approx(K_PEAK * i_q_pk, rel=1e-13, abs=1e-12)


@pytest.mark.parametrize("params", [SYRM_6_7KW, PM_SYRM], ids=["syrm", "pm-syrm"])
def test_currents_are_the_gradient_of_the_magnetic_energy_and_reciprocal(params):
    """Central differences over the grid: dW/dpsi_d = i_d and dW/dpsi_q = i_q (the stated energy is
    the model's), and d i_d / d psi_q = d i_q / d psi_d: the incremental inductance matrix, the
    inverse of [[d i_d/d psi_d, d i_d/d psi_q], [d i_q/d psi_d, d i_q/d psi_q]], is symmetric."""
    part = SynchronousMachine.from_params("sm", params)
    p, h = part.p, 1e-5
    crossed = 0.0
    for psi_d, psi_q in GRID:
        i_d, i_q = magnetic_currents(p, psi_d, psi_q)
        dW_d = (magnetic_energy(part.values, psi_d + h, psi_q)
                - magnetic_energy(part.values, psi_d - h, psi_q)) / (2 * h)  # fmt: skip
        dW_q = (magnetic_energy(part.values, psi_d, psi_q + h)
                - magnetic_energy(part.values, psi_d, psi_q - h)) / (2 * h)  # fmt: skip
        scale = 1.0 + abs(i_d) + abs(i_q)
        assert abs(dW_d - i_d) < 1e-6 * scale and abs(dW_q - i_q) < 1e-6 * scale
        did_dq = (magnetic_currents(p, psi_d, psi_q + h)[0]
                  - magnetic_currents(p, psi_d, psi_q - h)[0]) / (2 * h)  # fmt: skip
        diq_dd = (magnetic_currents(p, psi_d + h, psi_q)[1]
                  - magnetic_currents(p, psi_d - h, psi_q)[1]) / (2 * h)  # fmt: skip
        did_dd = (magnetic_currents(p, psi_d + h, psi_q)[0]
                  - magnetic_currents(p, psi_d - h, psi_q)[0]) / (2 * h)  # fmt: skip
        diq_dq = (magnetic_currents(p, psi_d, psi_q + h)[1]
                  - magnetic_currents(p, psi_d, psi_q - h)[1]) / (2 * h)  # fmt: skip
        crossed = max(crossed, abs(did_dq))
        assert abs(did_dq - diq_dd) < 1e-6 * (abs(did_dd) + abs(diq_dq))
        inductance = np.linalg.inv([[did_dd, did_dq], [diq_dd, diq_dq]])
        assert abs(inductance[0, 1] - inductance[1, 0]) < 1e-6 * np.max(np.abs(inductance))
    assert crossed > 10.0  # the cross-saturation term is present, not a zero on both sides


def test_algebraic_model_with_linear_coefficients_is_the_linear_model():
    """a_dd = a_qq = a_dq = 0, a_d0 = 1/L_d, a_q0 = 1/L_q: the algebraic branch, magnet shift
    included, gives the linear model's currents."""
    linear = linear_from(SERVO)
    algebraic = SynchronousMachine("sm", saturation=1, R_s=SERVO.R_s, n_p=SERVO.n_p,
                                   psi_m=SERVO.psi_m, a_d0=1.0 / SERVO.L_d,
                                   a_q0=1.0 / SERVO.L_q, S=3, T=2, U=1, V=2)  # fmt: skip
    for psi_d, psi_q in GRID:
        expected = magnetic_currents(linear.p, psi_d, psi_q)
        assert magnetic_currents(algebraic.p, psi_d, psi_q) == pytest.approx(expected, rel=1e-12)
        W = magnetic_energy(linear.values, psi_d, psi_q)
        assert magnetic_energy(algebraic.values, psi_d, psi_q) == pytest.approx(W, rel=1e-12)


def energy_at_angle(part, psi_s, theta):
    """W at the rotor angle theta with the stator flux psi_s (stationary frame) held."""
    psi_dq = psi_s * np.exp(-1j * part.values["n_p"] * theta)
    return magnetic_energy(part.values, psi_dq.real, psi_dq.imag)


def test_torque_is_minus_the_energy_derivative_at_constant_stator_flux():
    """tau_e = -dW/dtheta with the stator flux psi_s held (psi_dq = psi_s e^{-j n_p theta}): the
    torque output of the kernel against a central difference of the closed-form energy, at
    points over the grid and rotor angles, for the saturated SyRM and PM-SyRM."""
    for params in (SYRM_6_7KW, PM_SYRM):
        part = SynchronousMachine.from_params("sm", params)
        tau_slot = part.OUTPUTS.slot("tau_e")
        for k, (psi_d, psi_q) in enumerate(GRID):
            theta, h = 0.1 * k, 1e-6
            psi_s = complex(psi_d, psi_q) * np.exp(1j * params.n_p * theta)
            x = part.initial_state(psi_dq=complex(psi_d, psi_q), theta=theta)
            y = np.zeros(part.OUTPUTS.size())
            synchronous_state_outputs(0.0, x, part.p, y)

            W = [energy_at_angle(part, psi_s, angle) for angle in (theta + h, theta - h)]
            torque = -(W[0] - W[1]) / (2.0 * h)
            assert y[tau_slot] == pytest.approx(torque, rel=1e-6, abs=1e-6)


@pytest.mark.parametrize("w_r", [0.0, 150.0, -420.0])
def test_kernel_jacobian_is_the_linear_pm_plant_and_the_saturated_incremental_model(w_r):
    """The Jacobian of the part's kernels (``analysis._kernel_jacobian``), fed from the stationary
    frame, central differences of step 1e-5 (the saturated kernel is not linear): with linear
    magnetics, carried to current coordinates (A_i = L^-1 A_psi L), it is the PM
    current subsystem of Ugalde-Loo et al. (9)-(11) (``dq_current_ss``); with saturation, d i/d psi
    (its C block) is symmetric and A = -R_s d i/d psi - j w_r, the voltage equation linearised."""
    rotate = np.array([[0.0, 1.0], [-1.0, 0.0]])  # -j as a real 2 x 2 gain
    point = {"psi_dq": 0.45 - 0.2j, "theta": 0.7}
    for part in (linear_from(SERVO), SynchronousMachine.from_params("sm", SYRM_6_7KW)):
        e_r = np.exp(1j * part.values["n_p"] * point["theta"])
        jac = kernel_jacobian(part, {**point, "e_r": e_r},
                              {"v_s": (20.0 + 5.0j) * e_r, "w": w_r / part.values["n_p"]},
                              relative_step=1e-5)  # fmt: skip
        m, _, _ = jac.subsystem(("psi_dq",), ("v_s",), ("i_dq",))
        A, C = m["A"], m["C"]
        scale = np.max(np.abs(A))
        assert np.max(np.abs(A - (-part.values["R_s"] * C + w_r * rotate))) < 1e-9 * scale
        if part.values["saturation"] == 0:
            L = np.diag([SERVO.L_d, SERVO.L_q])
            A_i = np.linalg.inv(L) @ A @ L
            expected = dq_current_ss(SERVO, w_r)[0]
            assert np.max(np.abs(A_i - expected)) < 1e-9 * np.max(np.abs(expected))
        else:
            assert abs(C[0, 1]) > 1.0 and abs(C[0, 1] - C[1, 0]) < 1e-7 * np.max(np.abs(C))


# --- energy balance of a run ------------------------------------------------------------------
#: DC voltage steps (stationary frame): the rotor swings towards each new field, so speed and
#: flux both move, and the flux reaches the saturated range (|psi| about 0.6 Wb)
STEPS = [(0.0, 9.0 + 2.0j), (0.12, -3.0 + 8.0j), (0.25, 6.0 - 7.0j)]
END = 0.4


@pytest.mark.parametrize("params", [SYRM_6_7KW, PM_SYRM], ids=["syrm", "pm-syrm"])
def test_energy_balance_of_a_run_closes_with_the_magnetic_energy(params):
    """Integral of Re(v_s conj(i_s)) = integral of R_s |i_s|^2 + integral of tau_e w + W(end) -
    W(start), W the closed-form magnetic energy of the model, each voltage step integrated on its
    own (the currents are smooth between steps): closes to 1e-10 of the electrical input. A torque
    off by 3/2 or an energy in the published (peak-valued) scaling misses by far more."""
    sm = SynchronousMachine.from_params("sm", params)
    shaft = Shaft("shaft", J=params.J, B=0.0)
    re = [[0.0, STEPS[0][1].real]]
    im = [[0.0, STEPS[0][1].imag]]
    for (t, v), (_, before) in zip(STEPS[1:], STEPS[:-1], strict=True):
        re += [[t, before.real], [t, v.real]]
        im += [[t, before.imag], [t, v.imag]]
    source = ComplexProgram("source", re=re, im=im)
    wires = [(source.out.v_ref, sm.inp.v_s), (shaft.out.w, sm.inp.w),
             (sm.out.tau_e, shaft.inp.tau_e)]  # fmt: skip
    system = System([sm, shaft, source], wires)
    result = system.compile().run(END, 2e-5, 2, log=[sm.out.i_s, sm.out.psi_dq, sm.out.tau_e,
                                                     shaft.out.w, source.out.v_ref])  # fmt: skip
    t, i_s = result.t, result.signal(sm.out.i_s)
    tau_e, w = result.signal(sm.out.tau_e), result.signal(shaft.out.w)
    psi = result.signal(sm.out.psi_dq)
    assert np.max(np.abs(psi)) > 0.55 and np.ptp(w) > 5.0  # saturated, and the shaft moved
    e_in = e_cu = e_mech = 0.0
    ends = [start for start, _ in STEPS[1:]] + [END]
    for (start, v), end in zip(STEPS, ends, strict=True):
        inside = (t >= start - 1e-12) & (t <= end + 1e-12)
        x = t[inside]
        e_in += (v * np.conj(simpson(i_s[inside], x=x))).real
        e_cu += simpson(params.R_s * np.abs(i_s[inside]) ** 2, x=x)
        e_mech += simpson(tau_e[inside] * w[inside], x=x)
    W = magnetic_energy(sm.values, psi.real, psi.imag)
    residual = e_in - e_cu - e_mech - (W[-1] - W[0])
    assert abs(e_mech) > 1e-3 * e_in and abs(W[-1] - W[0]) > 1e-3 * e_in
    assert abs(residual) < 1e-10 * e_in, (residual, e_in, e_cu, e_mech, W[-1] - W[0])


# --- native loop, bit for bit -------------------------------------------------------------------
@pytest.mark.skipif(_native.compiler() is None, reason="no C compiler on this machine")
@pytest.mark.parametrize("params", [SERVO, SYRM_6_7KW, PM_SYRM], ids=["linear", "syrm", "pm-syrm"])
def test_native_loop_equals_numba_bit_for_bit(params, monkeypatch):
    """An open-loop V/f program into the machine on a free shaft: the C generated from the
    part's kernels runs the loop to numba's bits, for both magnetic models."""
    if isinstance(params, PMSGParams):
        sm, J = linear_from(params), 2e-4
    else:
        sm, J = SynchronousMachine.from_params("sm", params), params.J
    shaft = Shaft("shaft", J=J, B=1e-4)
    program = VoltageProgram("program", V_pk=[[0.0, 5.0], [0.05, 60.0]],
                             f=[[0.0, 1.0], [0.05, 20.0]])  # fmt: skip
    wires = [(program.out.v_ref, sm.inp.v_s), (shaft.out.w, sm.inp.w),
             (sm.out.tau_e, shaft.inp.tau_e)]  # fmt: skip
    system = System([sm, shaft, program], wires)
    runs = {}
    for tier in ("native", "specialised"):
        monkeypatch.setenv("ACDRIVE_LOOP_TIER", tier)
        compiled = system.compile()
        assert compiled.tier == tier
        runs[tier] = compiled.run(0.06, 1e-4, 2, log=[sm.out.i_dq, sm.out.psi_dq, sm.out.tau_e])
    assert np.max(np.abs(runs["native"].signal(sm.out.i_dq))) > 1.0
    assert np.array_equal(runs["native"].data, runs["specialised"].data)


# --- parameters ---------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"saturation": 0}, r"sm\.L_d: the linear model \(saturation = 0\) needs L_d > 0"),
        ({"saturation": 2}, r"sm\.saturation: must be 0 or 1"),
        ({"a_q0": 0.0}, r"sm\.a_q0: the algebraic model \(saturation = 1\) needs a_q0 > 0"),
        ({"a_dd": -1.0}, r"sm\.a_dd: must be >= 0"),
        ({"S": 1.5}, r"sm\.S: must be an integer >= 0"),
        ({"T": -1}, r"sm\.T: must be an integer >= 0"),
        ({"V": 16}, r"sm\.V: the exponents S, T, U, V of the algebraic model must be at most 15"),
        ({"psi_m": float("nan")}, r"sm\.psi_m"),
    ],
)
def test_bad_parameters_are_refused_by_name(changes, message):
    values = {v.name: getattr(SYRM_6_7KW, v.name) for v in SynchronousMachine.PARAMS}
    with pytest.raises(InputError, match=message):
        SynchronousMachine("sm", **{**values, **changes})


def test_the_record_is_validated_as_the_part_and_the_built_in_is_the_published_machine():
    with pytest.raises(InputError, match=r"^L_q: the linear model \(saturation = 0\) needs L_q"):
        SynchronousMachineParams(R_s=0.5, n_p=2, L_d=0.04)
    with pytest.raises(InputError, match=r"^psi_m: torque needs a magnet or saliency"):
        SynchronousMachineParams(R_s=0.5, n_p=2, L_d=0.04, L_q=0.04)
    assert SYRM_6_7KW.R_s == 0.54 and SYRM_6_7KW.n_p == 2 and SYRM_6_7KW.saturation == 1
    coefficients = ("a_d0", "a_dd", "S", "a_q0", "a_qq", "T", "a_dq", "U", "V")
    assert tuple(getattr(SYRM_6_7KW, n) for n in coefficients) == (
        17.4, 373.0, 5, 52.1, 658.0, 1, 1120.0, 1, 0)  # fmt: skip


# --- FMUs ---------------------------------------------------------------------------------------
def assert_fmu_pair_runs_as_the_loop(system, machine, shaft, T_s, duration, folder, what):
    """The system's sampled part as a controller FMU and its ``machine`` with its ``shaft`` as a
    plant FMU (the C generated from the kernels), stepped by a Gauss-Seidel master: the stator
    current and the speed of the loop's run to 1e-9 of their peaks (``what`` names the plant)."""
    from fmpy.validation import validate_fmu

    from acdrive.export import to_c
    from acdrive.export._fmu import build_fmu, controller_model, plant_model
    from acdrive.export._fmu_check import _closed_loop
    from acdrive.sim._ccode._plant_source import to_plant_c

    native = system.compile().run(duration, T_s, 4, log=[machine.out.i_s, shaft.out.w])
    export = to_c(system, T_s, name=f"{machine.name}_controller", open_loop=True)
    plant_export = to_plant_c(system, T_s, 4, name=f"{machine.name}_plant")
    models = {
        "controller": controller_model(export, T_s, duration, "V/f program"),
        "plant": plant_model(plant_export, system, None, T_s, duration, what),
    }
    paths = {k: build_fmu(m, folder / f"{m.identifier}.fmu") for k, m in models.items()}
    assert all(validate_fmu(str(p)) == [] for p in paths.values())
    fmu = _closed_loop(paths, round(duration / T_s), T_s)
    i_s, w = native.signal(machine.out.i_s), native.signal(shaft.out.w)
    for name, reference in ((f"{machine.name}.i_s.re", i_s.real),
                            (f"{machine.name}.i_s.im", i_s.imag), ("shaft.w", w)):  # fmt: skip
        peak = np.max(np.abs(reference))
        assert peak > 0.5, name
        assert np.max(np.abs(fmu[name] - reference)) <= 1e-9 * peak, name


@pytest.mark.slow
@pytest.mark.skipif(_native.compiler() is None, reason="no C compiler on this machine")
def test_the_saturated_syrm_runs_in_fmus_as_in_the_loop(monkeypatch, tmp_path):
    """The V/f program as a controller FMU and the saturated SyRM with its shaft as a plant FMU,
    the C generated from the kernels, stepped by a Gauss-Seidel master: the loop's run to 1e-9."""
    T_s, duration = 1e-4, 0.08
    monkeypatch.setenv("ACDRIVE_LOOP_TIER", "native")
    syrm = SynchronousMachine.from_params("syrm", SYRM_6_7KW)
    shaft = Shaft("shaft", J=SYRM_6_7KW.J, B=0.01)
    program = VoltageProgram("program", V_pk=[[0.0, 5.0], [0.08, 60.0]],
                             f=[[0.0, 1.0], [0.08, 20.0]])  # fmt: skip
    wires = [(program.out.v_ref, syrm.inp.v_s), (shaft.out.w, syrm.inp.w),
             (syrm.out.tau_e, shaft.inp.tau_e)]  # fmt: skip
    system = System([program, syrm, shaft], wires)
    assert_fmu_pair_runs_as_the_loop(system, syrm, shaft, T_s, duration, tmp_path,
                                     "SyRM on a shaft")  # fmt: skip
