"""Doubly-fed induction machine (DFIM): parameters, complex model, steady state.

All relations follow M. Bodson, "Speed Control for Doubly-Fed Induction Motors With and Without
Current Feedback" (called "Bodson" below). Space vectors are complex numbers in the
power-invariant scaling of Bodson (1)-(8); rotor quantities are referred to the stator frame.
"""

from __future__ import annotations

import numpy as np

from acdrive._jit import jit, python_from_python
from acdrive.errors import InputError, require_finite, require_positive
from acdrive.machines._dfim_part import (  # noqa: F401 (the model's, here for its users)
    L_R,
    L_S,
    M_SR,
    N_P,
    R_R,
    R_S,
    DoublyFedMachine,
    currents_from_fluxes,
    electromagnetic_torque,
)
from acdrive.machines._record import machine_record
from acdrive.machines._windings import leakage_factor


@machine_record(DoublyFedMachine, leave_out=("V_loss",))
class DFIMParams:
    """Electrical and mechanical parameters of a DFIM (Bodson (9), (26)): the parameters of
    ``DoublyFedMachine`` and of the ``plant.Shaft`` it drives (J of motor and load)."""

    @property
    def sigma(self) -> float:
        """Leakage factor sigma = 1 - M^2 / (L_s L_r) (Bodson, after (45))."""
        return leakage_factor(self.L_s, self.L_r, self.M)


#: The laboratory DFIM of Bodson section III-D / IV-A (standstill estimates, J of motor + DC load).
BODSON_DFIM = DFIMParams(R_s=0.66, R_r=0.94, L_s=13.1e-3, L_r=9.8e-3, M=9.7e-3, n_p=2, J=3.5e-4)


# ---------------------------------------------------------------------------------------------
# Compiled code reads the parameter vector of ``DoublyFedMachine.PARAMS`` through its slot
# constants (compile-time constants for numba), so it reads ``p[R_S]`` like the paper reads R_S.
# ---------------------------------------------------------------------------------------------


def machine_vector(params: DFIMParams) -> np.ndarray:
    """``params`` packed as the ``DoublyFedMachine`` part packs them (V_loss = 0): the float64
    vector read by the compiled functions below."""
    return DoublyFedMachine.from_params("machine", params).p


@jit
def impedances(p, w_e, w_m):
    """Z_S, Z_MS, Z_R, Z_MR of Bodson (11) at electrical frequency w_e and shaft speed w_m."""
    w_slip = w_e - p[N_P] * w_m
    Z_S = p[R_S] + 1j * w_e * p[L_S]
    Z_MS = 1j * w_e * p[M_SR]
    Z_R = p[R_R] + 1j * w_slip * p[L_R]
    Z_MR = 1j * w_slip * p[M_SR]
    return Z_S, Z_MS, Z_R, Z_MR


@jit
def _over_j(z, x):
    """z / (j x) for real x: the numbers of the complex division by Z_MS = j w_e M (Bodson (11)),
    but the signs of zeros, without its branches and its raise path for a zero divisor (the C
    generated from it is the same)."""
    return complex(z.imag / x, -z.real / x)


@jit
def rotor_voltage_for(p, w_e, w_m, v_s, i_s):
    """Steady-state rotor voltage that gives stator current ``i_s`` (Bodson (20))."""
    Z_S, Z_MS, Z_R, Z_MR = impedances(p, w_e, w_m)
    return _over_j(Z_R * v_s - (Z_S * Z_R - Z_MS * Z_MR) * i_s, Z_MS.imag)


@jit
def rotor_current_for(p, w_e, v_s, i_s):
    """Steady-state rotor current that gives stator current ``i_s`` (Bodson (43), from (19))."""
    Z_S = p[R_S] + 1j * w_e * p[L_S]
    return _over_j(v_s - Z_S * i_s, w_e * p[M_SR])


@jit
def steady_state_currents(p, w_e, w_m, v_s, v_r):
    """Solve the steady-state equations (19) for (i_s, i_r) given both voltages."""
    Z_S, Z_MS, Z_R, Z_MR = impedances(p, w_e, w_m)
    det = Z_S * Z_R - Z_MS * Z_MR
    i_s = (Z_R * v_s - Z_MS * v_r) / det
    i_r = (Z_S * v_r - Z_MR * v_s) / det
    return i_s, i_r


