"""C steps of Bodson's DFIM speed controller (``acdrive.control._bodson``) and the machine
relations it evaluates on line (``acdrive.machines._dfim``): each function mirrors its numba
counterpart operation for operation (same order, same complex algorithms), so the double build
rounds as the kernels do. The equation numbers are Bodson's."""

from __future__ import annotations

from acdrive.control._bodson import (
    MODE_CURRENT,
    MODE_VOLTAGE,
    SpeedController,
    SpeedEstimator,
    SupplyFrequencyEstimator,
    Synchroniser,
)
from acdrive.control._dfim import MIN_SUPPLY_FREQUENCY
from acdrive.sim._ccode._translate import c_step
from acdrive.sim._ccode._kinds import CStep, CSupport, register
from acdrive.sim._ccode._kinds.common import CLIP_MAGNITUDE, SPEED_PI, WRAP

#: constants of the laws, taken from the Python modules that define them
CONSTANTS = CSupport(
    "dfim_constants",
    f"""
#define ACD_DFIM_MIN_SUPPLY_FREQUENCY ACD_R({MIN_SUPPLY_FREQUENCY!r}) /* rad/s: below, (20) is not evaluated */
#define ACD_DFIM_MODE_VOLTAGE ACD_R({MODE_VOLTAGE!r})
#define ACD_DFIM_MODE_CURRENT ACD_R({MODE_CURRENT!r})
/* the machine estimates every DFIM law reads, from a part's parameter struct */
#define ACD_DFIM_ESTIMATES(p) (p)->R_s, (p)->R_r, (p)->L_s, (p)->L_r, (p)->M, (p)->n_p
#define ACD_DFIM_ESTIMATE_ARGS ACDRIVE_REAL R_s, ACDRIVE_REAL R_r, ACDRIVE_REAL L_s, \\
    ACDRIVE_REAL L_r, ACDRIVE_REAL M, ACDRIVE_REAL n_p
""",
)

IMPEDANCES = CSupport(
    "dfim_impedances",
    r"""
/* z / (j x) for real x: the division by Z_MS = j w_e M without Smith's branches (the numbers
   of acd_cdiv but the signs of zeros) */
static acd_complex acd_dfim_over_j(acd_complex z, ACDRIVE_REAL x)
{
    return acd_c(z.im / x, -z.re / x);
}

/* Z_S, Z_MS, Z_R, Z_MR of Bodson (11) at electrical frequency w_e and shaft speed w_m */
static void acd_dfim_impedances(ACD_DFIM_ESTIMATE_ARGS, ACDRIVE_REAL w_e, ACDRIVE_REAL w_m,
                                acd_complex Z[4])
{
    ACDRIVE_REAL w_slip = w_e - n_p * w_m;
    Z[0] = acd_c(R_s, w_e * L_s);
    Z[1] = acd_c(ACD_R(0.0), w_e * M);
    Z[2] = acd_c(R_r, w_slip * L_r);
    Z[3] = acd_c(ACD_R(0.0), w_slip * M);
}

/* steady-state rotor voltage that gives stator current i_s, Bodson (20) */
static acd_complex acd_dfim_rotor_voltage_for(ACD_DFIM_ESTIMATE_ARGS, ACDRIVE_REAL w_e,
                                              ACDRIVE_REAL w_m, acd_complex v_s, acd_complex i_s)
{
    acd_complex Z[4], det;
    acd_dfim_impedances(R_s, R_r, L_s, L_r, M, n_p, w_e, w_m, Z);
    det = acd_csub(acd_cmul(Z[0], Z[2]), acd_cmul(Z[1], Z[3]));
    return acd_dfim_over_j(acd_csub(acd_cmul(Z[2], v_s), acd_cmul(det, i_s)), Z[1].im);
}

/* steady-state rotor current that gives stator current i_s, Bodson (43) from (19) */
static acd_complex acd_dfim_rotor_current_for(ACD_DFIM_ESTIMATE_ARGS, ACDRIVE_REAL w_e,
                                              ACDRIVE_REAL v_s, acd_complex i_s)
{
    acd_complex Z_S = acd_c(R_s, w_e * L_s), Z_MS = acd_c(ACD_R(0.0), w_e * M);
    (void)R_r;
    (void)L_r;
    (void)n_p;
    return acd_dfim_over_j(acd_csub(acd_c(v_s, ACD_R(0.0)), acd_cmul(Z_S, i_s)), Z_MS.im);
}
""",
    needs=(CONSTANTS,),
)

