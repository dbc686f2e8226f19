"""Checks of a sampled speed or current loop shared by the drives (``drives.<kind>._period``).

A drive's pre-run checks compare its control period T_s with the time scales of its loops: a
sampled loop that is unstable is refused, one whose bandwidth times T_s exceeds the thresholds
below is warned about (it no longer behaves as its continuous design).
"""

from __future__ import annotations

import math

import numpy as np

#: a T_s above which a sampled speed loop of design root a is warned about (a_D,VEL for the DFIM)
SPEED_BANDWIDTH_T_S_WARN = 0.5
#: a_C T_s above which a sampled current loop of bandwidth a_C is warned about (a_D,CUR for the DFIM)
CURRENT_BANDWIDTH_T_S_WARN = 1.0


def speed_loop_radius(K_P: float, K_I: float, J: float, T_s: float, filter_tau: float) -> float:
    """Spectral radius of the sampled speed loop of Bodson (25)-(26) (``drives.dfim._period``).

    State [w_k, w_{k-1}, e_k, w_f,k-1]: with the torque u_k held over the sample the encoder's
    backward difference at t_k is (w_{k-1} + w_k) / 2; the filter w_f,k = w_f,k-1 + c (that -
    w_f,k-1), c = T_s / (tau + T_s); u_k = -K_P w_f,k + K_I e_k; e_k+1 = e_k - T_s w_f,k (the
    reference is zero: stability does not depend on it); w_k+1 = w_k + T_s u_k / J. With
    K_I = 0 (a proportional speed loop) the integral state is left out."""
    c = T_s / (filter_tau + T_s)

    def step(x):
        w, w_prev, e, wf_prev = x
        wf = wf_prev + c * (0.5 * (w + w_prev) - wf_prev)
        u = -K_P * wf + K_I * e
        return np.array([w + T_s * u / J, w, e - T_s * wf, wf])

    A = np.column_stack([step(col) for col in np.eye(4)])
    if K_I == 0.0:  # a P loop: the integral state acts on nothing and is left out
        A = np.delete(np.delete(A, 2, axis=0), 2, axis=1)
    return float(np.max(np.abs(np.linalg.eigvals(A))))


def current_loop_radius(
    L: float, R: float, K_P: float, K_I: float, T_s: float, hold_samples: int = 1
) -> float:
    """Spectral radius of a sampled PI current loop on a first-order plant (one axis; the rotor
    current loop of Bodson (45)-(50) with L = sigma L_r, R = R_T; one rotor-frame axis of the PM
    drive): L di/dt = v - R i with v held (i_k+1 = phi i_k + gamma v_k, phi = exp(-R T_s / L),
    gamma = (1 - phi) / R), the PI v = -K_P i + K_I I with I_k+1 = I_k - T_s i_k every sample
    (reference zero), and the command v computed at the first of every ``hold_samples`` samples
    and held over them (a converter that takes its command once per carrier period). The map
    over one hold is the product of the samples' maps; below 1 the loop is stable."""
    rate = R / L
    phi = math.exp(-rate * T_s)
    gamma = (1.0 - phi) / R if rate * T_s > 1e-12 else T_s / L
    if K_I == 0.0 and hold_samples == 1:  # no integral action: the integrator acts on nothing
        return abs(phi - gamma * K_P)
    # state (i, I, v): the command is taken at the start of the hold, then held
    take = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-K_P, K_I, 0.0]])
    sample = np.array([[phi, 0.0, gamma], [-T_s, 1.0, 0.0], [0.0, 0.0, 1.0]])
    period = np.linalg.matrix_power(sample, int(hold_samples)) @ take
    if K_I == 0.0:  # the integral state then acts on nothing: leave it out
        period = np.delete(np.delete(period, 1, axis=0), 1, axis=1)
    return float(np.max(np.abs(np.linalg.eigvals(period))))
