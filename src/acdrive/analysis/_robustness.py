"""Robustness sweeps: rotor speed and parameter perturbations, worst case of each ICAD figure.

Amezquita-Brooks et al. sec. V-E and VIII assess the design on perturbed machines: the heavy
case R_s, R_r x 2 and L_s, L_r x 0.6, L_m x 0.59 ("approx 100 % perturbation": resistances grow
with heat, inductances fall with saturation), and a family of "critical" variations (Fig. 9).
Here a perturbation is a set of factors on the IM parameters; ``random_perturbations`` draws
reproducible sets (seeded) and discards draws whose leakage factor sigma would not be positive.

``speed_sweep`` and ``perturbation_sweep`` run the full ICAD (``acdrive.analysis.analyse``)
at every (case, speed) and return a ``RobustnessResult`` whose ``worst`` holds, for each figure,
the worst value and the case and speed where it occurs.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from acdrive._arguments import (
    COUNT,
    NONNEGATIVE,
    POSITIVE,
    SEED,
    TEXT,
    Array,
    Instance,
    Items,
    Text,
    checked,
)
from acdrive.analysis._design import PLANT_FAMILY, loop_gain_margin_db, plant_family
from acdrive.control._lti import CONTROLLER
from acdrive.analysis._freqresp import LTI
from acdrive.analysis._icad import analyse, default_grid
from acdrive.analysis._icad_closed_forms import gm_min, im_msf_magnitude_at_rotor_speed
from acdrive.analysis._plants import plant_from_params
from acdrive.errors import InputError, require_nonnegative, require_positive
from acdrive.machines._induction import IMParams


@checked(
    R_s=POSITIVE, R_r=POSITIVE, L_s=POSITIVE, L_r=POSITIVE, L_m=POSITIVE, label=Text(empty=True),
)
@dataclass(frozen=True)
class Perturbation:
    """Multiplicative factors on R_s, R_r, L_s, L_r, L_m of an IM, with a label."""

    R_s: float = 1.0
    R_r: float = 1.0
    L_s: float = 1.0
    L_r: float = 1.0
    L_m: float = 1.0
    label: str = ""

    def __post_init__(self):
        for name in ("R_s", "R_r", "L_s", "L_r", "L_m"):
            object.__setattr__(self, name, require_positive(name, getattr(self, name)))

    def apply(self, p: IMParams) -> IMParams:
        """Perturbed parameters (InputError if sigma would not be positive)."""
        if not isinstance(p, IMParams):
            raise InputError("params", f"perturbations apply to IMParams, got {type(p).__name__}")
        return replace(
            p,
            R_s=p.R_s * self.R_s,
            R_r=p.R_r * self.R_r,
            L_s=p.L_s * self.L_s,
            L_r=p.L_r * self.L_r,
            L_m=p.L_m * self.L_m,
        )


NOMINAL = Perturbation(label="nominal")

#: Amezquita-Brooks et al. sec. VIII: R x 2, L_s, L_r x 0.6, L_m x 0.59.
PAPER_PERTURBATION = Perturbation(2.0, 2.0, 0.6, 0.6, 0.59, label="R x 2, L x 0.6 (paper)")


@checked(
    n=COUNT, seed=SEED, r_range=Items(POSITIVE), l_range=Items(POSITIVE), l_spread=NONNEGATIVE,
    params=Instance(IMParams, optional=True), max_draws=COUNT,
)
def random_perturbations(
    n: int,
    seed: int = 0,
    r_range: tuple[float, float] = (0.8, 2.0),
    l_range: tuple[float, float] = (0.6, 1.1),
    l_spread: float = 0.01,
    params: IMParams | None = None,
    max_draws: int = 100,
) -> list[Perturbation]:
    """``n`` seeded random perturbations of an IM.

    Resistance factors (R_s, R_r independent) are uniform in ``r_range``. Inductances share one
    factor uniform in ``l_range`` (saturation scales the whole magnetic circuit, as in the
    paper's 0.6 / 0.6 / 0.59 case), times an independent factor uniform in
    [1 - l_spread, 1 + l_spread] for each of L_s, L_r, L_m (the leakage factor sigma is a small
    difference of large numbers, so independent changes of several percent are not physical:
    they would change sigma several-fold). Draws that make sigma <= 0 for ``params`` (if given)
    are redrawn; InputError after ``max_draws`` times ``n`` draws.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise InputError("n", f"must be a positive integer, got {n!r}")
    for name, (lo, hi) in (("r_range", r_range), ("l_range", l_range)):
        require_positive(f"{name}[0]", lo)
        require_positive(f"{name}[1]", hi)
        if hi < lo:
            raise InputError(name, "upper bound must be >= lower bound")
    spread = require_nonnegative("l_spread", l_spread)
    if spread >= 1.0:
        raise InputError("l_spread", "must be < 1")
    rng = np.random.default_rng(seed)
    out: list[Perturbation] = []
    for _ in range(max_draws * n):
        r = rng.uniform(*r_range, size=2)
        ell = rng.uniform(*l_range) * rng.uniform(1.0 - spread, 1.0 + spread, size=3)
        cand = Perturbation(r[0], r[1], ell[0], ell[1], ell[2], label=f"random #{len(out) + 1}")
        if params is not None:
            try:
                cand.apply(params)
            except InputError:
                continue
        out.append(cand)
        if len(out) == n:
            return out
    raise InputError("l_spread", "too many draws give sigma <= 0; narrow the inductance spread")


@dataclass(frozen=True)
class WorstCase:
    """Worst value of one figure over a sweep, and where (case label, electrical speed)."""

    figure: str
    value: float
    case: str
    speed: float
    unit: str


@dataclass(frozen=True)
class CaseResult:
    """Figures of one (case, speed) analysis."""

    case: str
    speed: float
    conditions: bool  # i-iv
    closed_loop_stable: bool
    b2: bool
    structural_gm_db: float  # of gamma
    structural_gm_h_db: float  # of gamma h_j (min over channels)
    pm_deg: float  # channel c_i (min over channels)
    gm_db: float  # channel c_i, min(upward, |reduction|)
    kg_pm_deg: float
    kg_gm_db: float
    crossover_rad_s: float
    bandwidth_rad_s: float
    coupling_peak_db: float
    msf_at_wr: float  # |gamma(j w_r)| (18) for IMs, nan otherwise
    gm_min: float  # G_M,min (19) of the case for IMs, nan otherwise


#: (attribute, lower is worse, unit) of every figure reported in ``RobustnessResult.worst``.
FIGURES = (
    ("structural_gm_db", True, "dB"),
    ("structural_gm_h_db", True, "dB"),
    ("pm_deg", True, "deg"),
    ("gm_db", True, "dB"),
    ("kg_pm_deg", True, "deg"),
    ("kg_gm_db", True, "dB"),
    ("crossover_rad_s", True, "rad/s"),
    ("bandwidth_rad_s", True, "rad/s"),
    ("coupling_peak_db", False, "dB"),
    ("msf_at_wr", False, ""),
    ("gm_min", False, ""),
)


@dataclass(frozen=True)
class RobustnessResult:
    """All (case, speed) results of a sweep and the worst case of each figure.

    ``all_conditions``, ``all_stable``, ``all_b2``: conditions i-iv, closed-loop stability and
    (b.2) hold at every (case, speed); ``failures`` lists the (case, speed) where one fails.
    """

    results: tuple[CaseResult, ...]
    worst: dict[str, WorstCase]
    all_conditions: bool
    all_stable: bool
    all_b2: bool
    failures: tuple[tuple[str, float], ...]


def _case_result(case: str, plant, params, k1: LTI, k2: LTI, w) -> CaseResult:
    a = analyse(plant, k1, k2, w, verify=False)
    c = a.conditions
    chans = a.channels
    speed = float(plant.speed) if plant.speed is not None else math.nan
    is_im = isinstance(params, IMParams)
    return CaseResult(
        case=case,
        speed=speed,
        conditions=bool(c.i and c.ii and c.iii and c.iv),
        closed_loop_stable=bool(a.closed_loop_stable),
        b2=bool(a.b2),
        structural_gm_db=float(a.structural.gm_db),
        structural_gm_h_db=min(float(ch.structural.gm_db) for ch in chans),
        pm_deg=min(float(ch.margins.pm_deg) for ch in chans),
        gm_db=min(float(loop_gain_margin_db(ch.margins)) for ch in chans),
        kg_pm_deg=min(float(ch.kg_margins.pm_deg) for ch in chans),
        kg_gm_db=min(float(loop_gain_margin_db(ch.kg_margins)) for ch in chans),
        crossover_rad_s=min(float(ch.margins.crossover_rad_s) for ch in chans),
        bandwidth_rad_s=min(float(ch.bandwidth_rad_s) for ch in chans),
        coupling_peak_db=float(a.coupling_peak_db),
        msf_at_wr=float(im_msf_magnitude_at_rotor_speed(params, speed))
        if is_im and speed != 0.0
        else (0.0 if is_im else math.nan),
        gm_min=float(gm_min(params)) if is_im else math.nan,
    )


def summarize_cases(results: Sequence[CaseResult]) -> RobustnessResult:
    """Worst case of every figure over ``results``."""
    if not results:
        raise InputError("results", "must not be empty")
    worst = {}
    for name, lower_worse, unit in FIGURES:
        vals = np.array([getattr(r, name) for r in results], dtype=float)
        if np.all(np.isnan(vals)):
            continue
        filled = np.where(np.isnan(vals), np.inf if lower_worse else -np.inf, vals)
        k = int(np.argmin(filled) if lower_worse else np.argmax(filled))
        worst[name] = WorstCase(name, float(vals[k]), results[k].case, results[k].speed, unit)
    failures = tuple(
        (r.case, r.speed) for r in results if not (r.conditions and r.closed_loop_stable and r.b2)
    )
    return RobustnessResult(
        results=tuple(results),
        worst=worst,
        all_conditions=all(r.conditions for r in results),
        all_stable=all(r.closed_loop_stable for r in results),
        all_b2=all(r.b2 for r in results),
        failures=failures,
    )


def _speeds(speeds) -> np.ndarray:
    speeds = np.atleast_1d(np.asarray(speeds, dtype=float))
    if speeds.ndim != 1 or speeds.size == 0:
        raise InputError("speeds", "must be a non-empty 1-D array")
    if not np.all(np.isfinite(speeds)):
        raise InputError("speeds", "must be finite (no NaN or infinity)")
    return speeds


def _grid(plant, k1, k2, w):
    return default_grid(plant, k1, k2, n=2000) if w is None else w


@checked(
    plant=PLANT_FAMILY, k1=CONTROLLER, k2=CONTROLLER, speeds=Array((0, 1)),
    w=Array(1, low=0.0, optional=True), case=TEXT,
)
def speed_sweep(plant, k1: LTI, k2: LTI, speeds, *, w=None, case: str = "nominal"):
    """ICAD at every speed of ``speeds`` for a machine name, parameters or plant family."""
    speeds = _speeds(speeds)
    family = plant_family(plant)
    params = plant if isinstance(plant, IMParams) else None
    if isinstance(plant, str):
        from acdrive.analysis._plants import machine_params

        params = machine_params(plant)
    plants = [family(float(s)) for s in speeds]
    w = _grid(plants[int(np.argmax(np.abs(speeds)))], k1, k2, w)
    return summarize_cases([_case_result(case, p, params, k1, k2, w) for p in plants])


@checked(
    params=Instance(IMParams), k1=CONTROLLER, k2=CONTROLLER, speeds=Array((0, 1)),
    perturbations=Items(Instance(Perturbation)), w=Array(1, low=0.0, optional=True),
)
def perturbation_sweep(
    params: IMParams,
    k1: LTI,
    k2: LTI,
    speeds,
    perturbations: Sequence[Perturbation] = (NOMINAL, PAPER_PERTURBATION),
    *,
    w=None,
) -> RobustnessResult:
    """ICAD at every (perturbation, speed) of an IM; worst case of each figure over all."""
    if not isinstance(params, IMParams):
        raise InputError("params", f"must be IMParams, got {type(params).__name__}")
    speeds = _speeds(speeds)
    if not perturbations:
        raise InputError("perturbations", "must not be empty")
    top = float(speeds[int(np.argmax(np.abs(speeds)))])
    w = _grid(plant_from_params(params, top), k1, k2, w)
    results = []
    for n, pert in enumerate(perturbations):
        p = pert.apply(params)
        label = pert.label or f"case {n + 1}"
        for s in speeds:
            results.append(_case_result(label, plant_from_params(p, float(s)), p, k1, k2, w))
    return summarize_cases(results)