STATOR_CURRENT = CSupport(
    "dfim_stator_current",
    r"""
/* stator current for torque tau and reactive power Q with real v_s > 0, Bodson (22) (24), the
   minus root in the cancellation-free form b / (a + sqrt(a^2 - b)); *limited = 1 where the
   radicand is negative (clamped to zero) */
static acd_complex acd_dfim_stator_current_command(ACDRIVE_REAL R_s, ACDRIVE_REAL n_p,
                                                   ACDRIVE_REAL w_e, ACDRIVE_REAL v_s,
                                                   ACDRIVE_REAL tau, ACDRIVE_REAL Q, int *limited)
{
    ACDRIVE_REAL a = v_s / (ACD_R(2.0) * R_s);
    ACDRIVE_REAL b = w_e * tau / (n_p * R_s) + Q * Q / (v_s * v_s);
    ACDRIVE_REAL radicand = a * a - b, i_d;
    *limited = radicand < ACD_R(0.0);
    if (*limited) {
        radicand = ACD_R(0.0);
        b = a * a;
    }
    i_d = b / (a + ACD_SQRT(radicand));
    return acd_c(i_d - ACD_R(0.0) / v_s, ACD_R(0.0) - Q / v_s);
}

/* stator current for torque tau and reactive power Q when R_s = 0, Bodson (38) */
static acd_complex acd_dfim_stator_current_lossless(ACDRIVE_REAL n_p, ACDRIVE_REAL w_e,
                                                    ACDRIVE_REAL v_s, ACDRIVE_REAL tau,
                                                    ACDRIVE_REAL Q)
{
    return acd_c(w_e * tau / (v_s * n_p) - ACD_R(0.0) / v_s, ACD_R(0.0) - Q / v_s);
}
""",
)

