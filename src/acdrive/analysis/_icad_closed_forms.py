"""Closed forms of the multivariable structure function printed in the papers, against which the
state-space ICAD is checked: the cage IM's gamma (Amezquita-Brooks et al. (8)), its value and
crossing at the rotor speed, the least gain margin G_M,min, and the PMSG's gamma (Ugalde-Loo et
al.).
"""

from __future__ import annotations

import math

import numpy as np

from acdrive._arguments import REAL, Array, Instance, checked
from acdrive.errors import InputError, require_finite
from acdrive.machines._induction import IMParams
from acdrive.machines._pmsm import PMSGParams

# ---------------------------------------------------------------------------------------------
# closed forms of the papers


@checked(p=Instance(IMParams), w_r=REAL, w=Array())
def im_msf_closed_form(p: IMParams, w_r: float, w) -> np.ndarray:
    """gamma(j w) of the IM, Ugalde-Loo et al. (60)-(61) (real numerator over d_gamma^2)."""
    w_r = require_finite("w_r", w_r)
    w = np.asarray(w, dtype=float)
    re, im = im_dgamma_re_im(p, w_r, w)
    Lr, Lm, Rr = p.L_r, p.L_m, p.R_r
    return Lr**2 * Lm**4 * Rr**2 * w_r**2 * w**2 / (re + 1j * im) ** 2


@checked(p=Instance(IMParams), w_r=REAL, w=Array())
def im_dgamma_re_im(p: IMParams, w_r: float, w):
    """(Re, Im) of d_gamma(j w), Ugalde-Loo et al. (61), the denominator of the IM's
    multivariable structure function (60); ``w`` a number or an array."""
    sig, Ls, Lr, Lm, Rs, Rr = p.sigma, p.L_s, p.L_r, p.L_m, p.R_s, p.R_r
    re = (
        -(Lr**3) * Rs * w_r**2
        + 2 * w**2 * sig * Ls * Lr**2 * Rr
        + w**2 * Lr**3 * Rs
        - Lr * Rs * Rr**2
        + w**2 * Lr * Lm**2 * Rr
    )
    im = (
        -w * sig * Ls * Lr**3 * w_r**2
        + w**3 * sig * Ls * Lr**3
        - w * sig * Ls * Lr * Rr**2
        - 2 * w * Lr**2 * Rs * Rr
        - w * Lm**2 * Rr**2
    )
    return re, im


@checked(p=Instance(IMParams), w_r=REAL)
def im_msf_at_rotor_speed(p: IMParams, w_r: float) -> complex:
    """gamma(j w_r) of the IM, Amezquita-Brooks et al. (14)."""
    w_r = require_finite("w_r", w_r)
    sig, Ls, Lr, Lm, Rs, Rr = p.sigma, p.L_s, p.L_r, p.L_m, p.R_s, p.R_r
    re = 2 * w_r**2 * sig * Ls * Lr**2 + w_r**2 * Lr * Lm**2 - Lr * Rs * Rr
    im = -w_r * sig * Ls * Lr * Rr - 2 * w_r * Lr**2 * Rs - w_r * Lm**2 * Rr
    return Lr**2 * Lm**4 * w_r**4 / complex(re, im) ** 2


@checked(p=Instance(IMParams), w_r=REAL)
def im_msf_magnitude_at_rotor_speed(p: IMParams, w_r: float) -> float:
    """|gamma(j w_r)| of the IM, Amezquita-Brooks et al. (18)."""
    w_r = require_finite("w_r", w_r)
    sig, Ls, Lr, Lm, Rs, Rr = p.sigma, p.L_s, p.L_r, p.L_m, p.R_s, p.R_r
    re = 2 * w_r**2 * sig * Ls * Lr**2 + w_r**2 * Lr * Lm**2 - Lr * Rs * Rr
    im = -w_r * sig * Ls * Lr * Rr - 2 * w_r * Lr**2 * Rs - w_r * Lm**2 * Rr
    return Lr**2 * Lm**4 * w_r**4 / math.sqrt((re**2 - im**2) ** 2 + 4 * re**2 * im**2)


@checked(p=Instance(IMParams), w_r=REAL)
def im_msf_positive_crossing(p: IMParams, w_r: float) -> tuple[float, float]:
    """(w, gamma(j w)) where the IM's MSF crosses the positive real axis (w_r != 0).

    Ugalde-Loo (61), (72)-(73): gamma(jw) = num / d^2 with d = re + j im is real positive where
    im = 0, w != 0. Solving im = 0 gives w^2 = [Psi (w_r^2 L_r^2 + R_r^2) + Upsilon]/(Psi L_r^2)
    with Psi = sigma L_s L_r, Upsilon = 2 L_r^2 R_s R_r + L_m^2 R_r^2. The printed F(3) of (73)
    divides by Psi^2 instead of Psi L_r and has 2 L_r R_s R_r in Upsilon; both are dimensionally
    inconsistent misprints (the printed F(2), where re = 0, is right).
    """
    w_r = require_finite("w_r", w_r)
    if w_r == 0.0:
        raise InputError("w_r", "gamma is identically zero at standstill (no crossing)")
    sig, Ls, Lr, Lm, Rs, Rr = p.sigma, p.L_s, p.L_r, p.L_m, p.R_s, p.R_r
    psi = sig * Ls * Lr
    upsilon = 2 * Lr**2 * Rs * Rr + Lm**2 * Rr**2
    w = math.sqrt(psi * (psi * (w_r**2 * Lr**2 + Rr**2) + upsilon)) / (psi * Lr)
    return w, float(im_msf_closed_form(p, w_r, np.array([w]))[0].real)


@checked(p=Instance(IMParams))
def gm_min(p: IMParams) -> float:
    """Structural gain-margin lower bound G_M,min of the IM, Amezquita-Brooks et al. (19)."""
    sig, Ls, Lr, Lm = p.sigma, p.L_s, p.L_r, p.L_m
    return (
        Lr**2 * Lm**4 / (Lr**2 * Lm**4 + 4 * sig * Lr**3 * Ls * Lm**2 + 4 * sig**2 * Lr**4 * Ls**2)
    )


@checked(p=Instance(PMSGParams), w_r=REAL, s=Array(complex=True))
def pmsg_msf(p: PMSGParams, w_r: float, s) -> np.ndarray:
    """gamma(s) of the PMSG, Ugalde-Loo et al. (18): -L_d L_q w_r^2 / ((L_q s + R_s)(L_d s + R_s))."""
    w_r = require_finite("w_r", w_r)
    s = np.asarray(s, dtype=complex)
    return -p.L_d * p.L_q * w_r**2 / ((p.L_q * s + p.R_s) * (p.L_d * s + p.R_s))
