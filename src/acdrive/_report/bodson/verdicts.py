"""The verdicts of the Bodson reproduction report (``acdrive reproduce bodson``): the tolerances,
each printed in the sentence that uses it, and one function per claim of the paper that turns
computed numbers into a ``acdrive._verdicts.Verdict``.
"""

from __future__ import annotations

import math

from acdrive._verdicts import Verdict, num, ratio_at_least, within_abs, within_rel
from acdrive.drives.dfim._outcome import OSCILLATION_FINDING_RPM
from acdrive.drives.dfim._result import OSCILLATION_BAND_HZ

# --- tolerances of the verdicts (each printed in the sentence that uses it) ------------------
#: Delta_2 of (17) against its closed form (18): the same number to this relative tolerance.
DETERMINANT_REL_TOL = 1e-9
#: An electrical pole has a 'small time constant' against the velocity loop when its rate
#: |Re s| is at least this factor (a decade) above a_D,VEL.
TIME_SCALE_SEPARATION = 10.0
#: Points of the Q_COM grid on which the case-2 rotor limit (42) is maximised numerically; the
#: closed form and the grid optimum agree within one grid step.
Q_GRID_POINTS = 2001
#: The rotor voltage is 'minimised around the synchronous speed' (Fig. 5) when its minimum lies
#: within this fraction of the synchronous speed.
SYNC_SPEED_TOL_FRACTION = 0.05
#: A peak rotor current holds its limit when it exceeds it by at most this fraction (the current
#: loop holds the command at the limit; a sampled loop overshoots it by a fraction of a percent).
LIMIT_TOL_FRACTION = 0.01
#: One mode's response is faster when it reaches 90 % of the step this much earlier [s].
RESPONSE_TIME_TOL_S = 0.005
#: Two speed responses are 'very close' (Fig. 10) when the RMS of their difference is at most
#: this fraction of the largest reference step.
RESPONSE_CLOSE_FRACTION = 0.02
#: The relay closes with 'minimal transients' (IV-A) when the stator current peak within 0.1 s
#: of closing stays below this fraction of the stator current limit.
SYNC_TRANSIENT_FRACTION = 0.1
#: theta_adj found by the synchroniser matches the encoder's electrical offset within this
#: [rad] (2 deg, the synchroniser's default phase tolerance for closing the relay).
ALIGNMENT_TOL_RAD = math.radians(2.0)


def determinant_verdict(det17: float, closed18: float) -> Verdict:
    """Delta_2 of (17) against the closed form (18), and the sign that the Fact of section II
    needs for stability (Delta_2 > 0)."""
    same = within_rel(det17, closed18, DETERMINANT_REL_TOL)
    positive = det17 > 0 and closed18 > 0
    return Verdict(
        same.holds and positive,
        f"{same}; "
        + (
            "both > 0: the electrical model is stable (Fact)"
            if positive
            else "not both > 0: the Fact does not give stability"
        ),
    )


def time_scale_verdict(rate: float, bandwidth: float) -> Verdict:
    """Whether an electrical pole of rate |Re s| = ``rate`` has a small time constant against a
    velocity loop of bandwidth a_D,VEL = ``bandwidth`` (TIME_SCALE_SEPARATION apart)."""
    return ratio_at_least(
        rate,
        bandwidth,
        TIME_SCALE_SEPARATION,
        yes="small against the velocity loop",
        no=f"not small against the velocity loop: abs(Re s) / a_D,VEL = {rate:.3g}/{bandwidth:g}",
    )


def near_synchronous_verdict(rpm_at_min: float, sync_rpm: float) -> Verdict:
    """Bodson IV-B (Fig. 5): the peak rotor voltage is smallest around the synchronous speed."""
    return within_abs(
        rpm_at_min,
        sync_rpm,
        SYNC_SPEED_TOL_FRACTION * sync_rpm,
        " rpm",
        yes="around the synchronous speed",
        no="away from the synchronous speed",
    )


