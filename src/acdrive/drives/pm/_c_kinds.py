"""The C steps of the PM drive's controller parts (``drives.pm._control``: the speed PI, the
torque reference, the rotor-frame current controller) and of the MTPA / field-weakening operating
point they evaluate on line (``drives.pm._design``): each function mirrors its numba counterpart
operation for operation, its bisections with the same fixed number of steps.

Importing the module registers the three kinds in the engine's C registry
(``sim._ccode._kinds``), which imports it when it first looks one of them up: each class names
it as its ``C_MODULE`` (``_control.C_KINDS``), so the registry, below the drives, names no drive.
"""

from __future__ import annotations

from acdrive._frames import K_PEAK
from acdrive.drives.pm._control import PMSpeedPI, PMTorqueReference, RotorFrameCurrentController
from acdrive.drives.pm._design import (
    BEYOND_REACH,
    BISECTION_STEPS,
    CURRENT_LIMITED,
    VOLTAGE_LIMITED,
)
from acdrive.sim._ccode._kinds import CStep, CSupport, register
from acdrive.sim._ccode._kinds.common import LIMIT_RTOL_C, SPEED_PI

DESIGN = CSupport(
    "pm_design",
    f"""
#define ACD_K_PEAK ACD_R({K_PEAK!r}) /* sqrt(3/2): peak per phase -> space vector */
#define ACD_PM_BISECTION_STEPS {BISECTION_STEPS}
#define ACD_PM_CURRENT_LIMITED {CURRENT_LIMITED}
#define ACD_PM_VOLTAGE_LIMITED {VOLTAGE_LIMITED}
#define ACD_PM_BEYOND_REACH {BEYOND_REACH}
"""
    + r"""
/* (T): tau = n_p (psi_f i_q + (L_d - L_q) i_d i_q) */
static ACDRIVE_REAL acd_pm_torque(ACDRIVE_REAL n_p, ACDRIVE_REAL psi_f, ACDRIVE_REAL L_d,
                                  ACDRIVE_REAL L_q, ACDRIVE_REAL i_d, ACDRIVE_REAL i_q)
{
    return n_p * (psi_f * i_q + (L_d - L_q) * i_d * i_q);
}

/* (MTPA): the point of current magnitude i_s (L_q >= L_d) */
static void acd_pm_mtpa_point(ACDRIVE_REAL psi_f, ACDRIVE_REAL L_d, ACDRIVE_REAL L_q,
                              ACDRIVE_REAL i_s, ACDRIVE_REAL *i_d, ACDRIVE_REAL *i_q)
{
    ACDRIVE_REAL dL = L_q - L_d;
    *i_d = -ACD_R(2.0) * dL * i_s * i_s /
           (psi_f + ACD_SQRT(psi_f * psi_f + ACD_R(8.0) * dL * dL * i_s * i_s));
    *i_q = ACD_SQRT(acd_max(i_s * i_s - *i_d * *i_d, ACD_R(0.0)));
}

static ACDRIVE_REAL acd_pm_mtpa_torque(ACDRIVE_REAL n_p, ACDRIVE_REAL psi_f, ACDRIVE_REAL L_d,
                                       ACDRIVE_REAL L_q, ACDRIVE_REAL i_s)
{
    ACDRIVE_REAL i_d, i_q;
    acd_pm_mtpa_point(psi_f, L_d, L_q, i_s, &i_d, &i_q);
    return acd_pm_torque(n_p, psi_f, L_d, L_q, i_d, i_q);
}

/* current magnitude of the MTPA point giving torque tau >= 0 (bisection on [0, i_max]) */
static ACDRIVE_REAL acd_pm_mtpa_current(ACDRIVE_REAL n_p, ACDRIVE_REAL psi_f, ACDRIVE_REAL L_d,
                                        ACDRIVE_REAL L_q, ACDRIVE_REAL tau, ACDRIVE_REAL i_max)
{
    ACDRIVE_REAL lo = ACD_R(0.0), hi = i_max;
    int step;
    if (acd_pm_mtpa_torque(n_p, psi_f, L_d, L_q, i_max) <= tau) {
        return i_max;
    }
    for (step = 0; step < ACD_PM_BISECTION_STEPS; ++step) {
        ACDRIVE_REAL mid = ACD_R(0.5) * (lo + hi);
        if (acd_pm_mtpa_torque(n_p, psi_f, L_d, L_q, mid) < tau) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return ACD_R(0.5) * (lo + hi);
}

/* (V): psi_max = (margin v_max - R_s i_max) / |w_e| (infinite at standstill) */
static ACDRIVE_REAL acd_pm_flux_limit(ACDRIVE_REAL R_s, ACDRIVE_REAL v_max, ACDRIVE_REAL margin,
                                      ACDRIVE_REAL i_max, ACDRIVE_REAL w_e)
{
    if (w_e == ACD_R(0.0)) {
        return ACD_INF;
    }
    return (margin * v_max - R_s * i_max) / ACD_FABS(w_e);
}

/* (i_d, i_q) of the flux psi_max e^{j phi} */
static void acd_pm_on_ellipse(ACDRIVE_REAL psi_f, ACDRIVE_REAL L_d, ACDRIVE_REAL L_q,
                              ACDRIVE_REAL psi_max, ACDRIVE_REAL phi, ACDRIVE_REAL *i_d,
                              ACDRIVE_REAL *i_q)
{
    *i_d = (psi_max * ACD_COS(phi) - psi_f) / L_d;
    *i_q = psi_max * ACD_SIN(phi) / L_q;
}

/* phi of the maximum torque on the flux ellipse |psi_dq| = psi_max */
static ACDRIVE_REAL acd_pm_mtpv_angle(ACDRIVE_REAL psi_f, ACDRIVE_REAL L_d, ACDRIVE_REAL L_q,
                                      ACDRIVE_REAL psi_max)
{
    ACDRIVE_REAL a = psi_f / L_d;
    ACDRIVE_REAL b = psi_max * (ACD_R(1.0) / L_q - ACD_R(1.0) / L_d);
    ACDRIVE_REAL c = ACD_R(2.0) * b / (a + ACD_SQRT(a * a + ACD_R(8.0) * b * b));
    return ACD_ACOS(acd_min(acd_max(c, -ACD_R(1.0)), ACD_R(1.0)));
}

/* phi of the smallest current on the flux ellipse (L_q >= L_d) */
static ACDRIVE_REAL acd_pm_min_current_angle(ACDRIVE_REAL psi_f, ACDRIVE_REAL L_d,
                                             ACDRIVE_REAL L_q, ACDRIVE_REAL psi_max)
{
    ACDRIVE_REAL k = ACD_R(1.0) / (L_q * L_q) - ACD_R(1.0) / (L_d * L_d), c;
    if (k == ACD_R(0.0)) {
        return ACD_R(0.0);
    }
    c = -psi_f / (L_d * L_d * psi_max * k);
    return ACD_ACOS(acd_min(acd_max(c, -ACD_R(1.0)), ACD_R(1.0)));
}

/* current reference for torque tau with |i| <= i_max and |psi_dq| <= psi_max: MTPA, then field
   weakening (drives.pm._design.operating_point); returns the ACD_PM_* flags */
static int acd_pm_operating_point(ACDRIVE_REAL n_p, ACDRIVE_REAL psi_f, ACDRIVE_REAL L_d,
                                  ACDRIVE_REAL L_q, ACDRIVE_REAL tau, ACDRIVE_REAL i_max,
                                  ACDRIVE_REAL psi_max, ACDRIVE_REAL *i_d_out,
                                  ACDRIVE_REAL *i_q_out)
{
    ACDRIVE_REAL sign = tau >= ACD_R(0.0) ? ACD_R(1.0) : -ACD_R(1.0);
    ACDRIVE_REAL T = ACD_FABS(tau), i_s, i_d, i_q, phi_top, phi, phi_low, a, b, lo, hi, f, q;
    int flags = 0, step;
    i_s = acd_pm_mtpa_current(n_p, psi_f, L_d, L_q, T, i_max);
    acd_pm_mtpa_point(psi_f, L_d, L_q, i_s, &i_d, &i_q);
    if (acd_pm_torque(n_p, psi_f, L_d, L_q, i_d, i_q) < T * (ACD_R(1.0) - ACD_R(1e-12))) {
        flags |= ACD_PM_CURRENT_LIMITED;
        T = acd_pm_torque(n_p, psi_f, L_d, L_q, i_d, i_q);
    }
    f = L_d * i_d + psi_f;
    q = L_q * i_q;
    if (ACD_SQRT(f * f + q * q) <= psi_max) {
        *i_d_out = i_d;
        *i_q_out = sign * i_q;
        return flags;
    }
    flags |= ACD_PM_VOLTAGE_LIMITED;
    phi_top = acd_pm_mtpv_angle(psi_f, L_d, L_q, psi_max);
    if (n_p * psi_max * ACD_SIN(phi_top) *
            (psi_f / L_d + psi_max * (ACD_R(1.0) / L_q - ACD_R(1.0) / L_d) * ACD_COS(phi_top)) >
        T) {
        lo = ACD_R(0.0); /* the rising branch: torque increases with phi */
        hi = phi_top;
        for (step = 0; step < ACD_PM_BISECTION_STEPS; ++step) {
            ACDRIVE_REAL mid = ACD_R(0.5) * (lo + hi);
            acd_pm_on_ellipse(psi_f, L_d, L_q, psi_max, mid, &a, &b);
            if (acd_pm_torque(n_p, psi_f, L_d, L_q, a, b) < T) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        phi = ACD_R(0.5) * (lo + hi);
    } else {
        phi = phi_top;
    }
    acd_pm_on_ellipse(psi_f, L_d, L_q, psi_max, phi, &i_d, &i_q);
    if (i_d * i_d + i_q * i_q <= i_max * i_max) {
        *i_d_out = i_d;
        *i_q_out = sign * i_q;
        return flags;
    }
    flags |= ACD_PM_CURRENT_LIMITED;
    phi_low = acd_min(acd_pm_min_current_angle(psi_f, L_d, L_q, psi_max), phi);
    acd_pm_on_ellipse(psi_f, L_d, L_q, psi_max, phi_low, &a, &b);
    if (a * a + b * b > i_max * i_max) {
        *i_d_out = a;
        *i_q_out = sign * b;
        return flags | ACD_PM_BEYOND_REACH;
    }
    lo = phi_low; /* |i| grows with phi here */
    hi = phi;
    for (step = 0; step < ACD_PM_BISECTION_STEPS; ++step) {
        ACDRIVE_REAL mid = ACD_R(0.5) * (lo + hi);
        acd_pm_on_ellipse(psi_f, L_d, L_q, psi_max, mid, &a, &b);
        if (a * a + b * b < i_max * i_max) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    acd_pm_on_ellipse(psi_f, L_d, L_q, psi_max, lo, &i_d, &i_q);
    *i_d_out = i_d;
    *i_q_out = sign * i_q;
    return flags;
}

/* the largest torque within |i| <= i_max and |psi_dq| <= psi_max (0 beyond reach) */
static ACDRIVE_REAL acd_pm_available_torque(ACDRIVE_REAL n_p, ACDRIVE_REAL psi_f,
                                            ACDRIVE_REAL L_d, ACDRIVE_REAL L_q,
                                            ACDRIVE_REAL i_max, ACDRIVE_REAL psi_max)
{
    ACDRIVE_REAL i_d, i_q;
    int flags = acd_pm_operating_point(n_p, psi_f, L_d, L_q, ACD_INF, i_max, psi_max, &i_d, &i_q);
    if (flags & ACD_PM_BEYOND_REACH) {
        return ACD_R(0.0);
    }
    return acd_pm_torque(n_p, psi_f, L_d, L_q, i_d, i_q);
}
""",
)