@jit
def _minus_j_over(x, Q, v_s):
    """x - j Q / v_s for real x, Q and v_s, written out: the numbers of the complex division
    (0 + j Q) / v_s, without its branches and its raise path for a zero divisor (the C
    generated from it is the same)."""
    return complex(x - 0.0 / v_s, 0.0 - Q / v_s)


@jit
def stator_current_command(p, w_e, v_s, tau, Q):
    """Stator current giving torque ``tau`` and reactive power ``Q`` with real ``v_s`` > 0.

    Bodson (22) (and (24) for Q = 0). The root with the minus sign is evaluated in the
    cancellation-free form b / (a + sqrt(a^2 - b)), a = v_s / (2 R_s). Where the radicand is
    negative no stator current achieves the command; the radicand is then clamped to zero (the
    largest achievable power) and ``limited`` is True.
    Returns (i_s, limited).
    """
    a = v_s / (2.0 * p[R_S])
    b = w_e * tau / (p[N_P] * p[R_S]) + Q * Q / (v_s * v_s)
    radicand = a * a - b
    limited = radicand < 0.0
    if limited:
        radicand = 0.0
        b = a * a
    i_d = b / (a + np.sqrt(radicand))
    return _minus_j_over(i_d, Q, v_s), limited


@jit
def stator_current_lossless(p, w_e, v_s, tau, Q):
    """Stator current for torque ``tau`` and reactive power ``Q`` when R_s = 0 (Bodson (38));
    with (20) it gives the control law (39)."""
    return _minus_j_over(w_e * tau / (v_s * p[N_P]), Q, v_s)


def lossless_law_torque(machine: DFIMParams, w_e: float, v_s: float, tau_com: float) -> float:
    """The torque [N m] the R_S = 0 law (38)-(39) produces at command ``tau_com`` on a machine
    whose R_S is not 0: the law sets the real stator current i_S = w_e tau_COM / (v_S n_P) of
    (38) (with Q_COM = 0; v_R from (20) holds it exactly at any speed), and (31) then gives
    tau_e = tau_COM - n_P R_S i_S^2 / w_e (Bodson's listing at the end of sec. IV)."""
    if not isinstance(machine, DFIMParams):
        raise InputError("machine", f"must be DFIMParams, got {type(machine).__name__}")
    w_e = require_positive("w_e", w_e)
    v_s = require_positive("v_s", v_s)
    tau_com = require_finite("tau_com", tau_com)
    i_s = w_e * tau_com / (v_s * machine.n_p)
    return tau_com - machine.n_p * machine.R_s * i_s * i_s / w_e


@jit
def _torque_at_stator_current(p, w_e, v_s, i_d):
    """Torque for a real stator current i_d (Q = 0), from (31): n_p/w_e (v_s i_d - R_s i_d^2)."""
    return p[N_P] / w_e * (v_s * i_d - p[R_S] * i_d * i_d)


@python_from_python
@jit
def torque_limits_case1(p, w_e, v_s, i_s_max, i_r_max):
    """Torque limits with Q = 0 (Bodson case 1, (29)-(37)), for motoring and generating torque.

    Returns (tau_max_1, tau_max_2, tau_max_3, tau_min_2, tau_min_3, feasible):
    tau_max_1 (30) keeps the root of (24) real; tau_max_2 (32) / tau_min_2 keep |i_s| <= i_s_max;
    tau_max_3 (37) / tau_min_3 keep |i_r| <= i_r_max through (33)-(36). Generating limits use the
    other root of the same quadratics (the paper's "slightly different" negative limits); there is
    no generating counterpart of tau_max_1 since (24) is real for every tau < 0.
    ``feasible`` is False when the rotor current limit is below the magnetising current the
    stator voltage needs (a_2^2 + a_1 a_3 < 0): no torque then keeps |i_r| <= i_r_max, and the
    rotor limits collapse to zero.
    """
    n_p, R_s, M = p[N_P], p[R_S], p[M_SR]
    tau_max_1 = n_p / w_e * v_s * v_s / (4.0 * R_s)
    tau_max_2 = _torque_at_stator_current(p, w_e, v_s, i_s_max)
    tau_min_2 = _torque_at_stator_current(p, w_e, v_s, -i_s_max)
    wM2 = w_e * w_e * M * M
    a_1 = (R_s * R_s + w_e * w_e * p[L_S] * p[L_S]) / wM2
    a_2 = R_s * v_s / wM2
    a_3 = i_r_max * i_r_max - v_s * v_s / wM2
    disc = a_2 * a_2 + a_1 * a_3
    feasible = disc >= 0.0 and a_3 >= 0.0
    if not feasible:
        return tau_max_1, tau_max_2, 0.0, tau_min_2, 0.0, False
    i_s_rmax = (a_2 + np.sqrt(disc)) / a_1
    i_s_rmin = (a_2 - np.sqrt(disc)) / a_1
    # beyond the peak of (31) at i_d = v_s/(2 R_s) the torque falls again: clip to the peak
    i_peak = v_s / (2.0 * R_s)
    tau_max_3 = _torque_at_stator_current(p, w_e, v_s, min(i_s_rmax, i_peak))
    tau_min_3 = _torque_at_stator_current(p, w_e, v_s, i_s_rmin)
    return tau_max_1, tau_max_2, tau_max_3, tau_min_2, tau_min_3, True


