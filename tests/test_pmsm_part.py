"""The PMSM/PMSG part (``machines/_pmsm_part.py``, Ugalde-Loo et al. (7)-(8)).

* its linearised current subsystem at a fixed speed is ``machines.pmsm.dq_current_ss`` (9)-(11):
  ``test_kernel_jacobian.py``, with the other machines;
* its currents agree with a Radau solution of (7) written here in the paper's own variables
  (amplitude-invariant Park transform of the phase voltages, the paper's psi_m), which also
  checks the power-invariant scaling psi_pm = sqrt(3/2) psi_m; RK4 converges with order 4;
* power balance Re(v_s conj(i_s)) = R_s |i_s|^2 + dW/dt + tau_e w, at every state and over a
  run on a ``Shaft`` (the rotor aligning with a DC stator field: the motor-convention sign).
"""

import math

import numpy as np
import pytest
from scipy.integrate import simpson, solve_ivp

from acdrive._frames import K_PEAK, complex_to_abc
from acdrive.control import ComplexProgram
from acdrive.errors import InputError
from acdrive.machines import PermanentMagnetMachine
from acdrive.machines._pmsm import PMSG_2MW, PMSGParams
from acdrive.plant._mechanics import PrescribedSpeed, Shaft, brake_torque, load_torque
from acdrive.sim import System

#: generator speed of PMSG_2MW at its rated 50 Hz (n_P = 2) [rad/s]
W_RATED = 2.0 * math.pi * 50.0 / PMSG_2MW.n_p
#: PMSG_2MW made salient (L_q = 1.6 L_d, test values) so the (L_d - L_q) terms of (7)-(8) count
SALIENT = PMSGParams(R_s=PMSG_2MW.R_s, L_d=PMSG_2MW.L_d, L_q=1.6 * PMSG_2MW.L_d,
                     psi_m=PMSG_2MW.psi_m, n_p=PMSG_2MW.n_p)  # fmt: skip
MACHINES = {"pmsg-2mw": PMSG_2MW, "salient": SALIENT}


def at_speed(params, w=0.0, v_re=0.0, v_im=0.0):
    """The machine at a prescribed speed, fed by a complex voltage program (tables or numbers)."""
    pm = PermanentMagnetMachine.from_params("pm", params)
    speed = PrescribedSpeed("speed", w=w)
    source = ComplexProgram("source", re=v_re, im=v_im)
    wires = [(source.out.v_ref, pm.inp.v_s), (speed.out.w, pm.inp.w)]
    return pm, source, System([pm, speed, source], wires)


def state_slot(system, part, name):
    return system.slots[part.name].x[0] + part.STATES.slot(name)


# --- parameters and conventions ----------------------------------------------------------------
def test_parameters_follow_pmsg_params_and_are_validated():
    pm = PermanentMagnetMachine.from_params("pm", PMSG_2MW)
    assert pm.values == {"R_s": 4.523e-3, "L_d": 322e-6, "L_q": 322e-6, "psi_m": 1.79, "n_p": 2}
    with pytest.raises(InputError, match=r"pm.L_q: must be > 0"):
        PermanentMagnetMachine("pm", R_s=1.0, L_d=1e-3, L_q=0.0, psi_m=0.1)
    with pytest.raises(InputError, match=r"pm.n_p: must be a positive integer"):
        PermanentMagnetMachine("pm", R_s=1.0, L_d=1e-3, L_q=1e-3, psi_m=0.1, n_p=1.5)
    # an initial rotor angle sets the rotor phasor with it
    x = pm.initial_state(theta=0.3)
    e_r = complex(x[pm.STATES.slot("e_r")], x[pm.STATES.slot("e_r") + 1])
    assert e_r == pytest.approx(np.exp(2j * 0.3), abs=1e-15)


# --- (a) Radau solution of (7) in the paper's variables ---------------------------------------
def paper_phase_currents(params, w_gen, theta_e0, pieces, t_out):
    """Phase currents of (7) as printed, in the paper's variables, by Radau (rtol 1e-10).

    The paper's dq quantities are amplitude-invariant (the 3/2 of (8)): x_d = (2/3) sum_k x_k
    cos(theta_e - k 2 pi / 3), x_q = -(2/3) sum_k x_k sin(theta_e - k 2 pi / 3), inverse
    x_k = x_d cos(theta_e - k 2 pi / 3) - x_q sin(theta_e - k 2 pi / 3), with the d axis at
    theta_e = theta_e0 + n_P w_gen t from phase a. ``pieces`` is a list of (start time, phase
    voltages (a, b, c)), each held until the next start."""
    R, L_d, L_q, psi_m, w_r = params.R_s, params.L_d, params.L_q, params.psi_m, params.n_p * w_gen
    shifts = np.array([0.0, -2.0 * np.pi / 3.0, 2.0 * np.pi / 3.0])

    def rhs(t, x, v_abc):
        angles = theta_e0 + w_r * t + shifts
        v_d = 2.0 / 3.0 * np.dot(v_abc, np.cos(angles))
        v_q = -2.0 / 3.0 * np.dot(v_abc, np.sin(angles))
        i_d, i_q = x
        return [v_d / L_d - R / L_d * i_d + L_q / L_d * w_r * i_q,
                v_q / L_q - R / L_q * i_q - L_d / L_q * w_r * i_d - psi_m * w_r / L_q]  # fmt: skip

    x = np.zeros(2)
    out = np.zeros((t_out.size, 3))
    ends = [start for start, _ in pieces[1:]] + [t_out[-1]]
    for (start, v_abc), end in zip(pieces, ends, strict=True):
        sol = solve_ivp(rhs, (start, end), x, method="Radau", rtol=1e-10, atol=1e-7,
                        dense_output=True, args=(np.asarray(v_abc, dtype=float),))  # fmt: skip
        assert sol.success, sol.message
        inside = (t_out >= start) & (t_out <= end)
        i_d, i_q = sol.sol(t_out[inside])
        angles = theta_e0 + w_r * t_out[inside][:, None] + shifts
        out[inside] = i_d[:, None] * np.cos(angles) - i_q[:, None] * np.sin(angles)
        x = sol.y[:, -1]
    return out