register(
    PMTorqueReference,
    CStep(
        source="torque -> rotor-frame current reference: MTPA, field weakening on (V)",
        body=r"""
    ACDRIVE_REAL n_p = p->n_p, L_d = p->L_d, L_q = p->L_q, psi_f = ACD_K_PEAK * p->psi_m;
    ACDRIVE_REAL w_e = n_p * u->w, i_d, i_q, psi_max;
    uint32_t events = 0u;
    int flags;
    psi_max = acd_pm_flux_limit(p->R_s, p->V_dc / ACD_SQRT(ACD_R(2.0)), p->margin, p->i_max, w_e);
    flags = acd_pm_operating_point(n_p, psi_f, L_d, L_q, u->tau_ref, p->i_max, psi_max, &i_d,
                                   &i_q);
    y->i_dq_ref = acd_c(i_d, i_q);
    y->tau_lim = acd_pm_torque(n_p, psi_f, L_d, L_q, i_d, i_q);
    y->psi_max = acd_min(ACD_HUGE, psi_max);
    if (flags & ACD_PM_CURRENT_LIMITED) {
        events |= ACD_PM_TORQUE_REFERENCE_CURRENT_LIMIT;
    }
    if (flags & ACD_PM_VOLTAGE_LIMITED) {
        events |= ACD_PM_TORQUE_REFERENCE_VOLTAGE_LIMIT;
    }
    if (flags & ACD_PM_BEYOND_REACH) {
        events |= ACD_PM_TORQUE_REFERENCE_BEYOND_REACH;
    }
    return events;
""",
        support=(DESIGN,),
    ),
)

