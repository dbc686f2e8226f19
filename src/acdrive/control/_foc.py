"""Indirect field-oriented control (IFOC) of the cage induction motor as sampled parts
(Amezquita-Brooks et al., section VI-B/C, Fig. 12 and (21)).

Fig. 12 is the cascade of a drive: position loop -> speed loop -> IFOC (torque and flux to
stator-current references) -> stator current controller -> inverter. The parts here are the
outer blocks; the current controller is a separate part, and the speed is measured from the
encoder angle with ``plant.Encoder`` and ``control.SpeedEstimator`` (backward
difference, optional low-pass), which suit any shaft.

* :class:`IndirectFOC`: torque reference and rotor-flux reference -> stationary-frame stator
  current reference, field angle from the encoder angle plus the integrated slip frequency.
* :class:`SaturatedSpeedP`: the saturated proportional speed controller (21).
* :class:`SpeedPI`: speed PI with clamping anti-windup and a torque limit (``control._speed``).
* :class:`PositionP`: P position loop giving the speed reference of a ``SpeedPI`` (P-PI cascade).

**Field orientation, derived from the plant model** (``machines._cage_part``, Amezquita-Brooks
(1)-(2) in acdrive's power-invariant scaling). The rotor-flux equation in the stationary frame,

    dpsi_r/dt = (L_m R_r / L_r) i_s - (R_r / L_r - j w_r) psi_r,      w_r = n_p w,

written in a frame of angle theta_f (x = x_dq e^{j theta_f}, w_f = dtheta_f/dt) becomes

    dpsi_dq/dt = (L_m R_r / L_r) i_dq - (R_r / L_r) psi_dq - j (w_f - w_r) psi_dq.

Field orientation puts the rotor flux on the d axis, psi_dq = psi_d (real, psi_q = 0 at all
times). The imaginary part then fixes the slip frequency and the real part the flux dynamics:

    w_slip = w_f - w_r = (L_m R_r / L_r) i_q / psi_d                                  (slip)
    dpsi_d/dt = (R_r / L_r) (L_m i_d - psi_d)                                         (flux)

and the torque of (2), tau_e = n_p (L_m / L_r) Im(conj(psi_r) i_s), becomes

    tau_e = n_p (L_m / L_r) psi_d i_q.                                              (torque)

In steady state i_d = psi_ref / L_m, and eliminating i_q: w_slip = R_r tau_e / (n_p psi_d^2).
*Indirect* FOC does not measure the flux: it computes psi_d with (flux) from its own i_d
command (the flux model; exact if the current controller makes i_s equal its reference and the
estimates R_r, L_r, L_m are right) and imposes the orientation by integrating (slip):

    theta_f = n_p theta_enc + theta_slip,    theta_slip(k+1) = theta_slip(k) + T_s w_slip(k).

The electrical rotor speed is integrated exactly by taking n_p times the encoder angle (its
increment over a sample is the integral of n_p w), not the filtered speed estimate; an encoder
offset only adds a constant to theta_f, which a cage rotor does not notice. With the flux
settled the slip integral is exact for the zero-order hold (i_q(k), hence w_slip(k), held over
the sample); while the flux changes it uses the flux at the sample. The reference is computed
at the field angle of the sample instant and held, while the field turns by w_f T_s over the
sample (0.003 rad at 150 rad/s and 20 us); no angle advance is added for it.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import ClassVar

import numpy as np

from acdrive._jit import jit
from acdrive.control._speed import SpeedPIGains, speed_pi
from acdrive.core._parts import SampledPart
from acdrive.core._signals import Layout, Relation, cplx, real, table
from acdrive.core._tables import table_at
from acdrive.errors import InputError
from acdrive.machines._cage_part import CageInductionMachine
from acdrive.machines._induction import DELORENZO_IM, UGALDE_IM_300W

# --- default numbers, from the DeLorenzo DL10115A1 machine of the paper --------------------------

#: Nameplate of the DeLorenzo DL10115A1 IM (Amezquita-Brooks et al. section VI; parameters in
#: their Appendix, ``machines.DELORENZO_IM``): 300 W, 380 V rms line-to-line, 3450 rpm,
#: 2 poles (so 60 Hz: synchronous speed 3600 rpm, slip 4.2 %).
RATED_POWER, RATED_VOLTAGE_LL_RMS, RATED_SPEED_RPM, RATED_FREQUENCY = 300.0, 380.0, 3450.0, 60.0
#: rated mechanical speed [rad/s] (361.3 rad/s)
RATED_SPEED = RATED_SPEED_RPM * 2.0 * math.pi / 60.0
#: rated torque P / w = 0.830 N m (nameplate; the Appendix parameters give 0.63 N m at rated
#: voltage, frequency and speed: identified parameters do not reproduce a nameplate exactly)
RATED_TORQUE = RATED_POWER / RATED_SPEED

#: Rotor-flux reference [Wb, space-vector magnitude]: the rotor flux of the Appendix machine at
#: its rated voltage and frequency and rated speed, i.e. the flux the machine is designed for.
#: In acdrive's power-invariant scaling |v_s| = V_LL,rms = 380 V at w_e = 2 pi 60 rad/s; the
#: steady state of cage_part's equations at w_r = 361.3 rad/s gives |psi_r| = 0.964 Wb
#: (|i_s| = 0.968 A; ``tests/test_foc.py`` recomputes it). Steady state, i_d = psi_ref / L_m =
#: 0.68 A. Field-oriented steady state needs v_dq = (R_s + j w_e sigma L_s) i_dq +
#: j w_e (L_m / L_r) psi_d, so with the paper's 310 V DC link (|v| <= V_dc / sqrt 2 = 219 V,
#: ``plant._converter``) this flux is held up to w_e = 224 rad/s at no load and 209 rad/s at rated
#: torque; faster runs need a lower flux (``psi_ref`` as a table: field weakening), which is the
#: user's choice and not guessed here.
RATED_FLUX = 0.964

#: Inertia estimate [kg m^2]: the 300 W IM of Ugalde-Loo et al. section 4.5 (J = 0.000711), whose
#: parameters were identified by the same group with the same method (their reference [34] =
#: Amezquita-Brooks' [34]); the paper itself gives no inertia. Used only to turn bandwidths into
#: default gains: give your own J to ``speed_p_gain`` / ``SpeedPIGains.design``.
J_ESTIMATE = UGALDE_IM_300W.J

#: Current magnitude limit [A, space-vector magnitude]: 1.5 times the current of rated torque at
#: rated flux, |psi_ref / L_m + j RATED_TORQUE L_r / (n_p L_m psi_ref)| = |0.68 + 0.91 j| = 1.13 A,
#: so the speed controllers' torque limit (rated torque) never meets it in steady state; it acts
#: while the flux builds up (i_q = tau / (k psi_d) is large while psi_d is small). 1.7 A is a
#: phase peak of 1.39 A (Bodson (8)).
CURRENT_LIMIT = 1.7

#: Flux below which no torque current is commanded [Wb]: about 10 % of RATED_FLUX. With psi_d
#: near zero (slip) and (torque) would ask for unbounded slip and current; a drive magnetises
#: first. From standstill with i_d = psi_ref / L_m the flux model passes 0.1 Wb after
#: (L_r / R_r) ln(1 / (1 - 0.1 / 0.964)) = 7 ms.
MIN_FLUX = 0.1

#: Speed-loop bandwidths [rad/s]. The paper's stationary current controllers cross over near
#: K_P / (sigma L_s) = 360 / 0.0957 = 3.8e3 rad/s (section VI-D: the PI is designed to cross over
#: where (20) does). A speed loop a decade or more below it sees the current loop, and with IFOC
#: the torque, as ideal: 100 rad/s for the proportional loop (21) (first order, k_p = J w_bw;
#: steady-state error under rated torque RATED_TORQUE / k_p = 11.7 rad/s, 3 % of rated speed,
#: the price of (21) having no integral), and both PI roots at -50 rad/s (crossover about
#: 2 x 50 = 100 rad/s, the same). The backward-difference speed estimate delays by T_s / 2 =
#: 100 us at 5 kHz: 0.6 degrees of phase at 100 rad/s.
SPEED_P_BANDWIDTH = 100.0
SPEED_PI_BANDWIDTH = 50.0
#: Position-loop gain [1/s]: a fifth of the speed PI's root, so the speed loop is close to unity
#: (phase lag under 1 degree) at the position crossover of about 10 rad/s.
POSITION_GAIN = SPEED_PI_BANDWIDTH / 5.0


def speed_p_gain(J: float, bandwidth: float) -> float:
    """k_p of (21) for a closed-loop bandwidth ``bandwidth`` [rad/s] with inertia ``J``: with an
    ideal torque, J dw/dt = k_p (w_ref - w) has its pole at -k_p / J, so k_p = J w_bw."""
    if not (J > 0.0 and bandwidth > 0.0):
        raise InputError("bandwidth", "J and the bandwidth must be > 0")
    return J * bandwidth


_PI_DEFAULT = SpeedPIGains.design(J_ESTIMATE, SPEED_PI_BANDWIDTH, K_F=1.0)


@jit
def _wrap(angle):
    return (angle + np.pi) % (2.0 * np.pi) - np.pi


@jit
def _clip(x, limit):
    """(x clipped to [-limit, limit], clipped?)."""
    if x > limit:
        return limit, True
    if x < -limit:
        return -limit, True
    return x, False


# --- IFOC: torque and flux references -> stator current reference ------------------------------

#: the machine parameters the IFOC uses, as the cage IM part declares them (its estimates of them)
IFOC_ESTIMATES = ("R_r", "L_r", "L_m", "n_p")
IFOC_PARAMS = Layout(
    *(
        replace(v, doc=f"{v.doc} (controller's estimate)")
        for v in CageInductionMachine.PARAMS
        if v.name in IFOC_ESTIMATES
    ),
    real("i_max", "A", "stator current magnitude limit (space vector)", "positive"),
    real("psi_min", "Wb", "flux estimate below which no torque current is given", "nonnegative"),
    table("psi_ref", "Wb", "rotor-flux reference profile"),
    relations=(
        Relation(
            ("L_r", "L_m"),
            "must not exceed L_r (L_r = L_m + rotor leakage)",
            lambda L_r, L_m: L_m <= L_r,
            c="{L_m} <= {L_r}",
        ),
    ),
)
IFOC_STATES = Layout(
    real("theta_slip", "rad", "integrated slip angle (wrapped to [-pi, pi))"),
    real("psi_est", "Wb", "rotor flux of the controller's flux model"),
)
IFOC_INPUTS = Layout(
    real("tau_ref", "N m", "torque reference"),
    real("theta", "rad", "measured shaft angle (encoder)"),
)
IFOC_OUTPUTS = Layout(
    cplx("i_s_ref", "A", "stator current reference, stationary frame"),
    cplx("i_dq_ref", "A", "stator current reference i_d + j i_q, field frame"),
    real("theta_f", "rad", "field angle (wrapped to [-pi, pi))"),
    real("w_slip", "rad/s", "slip frequency"),
    real("psi_est", "Wb", "rotor flux of the flux model"),
    real("tau_est", "N m", "torque expected from the limited current reference"),
)
IFOC_EVENTS = ("current_limit", "unmagnetised")
_EV_CURRENT_LIMIT, _EV_UNMAGNETISED = 1, 2
_F_RR, _F_LR, _F_LM, _F_NP, _F_IMAX, _F_PSIMIN = (
    IFOC_PARAMS.slot(n) for n in ("R_r", "L_r", "L_m", "n_p", "i_max", "psi_min")
)
_F_PSIREF = IFOC_PARAMS.table_start
_F_SLIP, _F_PSI = IFOC_STATES.slot("theta_slip"), IFOC_STATES.slot("psi_est")
_F_TAU, _F_THETA = IFOC_INPUTS.slot("tau_ref"), IFOC_INPUTS.slot("theta")
_F_O_IS, _F_O_IDQ, _F_O_THETA, _F_O_SLIP, _F_O_PSI, _F_O_TAU = (
    IFOC_OUTPUTS.slot(n) for n in ("i_s_ref", "i_dq_ref", "theta_f", "w_slip", "psi_est", "tau_est")
)


@jit
def ifoc_step(t, T_s, u, p, s, y):
    """One sample of indirect FOC (module docstring: (slip), (flux), (torque)).

    i_d = psi_ref / L_m; i_q = tau_ref L_r / (n_p L_m psi_est) while psi_est >= psi_min (else 0,
    event ``unmagnetised`` if torque was asked); |i_d + j i_q| <= i_max with the flux current
    first (event ``current_limit``); w_slip = (L_m R_r / L_r) i_q / psi_est from the limited i_q;
    i_s_ref = (i_d + j i_q) e^{j theta_f}, theta_f = n_p theta + theta_slip. Then the states
    advance over the sample with the commands held: theta_slip += T_s w_slip, and psi_est by the
    exact zero-order-hold solution of (flux), psi += (1 - e^{-T_s R_r / L_r}) (L_m i_d - psi).
    """
    R_r, L_r, L_m, n_p = p[_F_RR], p[_F_LR], p[_F_LM], p[_F_NP]
    i_max = p[_F_IMAX]
    psi = s[_F_PSI]
    tau_ref = u[_F_TAU]
    events = 0
    i_d = table_at(p, _F_PSIREF, t) / L_m
    magnetised = psi > 0.0 and psi >= p[_F_PSIMIN]
    if magnetised:
        i_q = tau_ref * L_r / (n_p * L_m * psi)
    else:
        i_q = 0.0
        if tau_ref != 0.0:
            events |= _EV_UNMAGNETISED
    if abs(i_d) >= i_max:  # the flux current alone uses the whole limit
        i_d = i_max if i_d > 0.0 else -i_max
        if i_q != 0.0:
            events |= _EV_CURRENT_LIMIT
        i_q = 0.0
    else:
        i_q, limited = _clip(i_q, np.sqrt(i_max * i_max - i_d * i_d))
        if limited:
            events |= _EV_CURRENT_LIMIT
    w_slip = L_m * R_r / L_r * i_q / psi if magnetised else 0.0
    theta_f = _wrap(n_p * u[_F_THETA] + s[_F_SLIP])
    i_s = complex(i_d, i_q) * complex(np.cos(theta_f), np.sin(theta_f))
    y[_F_O_IS], y[_F_O_IS + 1] = i_s.real, i_s.imag
    y[_F_O_IDQ], y[_F_O_IDQ + 1] = i_d, i_q
    y[_F_O_THETA] = theta_f
    y[_F_O_SLIP] = w_slip
    y[_F_O_PSI] = psi
    y[_F_O_TAU] = n_p * L_m / L_r * psi * i_q
    s[_F_SLIP] = _wrap(s[_F_SLIP] + T_s * w_slip)
    s[_F_PSI] = psi + (1.0 - np.exp(-T_s * R_r / L_r)) * (L_m * i_d - psi)
    return events


class IndirectFOC(SampledPart):
    """Indirect field-oriented control (Fig. 12, module docstring): torque reference and rotor
    flux reference to the stationary-frame stator current reference.

    Parameters are the controller's own estimates (``R_r``, ``L_r``, ``L_m``, ``n_p``: a
    detuned controller is built by giving values other than the plant's), the current limit
    ``i_max`` and the magnetising threshold ``psi_min``, and the flux reference ``psi_ref`` (a
    number or a table). The flux model ``psi_est`` starts at zero (a demagnetised machine);
    ``initial={name: {"psi_est": ...}}`` starts it magnetised. Defaults: the DeLorenzo machine
    of the Appendix, rated flux (``RATED_FLUX``), ``CURRENT_LIMIT``, ``MIN_FLUX``.
    """

    SOURCE = "indirect field orientation: (slip), (flux), (torque) of control._foc's docstring"

    PARAMS, STATES, INPUTS, OUTPUTS = IFOC_PARAMS, IFOC_STATES, IFOC_INPUTS, IFOC_OUTPUTS
    DEFAULTS: ClassVar[dict] = {**{n: getattr(DELORENZO_IM, n) for n in IFOC_ESTIMATES},
                                "i_max": CURRENT_LIMIT, "psi_min": MIN_FLUX,
                                "psi_ref": RATED_FLUX}  # fmt: skip
    EVENTS = IFOC_EVENTS
    step = ifoc_step

    def check(self):
        start = self.PARAMS.table_start
        n = int(self.p[start])
        if np.any(self.p[start + 1 + n : start + 1 + 2 * n] <= 0.0):
            raise InputError(f"{self.name}.psi_ref", "flux reference values must be > 0")

    @classmethod
    def from_params(cls, name, params, **values) -> IndirectFOC:
        """With the estimates taken from an ``acdrive.machines.IMParams`` (``values``
        override them, e.g. a detuned ``R_r``)."""
        estimates = {n: getattr(params, n) for n in IFOC_ESTIMATES}
        return cls(name, **{**estimates, **values})


# --- speed and position controllers ------------------------------------------------------------

SPEED_INPUTS = Layout(
    real("w_ref", "rad/s", "speed reference"),
    real("w", "rad/s", "measured shaft speed"),
)
TORQUE_OUTPUTS = Layout(real("tau_ref", "N m", "torque reference"))
TORQUE_EVENTS = ("torque_limit",)
_EV_TORQUE_LIMIT = 1
_W_REF, _W = SPEED_INPUTS.slot("w_ref"), SPEED_INPUTS.slot("w")

SAT_P_PARAMS = Layout(
    real("k_p", "N m s/rad", "proportional speed gain", "positive"),
    real("tau_max", "N m", "torque limit", "positive"),
)
_SP_KP, _SP_TMAX = SAT_P_PARAMS.slot("k_p"), SAT_P_PARAMS.slot("tau_max")


@jit
def saturated_p_step(t, T_s, u, p, s, y):
    """(21): tau_ref = k_p (w_ref - w) clipped to [-tau_max, tau_max] (event ``torque_limit``)."""
    tau, limited = _clip(p[_SP_KP] * (u[_W_REF] - u[_W]), p[_SP_TMAX])
    y[0] = tau
    return _EV_TORQUE_LIMIT if limited else 0


class SaturatedSpeedP(SampledPart):
    """The saturated proportional speed controller (21) of Amezquita-Brooks et al.

    The paper's w_r is the rotor speed of a 2-pole machine; here ``w`` is the mechanical shaft
    speed (equal for n_p = 1). (21) has no integral: under a load torque tau_L the speed settles
    tau_L / k_p below the reference, and a large step saturates the torque, so the speed ramps at
    (tau_max - tau_L) / J (section VI-D). Defaults: ``k_p = J_ESTIMATE * SPEED_P_BANDWIDTH`` =
    0.0711 N m s/rad (``speed_p_gain``; the paper gives no number) and ``tau_max`` = the
    nameplate torque 0.830 N m (``RATED_TORQUE``: the paper's limit keeps currents and voltage
    within the drive's ratings; no overload rating is given).
    """

    SOURCE = "Amezquita-Brooks (21): saturated proportional speed controller"

    PARAMS, INPUTS, OUTPUTS = SAT_P_PARAMS, SPEED_INPUTS, TORQUE_OUTPUTS
    DEFAULTS: ClassVar[dict] = {
        "k_p": speed_p_gain(J_ESTIMATE, SPEED_P_BANDWIDTH),
        "tau_max": RATED_TORQUE,
    }
    EVENTS = TORQUE_EVENTS
    step = saturated_p_step


SPEED_PI_PARAMS = Layout(
    real("K_P", "N m s/rad", "proportional gain", "nonnegative"),
    real("K_I", "N m/rad", "integral gain", "nonnegative"),
    real("K_F", "", "reference weight of the proportional term (1: PI on the error)", "fraction"),
    real("tau_max", "N m", "torque limit", "positive"),
)
SPEED_PI_STATES = Layout(real("e_int", "rad", "integral of the speed error"))
_PI_KP, _PI_KI, _PI_KF, _PI_TMAX = (
    SPEED_PI_PARAMS.slot(n) for n in ("K_P", "K_I", "K_F", "tau_max")
)
_PI_EINT = SPEED_PI_STATES.slot("e_int")


@jit
def speed_pi_step(t, T_s, u, p, s, y):
    """tau_ref = K_F K_P w_ref - K_P w + K_I int(w_ref - w) within [-tau_max, tau_max]; the
    integral advances (forward Euler) only while the output is inside the limits (clamping),
    ``control._speed.speed_pi``."""
    tau, s[_PI_EINT], limited = speed_pi(p[_PI_KP], p[_PI_KI], p[_PI_KF], s[_PI_EINT],
                                         u[_W_REF], u[_W], -p[_PI_TMAX], p[_PI_TMAX],
                                         T_s)  # fmt: skip
    y[0] = tau
    return _EV_TORQUE_LIMIT if limited else 0


class SpeedPI(SampledPart):
    """Speed PI with clamping anti-windup and a symmetric torque limit (event ``torque_limit``).

    With an ideal torque (IFOC with a fast current loop) the speed loop is J s^2 + K_P s + K_I;
    the defaults put both roots at -SPEED_PI_BANDWIDTH = -50 rad/s for J = J_ESTIMATE
    (``SpeedPIGains.design``, Bodson (27)): K_P = 2 a J = 0.0711 N m s/rad, K_I = a^2 J =
    1.78 N m/rad. ``K_F = 1`` is the plain PI on the error (a step overshoots by e^-2 = 13.5 %
    while unsaturated); Bodson's K_F = 2/3 reduces it to e^-4 / 3 = 0.61 %, and K_F <= 1/2
    removes it (``SpeedPIGains.step_overshoot``). ``tau_max`` = RATED_TORQUE.
    The clamping freezes the integral whenever the output is limited, so after a saturated step
    the integral holds what it had and the loop leaves the limit without a windup delay.
    """

    SOURCE = "speed PI with clamping anti-windup and torque limit (control._speed.speed_pi)"

    PARAMS, STATES, INPUTS, OUTPUTS = SPEED_PI_PARAMS, SPEED_PI_STATES, SPEED_INPUTS, TORQUE_OUTPUTS
    DEFAULTS: ClassVar[dict] = {"K_P": _PI_DEFAULT.K_P, "K_I": _PI_DEFAULT.K_I, "K_F": 1.0,
                                "tau_max": RATED_TORQUE}  # fmt: skip
    EVENTS = TORQUE_EVENTS
    step = speed_pi_step


POSITION_PARAMS = Layout(
    real("K_theta", "1/s", "position gain (speed reference per rad of error)", "positive"),
    real("w_max", "rad/s", "speed reference limit", "positive"),
    table("theta_ref", "rad", "position reference profile (encoder angle)"),
)
POSITION_INPUTS = Layout(real("theta", "rad", "measured shaft angle (encoder)"))
POSITION_OUTPUTS = Layout(
    real("w_ref", "rad/s", "speed reference"),
    real("theta_ref", "rad", "position reference"),
)
POSITION_EVENTS = ("speed_limit",)
_PO_K, _PO_WMAX = POSITION_PARAMS.slot("K_theta"), POSITION_PARAMS.slot("w_max")
_PO_REF = POSITION_PARAMS.table_start
_PO_O_W, _PO_O_REF = POSITION_OUTPUTS.slot("w_ref"), POSITION_OUTPUTS.slot("theta_ref")


@jit
def position_p_step(t, T_s, u, p, s, y):
    """w_ref = K_theta (theta_ref(t) - theta) clipped to [-w_max, w_max] (event
    ``speed_limit``)."""
    theta_ref = table_at(p, _PO_REF, t)
    w_ref, limited = _clip(p[_PO_K] * (theta_ref - u[0]), p[_PO_WMAX])
    y[_PO_O_W], y[_PO_O_REF] = w_ref, theta_ref
    return 1 if limited else 0


class PositionP(SampledPart):
    """Proportional position loop feeding a speed PI: the P-PI cascade of servo drives
    (Fig. 12's position controller; the paper's own design is in its [25]).

    Why P-PI and not PD on torque: the speed PI's integral holds a constant load torque with
    zero speed error, and at standstill zero speed reference means zero position error, so the
    cascade rejects a constant load with no steady-state position error (Fig. 14 shows the load
    rejected), whereas a PD leaves tau_L / K_P; the speed limit ``w_max`` comes free as the
    clip on the speed reference; the speed loop is tuned and tested on its own. Defaults:
    ``K_theta`` = POSITION_GAIN = 10 1/s (a fifth of the speed PI's root), ``w_max`` = the
    rated speed 361 rad/s. No speed feed-forward: a ramp reference is followed with the lag
    w / K_theta. The reference is in encoder angle (an encoder offset shifts the zero).
    """

    SOURCE = "P position loop of the P-PI cascade (Fig. 12)"

    PARAMS, INPUTS, OUTPUTS = POSITION_PARAMS, POSITION_INPUTS, POSITION_OUTPUTS
    DEFAULTS: ClassVar[dict] = {"K_theta": POSITION_GAIN, "w_max": RATED_SPEED}
    EVENTS = POSITION_EVENTS
    step = position_p_step
