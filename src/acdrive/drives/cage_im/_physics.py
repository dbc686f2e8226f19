"""Physics helpers of the cage induction motor drive: the SVPWM modulation signals, the
field-oriented steady voltage and the bumpless start of a stationary current controller (the
sampled current loop's pre-check is ``drives.cage_im._current_loop``)."""

from __future__ import annotations

import numpy as np
import scipy.linalg

from acdrive._frames import complex_to_abc
from acdrive.control._current import (
    StationaryCurrentController,
)
from acdrive.machines._induction import IMParams


def modulation_signals(v: np.ndarray, v_dc: np.ndarray) -> np.ndarray:
    """Phase modulation signals 2 d_x - 1 (rows a, b, c) of centred SVPWM for the limited
    voltage vectors ``v`` on DC links ``v_dc``: the min-max zero sequence added to the phase
    values (Bodson (2)), over v_dc / 2, as ``plant._inverter`` sets its duty cycles."""
    x = np.array(complex_to_abc(np.asarray(v, dtype=complex)))
    offset = -0.5 * (x.max(axis=0) + x.min(axis=0))
    with np.errstate(invalid="ignore", divide="ignore"):
        m = np.where(v_dc > 0.0, 2.0 * (x + offset) / np.where(v_dc > 0, v_dc, 1.0), 0.0)
    return np.clip(m, -1.0, 1.0)


def foc_voltage(p: IMParams, psi: float, tau: float, w: float) -> complex:
    """Stator voltage v_dq [V, space vector] of the field-oriented steady state of the cage
    machine (1)-(2) with rotor flux ``psi`` on the d axis, torque ``tau`` at mechanical speed
    ``w``: i_d = psi / L_m, i_q = tau L_r / (n_p L_m psi), w_e = n_p w + R_r tau / (n_p psi^2)
    and, from the stator row of (1) in the frame turning at w_e,
    v = (R_s + L_m^2 R_r / L_r^2 + j w_e sigma L_s) i - (L_m / L_r)(R_r / L_r - j n_p w) psi."""
    i = complex(psi / p.L_m, tau * p.L_r / (p.n_p * p.L_m * psi))
    w_r = p.n_p * w
    w_e = w_r + p.R_r * tau / (p.n_p * psi * psi)
    R_eq = p.R_s + p.L_m**2 * p.R_r / p.L_r**2
    return (R_eq + 1j * w_e * p.sigma * p.L_s) * i - p.L_m / p.L_r * (
        p.R_r / p.L_r - 1j * w_r
    ) * psi


def bumpless_state(part: StationaryCurrentController, v: complex) -> dict:
    """Initial state of the current controller that outputs ``v`` with zero error and stays
    there (x = A_d x, C_d x = v: the integrators' direction); zero if it has no integrator."""
    d = part.discrete
    n = d.order
    if n == 0:
        return {}
    null = scipy.linalg.null_space(d.Ad - np.eye(n), rcond=1e-9)
    if null.shape[1] == 0:
        return part.state_for(np.zeros(n))
    target = np.array([v.real, v.imag])
    coef, *_ = np.linalg.lstsq(d.Cd @ null, target, rcond=None)
    x = null @ coef
    if np.linalg.norm(d.Cd @ x - target) > 1e-9 * max(1.0, abs(v)):
        x = np.zeros(n)
    return part.state_for(x)