register(
    PMSpeedPI,
    CStep(
        source="Bodson (25) limited to min(tau_max, the torque available at the measured speed)",
        body=r"""
    ACDRIVE_REAL n_p = p->n_p, w = u->w, psi_max, limit;
    int limited;
    psi_max = acd_pm_flux_limit(p->R_s, p->V_dc / ACD_SQRT(ACD_R(2.0)), p->margin, p->i_max,
                                n_p * w);
    limit = acd_min(p->tau_max, acd_pm_available_torque(n_p, ACD_K_PEAK * p->psi_m, p->L_d,
                                                         p->L_q, p->i_max, psi_max));
    y->tau_ref = acd_speed_pi(p->K_P, p->K_I, p->K_F, &s->e_int, u->w_ref, w, -limit, limit,
                              T_s, &limited);
    y->tau_avail = limit;
    return limited ? ACD_PM_SPEED_PI_TORQUE_LIMIT : 0u;
""",
        support=(DESIGN, SPEED_PI),
    ),
)

register(
    RotorFrameCurrentController,
    CStep(
        source="rotor-frame PI per axis with decoupling, back-EMF feed-forward and "
        "back-calculation anti-windup at V_dc / sqrt(2)",
        body=r"""
    ACDRIVE_REAL n_p = p->n_p, theta_e = n_p * u->theta, w_e = n_p * u->w;
    ACDRIVE_REAL e_d, e_q, k, ff_d, ff_q, v_d, v_q, v_max, magnitude, scale, a_d, a_q, r_d, r_q;
    ACDRIVE_REAL angle;
    acd_complex rotor = acd_c(ACD_COS(theta_e), ACD_SIN(theta_e)), i_dq;
    uint32_t events = 0u;
    i_dq = acd_cmul(u->i_s, acd_conj(rotor));
    e_d = u->i_dq_ref.re - i_dq.re;
    e_q = u->i_dq_ref.im - i_dq.im;
    k = p->decouple;
    ff_d = -k * w_e * p->L_q * i_dq.im;
    ff_q = k * w_e * (p->L_d * i_dq.re + ACD_K_PEAK * p->psi_m);
    v_d = p->K_P_d * e_d + s->x.re + ff_d;
    v_q = p->K_P_q * e_q + s->x.im + ff_q;
    v_max = p->V_dc / ACD_SQRT(ACD_R(2.0));
    magnitude = ACD_SQRT(v_d * v_d + v_q * v_q);
    scale = ACD_R(1.0);
    if (magnitude > v_max + ACD_LIMIT_RTOL * v_max) {
        scale = v_max / magnitude;
        events = ACD_ROTOR_FRAME_CURRENT_CONTROLLER_SATURATED;
    }
    a_d = scale * v_d;
    a_q = scale * v_q;
    r_d = e_d + (p->K_P_d > ACD_R(0.0) ? (a_d - v_d) / p->K_P_d : ACD_R(0.0));
    r_q = e_q + (p->K_P_q > ACD_R(0.0) ? (a_q - v_q) / p->K_P_q : ACD_R(0.0));
    s->x.re += T_s * p->K_I_d * r_d;
    s->x.im += T_s * p->K_I_q * r_q;
    angle = theta_e + p->advance * w_e * T_s;
    y->v_ref = acd_cmul(acd_c(a_d, a_q), acd_c(ACD_COS(angle), ACD_SIN(angle)));
    y->v_dq_ref = acd_c(a_d, a_q);
    y->v_dq_wanted = acd_c(v_d, v_q);
    y->i_dq = i_dq;
    return events;
""",
        support=(DESIGN, LIMIT_RTOL_C),
    ),
)
