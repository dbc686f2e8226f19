"""The core control code listed at the end of Bodson section IV, checked against (39).

Bodson lists the few lines of Matlab that compute the rotor voltage from a torque command in
voltage-command mode, "assuming R_S = 0 and Q_S,COM = 0". ``listing_rotor_voltage`` restates the
arithmetic of that listing in Python (our transcription of its formula, not its code): the
impedances of (11) and the law (39) with Q_COM = 0, with the rotor impedances taken either at the
slip frequency w_e - n_P w that (11) prescribes ("corrected") or at the product w_e n_P w that the
listing prints ("as printed"). The report compares both with acdrive's own (39)
(``machines._dfim.rotor_voltage_for`` at the R_S = 0 stator current (38),
``stator_current_lossless``), and computes what the listing's R_S = 0 current does on the
laboratory motor, whose R_S is 0.66 ohm: the torque it produces follows from (31).
"""

from __future__ import annotations

import math

from acdrive._verdicts import ROUNDOFF_FLOOR, Verdict, below_floor, num, within_rel
from acdrive.machines._dfim import (
    DFIMParams,
    electromagnetic_torque,
    lossless_law_torque,
    machine_vector,
    rotor_voltage_for,
    stator_current_lossless,
    steady_state_currents,
)

#: The corrected listing and acdrive's (39) are the same formula evaluated in a different order:
#: they agree to rounding, far inside this relative tolerance.
LISTING_REL_TOL = 1e-12
#: The torque the R_S = 0 law produces, solved from the steady state (19), against the closed
#: form from (31): the same number to this relative tolerance.
TORQUE_FORM_REL_TOL = 1e-12
#: The R_S = 0 law delivers its torque command on the 0.66 ohm motor when the produced torque is
#: within this fraction of the command (the reading tolerance of the paper's 3-digit tau_LIM).
TORQUE_DELIVERED_REL_TOL = 0.002
#: Shaft speeds [rpm] and torque fractions of tau_LIM at which the listing is compared with (39):
#: the speed range of the paper's experiments (0 to 2,700 rpm) and motoring and generating torque.
LISTING_SPEEDS_RPM = (0.0, 900.0, 1500.0, 1800.0, 2100.0, 2700.0)
LISTING_TORQUE_FRACTIONS = (-1.0, -0.5, 0.0, 0.5, 1.0)
#: Torque commands [N m] at which the R_S = 0 law's torque on the 0.66 ohm motor is shown, besides
#: tau_LIM: a round command inside the range, so the quadratic growth of the shortfall shows.
SHORTFALL_COMMANDS = (0.1, 0.2)


def listing_rotor_voltage(
    machine: DFIMParams,
    w_e: float,
    w_m: float,
    v_s: float,
    tau_com: float,
    as_printed: bool = False,
    stator_resistance: float | None = None,
) -> complex:
    """The rotor voltage (stator-voltage frame, v_S real) of the listing at the end of Bodson
    section IV (its ``vrc``), for torque command ``tau_com`` [N m] at shaft speed ``w_m`` [rad/s].

    The listing's formula: Z_S = R_S + j w_e L_S, Z_MS = j w_e M, Z_R = R_R + j w_r L_R,
    Z_MR = j w_r M and v_R = Z_R v_S / Z_MS - (Z_S Z_R - Z_MS Z_MR) w_e tau_COM / (Z_MS v_S n_P),
    i.e. (39) with Q_COM = 0. ``as_printed`` False takes the rotor frequency w_r of (11), the slip
    frequency w_e - n_P w_m; True takes the listing's printed ``ome*np*om`` = w_e n_P w_m
    (a misprint). ``stator_resistance`` replaces R_S in Z_S (0: the listing's "assuming R_S = 0"
    taken everywhere)."""
    n_p = machine.n_p
    w_r = w_e * n_p * w_m if as_printed else w_e - n_p * w_m
    r_s = machine.R_s if stator_resistance is None else stator_resistance
    z_s = r_s + 1j * w_e * machine.L_s
    z_r = machine.R_r + 1j * w_r * machine.L_r
    z_ms = 1j * w_e * machine.M
    z_mr = 1j * w_r * machine.M
    return z_r * v_s / z_ms - (z_s * z_r - z_ms * z_mr) * w_e * tau_com / (z_ms * v_s * n_p)