def sequence_verdict(rate_below: float, rate_above: float, slip_below, slip_above) -> Verdict:
    """Bodson IV-B (Fig. 7): rotor currents in forward sequence below the synchronous speed and
    reverse above; the rates [rad/s] must also lie within the slip-frequency ranges
    (``slip_below``, ``slip_above``: (low, high) of w_e - n_P w over each speed band)."""
    signs = rate_below > 0 > rate_above
    inside = min(slip_below) <= rate_below <= max(slip_below) and min(
        slip_above
    ) <= rate_above <= max(slip_above)
    return Verdict(
        signs and inside,
        (
            "forward sequence below synchronous speed, reverse above"
            if signs
            else "NOT forward below and reverse above synchronous speed"
        )
        + (
            "; both rates within the slip-frequency ranges"
            if inside
            else "; a rate lies outside its slip-frequency range"
        ),
    )


def limit_verdict(peak: float, limit: float) -> Verdict:
    """A peak phase current against its limit, LIMIT_TOL_FRACTION tolerated."""
    ok = peak <= limit * (1.0 + LIMIT_TOL_FRACTION)
    return Verdict(
        ok,
        f"{'holds' if ok else 'exceeds'} the {limit:g} A limit (peak {peak:.3f} A, "
        f"{100 * (peak / limit - 1):+.2f} %, tolerance {100 * LIMIT_TOL_FRACTION:g} %)",
    )


def faster_verdict(t_first: float, t_second: float) -> Verdict:
    """Whether the first response reaches 90 % of its step earlier than the second by more than
    RESPONSE_TIME_TOL_S."""
    lead = t_second - t_first
    ok = lead > RESPONSE_TIME_TOL_S
    return Verdict(
        ok,
        f"{'faster' if ok else 'not faster'} by {1e3 * lead:+.1f} ms "
        f"(tolerance {1e3 * RESPONSE_TIME_TOL_S:g} ms)",
    )


def close_responses_verdict(rms_difference: float, largest_step: float) -> Verdict:
    """Bodson Fig. 10: two speed responses 'very close' (RMS of the difference against
    RESPONSE_CLOSE_FRACTION of the largest reference step)."""
    frac = rms_difference / largest_step
    ok = frac <= RESPONSE_CLOSE_FRACTION
    return Verdict(
        ok,
        f"{'very close' if ok else 'not very close'}: RMS difference {rms_difference:.1f} rpm = "
        f"{100 * frac:.2f} % of the largest step ({largest_step:.0f} rpm; tolerance "
        f"{100 * RESPONSE_CLOSE_FRACTION:g} %)",
    )


def better_limit_verdict(peak_cc: float, peak_vc: float, limit: float) -> Verdict:
    """Bodson Fig. 11: current command respects the rotor limit better than voltage command when
    its excursion above the limit is smaller by more than LIMIT_TOL_FRACTION of the limit."""
    over_cc, over_vc = max(0.0, peak_cc - limit), max(0.0, peak_vc - limit)
    ok = over_vc - over_cc > LIMIT_TOL_FRACTION * limit
    return Verdict(
        ok,
        f"current command {'respects the limit better' if ok else 'does not respect the limit better'}"
        f" (excursion above {limit:g} A: current {over_cc:.3f} A, voltage {over_vc:.3f} A; "
        f"tolerance {LIMIT_TOL_FRACTION * limit:.3g} A)",
    )


def transient_verdict(fraction_of_limit: float) -> Verdict:
    """Bodson IV-A: 'minimal transients' when the relay closes."""
    ok = fraction_of_limit <= SYNC_TRANSIENT_FRACTION
    return Verdict(
        ok,
        f"{'minimal' if ok else 'not minimal'} ({100 * fraction_of_limit:.1f} % of the limit; "
        f"tolerance {100 * SYNC_TRANSIENT_FRACTION:g} %)",
    )


def oscillation_verdict(rms_rpm: float) -> Verdict:
    """A run's speed-error RMS in the limit-cycle band against the summary's finding threshold."""
    ok = rms_rpm <= OSCILLATION_FINDING_RPM
    low, high = OSCILLATION_BAND_HZ
    # a limit cycle's RMS moves in its third digit between platforms: two significant digits
    shown_rms = f"{rms_rpm:.2f}" if ok else num(rms_rpm, 2)
    return Verdict(
        ok,
        f"{'tracks without a limit cycle' if ok else 'limit-cycles'} ({shown_rms} rpm RMS in "
        f"the {low:g}-{high:g} Hz band; threshold {OSCILLATION_FINDING_RPM:g} rpm)",
    )