STEP_T, STEP_V, THETA0 = 0.01, 40.0 * np.exp(0.6j), 0.4  # s, V (stationary frame), rad


def part_phase_currents(params, w_gen, sample_time, substeps, duration=0.1):
    """The part's stator current as phase currents: stator shorted (v_s = 0, the magnet drives a
    short-circuit current from zero) until STEP_T, then a stationary-frame voltage step."""
    pm, _, system = at_speed(params, w=w_gen,
                             v_re=[[0.0, 0.0], [STEP_T, 0.0], [STEP_T, STEP_V.real]],
                             v_im=[[0.0, 0.0], [STEP_T, 0.0], [STEP_T, STEP_V.imag]])  # fmt: skip
    result = system.compile().run(duration, sample_time, substeps, initial={"pm": {"theta": THETA0}},
                                  log=[pm.out.i_s])  # fmt: skip
    return result.t, np.column_stack(complex_to_abc(result.signal(pm.out.i_s)))


def reference_for(params, w_gen, t):
    pieces = [(0.0, (0.0, 0.0, 0.0)), (STEP_T, complex_to_abc(STEP_V))]
    return paper_phase_currents(params, w_gen, params.n_p * THETA0, pieces, t)


@pytest.mark.slow
@pytest.mark.parametrize("name", MACHINES)
def test_currents_match_radau_of_the_paper_equations(name):
    params, w_gen = MACHINES[name], 0.8 * W_RATED
    t, i_abc = part_phase_currents(params, w_gen, 1e-4, 4)
    ref = reference_for(params, w_gen, t)
    scale = np.max(np.abs(ref))
    assert scale > 1e3  # kiloamperes of short-circuit and step current, not a trivial zero
    error = np.max(np.abs(i_abc - ref)) / scale
    assert error < 1e-8, error


def test_rk4_converges_with_order_4():
    """Halving the RK4 step (substeps 1, 2, 4, 8 per 1 ms sample; the input is constant over each
    sample, so the step alone sets the error) divides the error by 16."""
    params, w_gen = SALIENT, 0.8 * W_RATED
    errors = []
    for substeps in (1, 2, 4, 8):
        t, i_abc = part_phase_currents(params, w_gen, 1e-3, substeps)
        ref = reference_for(params, w_gen, t)
        errors.append(np.max(np.abs(i_abc - ref)) / np.max(np.abs(ref)))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert errors[-1] > 1e-8  # well above the reference's own error
    assert np.all((orders > 3.7) & (orders < 4.3)), (errors, orders)


# --- (b) power balance ---------------------------------------------------------------------------
@pytest.mark.parametrize("name", MACHINES)
def test_power_balance_at_every_state(name):
    """Re(v_s conj(i_s)) = R_s |i_s|^2 + d/dt (L_d i_d^2 + L_q i_q^2)/2 + tau_e w, from the compiled
    outputs and right-hand side at random states, inputs, speeds and rotor angles; the outputs
    i_s, psi_s and tau_e = n_p Im(conj(psi_s) i_s) agree with the states."""
    params = MACHINES[name]
    pm, source, system = at_speed(params)
    compiled = system.compile()
    speed = system.part("speed")
    rng = np.random.default_rng(7)
    i_at, v_at = state_slot(system, pm, "i_dq"), system.output_slot(source.out.v_ref)
    worst = 0.0
    for _ in range(200):
        w = rng.uniform(-1.5, 1.5) * W_RATED
        theta = rng.uniform(-10.0, 10.0)
        X, _ = system.pack_initial({"pm": {"theta": theta}})
        i_dq = complex(*rng.normal(0.0, 3000.0, 2))
        v_s = complex(*rng.normal(0.0, 500.0, 2))
        X[i_at], X[i_at + 1] = i_dq.real, i_dq.imag
        held = np.zeros(system.sizes["y"])
        held[v_at], held[v_at + 1] = v_s.real, v_s.imag
        Y, dX = compiled.evaluate(0.0, X, held, parts=[speed.with_params(w=w)])
        i_s, tau_e = compiled.output(Y, pm.out.i_s), compiled.output(Y, pm.out.tau_e)
        e_r = np.exp(1j * params.n_p * theta)
        assert abs(i_s - i_dq * e_r) < 1e-12 * abs(i_dq)
        # the flux output and the torque as n_p Im(conj(psi_s) i_s), in any frame
        psi_dq = params.L_d * i_dq.real + K_PEAK * params.psi_m + 1j * params.L_q * i_dq.imag
        psi_s = compiled.output(Y, pm.out.psi_s)
        assert abs(psi_s - psi_dq * e_r) < 1e-12 * abs(psi_dq)
        assert tau_e == pytest.approx(params.n_p * (np.conj(psi_s) * i_s).imag, rel=1e-9)
        p_in = (v_s * np.conj(i_s)).real
        copper = params.R_s * abs(i_s) ** 2
        dW = params.L_d * i_dq.real * dX[i_at] + params.L_q * i_dq.imag * dX[i_at + 1]
        mechanical = tau_e * w
        residual = p_in - copper - dW - mechanical
        worst = max(worst, abs(residual) / (abs(p_in) + copper + abs(dW) + abs(mechanical)))
    assert worst < 1e-13, worst


