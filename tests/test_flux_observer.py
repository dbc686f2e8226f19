"""The reduced-order flux observer with speed and position adaptation
(``control.SynchronousFluxObserver``, Hinkkanen et al. 2018): with exact parameters it finds the
rotor angle and speed of acdrive's own PM machine run open loop, its linearised error dynamics
have the designed poles under its forward-Euler discretisation, its C equals its kernel, and bad
design inputs are refused by name.

The machine is the 2.2-kW interior PM machine of the catalog (salient: L_d != L_q, so the
saliency term of the decoupling gain (G1) matters). The design is alpha_f = 100 rad/s,
alpha_w = 40 rad/s, zeta_inf = 0.5, so the lowest speed the observer is designed for is
|w| = alpha_f = 100 rad/s electrical (module docstring of ``control._flux_observer``).
"""

from __future__ import annotations

import math
import shutil

import numpy as np
import pytest


from acdrive._frames import K_PEAK
from acdrive._jit import jit
from acdrive.control import ComputationDelay, SynchronousFluxObserver
from acdrive.control._flux_observer import flux_observer_step, flux_poles, speed_poles
from acdrive.core import Layout, SampledPart, cplx, real
from acdrive.errors import InputError
from acdrive.machines import PermanentMagnetMachine
from acdrive.machines._pm_catalog import IPMSM_2KW2 as MACHINE
from acdrive.plant import AveragedConverter, PrescribedSpeed
from acdrive.sim import System

T_S = 1e-4
ALPHA_F, ALPHA_W, ZETA_INF = 100.0, 40.0, 0.5
W_MAX = 4000.0
#: the operating current, rotor coordinates (a motoring point with some flux weakening)
I_DQ = complex(-2.0, 4.0)
#: the stated initial estimation errors: angle (electrical rad) and electrical speed (rad/s)
ANGLE_ERROR, SPEED_ERROR = 0.5, 10.0


def _observer(**values):
    design = {"alpha_f": ALPHA_F, "alpha_w": ALPHA_W, "zeta_inf": ZETA_INF, "w_max": W_MAX}
    return SynchronousFluxObserver.from_params("obs", MACHINE, **{**design, **values})


def _operating_point(w_r):
    """Flux and voltage of the machine in rotor coordinates at the current I_DQ and electrical
    speed w_r in steady state (Ugalde-Loo (7) with d/dt = 0)."""
    psi = complex(MACHINE.L_d * I_DQ.real + K_PEAK * MACHINE.psi_m, MACHINE.L_q * I_DQ.imag)
    return psi, MACHINE.R_s * I_DQ + 1j * w_r * psi


# --- an open-loop voltage program: v = v_dq e^{j w_r t} ------------------------------------
PROGRAM_PARAMS = Layout(
    real("w_r", "rad/s", "electrical frequency of the voltage"),
    cplx("v_dq", "V", "voltage in coordinates turning at w_r from angle 0"),
)
PROGRAM_OUTPUTS = Layout(cplx("v_ref", "V", "voltage command, stationary frame"))


@jit
def rotating_voltage_step(t, T_s, u, p, s, y):
    angle = p[0] * t
    v = complex(p[1], p[2]) * complex(np.cos(angle), np.sin(angle))
    y[0], y[1] = v.real, v.imag
    return 0


class RotatingVoltage(SampledPart):
    """The command v_dq e^{j w_r t} at each sample."""

    PARAMS, OUTPUTS = PROGRAM_PARAMS, PROGRAM_OUTPUTS
    step = rotating_voltage_step


def _open_loop_system(w_r, **design):
    """The PM machine at the constant electrical speed w_r (a prescribed shaft speed), fed by an
    averaged converter with the voltage of the operating point; the observer reads the sampled
    current and, through one sample of delay, the command the converter applied over the last
    sample."""
    _, v_dq = _operating_point(w_r)
    program = RotatingVoltage("program", w_r=w_r, v_dq=v_dq)
    converter = AveragedConverter("converter", V_dc=1000.0)
    machine = PermanentMagnetMachine.from_params("pm", MACHINE)
    rotor = PrescribedSpeed("rotor", w=w_r / MACHINE.n_p)
    delay = ComputationDelay("delay")
    observer = _observer(**design)
    wires = [(program.out.v_ref, converter.inp.v_ref), (converter.out.v, machine.inp.v_s),
             (rotor.out.w, machine.inp.w), (program.out.v_ref, delay.inp.x),
             (delay.out.x, observer.inp.v_s), (machine.out.i_s, observer.inp.i_s)]  # fmt: skip
    parts = [program, converter, machine, rotor, delay, observer]
    return System(parts, wires), machine, observer


def _slowest_designed_rate(w_r):
    """The smallest distance from the imaginary axis among the designed poles (P1), (P2)."""
    poles = np.concatenate([flux_poles(ALPHA_F, ZETA_INF, w_r), speed_poles(ALPHA_W)])
    return float(np.min(-poles.real))