TORQUE_LIMITS = CSupport(
    "dfim_torque_limits",
    r"""
/* torque for a real stator current i_d (Q = 0), from Bodson (31) */
static ACDRIVE_REAL acd_dfim_torque_at(ACDRIVE_REAL R_s, ACDRIVE_REAL n_p, ACDRIVE_REAL w_e,
                                       ACDRIVE_REAL v_s, ACDRIVE_REAL i_d)
{
    return n_p / w_e * (v_s * i_d - R_s * i_d * i_d);
}

/* admissible torque interval [*tau_lo, *tau_hi] with Q = 0: the tightest of Bodson's case 1
   limits (29)-(37) (machines._dfim.torque_limits_case1 and torque_window); returns 0 when the
   rotor current limit is below the magnetising need (no torque is then admissible) */
static int acd_dfim_torque_window(ACD_DFIM_ESTIMATE_ARGS, ACDRIVE_REAL w_e, ACDRIVE_REAL v_s,
                                  ACDRIVE_REAL i_s_max, ACDRIVE_REAL i_r_max,
                                  ACDRIVE_REAL *tau_lo, ACDRIVE_REAL *tau_hi)
{
    ACDRIVE_REAL t1 = n_p / w_e * v_s * v_s / (ACD_R(4.0) * R_s);
    ACDRIVE_REAL t2 = acd_dfim_torque_at(R_s, n_p, w_e, v_s, i_s_max);
    ACDRIVE_REAL m2 = acd_dfim_torque_at(R_s, n_p, w_e, v_s, -i_s_max);
    ACDRIVE_REAL wM2 = w_e * w_e * M * M;
    ACDRIVE_REAL a_1 = (R_s * R_s + w_e * w_e * L_s * L_s) / wM2;
    ACDRIVE_REAL a_2 = R_s * v_s / wM2;
    ACDRIVE_REAL a_3 = i_r_max * i_r_max - v_s * v_s / wM2;
    ACDRIVE_REAL disc = a_2 * a_2 + a_1 * a_3;
    ACDRIVE_REAL t3, m3;
    int feasible = disc >= ACD_R(0.0) && a_3 >= ACD_R(0.0);
    (void)R_r;
    (void)L_r;
    if (!feasible) {
        t3 = ACD_R(0.0);
        m3 = ACD_R(0.0);
    } else {
        ACDRIVE_REAL i_s_rmax = (a_2 + ACD_SQRT(disc)) / a_1;
        ACDRIVE_REAL i_s_rmin = (a_2 - ACD_SQRT(disc)) / a_1;
        ACDRIVE_REAL i_peak = v_s / (ACD_R(2.0) * R_s); /* beyond it (31) falls again */
        t3 = acd_dfim_torque_at(R_s, n_p, w_e, v_s, acd_min(i_s_rmax, i_peak));
        m3 = acd_dfim_torque_at(R_s, n_p, w_e, v_s, i_s_rmin);
    }
    *tau_hi = acd_min(t1, acd_min(t2, t3));
    *tau_lo = acd_max(m2, m3);
    return feasible;
}

/* torque limits for R_s = 0 and any Q, Bodson case 2 (40)-(42): -1 where Q alone violates one */
static void acd_dfim_torque_limit_case2(ACD_DFIM_ESTIMATE_ARGS, ACDRIVE_REAL w_e,
                                        ACDRIVE_REAL v_s, ACDRIVE_REAL Q, ACDRIVE_REAL i_s_max,
                                        ACDRIVE_REAL i_r_max, ACDRIVE_REAL *tau_max_2,
                                        ACDRIVE_REAL *tau_max_3)
{
    ACDRIVE_REAL k = w_e / (v_s * n_p);
    ACDRIVE_REAL q = Q / v_s;
    ACDRIVE_REAL rest_s = i_s_max * i_s_max - q * q;
    ACDRIVE_REAL m = L_s / M;
    ACDRIVE_REAL r = v_s / (w_e * M) - m * Q / v_s;
    ACDRIVE_REAL rest_r = i_r_max * i_r_max - r * r;
    (void)R_s;
    (void)R_r;
    (void)L_r;
    *tau_max_2 = rest_s >= ACD_R(0.0) ? ACD_SQRT(rest_s) / k : -ACD_R(1.0);
    *tau_max_3 = rest_r >= ACD_R(0.0) ? ACD_SQRT(rest_r) / (m * k) : -ACD_R(1.0);
}
""",
)

register(
    SpeedEstimator,
    c_step(
        SpeedEstimator,
        source="Bodson IV-A: speed from the encoder, backward difference, first-order filter",
    ),
)

register(
    SupplyFrequencyEstimator,
    c_step(
        SupplyFrequencyEstimator,
        source="supply frequency from the grid voltage's phase advance per sample, filtered",
    ),
)

SYNC_SUPPORT = CSupport(
    "synchroniser",
    r"""
static void acd_synchroniser_set_theta_adj(acd_synchroniser_state *s, ACDRIVE_REAL theta_adj)
{
    s->theta_adj = theta_adj;
    s->adj = acd_c(ACD_COS(theta_adj), ACD_SIN(theta_adj));
}
""",
)

