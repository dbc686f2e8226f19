"""C steps of the cage-IM controllers: indirect field orientation, the speed and position loops
(``acdrive.control._foc``, Amezquita-Brooks et al. section VI, Fig. 12, (21)) and the
stationary-frame current controller of any order with its limit and anti-windup
(``acdrive.control._current``: controller (20) or the PI, discretised). Each mirrors its kernel
operation for operation."""

from __future__ import annotations

from acdrive.control._current import PERIOD_TOL, StationaryCurrentController
from acdrive.control._foc import IndirectFOC, PositionP, SaturatedSpeedP, SpeedPI
from acdrive.sim._ccode._kinds import CStep, CSupport, register
from acdrive.sim._ccode._kinds.common import CLIP, LIMIT_RTOL_C, SPEED_PI, TABLE_AT, WRAP

register(
    IndirectFOC,
    CStep(
        source="indirect field orientation: (slip), (flux), (torque) of control._foc's docstring",
        body=r"""
    ACDRIVE_REAL R_r = p->R_r, L_r = p->L_r, L_m = p->L_m, n_p = p->n_p, i_max = p->i_max;
    ACDRIVE_REAL psi = s->psi_est, tau_ref = u->tau_ref, i_d, i_q, w_slip, theta_f;
    uint32_t events = 0u;
    int magnetised;
    i_d = acd_table_at(p->psi_ref.n, p->psi_ref.t, p->psi_ref.v, t) / L_m;
    magnetised = psi > ACD_R(0.0) && psi >= p->psi_min;
    if (magnetised) {
        i_q = tau_ref * L_r / (n_p * L_m * psi);
    } else {
        i_q = ACD_R(0.0);
        if (tau_ref != ACD_R(0.0)) {
            events |= ACD_INDIRECT_FOC_UNMAGNETISED;
        }
    }
    if (ACD_FABS(i_d) >= i_max) { /* the flux current alone uses the whole limit */
        i_d = i_d > ACD_R(0.0) ? i_max : -i_max;
        if (i_q != ACD_R(0.0)) {
            events |= ACD_INDIRECT_FOC_CURRENT_LIMIT;
        }
        i_q = ACD_R(0.0);
    } else {
        int limited;
        i_q = acd_clip(i_q, ACD_SQRT(i_max * i_max - i_d * i_d), &limited);
        if (limited) {
            events |= ACD_INDIRECT_FOC_CURRENT_LIMIT;
        }
    }
    w_slip = magnetised ? L_m * R_r / L_r * i_q / psi : ACD_R(0.0);
    theta_f = acd_wrap(n_p * u->theta + s->theta_slip);
    y->i_s_ref = acd_cmul(acd_c(i_d, i_q), acd_c(ACD_COS(theta_f), ACD_SIN(theta_f)));
    y->i_dq_ref = acd_c(i_d, i_q);
    y->theta_f = theta_f;
    y->w_slip = w_slip;
    y->psi_est = psi;
    y->tau_est = n_p * L_m / L_r * psi * i_q;
    /* the states advance over the sample with the commands held (exact for the flux model) */
    s->theta_slip = acd_wrap(s->theta_slip + T_s * w_slip);
    s->psi_est = psi + (ACD_R(1.0) - ACD_EXP(-T_s * R_r / L_r)) * (L_m * i_d - psi);
    return events;
""",
        support=(TABLE_AT, CLIP, WRAP),
    ),
)

register(
    SpeedPI,
    CStep(
        source="speed PI with clamping anti-windup and torque limit (control._speed.speed_pi)",
        body=r"""
    int limited;
    y->tau_ref = acd_speed_pi(p->K_P, p->K_I, p->K_F, &s->e_int, u->w_ref, u->w, -p->tau_max,
                              p->tau_max, T_s, &limited);
    return limited ? ACD_SPEED_PI_TORQUE_LIMIT : 0u;
""",
        support=(SPEED_PI,),
    ),
)

register(
    SaturatedSpeedP,
    CStep(
        source="Amezquita-Brooks (21): saturated proportional speed controller",
        body=r"""
    int limited;
    y->tau_ref = acd_clip(p->k_p * (u->w_ref - u->w), p->tau_max, &limited);
    return limited ? ACD_SATURATED_SPEED_P_TORQUE_LIMIT : 0u;
""",
        support=(CLIP,),
    ),
)