@pytest.mark.parametrize(
    ("w_r", "angle_error", "speed_error"),
    [(300.0, ANGLE_ERROR, SPEED_ERROR), (1000.0, ANGLE_ERROR, SPEED_ERROR),
     (-300.0, ANGLE_ERROR, SPEED_ERROR), (100.0, 0.2, 3.0)],
)  # fmt: skip
def test_the_observer_finds_angle_and_speed_of_the_machine_run_open_loop(
    w_r, angle_error, speed_error
):
    """From an angle error of 0.5 rad and a speed error of 10 rad/s (at the lowest designed
    speed, 100 rad/s, from 0.2 rad and 3 rad/s: from 0.5 rad it settles on a wrong equilibrium
    there, a limit of the region of attraction that the guide states), the estimates reach the
    true angle within 0.01 rad and the true speed within 0.5 rad/s after 12 / r seconds, r the
    slowest designed decay rate (at 100 rad/s the flux pole -sigma + sqrt(sigma^2 - w^2) =
    -38.2 rad/s, elsewhere the double speed pole -40 rad/s): the double pole leaves
    (1 + 12) e^-12 = 8e-5 of an initial error; the bounds leave room for the nonlinear start and
    the ripple of the sampled current. Before that time the angle error is still above 0.01 rad
    (the convergence is the observer's work, not the start's)."""
    system, machine, observer = _open_loop_system(w_r)
    t_converged = 12.0 / _slowest_designed_rate(w_r)
    initial = {"pm": {"i_dq": I_DQ},
               "obs": {"theta": -angle_error, "w": w_r - speed_error}}  # fmt: skip
    log = [machine.out.theta, observer.out.theta, observer.out.w]
    result = system.compile().run(1.1 * t_converged, T_S, 4, initial=initial, log=log)
    t = result.t
    true_angle = MACHINE.n_p * result.signal(machine.out.theta)
    angle_error = np.angle(np.exp(1j * (true_angle - result.signal(observer.out.theta))))
    speed_error = w_r - result.signal(observer.out.w)
    late = t >= t_converged
    assert np.max(np.abs(angle_error[late])) < 0.01
    assert np.max(np.abs(speed_error[late])) < 0.5
    assert np.max(np.abs(angle_error[t < 0.25 * t_converged])) > 0.01
    estimate = result.signal(observer.out.theta)
    assert np.all(estimate > -math.pi) and np.all(estimate <= math.pi)  # wrapped to (-pi, pi]


def _error_map(w_r, observer, errors):
    """One sample of the observer against an exact machine at constant electrical speed w_r:
    estimation errors (flux error in estimated coordinates, d and q; angle error; speed error)
    at sample k -> the same at sample k + 1.

    The machine is in steady state at the current I_DQ: its current at k is I_DQ e^{j theta_k},
    the voltage over the sample is the one whose mean in rotor coordinates is v_dq (what the
    observer's mean-voltage transform inverts exactly). The observer's kept terms are first set
    from sample k by a step with T_s = 0 (which advances nothing)."""
    psi, v_dq = _operating_point(w_r)
    d_psi, d_theta, d_w = complex(errors[0], errors[1]), errors[2], errors[3]
    theta_k = 0.3
    theta_next = theta_k + w_r * T_S
    s = observer.initial_state(theta=theta_k - d_theta, w=w_r - d_w,
                               psi=np.exp(1j * d_theta) * psi - d_psi)  # fmt: skip
    y = np.zeros(16)
    i_k = I_DQ * np.exp(1j * theta_k)
    flux_observer_step(0.0, 0.0, np.array([i_k.real, i_k.imag, 0.0, 0.0]), observer.p, s, y)
    x = 0.5 * w_r * T_S
    v = v_dq * np.exp(1j * (theta_k + x)) * x / math.sin(x)
    i_next = I_DQ * np.exp(1j * theta_next)
    u = np.array([i_next.real, i_next.imag, v.real, v.imag])
    flux_observer_step(T_S, T_S, u, observer.p, s, y)
    angle_error = float(np.angle(np.exp(1j * (theta_next - s[2]))))
    flux_error = np.exp(1j * angle_error) * psi - complex(s[0], s[1])
    return np.array([flux_error.real, flux_error.imag, angle_error, w_r - s[3]])


