"""C steps of the cage-IM controllers: indirect field orientation, the speed and position loops
(``acdrive.control._foc``, Amezquita-Brooks et al. section VI, Fig. 12, (21)) and the
stationary-frame current controller of any order with its limit and anti-windup
(``acdrive.control._current``: controller (20) or the PI, discretised). The IFOC and the speed
and position loops are generated from their kernels (``sim._ccode._translate``); the current
controller, whose layout is set per instance, mirrors its kernel operation for operation."""

from __future__ import annotations

from acdrive.control._current import PERIOD_TOL, StationaryCurrentController
from acdrive.control._foc import IndirectFOC, PositionP, SaturatedSpeedP, SpeedPI
from acdrive.sim._ccode._translate import c_step
from acdrive.sim._ccode._kinds import CStep, CSupport, register
from acdrive.sim._ccode._kinds.common import LIMIT_RTOL_C

register(
    IndirectFOC,
    c_step(
        IndirectFOC,
        source="indirect field orientation: (slip), (flux), (torque) of control._foc's docstring",
    ),
)

register(
    SpeedPI,
    c_step(
        SpeedPI,
        source="speed PI with clamping anti-windup and torque limit (control._speed.speed_pi)",
    ),
)

register(
    SaturatedSpeedP,
    c_step(
        SaturatedSpeedP,
        source="Amezquita-Brooks (21): saturated proportional speed controller",
    ),
)

register(PositionP, c_step(PositionP, source="P position loop of the P-PI cascade (Fig. 12)"))

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
