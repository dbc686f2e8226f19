"""The "Numbers" section of the Bodson reproduction report: every number of sections II-III (gains
(27), (49), the determinant (17)-(18), the torque limits (41)-(42), the electrical poles, the
listing's quantities) recomputed from the equations and the paper's parameters, beside the printed
value.
"""

from __future__ import annotations

import math

import numpy as np

from acdrive._frames import K_PEAK
from acdrive._report.bodson.experiments import EXPERIMENTS
from acdrive._report.bodson.verdicts import Q_GRID_POINTS, determinant_verdict, time_scale_verdict
from acdrive._report.bodson_listing import listing_rows
from acdrive._report.speed_overshoot import overshoot_rows
from acdrive._verdicts import printed_digits, within_abs
from acdrive.control._dfim import current_loop_gains
from acdrive.control._speed import SpeedPIGains
from acdrive.drives.dfim._converter_effect import magnetising_reactive_power
from acdrive.machines._dfim import (
    BODSON_DFIM,
    electrical_poles,
    machine_vector,
    shifted_delta_z_coefficients,
    torque_limit_case2,
    torque_limits_case1,
)
from acdrive.scenarios._loader import load_scenario

A_VEL, A_CUR, R_T = 314.0, 3142.0, 1.0


def table_row(item, paper, ours, note=""):
    return f"| {item} | {paper} | {ours} | {note} |"


def paper_numbers() -> tuple[list[str], np.ndarray]:
    m = BODSON_DFIM
    p = machine_vector(m)
    w_e = 2 * math.pi * 60
    v_s, i_max = K_PEAK * 11.1, K_PEAK * 6.0
    t1, t2, t3, m2, m3, _ = torque_limits_case1(p, w_e, v_s, i_max, i_max)
    gains = SpeedPIGains.design(m.J, A_VEL, K_F=2 / 3)  # the text after (27): K_F = 2/3
    k_f_used = {
        name: motor.controller.gains.K_F
        for name, _, _ in EXPERIMENTS
        for motor in load_scenario(name).motors
    }
    K_PC, K_IC = current_loop_gains(m.sigma, m.L_r, R_T, A_CUR)
    a0, c1, c2 = shifted_delta_z_coefficients(m, 100.0)
    a1, b1, a2, b2 = c1.real, c1.imag, c2.real, c2.imag
    det17 = np.linalg.det(np.array([[a1, 0, -b2], [a0.real, a2, -b1], [0, b2, a1]]))
    closed18 = (m.L_s * m.R_r + m.L_r * m.R_s) ** 2 * m.R_s * m.R_r + (
        m.L_s * m.L_r * m.R_s * m.R_r
    ) * (m.n_p * 100.0) ** 2 * (m.sigma * m.L_s * m.L_r)
    q_best = magnetising_reactive_power(m.L_s, v_s, w_e)
    q_grid = np.linspace(-20, 2 * q_best, Q_GRID_POINTS)
    p0 = p.copy()
    p0[0] = 1e-9  # case 2: R_s = 0
    t3_grid = [torque_limit_case2(p0, w_e, v_s, q, i_max, i_max)[1] for q in q_grid]
    q_opt = q_grid[int(np.argmax(t3_grid))]
    poles0 = electrical_poles(m, w_e, 0.0)
    slow = poles0[np.argmax(poles0.real)]
    stable = bool(np.all(poles0.real < 0))

    def printed(item, text, value, unit, fmt, note=""):
        verdict = printed_digits(text, value)
        return table_row(
            item,
            f"{text} {unit}".strip(),
            f"{value:{fmt}} {unit}".strip(),
            (f"{note}; {verdict}" if note else str(verdict)),
        )

    rows = [
        "| quantity | paper | acdrive | note |",
        "|---|---|---|---|",
        printed("v_S from 11.1 V_pk by (8)", "13.6", v_s, "V", ".3f"),
        printed("i_S,MAX = i_R,MAX from 6 A_pk by (8)", "7.35", i_max, "A", ".3f"),
        printed("tau_MAX,1 (30)", "0.371", t1, "N m", ".4f"),
        printed("tau_MAX,2 (32)", "0.341", t2, "N m", ".4f"),
        printed("tau_MAX,3 (37)", "0.274", t3, "N m", ".4f"),
        table_row(
            "tau_LIM",
            "0.274 N m (rotor current)",
            f"{min(t1, t2, t3):.4f} N m ({('tau_MAX,1', 'tau_MAX,2', 'tau_MAX,3')[int(np.argmin([t1, t2, t3]))]})",
            str(printed_digits("0.274", min(t1, t2, t3)))
            + (
                "; the rotor-current limit"
                if t3 <= min(t1, t2)
                else "; NOT the rotor-current limit"
            ),
        ),
        table_row(
            "generating limits (not printed)",
            "'slightly different'",
            f"{m2:.4f} / {m3:.4f} N m",
            "other roots of (31) and (34); tau_min,2 / tau_min,3",
        ),
        printed(
            "K_P = 2 a_D,VEL J (27)",
            "0.22",
            gains.K_P,
            "",
            ".4f",
            "a_D,VEL = 314 rad/s, J = 3.5e-4",
        ),
        printed("K_I = a_D,VEL^2 J (27)", "34.5", gains.K_I, "", ".2f"),
        table_row(
            f"K_F of the built-in scenarios ({', '.join(sorted(k_f_used))})",
            "0.67 (table; 2/3 in the text after (27))",
            ", ".join(f"{k:g}" for k in sorted(set(k_f_used.values()))),
            "input check (transcription): "
            + " / ".join(str(printed_digits("0.67", k)) for k in sorted(set(k_f_used.values()))),
        ),
        *overshoot_rows(m, gains, k_f_used, table_row),
        printed(
            "K_P,C = sigma L_R a_D,CUR (49)", "8.22", K_PC, "", ".3f", f"sigma = {m.sigma:.4f}"
        ),
        printed("K_I,C = R_T a_D,CUR (49)", "3142", K_IC, "", ".0f", "R_T = 1 ohm"),
        printed("a_D,CUR = 2 pi 500 Hz", "3,142", 2 * math.pi * 500, "rad/s", ".1f"),
        printed("a_D,VEL = 2 pi 50 Hz", "314", 2 * math.pi * 50, "rad/s", ".1f"),
        printed("synchronous speed, n_P = 2, 60 Hz", "1,800", 60 * 60 / m.n_p, "rpm", ".0f"),
        table_row(
            "Delta_2 of (17) vs closed form (18), at n_P w = 200 rad/s",
            "equal",
            f"{det17:.6e} vs {closed18:.6e}",
            str(determinant_verdict(det17, closed18)),
        ),
        table_row(
            "electrical poles at standstill (roots of (13))",
            "stable, 'small time constants'",
            ", ".join(f"{z.real:.1f}{z.imag:+.1f}j" for z in poles0),
            f"{'all in' if stable else 'NOT all in'} the open left half plane; the slow pole "
            f"(time constant {1e3 / abs(slow.real):.0f} ms) is "
            f"{time_scale_verdict(abs(slow.real), A_VEL)}: see below",
        ),
        table_row(
            "Q_COM maximising the case-2 rotor limit (42)",
            "v_S^2 / (w_e L_S)",
            f"{q_best:.2f} var (grid optimum {q_opt:.2f} var)",
            "grid optimum "
            + str(within_abs(q_opt, q_best, q_grid[1] - q_grid[0], " var"))
            + f" (tolerance: one step of the {Q_GRID_POINTS}-point grid)",
        ),
        *listing_rows(m, w_e, v_s, t3, table_row),
    ]
    return rows, poles0