def law_39_rotor_voltage(
    machine: DFIMParams, w_e: float, w_m: float, v_s: float, tau_com: float
) -> complex:
    """acdrive's (39) with Q_COM = 0: (20) at the R_S = 0 stator current (38)."""
    p = machine_vector(machine)
    i_s = stator_current_lossless(p, w_e, v_s, tau_com, 0.0)
    return complex(rotor_voltage_for(p, w_e, w_m, v_s, i_s))


def listing_differences(
    machine: DFIMParams, w_e: float, v_s: float, tau_lim: float
) -> tuple[float, float, float]:
    """Over the grid LISTING_SPEEDS_RPM x LISTING_TORQUE_FRACTIONS * ``tau_lim``: (largest
    relative difference |v_listing - v_39| / |v_39| of the corrected listing, smallest and
    largest ratio |v_printed| / |v_39| of the listing as printed)."""
    corrected, ratios = [], []
    for rpm in LISTING_SPEEDS_RPM:
        w_m = rpm * math.pi / 30.0
        for fraction in LISTING_TORQUE_FRACTIONS:
            tau = fraction * tau_lim
            ref = law_39_rotor_voltage(machine, w_e, w_m, v_s, tau)
            fixed = listing_rotor_voltage(machine, w_e, w_m, v_s, tau)
            printed = listing_rotor_voltage(machine, w_e, w_m, v_s, tau, as_printed=True)
            corrected.append(abs(fixed - ref) / abs(ref))
            ratios.append(abs(printed) / abs(ref))
    return float(max(corrected)), float(min(ratios)), float(max(ratios))


def lossless_law_torque_simulated(
    machine: DFIMParams, w_e: float, w_m: float, v_s: float, tau_com: float
) -> float:
    """The same torque solved from the steady state (19) with the rotor voltage of (39)
    (``steady_state_currents``) and the torque of (9) (``electromagnetic_torque``)."""
    p = machine_vector(machine)
    v_r = law_39_rotor_voltage(machine, w_e, w_m, v_s, tau_com)
    i_s, i_r = steady_state_currents(p, w_e, w_m, v_s, v_r)
    return float(electromagnetic_torque(p, i_s, i_r))


def lossless_everywhere_torque(
    machine: DFIMParams, w_e: float, w_m: float, v_s: float, tau_com: float
) -> float:
    """The torque on ``machine`` (steady state (19), torque (9)) of the listing's rotor voltage
    with R_S = 0 in Z_S as well: the law assuming R_S = 0 everywhere. Unlike the law that keeps
    R_S in (20), it does not hold the stator current of (38), so the torque depends on the
    speed ``w_m``."""
    p = machine_vector(machine)
    v_r = listing_rotor_voltage(machine, w_e, w_m, v_s, tau_com, stator_resistance=0.0)
    i_s, i_r = steady_state_currents(p, w_e, w_m, v_s, v_r)
    return float(electromagnetic_torque(p, i_s, i_r))


def relative_cell(x: float) -> str:
    """A relative difference as printed: round-off (``verdicts.ROUNDOFF_FLOOR``) as its bound."""
    return f"< {ROUNDOFF_FLOOR:g}" if below_floor(x, ROUNDOFF_FLOOR) else num(x, 2)


def corrected_listing_verdict(max_rel: float) -> Verdict:
    """The corrected listing against (39): the same formula within LISTING_REL_TOL."""
    ok = max_rel <= LISTING_REL_TOL
    return Verdict(
        ok,
        f"{'the same as (39)' if ok else 'NOT the same as (39)'} (largest relative difference "
        f"{relative_cell(max_rel)} over the grid, tolerance {LISTING_REL_TOL:g})",
    )


def printed_listing_verdict(low: float, high: float) -> Verdict:
    """The listing as printed against (39): it holds only if every ratio |v_printed| / |v_39|
    is within LISTING_REL_TOL of 1."""
    ok = abs(low - 1.0) <= LISTING_REL_TOL and abs(high - 1.0) <= LISTING_REL_TOL
    return Verdict(
        ok,
        (
            "the same as (39)"
            if ok
            else "misprint: the printed rotor frequency w_e n_P w (for (11)'s w_e - n_P w) gives "
            f"{num(low, 3)} to {num(high, 4)} times the rotor voltage of (39) over the grid"
        )
        + f" (tolerance {LISTING_REL_TOL:g} relative)",
    )


