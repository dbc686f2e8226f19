"""Whether a printed stator-current matrix is reachable within the rounding of the printed
machine parameters: Amezquita-Brooks et al. (13) from the Appendix parameters, Ugalde-Loo et al.
(80) from the parameters of their sec. 4.5.

Each printed parameter p_i may lie anywhere in its rounding interval [p_i - h_i, p_i + h_i],
h_i half a unit of its last printed digit (``acdrive._verdicts.half_unit``); each printed entry
y_k of the matrix stands for [y_k - e_k, y_k + e_k] likewise. The matrix is *reachable* if one
parameter set in the box gives all six entries of (1) / (41) (``stator_current_ss``) inside
their intervals, i.e. if

    r* = min over the box of max_k |a_k(p) - y_k| / e_k  <=  1.

Method: r* is minimised in epigraph form (minimise t subject to |a_k(p) - y_k| <= t e_k, p in
the box) with SLSQP from the centre and from each of the 32 corners of the box; the smallest
value is kept. A point found with r <= 1 is a certificate of reachability: its six entries are
evaluated again and judged one by one to the printed digits. As the minimiser of r is not
unique, the point printed is the parameter set nearest the printed values (sum of squared
deviations in half units, SLSQP) whose entries all lie within (1 + r*)/2 of a half unit: unique,
strictly inside the intervals, so that the report regenerates identically. A minimum above 1 is the smallest
value 33 local searches found, not a proof of unreachability, and the verdict says so.
Besides, the attainable range of each entry alone over the box: each entry is a rational
function of the parameters; its range is taken as the smallest and largest value over the 32
corners and over bounded L-BFGS-B searches started from them.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from acdrive._report import icad_targets as targets
from acdrive._report.icad.common import printed_digits
from acdrive._report.icad.stator_matrix import ENTRY_NAMES
from acdrive._report.markdown import Row, fmt
from acdrive._verdicts import Verdict, half_unit
from acdrive.machines._induction import IMParams, stator_current_ss

#: The five electrical parameters varied within their rounding, in IMParams order.
PARAMETERS = ("R_s", "R_r", "L_s", "L_r", "L_m")
#: The six distinct entries of the printed matrix, in ``PrintedIMMatrix`` order.
ENTRIES = ("a11", "a13", "a14_per_w", "a31", "a33", "b")


def matrix_entries(values) -> np.ndarray:
    """The six distinct entries of A, B of (1) / (41) (``stator_current_ss`` at w_r = 1, so the
    speed entry is a_14 / w_r) for the parameters ``values`` (R_s, R_r, L_s, L_r, L_m)."""
    A, B, _, _ = stator_current_ss(IMParams(*(float(v) for v in values)), 1.0)
    return np.array([A[0, 0], A[0, 2], A[0, 3], A[2, 0], A[2, 2], B[0, 0]])


@dataclass(frozen=True)
class RoundingReach:
    """Result of the rounding analysis of one printed matrix (module docstring)."""

    printed_params: dict  # name -> printed text
    params_half: np.ndarray  # h_i
    printed_entries: dict  # entry -> printed text
    entries_half: np.ndarray  # e_k
    ranges: np.ndarray  # (6, 2): attainable min, max of each entry over the box
    point: np.ndarray | None  # the certificate (module docstring), None if not reached
    best_ratio: float  # the smallest r found
    starts: int

    @property
    def reachable(self) -> bool:
        return self.point is not None and all(v.holds for v in self.entry_verdicts().values())

    def entry_verdicts(self) -> dict[str, Verdict]:
        """Each entry at the certificate point against its printed digits (empty if none)."""
        if self.point is None:
            return {}
        values = matrix_entries(self.point)
        return {
            k: printed_digits(self.printed_entries[k], float(v))
            for k, v in zip(ENTRIES, values, strict=True)
        }


def rounding_reach(printed_params: dict, printed_matrix: targets.PrintedIMMatrix) -> RoundingReach:
    """The rounding analysis (module docstring) of ``printed_matrix`` from the parameters
    ``printed_params`` (name -> ``icad_targets.Printed``)."""
    ptext = {k: targets.printed_text(printed_params[k].value) for k in PARAMETERS}
    centre = np.array([float(ptext[k]) for k in PARAMETERS])
    h = np.array([half_unit(ptext[k]) for k in PARAMETERS])
    etext = {k: targets.printed_text(getattr(printed_matrix, k)) for k in ENTRIES}
    y = np.array([float(etext[k]) for k in ENTRIES])
    e = np.array([half_unit(etext[k]) for k in ENTRIES])
    lo, hi = centre - h, centre + h
    bounds = list(zip(lo, hi, strict=True))
    corners = [lo + h * (1 + np.array(c)) for c in itertools.product((-1.0, 1.0), repeat=5)]
    starts = [centre, *corners]

    def ratio(x) -> float:
        return float(np.max(np.abs(matrix_entries(np.clip(x, lo, hi)) - y) / e))

    cons = [
        {"type": "ineq", "fun": lambda z: z[5] * e - (matrix_entries(z[:5]) - y)},
        {"type": "ineq", "fun": lambda z: z[5] * e + (matrix_entries(z[:5]) - y)},
    ]
    best_x, best_r = centre, ratio(centre)
    for x0 in starts:
        res = minimize(
            lambda z: z[5],
            np.append(x0, ratio(x0)),
            method="SLSQP",
            bounds=[*bounds, (0.0, None)],
            constraints=cons,
            options={"ftol": 1e-12, "maxiter": 500},
        )
        x = np.clip(res.x[:5], lo, hi)
        r = ratio(x)
        if r < best_r:
            best_x, best_r = x, r
    point = None
    if best_r <= 1.0:
        # the minimiser of r is not unique; the certificate is the parameter set nearest the
        # printed values (in half units) whose entries all lie within (1 + r*)/2 of a half
        # unit: unique, and strictly inside the printed intervals
        level = 0.5 * (1.0 + best_r)
        near = minimize(
            lambda x: float(np.sum(((x - centre) / h) ** 2)),
            best_x,
            method="SLSQP",
            bounds=bounds,
            constraints=[
                {"type": "ineq", "fun": lambda x: level * e - (matrix_entries(x) - y)},
                {"type": "ineq", "fun": lambda x: level * e + (matrix_entries(x) - y)},
            ],
            options={"ftol": 1e-15, "maxiter": 1000},
        )
        x = np.clip(near.x, lo, hi)
        point = x if ratio(x) <= 1.0 else best_x
    ranges = np.empty((len(ENTRIES), 2))
    at_corners = np.array([matrix_entries(c) for c in corners])
    for k in range(len(ENTRIES)):
        low, high = float(at_corners[:, k].min()), float(at_corners[:, k].max())
        for sign in (1.0, -1.0):
            for x0 in corners:
                res = minimize(
                    lambda x, k=k, sign=sign: sign * matrix_entries(x)[k],
                    x0,
                    method="L-BFGS-B",
                    bounds=bounds,
                )
                value = float(matrix_entries(np.clip(res.x, lo, hi))[k])
                low, high = min(low, value), max(high, value)
        ranges[k] = low, high
    return RoundingReach(ptext, h, etext, e, ranges, point, best_r, len(starts))


def rounding_rows(reach: RoundingReach, params_where: str, matrix_where: str) -> list[Row]:
    """Rows of the report: each entry's attainable range against its printed interval, and the
    verdict on the whole matrix."""
    rows = []
    verdicts = reach.entry_verdicts()
    for k, (low, high), eh in zip(ENTRIES, reach.ranges, reach.entries_half, strict=True):
        y = float(reach.printed_entries[k])
        inside = low <= y + eh and high >= y - eh
        at_point = f"; at the point below: {verdicts[k]}" if k in verdicts else ""
        rows.append(
            Row(
                f"{ENTRY_NAMES[k]}{' / w_r' if k == 'a14_per_w' else ''} over the rounding box "
                f"of the {params_where} parameters",
                matrix_where,
                f"{reach.printed_entries[k]} (+/- {eh:g})",
                f"range {fmt(low, 5)} ... {fmt(high, 5)}",
                f"printed interval {'inside' if inside else 'OUTSIDE'} the attainable range"
                + at_point,
            )
        )
    if reach.reachable:
        point = ", ".join(
            f"{name} = {fmt(v, 5)} ({reach.printed_params[name]} +/- {hh:g})"
            for name, v, hh in zip(PARAMETERS, reach.point, reach.params_half, strict=True)
        )
        verdict = (
            f"reachable: at {point} (the set nearest the printed values with every entry within "
            f"{fmt(0.5 * (1.0 + reach.best_ratio), 2)} of its half unit), all six entries round "
            "to the printed ones"
        )
    else:
        verdict = (
            f"not reached: the smallest largest deviation found is {fmt(reach.best_ratio, 3)} "
            "half units (> 1); a local search, not a proof that no point reaches it"
        )
    rows.append(
        Row(
            f"{matrix_where} within the rounding of the {params_where} parameters",
            matrix_where,
            "all six entries as printed",
            f"min over the box of the largest |entry - printed| / half unit = "
            f"{fmt(reach.best_ratio, 2)}",
            f"{verdict}. Method: parameters in [printed +/- half a unit of the last printed "
            f"digit]; epigraph minimisation with SLSQP from the centre and the 32 corners "
            f"({reach.starts} starts); each entry's range from the corners and L-BFGS-B",
        )
    )
    return rows