@python_from_python
@jit
def torque_window(p, w_e, v_s, i_s_max, i_r_max):
    """Admissible torque interval [tau_lo, tau_hi] with Q = 0, the tightest of case 1 limits.

    Returns (tau_lo, tau_hi, feasible). Bodson uses the smallest of (30), (32), (37) on line.
    """
    t1, t2, t3, m2, m3, feasible = torque_limits_case1(p, w_e, v_s, i_s_max, i_r_max)
    tau_hi = min(t1, min(t2, t3))
    tau_lo = max(m2, m3)
    return tau_lo, tau_hi, feasible


@jit
def torque_limit_case2(p, w_e, v_s, Q, i_s_max, i_r_max):
    """Torque limits for R_s = 0 and any Q (Bodson case 2, (40)-(42)).

    Returns (tau_max_2, tau_max_3): the largest |tau| allowed by the stator current constraint (40)
    and by the rotor current constraint (42) at reactive power Q (negative if Q alone violates it).
    """
    k = w_e / (v_s * p[N_P])
    q = Q / v_s
    rest_s = i_s_max * i_s_max - q * q
    tau_max_2 = np.sqrt(rest_s) / k if rest_s >= 0.0 else -1.0
    m = p[L_S] / p[M_SR]
    r = v_s / (w_e * p[M_SR]) - m * Q / v_s
    rest_r = i_r_max * i_r_max - r * r
    tau_max_3 = np.sqrt(rest_r) / (m * k) if rest_r >= 0.0 else -1.0
    return tau_max_2, tau_max_3


def delta_z_coefficients(params: DFIMParams, w_e: float, w_m: float) -> np.ndarray:
    """Coefficients [c2, c1, c0] of Delta Z(s) (Bodson (13)), highest power first (complex)."""
    p = machine_vector(params)
    Z_S, Z_MS, Z_R, Z_MR = impedances(p, w_e, w_m)
    L_s, L_r, M = params.L_s, params.L_r, params.M
    return np.array(
        [L_s * L_r - M * M, L_s * Z_R + L_r * Z_S - M * (Z_MR + Z_MS), Z_S * Z_R - Z_MR * Z_MS]
    )


def electrical_poles(params: DFIMParams, w_e: float, w_m: float) -> np.ndarray:
    """The two electrical poles, roots of Delta Z(s) (Bodson (13))."""
    return np.roots(delta_z_coefficients(params, w_e, w_m))


def shifted_delta_z_coefficients(params: DFIMParams, w_m: float) -> np.ndarray:
    """Coefficients of Delta Z(s - j w_e) = a0 s^2 + (a1 + j b1) s + a2 + j b2 (Bodson (15)-(16))."""
    L_s, L_r, M, R_s, R_r, n_p = (
        params.L_s,
        params.L_r,
        params.M,
        params.R_s,
        params.R_r,
        params.n_p,
    )
    a0 = L_s * L_r - M * M
    a1 = L_s * R_r + L_r * R_s
    a2 = R_s * R_r
    b1 = -n_p * w_m * a0
    b2 = -n_p * w_m * L_r * R_s
    return np.array([a0, a1 + 1j * b1, a2 + 1j * b2])


def stator_current_per_rotor_voltage(params: DFIMParams, w_e: float, w_m: float, s):
    """Transfer function i_s / v_r = (-s M - Z_MS) / Delta Z(s) (Bodson (14)), at complex ``s``."""
    s = np.asarray(s, dtype=complex)
    c2, c1, c0 = delta_z_coefficients(params, w_e, w_m)
    return (-s * params.M - 1j * w_e * params.M) / ((c2 * s + c1) * s + c0)