def delivered_torque_verdict(tau_e: float, tau_com: float) -> Verdict:
    """Whether the R_S = 0 law delivers its torque command (TORQUE_DELIVERED_REL_TOL)."""
    return within_rel(
        tau_e,
        tau_com,
        TORQUE_DELIVERED_REL_TOL,
        yes="delivers the command",
        no="falls short of the command",
    )


def listing_rows(machine: DFIMParams, w_e: float, v_s: float, tau_lim: float, row) -> list[str]:
    """Report rows (``row(item, paper, ours, note)``) of the listing: corrected and as printed
    against (39), and its R_S = 0 current applied to ``machine`` at tau_COM = ``tau_lim``."""
    worst, low, high = listing_differences(machine, w_e, v_s, tau_lim)
    grid = (
        f"{len(LISTING_SPEEDS_RPM)} speeds {LISTING_SPEEDS_RPM[0]:g}-{LISTING_SPEEDS_RPM[-1]:g} rpm"
        f" x tau_COM = {', '.join(f'{f:g}' for f in LISTING_TORQUE_FRACTIONS)} x tau_LIM"
    )
    return [
        row(
            "core m-code: zr",
            "Rr+1i*(ome*np*om)*Lr",
            "R_R + j(w_e - n_P w) L_R",
            "(11) has the slip frequency w_e - n_P w (rows below: the effect on v_R)",
        ),
        row(
            "core m-code vrc, corrected zr, zmr, against (39) (Q_COM = 0)",
            "(39)",
            f"max abs(dv_R) / abs(v_R) = {relative_cell(worst)}",
            f"{corrected_listing_verdict(worst)}; grid: {grid}",
        ),
        row(
            "core m-code vrc as printed against (39)",
            "(39)",
            f"abs(v_R,printed) / abs(v_R,(39)) = {num(low, 3)} to {num(high, 4)}",
            str(printed_listing_verdict(low, high)),
        ),
        *(
            _shortfall_row(machine, w_e, v_s, tau, tau == tau_lim, row)
            for tau in (*SHORTFALL_COMMANDS, tau_lim)
        ),
    ]


def _shortfall_row(machine: DFIMParams, w_e: float, v_s: float, tau_com: float, is_limit: bool,
                   row) -> str:  # fmt: skip
    """The torque the R_S = 0 law produces on ``machine`` at ``tau_com``, two ways, and beside
    it the torque of the law with R_S = 0 everywhere (``lossless_everywhere_torque``) over
    LISTING_SPEEDS_RPM."""
    tau_e = lossless_law_torque(machine, w_e, v_s, tau_com)
    tau_e_ss = lossless_law_torque_simulated(machine, w_e, 0.0, v_s, tau_com)
    same = within_rel(
        tau_e_ss, tau_e, TORQUE_FORM_REL_TOL, yes="agrees", no="differs", floor=ROUNDOFF_FLOOR
    )
    everywhere = [
        lossless_everywhere_torque(machine, w_e, rpm * math.pi / 30.0, v_s, tau_com)
        for rpm in LISTING_SPEEDS_RPM
    ]
    lo, hi = min(everywhere), max(everywhere)
    below = sum(x < tau_e for x in everywhere)
    delivered = sum(delivered_torque_verdict(x, tau_com).holds for x in everywhere)
    command = f"tau_LIM = {tau_com:.4f}" if is_limit else f"{tau_com:g}"
    return row(
        f"torque of the listing's R_S = 0 law on the R_S = {machine.R_s:g} ohm motor at "
        f"tau_COM = {command} N m",
        "(not printed; the listing assumes R_S = 0)",
        f"{tau_e:.4f} N m (steady state (19): {tau_e_ss:.4f} N m); with R_S = 0 everywhere "
        f"(also in Z_S of v_R): {everywhere[0]:.4f} N m at standstill, {lo:.4f} ... "
        f"{hi:.4f} N m over {LISTING_SPEEDS_RPM[0]:g}-{LISTING_SPEEDS_RPM[-1]:g} rpm",
        f"{delivered_torque_verdict(tau_e, tau_com)}: (31) loses n_P R_S i_S^2 / w_e "
        f"= {tau_com - tau_e:.4f} N m; closed form vs steady state {same}. With R_S in Z_S, v_R "
        "holds the current of (38) at any speed, so the torque does not depend on it; with "
        f"R_S = 0 everywhere it does (range beside): below the value with R_S in Z_S at {below} "
        f"of {len(everywhere)} speeds of the grid, the command delivered (tolerance "
        f"{100 * TORQUE_DELIVERED_REL_TOL:g} %) at {delivered} of them",
    )