register(
    Synchroniser,
    CStep(
        source="Bodson (28): grid synchronisation with the stator open",
        body=r"""
    uint32_t events = 0u;
    if (s->started == ACD_R(0.0)) { /* first sample: estimates not ready, hold */
        s->started = ACD_R(1.0);
        s->closed = p->enabled != ACD_R(0.0) ? ACD_R(0.0) : ACD_R(1.0);
        acd_synchroniser_set_theta_adj(s, p->theta_adj);
        s->m_adj = p->m_adj;
    } else if (s->closed == ACD_R(0.0)) {
        acd_complex v_g = u->v_g;
        ACDRIVE_REAL w_e = u->w_e;
        ACDRIVE_REAL v_g_mag = acd_cabs(v_g);
        if (v_g_mag < p->v_min || w_e < ACD_DFIM_MIN_SUPPLY_FREQUENCY) {
            events |= ACD_SYNCHRONISER_SUPPLY_LOST;
        } else {
            acd_complex v_s = u->v_s, v_r, frame, rotor;
            ACDRIVE_REAL gain = p->gain, angle;
            int close = 0;
            if (acd_cabs(v_s) > p->v_min) {
                /* v_S / v_G = rho e^{j phi} drives theta_adj and ln m_adj */
                acd_complex ratio = acd_cdiv(v_s, v_g);
                ACDRIVE_REAL rho = acd_cabs(ratio), phi = acd_carg(ratio);
                acd_synchroniser_set_theta_adj(s, acd_wrap(s->theta_adj - gain * T_s * phi));
                s->m_adj *= ACD_EXP(-gain * T_s * ACD_LOG(rho));
                if (ACD_FABS(rho - ACD_R(1.0)) < p->tol_magnitude &&
                    ACD_FABS(phi) < p->tol_phase) {
                    s->ok_time += T_s;
                } else {
                    s->ok_time = ACD_R(0.0);
                }
                close = s->ok_time >= p->hold;
            }
            v_r = acd_cmul(acd_cscale(s->m_adj, s->adj),
                           acd_dfim_rotor_voltage_for(ACD_DFIM_ESTIMATES(p), w_e, u->w,
                                                      acd_c(v_g_mag, ACD_R(0.0)),
                                                      acd_c(ACD_R(0.0), ACD_R(0.0))));
            /* grid-voltage frame -> stationary -> rotor coordinates (e^{-j n_p theta}) */
            angle = p->n_p * u->theta;
            frame = acd_cscale(ACD_R(1.0) / v_g_mag, v_g);
            rotor = acd_c(ACD_COS(angle), ACD_SIN(angle));
            s->v_r = acd_cmul(acd_cmul(v_r, frame), acd_conj(rotor));
            if (close) {
                s->closed = ACD_R(1.0);
                events |= ACD_SYNCHRONISER_RELAY_CLOSED;
            }
        }
    }
    y->v_r = s->v_r;
    y->closed = s->closed;
    y->theta_adj = s->theta_adj;
    y->adj = s->adj;
    y->m_adj = s->m_adj;
    return events;
""",
        support=(CONSTANTS, IMPEDANCES, WRAP, SYNC_SUPPORT),
    ),
)