#: a small salient motor (test values) on a shaft with friction and a brake
SERVO = PMSGParams(R_s=0.8, L_d=4e-3, L_q=6e-3, psi_m=0.12, n_p=3)
SERVO_SHAFT = {"J": 2e-4, "B": 1e-4, "tau_c": 2e-3, "brake": [[0.0, 0.0], [0.1, 0.0], [0.15, 5e-3]]}


@pytest.mark.slow
def test_rotor_aligns_with_a_dc_field_and_energy_balances():
    """A DC stator voltage v_s = V e^{j phi} drives i_s = v_s / R_s at rest; with the motoring
    torque of (8) the rotor's d axis settles on the current, n_p theta = phi (mod 2 pi) (with the
    opposite sign it would settle at phi + pi). Over the run the electrical input equals copper
    loss + field energy + kinetic energy + friction and brake dissipation: the mechanical work
    tau_e w is resolved to 1e-7 of itself, so a torque off by a sign or a factor 3/2 fails."""
    phi, V = 0.9, 20.0
    v_dc = complex(V * math.cos(phi), V * math.sin(phi))
    pm = PermanentMagnetMachine.from_params("pm", SERVO)
    shaft = Shaft("shaft", **SERVO_SHAFT)
    source = ComplexProgram("source", re=v_dc.real, im=v_dc.imag)
    wires = [(source.out.v_ref, pm.inp.v_s), (shaft.out.w, pm.inp.w),
             (pm.out.tau_e, shaft.inp.tau_e)]  # fmt: skip
    system = System([pm, shaft, source], wires)
    log = [pm.out.i_s, pm.out.i_dq, pm.out.tau_e, pm.out.theta, shaft.out.w, source.out.v_ref]
    result = system.compile().run(0.4, 2e-5, 4, log=log)
    i_s, i_dq, tau_e = (result.signal(pm.out.i_s), result.signal(pm.out.i_dq),
                        result.signal(pm.out.tau_e))  # fmt: skip
    w, t = result.signal(shaft.out.w), result.t
    # alignment: at rest with i_s = v_s / R_s along the d axis
    settled = np.angle(np.exp(1j * (SERVO.n_p * result.signal(pm.out.theta)[-1] - phi)))
    assert abs(settled) < 1e-4 and abs(w[-1]) < 1e-3
    assert abs(i_s[-1] - v_dc / SERVO.R_s) < 1e-3 * V / SERVO.R_s
    assert np.max(np.abs(w)) > 5.0  # it swung on its way there
    # energy over the run (Simpson's rule: the voltage is constant, the signals smooth)
    assert np.all(result.signal(source.out.v_ref) == v_dc)
    e_in = (v_dc * np.conj(simpson(i_s, x=t))).real
    e_cu = simpson(SERVO.R_s * np.abs(i_s) ** 2, x=t)
    W = 0.5 * (SERVO.L_d * i_dq.real**2 + SERVO.L_q * i_dq.imag**2)
    kinetic = 0.5 * SERVO_SHAFT["J"] * w**2
    drag = np.array([(load_torque(shaft.p, wk, tk) + brake_torque(shaft.p, wk, tk)) * wk
                     for wk, tk in zip(w, t, strict=True)])  # fmt: skip
    e_drag = simpson(drag, x=t)
    e_mech = simpson(tau_e * w, x=t)
    electrical = e_in - e_cu - (W[-1] - W[0]) - e_mech
    mechanical = e_mech - (kinetic[-1] - kinetic[0]) - e_drag
    # measured 3.5e-9 and 6.8e-9 of the mechanical work (16x smaller at 10 us: Simpson's order)
    assert abs(electrical) < 1e-7 * e_mech, electrical / e_mech
    assert abs(mechanical) < 1e-7 * e_mech, mechanical / e_mech
    assert e_drag > 0.0 and e_mech > 0.0
