"""The current sign the inverter's voltage error follows during a standstill injection.

The inverter loses U sign(i_a) of the phase-a voltage each carrier period, the sign that of the
current at the period's sample instant (``plant._inverter``; ``identify._dc``). A compensation
needs that sign. The sign of the logged reading is wrong wherever the current lies within a few
noise deviations of zero, and near a zero crossing the dead time clamps the current there: the
inverter's polarity flips between neighbouring samples, a pattern no filtering of the noisy
reading recovers. The fitted winding does recover it: its exact sampled model at standstill
(``identify._winding``: the inverse-Gamma circuit of ``identify._circuit`` or an RL branch),

    x_{k+1} = Phi x_k + Gamma (v_k - U s_k),   i_k = C x_k,   s_k = sign(i_k),

run over the logged command v_k from rest (the settling time lets the log's own start be
forgotten), with C the sampling row of ``_winding.discrete_winding`` (dead time included).
Its s_k is the inverter's polarity as far as the fitted parameters are right; it carries no
sensor noise.

**Two inverters at a zero crossing.** The recursion above holds each period's sign at the
sample instant (as acdrive's ``plant.Inverter`` does): a current driven towards zero chatters
around it from sample to sample. A real inverter takes each leg's direction at each switching
edge, so within the period the error adapts and holds the current at zero (zero-current
clamping; motulator's carrier-comparison converter does this). ``clamping=True`` models that
limit: s_k = +1 (-1) while the current stays positive (negative) under the full error, else the
fraction in [-1, 1] that brings the next sample to zero,

    s_k = clip((C Phi x_k + C Gamma v_k) / (C Gamma U), -1, 1).

A bench inverter lies between the two; ``identify._impedance`` fits with the held sign and, when
the residual exceeds the noise floor, adds the clamping fit's difference to the intervals.
"""

from __future__ import annotations

import numpy as np

from acdrive._jit import jit
from acdrive.identify._circuit import standstill_state_space
from acdrive.identify._winding import discrete_winding


def simulated_polarity(values, v: np.ndarray, hold: float, voltage_error: float,
                       dead_time: float = 0.0, state_space=standstill_state_space,
                       clamping: bool = False) -> np.ndarray:  # fmt: skip
    """s_k = sign(i_k) of the winding ``state_space(values)`` (default the inverse-Gamma circuit,
    values R_s, L_sigma, R_R, L_M; an RL branch for ``identify._pm``) fed the command ``v`` [V]
    held over periods ``hold`` [s] less ``voltage_error`` [V] times the sign (module docstring),
    from rest; the inverter's dead time ``dead_time`` [s] moves the sample t_d / 2 early
    (``identify._winding``); ``clamping`` holds a current that the error would drive through
    zero at zero instead (module docstring)."""
    A, B = state_space(values)
    Phi, Gamma, C = discrete_winding(A, B, hold, dead_time)
    if A.shape == (1, 1):  # one state: a second one that stays at rest
        Phi = np.array([[Phi[0, 0], 0.0], [0.0, 0.0]])
        Gamma, C = np.array([Gamma[0], 0.0]), np.array([C[0], 0.0])
    return _signs(np.ascontiguousarray(v, dtype=float), Phi, Gamma, C, float(voltage_error),
                  bool(clamping))


@jit
def _signs(v, Phi, Gamma, C, U, clamping):
    """The recursion of ``simulated_polarity`` (compiled: a log has tens of thousands of rows)."""
    signs = np.empty(v.size)
    x0 = 0.0
    x1 = 0.0
    reach = C[0] * Gamma[0] + C[1] * Gamma[1]  # the next sample's current per volt held
    for k in range(v.size):
        current = C[0] * x0 + C[1] * x1
        if clamping and U * reach > 0.0:
            free = (C[0] * (Phi[0, 0] * x0 + Phi[0, 1] * x1)
                    + C[1] * (Phi[1, 0] * x0 + Phi[1, 1] * x1) + reach * v[k])  # fmt: skip
            if current > 0.0 and free > reach * U:
                s = 1.0
            elif current < 0.0 and free < -reach * U:
                s = -1.0
            else:  # the error holds the current at zero (or drives it through within the period)
                s = min(1.0, max(-1.0, free / (reach * U)))
        else:
            s = 1.0 if current > 0.0 else (-1.0 if current < 0.0 else 0.0)
        signs[k] = s
        applied = v[k] - U * s
        x0, x1 = (Phi[0, 0] * x0 + Phi[0, 1] * x1 + Gamma[0] * applied,
                  Phi[1, 0] * x0 + Phi[1, 1] * x1 + Gamma[1] * applied)  # fmt: skip
    return signs


def feedback_gain(jacobian: np.ndarray, theta: np.ndarray, steps: np.ndarray,
                  polarity, sensitivity: np.ndarray) -> np.ndarray:  # fmt: skip
    """The matrix that carries a fixed-polarity fit's error into the self-consistent one's.

    The estimate solves J^T r(theta, P(theta)) = 0: the residual r = I - Y (V - U P) at the
    tones, with the polarity coefficients P simulated from the estimate itself. A current
    error dI moves a fit with P held fixed by d0 = -(J^T J)^-1 J^T dI; the self-consistent
    estimate moves by d = -(J^T J + J^T H)^-1 J^T dI = (J^T J + J^T H)^-1 J^T J d0, with
    H = dr/dP dP/dtheta. Measured on the DeLorenzo IM's standstill test (30 noise draws), the
    noise moved P through the estimate enough to double the spread of R_s over the
    fixed-polarity fit's; this gain puts that into the covariance and the bootstrap draws.

    ``jacobian``: J (real and imaginary parts stacked) at ``theta``; ``polarity(theta)``: the
    tones' coefficients of the simulated sign; ``sensitivity``: dr/dP at the tones (Y U,
    complex); ``steps``: the central-difference step of each theta (secants over the scale the
    noise moves the estimate: a sign flips at discrete samples)."""
    H = np.empty_like(jacobian)
    for j, step in enumerate(steps):
        up, down = theta.copy(), theta.copy()
        up[j] += step
        down[j] -= step
        column = sensitivity * (polarity(up) - polarity(down)) / (2.0 * step)
        H[:, j] = np.concatenate((column.real, column.imag))
    JTJ = jacobian.T @ jacobian
    if not np.all(np.isfinite(H)):  # a secant left the physical range: the feedback is unknown
        return np.full_like(JTJ, np.nan)
    return np.linalg.solve(JTJ + jacobian.T @ H, JTJ)