CONTROLLER_SUPPORT = CSupport(
    "speed_controller",
    r"""
/* rotor current control law (46)-(47) in the stator-voltage frame: decoupling u_R, then
   v_R = u_R - R_T i_R + K_P,C e + K_I,C int e; the integral advances only while the converter
   can apply v_R (conditional integration); *saturated = 1 where it cannot */
static acd_complex acd_speed_controller_current_loop(const acd_speed_controller_params *p,
                                                     acd_speed_controller_state *s,
                                                     ACDRIVE_REAL T_s, ACDRIVE_REAL w_e,
                                                     ACDRIVE_REAL w, ACDRIVE_REAL v_s,
                                                     acd_complex i_s, acd_complex i_r,
                                                     acd_complex i_r_com, int *saturated)
{
    acd_complex Z[4], u_r, error, integral, v_r, back;
    acd_dfim_impedances(ACD_DFIM_ESTIMATES(p), w_e, w, Z);
    back = acd_csub(acd_csub(acd_c(v_s, ACD_R(0.0)), acd_cmul(Z[0], i_s)), acd_cmul(Z[1], i_r));
    u_r = acd_cadd(acd_cadd(acd_cmul(Z[2], i_r), acd_cmul(Z[3], i_s)),
                   acd_cmul(acd_c(p->M / p->L_s, ACD_R(0.0)), back));
    error = acd_csub(i_r_com, i_r);
    integral = s->ir_int;
    v_r = acd_cadd(acd_cadd(acd_csub(u_r, acd_cscale(p->R_T, i_r)), acd_cscale(p->K_PC, error)),
                   acd_cscale(p->K_IC, integral));
    v_r = acd_clip_magnitude(v_r, p->v_r_max, saturated);
    if (!*saturated) {
        s->ir_int = acd_cadd(integral, acd_cscale(T_s, error));
    }
    return v_r;
}

/* Q command: Q_ref, plus a PI on the measured Q = Im(v_S i_S*) (5) when gains are set */
static ACDRIVE_REAL acd_speed_controller_q_command(const acd_speed_controller_params *p,
                                                   acd_speed_controller_state *s,
                                                   ACDRIVE_REAL T_s, ACDRIVE_REAL v_s_mag,
                                                   acd_complex i_s, int currents_valid)
{
    ACDRIVE_REAL q_ref = p->Q_ref, q_meas, error;
    if (!currents_valid || (p->Q_kp == ACD_R(0.0) && p->Q_ki == ACD_R(0.0))) {
        return q_ref;
    }
    q_meas = -v_s_mag * i_s.im; /* v_S real in its own frame */
    s->q_meas = q_meas;
    error = q_ref - q_meas;
    s->q_int += T_s * error;
    return q_ref + p->Q_kp * error + p->Q_ki * s->q_int;
}

/* one sample with the relay closed: the rotor voltage in rotor coordinates (the held one when
   the supply is lost), the event bits in *events */
static acd_complex acd_speed_controller_run(const acd_speed_controller_in *u,
                                            const acd_speed_controller_params *p,
                                            acd_speed_controller_state *s, ACDRIVE_REAL T_s,
                                            uint32_t *events)
{
    ACDRIVE_REAL w_e = u->w_e, w = u->w, v_s_mag = acd_cabs(u->v_s), angle, q_com;
    ACDRIVE_REAL tau_lo, tau_hi, tau_com;
    acd_complex rotor_angle, frame, adj, rotor_to_stator, i_s_f, i_r_f, i_s_com, i_r_com, v_r;
    int currents_valid, lossless, feasible, clipped, sqrt_limited, limited;
    *events = 0u;
    if (v_s_mag < p->v_min || w_e < ACD_DFIM_MIN_SUPPLY_FREQUENCY) {
        *events = ACD_SPEED_CONTROLLER_SUPPLY_LOST;
        return s->v_r;
    }
    angle = p->n_p * u->theta;
    rotor_angle = acd_c(ACD_COS(angle), ACD_SIN(angle)); /* e^{j n_p theta} as measured */
    frame = acd_cscale(ACD_R(1.0) / v_s_mag, u->v_s);
    currents_valid = u->currents_valid != ACD_R(0.0);
    if (s->mode == ACD_DFIM_MODE_CURRENT && !currents_valid) {
        s->mode = ACD_DFIM_MODE_VOLTAGE;
    }
    if (s->mode == ACD_DFIM_MODE_VOLTAGE && p->mode == ACD_DFIM_MODE_CURRENT) {
        *events |= ACD_SPEED_CONTROLLER_SENSOR_FALLBACK;
    }
    /* measured currents in the stator-voltage frame; theta_adj corrects the encoder offset */
    adj = u->adj;
    rotor_to_stator = acd_cmul(rotor_angle, acd_conj(adj));
    i_s_f = acd_cmul(u->i_s, acd_conj(frame));
    i_r_f = acd_cmul(acd_cmul(u->i_r, rotor_to_stator), acd_conj(frame));

    q_com = acd_speed_controller_q_command(p, s, T_s, v_s_mag, i_s_f, currents_valid);
    lossless = p->lossless != ACD_R(0.0);
    if (lossless) {
        ACDRIVE_REAL tau_max_2, tau_max_3;
        acd_dfim_torque_limit_case2(ACD_DFIM_ESTIMATES(p), w_e, v_s_mag, q_com, p->i_s_max,
                                    p->i_r_max, &tau_max_2, &tau_max_3);
        tau_hi = acd_max(acd_min(tau_max_2, tau_max_3), ACD_R(0.0));
        tau_lo = -tau_hi;
        feasible = acd_min(tau_max_2, tau_max_3) >= ACD_R(0.0);
    } else {
        feasible = acd_dfim_torque_window(ACD_DFIM_ESTIMATES(p), w_e, v_s_mag, p->i_s_max,
                                          p->i_r_max, &tau_lo, &tau_hi);
    }
    if (!feasible) {
        *events |= ACD_SPEED_CONTROLLER_NO_ROTOR_MARGIN;
    }
    tau_com = acd_speed_pi(p->K_P, p->K_I, p->K_F, &s->e_int, u->w_ref, w, tau_lo, tau_hi, T_s,
                           &clipped);
    if (clipped) {
        *events |= ACD_SPEED_CONTROLLER_TORQUE_LIMIT;
    }
    s->tau_com = tau_com;
    if (lossless) {
        i_s_com = acd_dfim_stator_current_lossless(p->n_p, w_e, v_s_mag, tau_com, q_com);
        sqrt_limited = 0;
    } else {
        i_s_com = acd_dfim_stator_current_command(p->R_s, p->n_p, w_e, v_s_mag, tau_com, q_com,
                                                  &sqrt_limited);
    }
    if (sqrt_limited) {
        *events |= ACD_SPEED_CONTROLLER_SQRT_LIMIT;
    }
    i_r_com = acd_clip_magnitude(
        acd_dfim_rotor_current_for(ACD_DFIM_ESTIMATES(p), w_e, v_s_mag, i_s_com), p->i_r_max,
        &limited);
    s->i_r_com = i_r_com;
    if (currents_valid) { /* a failed measurement leaves the last valid value */
        s->i_r_f = i_r_f;
    }
    if (s->mode == ACD_DFIM_MODE_CURRENT) {
        int saturated;
        if (limited) {
            *events |= ACD_SPEED_CONTROLLER_ROTOR_CURRENT_LIMIT;
        }
        v_r = acd_speed_controller_current_loop(p, s, T_s, w_e, w, v_s_mag, i_s_f, i_r_f,
                                                i_r_com, &saturated);
        if (saturated) {
            *events |= ACD_SPEED_CONTROLLER_CONVERTER_SATURATION;
        }
        v_r = acd_cmul(v_r, adj);
    } else {
        /* (20) with the adjustments of (28): m_adj scales the v_s term, theta_adj rotates */
        v_r = acd_cmul(adj, acd_dfim_rotor_voltage_for(ACD_DFIM_ESTIMATES(p), w_e, w,
                                                       acd_c(u->m_adj * v_s_mag, ACD_R(0.0)),
                                                       i_s_com));
    }
    /* voltage frame -> stationary (frame) -> rotor coordinates (e^{-j n_p theta}) */
    return acd_cmul(acd_cmul(v_r, frame), acd_conj(rotor_angle));
}
""",
    needs=(CONSTANTS, IMPEDANCES, STATOR_CURRENT, TORQUE_LIMITS, SPEED_PI, CLIP_MAGNITUDE),
)