register(
    PositionP,
    CStep(
        source="P position loop of the P-PI cascade (Fig. 12)",
        body=r"""
    int limited;
    ACDRIVE_REAL theta_ref = acd_table_at(p->theta_ref.n, p->theta_ref.t, p->theta_ref.v, t);
    y->w_ref = acd_clip(p->K_theta * (theta_ref - u->theta), p->w_max, &limited);
    y->theta_ref = theta_ref;
    return limited ? ACD_POSITION_P_SPEED_LIMIT : 0u;
""",
        support=(TABLE_AT, CLIP),
    ),
)

PERIOD = CSupport(
    "current_controller_period",
    f"#define ACD_PERIOD_TOL ACD_R({PERIOD_TOL!r}) /* control._current.PERIOD_TOL */\n",
)


def current_controller_body(part) -> str:
    """The difference equation of ``part`` (order n, control._current's module docstring) with
    its matrices' entries named as the part declares them, the sums unrolled in the kernel's
    order: v = C_d x + D_d e limited to v_max, x <- A_d x + B_d e + K_aw (w - v)."""
    n = part.discrete.order
    L = [
        "    ACDRIVE_REAL e0 = u->i_ref.re - u->i_meas.re;",
        "    ACDRIVE_REAL e1 = u->i_ref.im - u->i_meas.im;",
        "    ACDRIVE_REAL v0 = p->Dd_0_0 * e0 + p->Dd_0_1 * e1;",
        "    ACDRIVE_REAL v1 = p->Dd_1_0 * e0 + p->Dd_1_1 * e1;",
        "    ACDRIVE_REAL v_max, w0, w1, magnitude, dw0, dw1;",
        "    uint32_t events = 0u;",
    ]
    for j in range(n):
        L.append(f"    v0 += p->Cd_0_{j} * s->x_{j};")
        L.append(f"    v1 += p->Cd_1_{j} * s->x_{j};")
    if part.v_dc_input:
        L.append("    v_max = acd_max(u->v_dc, ACD_R(0.0)) / ACD_SQRT(ACD_R(2.0));")
    else:
        L.append("    v_max = p->v_max;")
    L += [
        "    w0 = v0;",
        "    w1 = v1;",
        "    magnitude = ACD_SQRT(v0 * v0 + v1 * v1);",
        "    if (magnitude > v_max + ACD_LIMIT_RTOL * v_max) {",
        "        ACDRIVE_REAL scale = v_max / magnitude;",
        "        w0 = v0 * scale;",
        "        w1 = v1 * scale;",
        "        events |= ACD_STATIONARY_CURRENT_CONTROLLER_SATURATED;",
        "    }",
        "    dw0 = w0 - v0;",
        "    dw1 = w1 - v1;",
    ]
    for i in range(n):
        L.append("    {")
        L.append(f"        ACDRIVE_REAL acc = p->Bd_{i}_0 * e0 + p->Bd_{i}_1 * e1;")
        L.append(f"        acc += p->Kaw_{i}_0 * dw0 + p->Kaw_{i}_1 * dw1;")
        for j in range(n):
            L.append(f"        acc += p->Ad_{i}_{j} * s->x_{j};")
        L.append(f"        s->next_{i} = acc;")
        L.append("    }")
    for i in range(n):
        L.append(f"    s->x_{i} = s->next_{i};")
    L += [
        "    y->v_ref = acd_c(w0, w1);",
        "    if (ACD_FABS(T_s - p->T_s) > ACD_PERIOD_TOL * p->T_s) {",
        "        events |= ACD_STATIONARY_CURRENT_CONTROLLER_PERIOD_MISMATCH;",
        "    }",
        "    return events;",
    ]
    return "\n".join(L) + "\n"


register(
    StationaryCurrentController,
    CStep(
        source="stationary-frame current controller K(z) with magnitude limit and anti-windup by "
        "conditioning (control._current; Amezquita-Brooks (20) or the PI)",
        body=current_controller_body,
        support=(LIMIT_RTOL_C, PERIOD),
    ),
)
