"""What the sections of the ICAD reproduction report share: the speed and frequency grids, the
tolerances used by more than one section, and two evaluations of a plant that several tables
and figures rest on.

Speeds are electrical rotor speeds w_r [rad/s]: seed 002 (Amezquita-Brooks et al.) runs from 0
to w_r,max = 375 rad/s, seed 001 (Ugalde-Loo et al.) takes the 300 W IM over the same range and
the 2 MW PMSG from 0 to its rated 50 Hz. A tolerance used by one section only lives in that
section's module.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from acdrive import _verdicts as verdicts
from acdrive._report import icad_targets as targets
from acdrive._verdicts import ROUNDOFF_FLOOR, Verdict, below_floor
from acdrive.analysis._freqresp import LTI, evaluate_ss
from acdrive.analysis._icad_frequency import icad_quantities, msf_positive_real_crossing

#: Speeds of the seed-002 families [rad/s, electrical] (0 ... w_r,max = 375).
SPEEDS_002 = np.array([0.0, 75.0, 150.0, 225.0, 300.0, 375.0])
#: Speeds of the seed-001 IM figures (same range) and of the PMSG (0 ... rated 50 Hz).
SPEEDS_001_IM = np.array([0.0, 100.0, 200.0, 300.0, 375.0])
SPEEDS_PMSG = 2.0 * np.pi * 50.0 * np.array([0.0, 0.25, 0.5, 0.75, 1.0])
#: Frequency grids [rad/s] of the Bode and of the Nyquist plots.
W_BODE = np.logspace(0, 5, 2000)
W_NYQ = np.logspace(-1, 5, 3000)
#: Speed of the single-speed checks of seed 002: w_r,max = 375 rad/s.
W_R = targets.W_R_MAX

# --- tolerances used by several sections (each printed in the sentence that uses it) ---------
#: A machine parameter or an exact structural coefficient as built in against its printed value.
EXACT_REL_TOL = 1e-12
#: A closed-form frequency response against the state-space response evaluated directly.
FREQRESP_REL_TOL = 1e-8
#: A frequency found by bisection (brentq) against the root it should equal.
ROOT_REL_TOL = 1e-6
#: The 'bandwidth' (crossover of c_i) quoted in the text: 3350 rad/s for the nominal plant
#: (sec. V-C), 3700 rad/s for the perturbed one (sec. VIII).
BANDWIDTH_REL_TOL = 0.01
#: Phase and gain margins quoted as whole degrees / decibels (67, 77, 80 deg; 20, 27 dB).
PM_TOL_DEG = 1.0
GM_TOL_DB = 1.0
#: Open-loop gains quoted as 'approximately' / 'near' a value (approx 20 dB at the resonance,
#: sec. VII; PI 'dropping near 0 dB around 375 rad/s', sec. VI-D).
APPROX_GAIN_TOL_DB = 2.0

# --- round-off: verdicts.ROUNDOFF_FLOOR -----------------------------------------------------------


def within_rel(value, reference, tol: float, yes="agrees", no="differs") -> Verdict:
    """``verdicts.within_rel`` with round-off printed as a bound (``ROUNDOFF_FLOOR``)."""
    return verdicts.within_rel(value, reference, tol, yes, no, floor=ROUNDOFF_FLOOR)


def error_within(
    err: float, tol: float, what: str = "max relative difference", yes="agrees", no="differs"
) -> Verdict:
    """``verdicts.error_within`` with round-off printed as a bound (``ROUNDOFF_FLOOR``)."""
    return verdicts.error_within(err, tol, what, yes, no, floor=ROUNDOFF_FLOOR)


def printed_digits(printed: str, value: float, yes="agrees to the printed digits", no="differs"):
    """``verdicts.printed_digits`` with round-off printed as a bound (``ROUNDOFF_FLOOR``)."""
    return verdicts.printed_digits(printed, value, yes, no, floor=ROUNDOFF_FLOOR)


def fmt_rel(x: float, digits: int = 2) -> str:
    """A relative difference for a table cell: round-off as "< 1e-12" (``ROUNDOFF_FLOOR``)."""
    return f"< {ROUNDOFF_FLOOR:g}" if below_floor(x, ROUNDOFF_FLOOR) else f"{x:.{digits}g}"


def channel_response(plant, k: LTI, w: np.ndarray) -> dict[str, np.ndarray]:
    """The ICAD quantities (``icad_quantities``: gamma, c_i, k_i g_ii, gamma h_j, coupling, ...)
    of ``plant`` with ``k`` on both channels at the frequencies ``w`` [rad/s]."""
    G = evaluate_ss(plant.A, plant.B, plant.C, plant.D, 1j * w)
    kv = k.freqresp(w)
    return icad_quantities(G, kv, kv)


def gamma_real_axis_crossing(plant, w=W_NYQ) -> tuple[float, float]:
    """(x_max, frequency) of the positive-real-axis crossings of gamma (x_max = 0 if none):
    ``analysis.msf_positive_real_crossing`` on the Nyquist grid."""
    return msf_positive_real_crossing(plant, w)