register(
    SpeedController,
    CStep(
        source="Bodson section III: speed PI (25), torque limits (30)-(42), law (20)-(24), "
        "rotor current loop (45)-(49), sensor fallback",
        body=r"""
    uint32_t events = 0u;
    int closed = u->closed != ACD_R(0.0);
    if (s->started == ACD_R(0.0)) { /* first sample: estimates not ready, hold */
        s->started = ACD_R(1.0);
        s->mode = p->mode;
        s->was_closed = closed ? ACD_R(1.0) : ACD_R(0.0);
    } else if (!closed) { /* synchronising: the synchroniser's voltage */
        s->v_r = u->v_r_sync;
    } else if (s->was_closed == ACD_R(0.0)) {
        /* the relay closed on this sample: bumpless handover from zero torque command */
        s->was_closed = ACD_R(1.0);
        s->e_int = (p->K_P * u->w - p->K_F * p->K_P * u->w_ref) / p->K_I;
        s->v_r = u->v_r_sync;
    } else {
        s->v_r = acd_speed_controller_run(u, p, s, T_s, &events);
    }
    y->v_r = s->v_r;
    y->tau_com = s->tau_com;
    y->i_r_com = s->i_r_com;
    y->i_r_f = s->i_r_f;
    y->mode = s->mode;
    return events;
""",
        support=(CONTROLLER_SUPPORT,),
    ),
)
