"""A cage-IM current step beside the ICAD model's linear closed loop: the linear step responses
(continuous, and with the loop's delay), the ringing measure and the comparison of a simulated
step with them, per run and as summary.json's ``step_responses`` (``step_summary``)."""

from __future__ import annotations

import numpy as np

from acdrive.analysis._plants import plant_from_params
from acdrive.drives.cage_im._result import IMDriveResult


def closed_loop_reference_ss(plant, k):
    """(A, B, C) of r -> (i_alpha, i_beta) for the plant ``plant`` (``analysis.Plant2x2``,
    D = 0) with the diagonal controller diag(k, k) on e = r - y (Amezquita-Brooks (5)-(6))."""
    import scipy.linalg  # here, not at the top: a run whose summary has no step comparison

    A, B, C = plant.A, plant.B, plant.C
    Ak, Bk, Ck = (scipy.linalg.block_diag(M, M) for M in (k.A, k.B, k.C))
    Dk = float(k.D[0, 0]) * np.eye(2)
    Acl = np.block([[A - B @ Dk @ C, B @ Ck], [-Bk @ C, Ak]])
    Bcl = np.vstack([B @ Dk, Bk])
    Ccl = np.hstack([C, np.zeros((2, Ak.shape[0]))])
    return Acl, Bcl, Ccl


def linear_step_response(params, w_mech: float, k, t: np.ndarray) -> np.ndarray:
    """(i_alpha, i_beta) per unit step of r_1 at t = 0 over ``t`` (continuous, no sampling):
    the stator-current plant (1) at electrical speed n_p w (``analysis._plants``) in closed loop
    with diag(k, k)."""
    import scipy.signal  # (0.3 CPU-s) only for the scenarios that compare step responses

    plant = plant_from_params(params, params.n_p * w_mech)
    A, B, C = closed_loop_reference_ss(plant, k)
    system = scipy.signal.StateSpace(A, B[:, :1], C, np.zeros((2, 1)))
    _, y, _ = scipy.signal.lsim(system, np.ones_like(t), t)
    return np.atleast_2d(y).reshape(t.size, 2)


def delayed_linear_step_response(
    params, w_mech: float, k, t: np.ndarray, delay: float, substeps: int = 50
) -> np.ndarray:
    """``linear_step_response`` with the controller's command reaching the plant ``delay`` [s]
    late (a single loop delay, e.g. the average delay N T_s / 2 of a sample-and-hold,
    ``analysis._coupling.hold_delay``): plant and controller discretised with a zero-order hold
    at dt = delay / ``substeps`` (exact for inputs constant over dt), the command delayed by
    ``substeps`` steps, the outputs interpolated onto ``t``."""
    import scipy.linalg

    plant = plant_from_params(params, params.n_p * w_mech)
    dt = delay / substeps if delay > 0 else float(np.min(np.diff(t))) / 10.0
    lag = substeps if delay > 0 else 0

    def zoh(A, B):
        n, m = B.shape
        M = scipy.linalg.expm(np.block([[A, B], [np.zeros((m, n + m))]]) * dt)
        return M[:n, :n], M[:n, n:]

    Ap, Bp = zoh(plant.A, plant.B)
    Ak, Bk = zoh(scipy.linalg.block_diag(k.A, k.A), scipy.linalg.block_diag(k.B, k.B))
    Ck = scipy.linalg.block_diag(k.C, k.C)
    Dk = float(k.D[0, 0])
    steps = int(np.ceil(t[-1] / dt)) + 1
    x, xk = np.zeros(Ap.shape[0]), np.zeros(Ak.shape[0])
    r = np.array([1.0, 0.0])
    pending = [np.zeros(2)] * lag
    out = np.empty((steps, 2))
    for i in range(steps):
        y = plant.C @ x
        out[i] = y
        e = r - y
        pending.append(Ck @ xk + Dk * e)
        xk = Ak @ xk + Bk @ e
        x = Ap @ x + Bp @ pending.pop(0)
    grid = dt * np.arange(steps)
    return np.column_stack([np.interp(t, grid, out[:, j]) for j in range(2)])


#: Ringing of a step response: the RMS deviation from its final value from this time [s] after
#: the step on (past the first overshoot of loops of a few thousand rad/s, Amezquita-Brooks
#: Figs. 18, 20), per unit of the step.
RINGING_AFTER_S = 0.005


def ringing(t, response, final) -> float:
    """RMS of ``response - final`` over ``t >= RINGING_AFTER_S`` (``t`` from the step, the
    response per unit of the step): how much a step response still rings after its first
    overshoot."""
    late = np.asarray(t) >= RINGING_AFTER_S
    return float(np.sqrt(np.mean((np.asarray(response)[late] - final) ** 2)))


def step_comparison(result: IMDriveResult) -> dict | None:
    """Simulated step response of the alpha current against the linear closed loop, both per
    unit of the step, after the step: overshoots, final values, ringing (``ringing``), largest
    difference and the largest coupling into i_beta (None unless the run is a current step on a
    held shaft)."""
    s = result.setup
    ref = s.current_reference
    if s.mode != "current" or ref is None or ref.waveform != "step" or s.mechanics.free:
        return None
    if ref.amplitude_pk == 0.0:
        return None
    w = float(s.mechanics.prescribed_speed[1][0])
    after = result.t >= ref.start
    t = result.t[after] - ref.start
    sim = result.phase_peak("i_s")[after] / ref.amplitude_pk
    lin = linear_step_response(s.plant, w, s.current_control.lti, t)
    final_sim = float(np.mean(sim.real[t >= 0.9 * t[-1]]))
    final_lin = float(np.mean(lin[t >= 0.9 * t[-1], 0]))
    return {
        "t": t,
        "simulated": sim,
        "linear": lin,
        "speed_rad_s": w,
        "overshoot_simulated": float(np.max(sim.real) - 1.0),
        "overshoot_linear": float(np.max(lin[:, 0]) - 1.0),
        "final_simulated": final_sim,
        "final_linear": final_lin,
        "ringing_simulated": ringing(t, sim.real, final_sim),
        "ringing_linear": ringing(t, lin[:, 0], final_lin),
        "max_difference": float(np.max(np.abs(sim.real - lin[:, 0]))),
        "coupling_peak_simulated": float(np.max(np.abs(sim.imag))),
        "coupling_peak_linear": float(np.max(np.abs(lin[:, 1]))),
    }


def step_summary(outcome) -> dict:
    """Per run (label) the ``step_comparison`` numbers (without the arrays), and at the top level
    ``step_overshoot_<label>`` and ``linear_step_overshoot_<label>``; empty for other runs."""
    out = {}
    for label, result in outcome.results.items():
        c = step_comparison(result)
        if c is None:
            continue
        numbers = {k: v for k, v in c.items() if not isinstance(v, np.ndarray)}
        out.setdefault("step_responses", {})[label] = numbers
        out[f"step_overshoot_{label}"] = numbers["overshoot_simulated"]
        out[f"linear_step_overshoot_{label}"] = numbers["overshoot_linear"]
    return out
