"""Reduced-order flux observer with speed and position adaptation for synchronous machines (PMSM,
SyRM), in estimated rotor coordinates; the observer framework of Hinkkanen, Saarakkala, Awan,
Mölsä, Tuovinen, "Observers for sensorless synchronous motor drives: framework for design and
analysis", IEEE Trans. Ind. Appl. 54(6), 2018 (the reduced-order observer with a complex gain
pair k_1, k_2 and an angle-error signal driving a phase-locked loop), derived here for acdrive's
machine model (``machines._pmsm_part``: power-invariant space vectors, psi_pm = sqrt(3/2) psi_m,
motor reference arrows). The labels (O1)-(P2) are this module's own, not the paper's equation
numbers: the error dynamics and the gain pair (G1) below are derived from the machine model here.
The framework's gain pair uses an auxiliary flux in the place of a; a as defined in (O2) carries
the saliency term (L_d - L_q) conj(i), which keeps the decoupling exact at a loaded operating
point of a salient machine (without it the designed poles are missed:
``tests/test_flux_observer.py``).

**Model.** In coordinates at the estimated electrical angle theta (speed w_c = dtheta/dt) the
stator flux obeys the voltage equation and the current model (hats: the observer's estimates of
R_s, L_d, L_q, psi_pm):

    dpsi/dt = v - R_s i - j w_c psi                                          (voltage model)
    psi_i = L_d i_d + psi_pm + j L_q i_q                                      (current model)

**Observer.** With e = psi_i - psi_hat, the error of the estimated flux against the current model,

    dpsi_hat/dt = v - R_s i - j w_c psi_hat + k_1 e + k_2 conj(e)                        (O1)
    a = psi_pm + (L_d - L_q) conj(i),   eps = -Im(e / a)                                  (O2)
    w_c = w_hat + k_theta eps,   dw_hat/dt = k_w eps,   dtheta/dt = w_c                  (O3)

**Error dynamics** (derived here; the framework's decoupling condition). Linearised at constant
electrical speed w with an angle error theta~ = theta_true - theta and a flux error psi~ = psi -
psi_hat (the true flux in estimated coordinates), the error signal of a current measured in the
estimated frame is e = psi~ - j a theta~ to first order (a as in (O2), evaluated at the operating
point: for a non-salient machine a = psi_pm, the magnet flux). The gain pair

    k_2 = k_1 a / conj(a)                                                                (G1)

makes the correction k_1 e + k_2 conj(e) = 2 k_1 a Re(e / a) blind to theta~, so the flux error
obeys an autonomous second-order system: with z = psi~ / a and k_1 = sigma real,

    dz/dt = -j w z - 2 sigma Re(z),   characteristic polynomial s^2 + 2 sigma s + w^2      (P1)

and eps = theta~ - Re(psi~ / (j a)) is theta~ plus a term of the (decaying) flux error, so

    d theta~/dt = w~ - k_theta eps,   d w~/dt = -k_w eps (w~ = w - w_hat, constant speed):
    characteristic polynomial s^2 + k_theta s + k_w                                        (P2)

**Design.** From the flux-observer bandwidth alpha_f, the speed-adaptation bandwidth alpha_w and a
high-speed damping zeta_inf:

    sigma = alpha_f + zeta_inf |w_hat|,   k_theta = 2 alpha_w,   k_w = alpha_w^2            (G2)

so (P2) has a double pole at -alpha_w and (P1) the poles -sigma +- sqrt(sigma^2 - w^2): both at
real part -sigma once |w| >= sigma, damping sigma / |w| -> zeta_inf at high speed. Below
|w| = sigma the slower flux pole is -sigma + sqrt(sigma^2 - w^2) ~ -w^2 / (2 sigma): the
model-based observer loses observability at zero speed (a pole at s = 0 for w = 0). The
lowest speed it is designed for is |w| = alpha_f: there the slower flux pole is
-(1 + zeta_inf - sqrt((1 + zeta_inf)^2 - 1)) alpha_f (-0.38 alpha_f for zeta_inf = 0.5), and
above it the flux error decays at least that fast. Standstill and lower speeds need signal
injection, which this part does not do.

**Discretisation.** Forward Euler, once per sample: the estimates at sample k follow from those at
k-1, the current measured at k-1 and the voltage command applied over [k-1, k]. That voltage is
constant in the stationary frame over the sample, so it is taken into the estimated frame at the
sample's middle angle theta_{k-1} + w_c T_s / 2 and scaled by sin(x)/x, x = w_c T_s / 2: the exact
mean of the rotating voltage, so a machine in steady state is a fixed point of the discrete
observer at any speed. The error dynamics then have the poles z = 1 + s T_s (to first order in
T_s) of the poles s of (P1) and (P2). For the pair of (P1) with |w| >= sigma,
|1 + s T_s|^2 = 1 - 2 sigma T_s + w^2 T_s^2: the poles move out from the circle of radius
e^{-sigma T_s} as the speed grows, and the discrete observer is unstable above
w^2 T_s > 2 sigma, i.e. |w| T_s > 2 zeta_inf at high speed (zeta_inf = 0.5: one radian of
electrical angle per sample). ``check_run`` refuses a sample time for which the observer is
unstable at the speed ``w_max``.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from acdrive._frames import K_PEAK
from acdrive._jit import jit
from acdrive.core._parts import SampledPart
from acdrive.core._signals import Layout, Relation, cplx, real
from acdrive.errors import InputError

PARAMS = Layout(
    real("R_s", "ohm", "stator resistance (observer's estimate)", "positive"),
    real("L_d", "H", "direct-axis inductance (observer's estimate)", "positive"),
    real("L_q", "H", "quadrature-axis inductance (observer's estimate)", "positive"),
    real("psi_m", "Wb", "magnet flux linkage, peak per phase (observer's estimate)", "nonnegative"),
    real("n_p", "", "pole pairs", "count"),
    real("alpha_f", "rad/s", "flux-observer bandwidth: sigma at zero speed, (G2)", "positive"),
    real("alpha_w", "rad/s", "speed-adaptation bandwidth: double pole of (P2)", "positive"),
    real("zeta_inf", "", "damping of the flux-observer poles at high speed, (G2)", "nonnegative"),
    real("w_max", "rad/s", "highest electrical speed the run may reach (check_run)", "positive"),
    relations=(
        Relation(
            ("L_d", "L_q", "psi_m"),
            "the observer needs a magnet or saliency: psi_m > 0 or L_d != L_q",
            lambda L_d, L_q, psi_m: psi_m > 0.0 or L_d != L_q,
            c="{psi_m} > 0.0 || {L_d} != {L_q}",
        ),
    ),
)
STATES = Layout(
    cplx("psi", "Wb", "estimated stator flux, estimated rotor coordinates"),
    real("theta", "rad", "estimated electrical angle of the d axis"),
    real("w", "rad/s", "estimated electrical speed (the adaptation's integrator)"),
    cplx("d_psi", "V", "-R_s i - j w_c psi + k_1 e + k_2 conj(e) of the last sample"),
    real("w_c", "rad/s", "speed of the estimated frame over the coming sample"),
    real("eps", "rad", "angle-error signal of the last sample"),
)
INPUTS = Layout(
    cplx("i_s", "A", "sampled stator current, stationary frame"),
    cplx("v_s", "V", "voltage command applied over the last sample, stationary frame"),
)
OUTPUTS = Layout(
    real("theta", "rad", "estimated electrical angle, wrapped to (-pi, pi]"),
    real("w", "rad/s", "estimated electrical speed"),
    real("w_m", "rad/s", "estimated mechanical speed"),
    cplx("psi_dq", "Wb", "estimated stator flux in estimated rotor coordinates"),
    cplx("e", "Wb", "flux error e = psi_i - psi_hat of (O1)"),
    real("eps", "rad", "angle-error signal eps of (O2)"),
)
_R_S, _L_D, _L_Q, _PSI_M, _N_P, _ALPHA_F, _ALPHA_W, _ZETA = (
    PARAMS.slot(n)
    for n in ("R_s", "L_d", "L_q", "psi_m", "n_p", "alpha_f", "alpha_w", "zeta_inf")
)
_S_PSI, _S_THETA, _S_W, _S_DPSI, _S_WC, _S_EPS = (
    STATES.slot(n) for n in ("psi", "theta", "w", "d_psi", "w_c", "eps")
)
_I_S, _V_S = INPUTS.slot("i_s"), INPUTS.slot("v_s")
_Y_THETA, _Y_W, _Y_WM, _Y_PSI, _Y_E, _Y_EPS = (
    OUTPUTS.slot(n) for n in ("theta", "w", "w_m", "psi_dq", "e", "eps")
)


@jit
def wrap_angle(angle):
    """``angle`` wrapped to (-pi, pi]."""
    return np.pi - (np.pi - angle) % (2.0 * np.pi)


@jit
def flux_observer_step(t, T_s, u, p, s, y):
    """One sample of (O1)-(O3) with the gains (G1)-(G2), forward Euler (module docstring).

    First the estimates advance from the previous sample to this one with the terms kept then
    and the voltage applied over the sample (taken into the estimated frame at the sample's
    middle angle, with its mean's factor sin(x)/x); then this sample's current gives the error
    e, the signal eps and the terms of the next advance.
    """
    L_d, L_q, n_p = p[_L_D], p[_L_Q], p[_N_P]
    psi_pm = K_PEAK * p[_PSI_M]
    k_theta = 2.0 * p[_ALPHA_W]
    k_w = p[_ALPHA_W] * p[_ALPHA_W]
    # advance from the previous sample (forward Euler)
    w_c = s[_S_WC]
    x = 0.5 * T_s * w_c
    mean = 1.0 if x == 0.0 else np.sin(x) / x
    middle = s[_S_THETA] + x
    v_s = complex(u[_V_S], u[_V_S + 1])
    v = mean * v_s * complex(np.cos(middle), -np.sin(middle))
    psi = complex(s[_S_PSI], s[_S_PSI + 1]) + T_s * (v + complex(s[_S_DPSI], s[_S_DPSI + 1]))
    theta = wrap_angle(s[_S_THETA] + T_s * w_c)
    w = s[_S_W] + T_s * k_w * s[_S_EPS]
    # this sample's error (O1)-(O2) and the terms of the next advance
    i_dq = complex(u[_I_S], u[_I_S + 1]) * complex(np.cos(theta), -np.sin(theta))
    e = complex(L_d * i_dq.real + psi_pm, L_q * i_dq.imag) - psi
    a = complex(psi_pm + (L_d - L_q) * i_dq.real, -(L_d - L_q) * i_dq.imag)
    aa = a.real * a.real + a.imag * a.imag
    sigma = p[_ALPHA_F] + p[_ZETA] * abs(w)
    if aa > 0.0:
        ratio = e * complex(a.real, -a.imag) / aa  # e / a
        eps = -ratio.imag
        correction = 2.0 * sigma * ratio.real * a  # k_1 e + k_2 conj(e), (G1)
    else:  # no magnet and no current: nothing tells the angle
        eps = 0.0
        correction = sigma * e
    w_c = w + k_theta * eps
    d_psi = -p[_R_S] * i_dq - complex(0.0, w_c) * psi + correction
    s[_S_PSI], s[_S_PSI + 1] = psi.real, psi.imag
    s[_S_THETA] = theta
    s[_S_W] = w
    s[_S_DPSI], s[_S_DPSI + 1] = d_psi.real, d_psi.imag
    s[_S_WC] = w_c
    s[_S_EPS] = eps
    y[_Y_THETA] = theta
    y[_Y_W] = w
    y[_Y_WM] = w / n_p
    y[_Y_PSI], y[_Y_PSI + 1] = psi.real, psi.imag
    y[_Y_E], y[_Y_E + 1] = e.real, e.imag
    y[_Y_EPS] = eps
    return 0


def flux_poles(alpha_f: float, zeta_inf: float, w: float) -> np.ndarray:
    """The designed poles of the flux error (P1) at electrical speed ``w``: the roots of
    s^2 + 2 sigma s + w^2 with sigma = alpha_f + zeta_inf |w| (G2)."""
    sigma = alpha_f + zeta_inf * abs(w)
    return np.roots([1.0, 2.0 * sigma, w * w])


def speed_poles(alpha_w: float) -> np.ndarray:
    """The designed poles of the angle and speed error (P2): a double pole at -alpha_w."""
    return np.array([-alpha_w, -alpha_w], dtype=complex)


class SynchronousFluxObserver(SampledPart):
    """Reduced-order flux observer with speed and position adaptation for a PMSM or SyRM
    (Hinkkanen et al. 2018; equations (O1)-(O3), design (G1)-(G2), forward Euler: module
    docstring).

    Parameters: the observer's estimates of the machine (``R_s``, ``L_d``, ``L_q``, ``psi_m``,
    ``n_p`` as ``machines.PMSGParams``), the flux-observer bandwidth ``alpha_f`` and the
    speed-adaptation bandwidth ``alpha_w`` (rad/s), the high-speed damping ``zeta_inf`` and the
    highest electrical speed ``w_max`` the run may reach. Inputs: the sampled stator current and
    the voltage command applied over the last sample, both in the stationary frame. The estimate
    starts at the magnet flux on the angle 0 and zero speed; ``initial={name: {"theta": ...,
    "w": ...}}`` starts it elsewhere.
    """

    SOURCE = (
        "reduced-order flux observer with speed adaptation, Hinkkanen et al., IEEE TIA 54(6) "
        "2018, forward Euler (control._flux_observer)"
    )

    PARAMS, STATES, INPUTS, OUTPUTS = PARAMS, STATES, INPUTS, OUTPUTS
    DEFAULTS: ClassVar[dict] = {"zeta_inf": 0.5}
    step = flux_observer_step

    def initial_state(self, **values):
        psi = values.pop("psi", K_PEAK * float(self.values["psi_m"]))
        return super().initial_state(psi=psi, **values)

    def check_run(self, sample_time: float) -> None:
        """Forward Euler keeps the flux-error poles of (P1) inside the unit circle while
        w^2 T_s < 2 sigma (module docstring); refused at ``w_max`` otherwise."""
        w_max = float(self.values["w_max"])
        sigma = float(self.values["alpha_f"]) + float(self.values["zeta_inf"]) * w_max
        if w_max * w_max * sample_time >= 2.0 * sigma:
            raise InputError(
                f"{self.name}.w_max",
                f"forward Euler makes the observer unstable at {w_max:g} rad/s with a sample "
                f"time of {sample_time:g} s (it needs w_max^2 T_s < 2 sigma = {2.0 * sigma:g} "
                f"rad/s: raise zeta_inf or alpha_f, or sample faster)",
            )

    @classmethod
    def from_params(cls, name, params, **values) -> SynchronousFluxObserver:
        """With the machine estimates taken from an ``acdrive.machines.PMSGParams`` (``values``
        give the bandwidths and override estimates, e.g. a detuned ``R_s``)."""
        estimates = {n: getattr(params, n) for n in ("R_s", "L_d", "L_q", "psi_m", "n_p")}
        return cls(name, **{**estimates, **values})