@pytest.mark.parametrize("w_r", [100.0, 300.0, 1000.0, 3000.0])
def test_the_linearised_error_dynamics_have_the_designed_poles(w_r):
    """The Jacobian of the sample-to-sample error map (central differences) has the eigenvalues
    z = 1 + s T_s of the designed poles s of (P1) and (P2): forward Euler's map.

    Tolerance: each eigenvalue within 10 % of |s| T_s of its designed value. The discrete map is
    I + T_s A up to terms of order (|s| T_s)^2 (the exact mean voltage, the angle advanced by
    w_c T_s inside the step), which move a simple eigenvalue by that order and split the
    double speed pole by about its square root; 10 % of |s| T_s holds both at these speeds
    (|s| T_s <= 0.3) and is tighter than the exact map's difference e^{s T_s} - (1 + s T_s) =
    (s T_s)^2 / 2 for the flux poles at 3000 rad/s, so the test tells the two maps apart there."""
    observer = _observer()
    steps = np.array([1e-7, 1e-7, 1e-7, 1e-4])
    columns = []
    for k in range(4):
        h = np.zeros(4)
        h[k] = steps[k]
        difference = _error_map(w_r, observer, h) - _error_map(w_r, observer, -h)
        columns.append(difference / (2 * steps[k]))
    eigenvalues = list(np.linalg.eigvals(np.column_stack(columns)))
    designed = np.concatenate([flux_poles(ALPHA_F, ZETA_INF, w_r), speed_poles(ALPHA_W)])
    for s in designed:
        z = 1.0 + s * T_S
        nearest = min(eigenvalues, key=lambda e: abs(e - z))
        eigenvalues.remove(nearest)
        assert abs(nearest - z) <= 0.1 * abs(s) * T_S, (s, nearest, z)
        if w_r == 3000.0 and abs(s) > 1000.0:
            assert abs(nearest - np.exp(s * T_S)) > 0.1 * abs(s) * T_S


@pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc is not installed")
def test_a_system_with_the_observer_runs_natively_equal_to_numba(monkeypatch):
    """Its C is generated from its kernel: the open-loop system runs on the native tier with
    the same bits as numba's specialised loop."""
    system, machine, observer = _open_loop_system(300.0)
    initial = {"pm": {"i_dq": I_DQ}, "obs": {"theta": -ANGLE_ERROR, "w": 300.0 - SPEED_ERROR}}
    results = {}
    for tier in ("native", "specialised"):
        monkeypatch.setenv("ACDRIVE_LOOP_TIER", tier)
        compiled = system.compile()
        assert compiled.tier == tier
        results[tier] = compiled.run(0.02, T_S, 4, initial=initial)
    assert np.array_equal(results["native"].data, results["specialised"].data)
    assert np.array_equal(results["native"].final_state, results["specialised"].final_state)


@pytest.mark.parametrize(
    ("field", "value"),
    [("alpha_f", 0.0), ("alpha_w", -1.0), ("L_d", 0.0), ("L_q", -1e-3), ("R_s", 0.0),
     ("n_p", 0.0), ("zeta_inf", -0.1), ("w_max", 0.0), ("psi_m", -0.1)],
)  # fmt: skip
def test_bad_design_inputs_are_refused_by_name(field, value):
    with pytest.raises(InputError, match=rf"obs\.{field}"):
        _observer(**{field: value})


def test_a_machine_without_magnet_and_saliency_is_refused():
    with pytest.raises(InputError, match="psi_m > 0 or L_d != L_q"):
        _observer(psi_m=0.0, L_q=MACHINE.L_d)


def test_a_sample_time_for_which_forward_euler_is_unstable_is_refused():
    """w_max^2 T_s < 2 sigma (module docstring): at w_max = 4000 rad/s and sigma = 100 + 0.5 *
    4000 = 2100 rad/s the limit is T_s < 2.6e-4 s."""
    observer = _observer()
    observer.check_run(2.5e-4)
    with pytest.raises(InputError, match=r"obs\.w_max"):
        observer.check_run(2.7e-4)


@pytest.mark.parametrize("w_r", [100.0, 3000.0, -3000.0])
def test_a_machine_in_steady_state_is_a_fixed_point_of_the_discrete_observer(w_r):
    """The applied voltage taken into the estimated frame at the sample's middle angle and
    scaled by sin(x)/x is its exact mean there (module docstring): estimates that start exact
    stay exact to rounding over 1000 samples, even at w T_s = 0.3 rad per sample."""
    observer = _observer()
    errors = np.zeros(4)
    for _ in range(1000):
        errors = _error_map(w_r, observer, errors)
    assert np.max(np.abs(errors[:3])) < 1e-12 and abs(errors[3]) < 1e-9


def test_the_guides_example_and_its_lowest_designed_speed():
    """docs/guide/sensorless.md: its example builds the observer, and at |w| = alpha_f the slower
    flux pole is -(1 + zeta - sqrt((1 + zeta)^2 - 1)) alpha_f = -0.38 alpha_f for zeta = 0.5."""
    import re
    from pathlib import Path

    guide = Path(__file__).resolve().parents[1] / "docs" / "guide" / "sensorless.md"
    code = re.search(r"```python\n(.*?)```", guide.read_text(), re.DOTALL).group(1)
    scope: dict = {}
    exec(compile(code, str(guide), "exec"), scope)  # noqa: S102  (the guide's example itself)
    assert scope["observer"].values["alpha_f"] == ALPHA_F
    slower = np.max(flux_poles(ALPHA_F, ZETA_INF, ALPHA_F).real)
    assert slower == pytest.approx(-(1.5 - math.sqrt(1.25)) * ALPHA_F, rel=1e-12)
    assert round(slower / ALPHA_F, 2) == -0.38
