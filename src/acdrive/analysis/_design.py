"""Specifications, controller checks and a loop-shaping helper for diagonal current controllers.

The specifications are those of Amezquita-Brooks et al. sec. V-B, made general:

- ``bandwidth_rad_s``: the channel bandwidth required at every speed. The paper calls the
  open-loop crossover frequency of c_i its "bandwidth" (3350 rad/s for (20), which is the
  crossover of c_i at w_r = 375 rad/s); ``bandwidth_measure='crossover'`` (default) checks the
  highest gain crossover of c_i, ``'closed_loop'`` the -3 dB bandwidth of c_i / (1 + c_i)
  (see ``acdrive.analysis._margins``).
- ``gm_db``, ``pm_deg``: robustness margins of the channels c_i and of the loops k_i g_ii
  (condition (b.1) asks both to be robust). The gain margin of a loop is the smaller of its
  upward margin and the magnitude of its gain-reduction margin (the channels with (20) are
  conditionally stable: the phase crosses -180 deg at frequencies where the gain is above one).
- ``coupling_db``: bound on the peak of |y_i / r_j| of (10).
- ``structural_gm_db``: minimum distance (as a gain margin) of gamma h_j to the critical point
  (1, 0), condition (b.2); 0 dB only asks that gamma h_j stays left of (1, 0).
- ``w_r_min``, ``w_r_max``, ``n_speeds``: the electrical speed range and how many equally spaced
  speeds the checks visit (both ends included).

``check_controller`` evaluates every specification at every speed with the full ICAD of
``acdrive.analysis._icad`` and reports the worst speed of each. ``propose_controller`` searches a
small explainable family (PI, then PI x lag as in Amezquita-Brooks et al. (22)): the crossover is
set from the bandwidth specification, the gain from the design model g_ii (1 - gamma) (their
sec. V-C: the channel with h_j = 1) at the worst speed, and the PI zero and the lag are chosen on
a grid to maximise the smallest normalised spec slack over the speed range; the result is then
checked with ``check_controller``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from acdrive._arguments import (
    COUNT,
    NONNEGATIVE,
    POSITIVE,
    REAL,
    TEXT,
    Array,
    Either,
    Function,
    Instance,
    Text,
    checked,
)
from acdrive.analysis._freqresp import LTI, evaluate_ss
from acdrive.analysis._icad import analyse, default_grid
from acdrive.analysis._icad_frequency import icad_quantities, stack_plants
from acdrive.analysis._plants import PLANT, Plant2x2, as_plant, plant_for, plant_from_params
from acdrive.control._lti import CONTROLLER
from acdrive.errors import InputError, require_finite, require_nonnegative, require_positive
from acdrive.machines._dfim import DFIMParams
from acdrive.machines._induction import IMParams
from acdrive.machines._pmsm import PMSGParams

BANDWIDTH_MEASURES = ("crossover", "closed_loop")


@checked(
    bandwidth_rad_s=POSITIVE, gm_db=NONNEGATIVE, pm_deg=NONNEGATIVE, coupling_db=REAL, w_r_min=REAL,
    w_r_max=REAL, n_speeds=COUNT, structural_gm_db=NONNEGATIVE,
    bandwidth_measure=Text(BANDWIDTH_MEASURES),
)
@dataclass(frozen=True)
class Specifications:
    """Performance and robustness specifications over a speed range (see module docstring).

    Defaults are Amezquita-Brooks et al. sec. V-B: bandwidth >= 3300 rad/s, GM >= 12 dB,
    PM >= 50 deg, coupling <= -15 dB, 0 <= w_r <= 375 rad/s.
    """

    bandwidth_rad_s: float = 3300.0
    gm_db: float = 12.0
    pm_deg: float = 50.0
    coupling_db: float = -15.0
    w_r_min: float = 0.0
    w_r_max: float = 375.0
    n_speeds: int = 7
    structural_gm_db: float = 0.0
    bandwidth_measure: str = "crossover"

    def __post_init__(self):
        object.__setattr__(
            self, "bandwidth_rad_s", require_positive("bandwidth_rad_s", self.bandwidth_rad_s)
        )
        object.__setattr__(self, "gm_db", require_nonnegative("gm_db", self.gm_db))
        pm = require_nonnegative("pm_deg", self.pm_deg)
        if pm >= 180.0:
            raise InputError("pm_deg", f"must be < 180 deg, got {pm:g}")
        object.__setattr__(self, "pm_deg", pm)
        object.__setattr__(self, "coupling_db", require_finite("coupling_db", self.coupling_db))
        lo = require_finite("w_r_min", self.w_r_min)
        hi = require_finite("w_r_max", self.w_r_max)
        if hi < lo:
            raise InputError("w_r_max", f"must be >= w_r_min ({lo:g}), got {hi:g}")
        object.__setattr__(self, "w_r_min", lo)
        object.__setattr__(self, "w_r_max", hi)
        n = self.n_speeds
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise InputError("n_speeds", f"must be a positive integer, got {n!r}")
        if n == 1 and hi != lo:
            raise InputError("n_speeds", "must be >= 2 when w_r_max > w_r_min")
        object.__setattr__(self, "n_speeds", int(n))
        object.__setattr__(
            self, "structural_gm_db", require_nonnegative("structural_gm_db", self.structural_gm_db)
        )
        if self.bandwidth_measure not in BANDWIDTH_MEASURES:
            raise InputError("bandwidth_measure", f"must be one of {', '.join(BANDWIDTH_MEASURES)}")

    def speeds(self) -> np.ndarray:
        """The speeds the checks visit [rad/s]."""
        return np.linspace(self.w_r_min, self.w_r_max, self.n_speeds)


#: The specifications of Amezquita-Brooks et al. sec. V-B.
PAPER_SPECS = Specifications()


# ---------------------------------------------------------------------------------------------
# plant families


PlantFamily = Callable[[float], Plant2x2]


#: the argument rule of a plant family (``plant_family``)
PLANT_FAMILY = Either(TEXT, Instance(IMParams, PMSGParams, DFIMParams), Function(), PLANT)


def plant_family(plant) -> PlantFamily:
    """A function speed -> Plant2x2 from a built-in machine name, machine parameters, a callable
    or a fixed plant (whose speed is then ignored)."""
    if isinstance(plant, str):
        return lambda w_r: plant_for(plant, w_r)
    if isinstance(plant, (IMParams, PMSGParams, DFIMParams)):
        return lambda w_r: plant_from_params(plant, w_r)
    if callable(plant) and not isinstance(plant, Plant2x2):
        return lambda w_r: as_plant(plant(w_r))
    fixed = as_plant(plant)
    return lambda w_r: fixed


def _check_speeds(speeds) -> np.ndarray:
    speeds = np.atleast_1d(np.asarray(speeds, dtype=float))
    if speeds.ndim != 1 or speeds.size == 0:
        raise InputError("speeds", "must be a non-empty 1-D array")
    if not np.all(np.isfinite(speeds)):
        raise InputError("speeds", "must be finite (no NaN or infinity)")
    return speeds


# ---------------------------------------------------------------------------------------------
# checking a controller


@dataclass(frozen=True)
class SpecCheck:
    """One specification at its worst speed: ``worst`` compared with ``required`` by ``relation``
    ('>=' or '<='); ``worst_speed`` is where it is worst (nan for yes/no checks)."""

    name: str
    required: float
    worst: float
    worst_speed: float
    relation: str
    unit: str
    met: bool


@dataclass(frozen=True)
class ControllerCheck:
    """Result of ``check_controller``: every spec at its worst speed, plus the structural and
    stability facts (conditions i-iv, closed-loop eigenvalues, (b.1), (b.2)) at every speed."""

    specs: Specifications
    speeds: np.ndarray
    checks: tuple[SpecCheck, ...]
    conditions_hold: bool
    closed_loop_stable: bool
    b1: bool
    b2: bool

    @property
    def met(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.checks if c.met)

    @property
    def unmet(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.checks if not c.met)

    @property
    def met_all(self) -> bool:
        return not self.unmet

    def get(self, name: str) -> SpecCheck:
        for c in self.checks:
            if c.name == name:
                return c
        raise KeyError(name)


def loop_gain_margin_db(margins) -> float:
    """Smallest gain change (dB, >= 0) that destabilises: min(upward GM, |gain-reduction GM|)."""
    return min(margins.gm_db, -margins.gm_reduction_db)


def _worst(values: np.ndarray, speeds: np.ndarray, lower_is_worse: bool):
    v = np.where(np.isnan(values), -np.inf if lower_is_worse else np.inf, values)
    k = int(np.argmin(v) if lower_is_worse else np.argmax(v))
    return float(v[k]), float(speeds[k])


@checked(
    plant_family_=PLANT_FAMILY, k1=CONTROLLER, k2=CONTROLLER, specs=Instance(Specifications),
    w=Array(1, low=0.0, optional=True), speeds=Array((0, 1), optional=True),
)
def check_controller(
    plant_family_, k1: LTI, k2: LTI, specs: Specifications, *, w=None, speeds=None
) -> ControllerCheck:
    """Check diag(k1, k2) against ``specs`` at every speed of the range (worst case reported).

    ``plant_family_``: a machine name, machine parameters, a callable speed -> plant, or a fixed
    plant. ``w``: frequency grid (default: ``default_grid`` of the top-speed plant, 2000 points).
    ``speeds`` overrides ``specs.speeds()``.
    """
    if not isinstance(specs, Specifications):
        raise InputError("specs", f"must be Specifications, got {type(specs).__name__}")
    family = plant_family(plant_family_)
    speeds = specs.speeds() if speeds is None else _check_speeds(speeds)
    plants = [family(float(s)) for s in speeds]
    if w is None:
        top = plants[int(np.argmax(np.abs(speeds)))]
        w = default_grid(top, k1, k2, n=2000)
    analyses = [analyse(p, k1, k2, w, verify=False) for p in plants]
    return _check_from_analyses(analyses, speeds, specs)


def _check_from_analyses(analyses, speeds, specs: Specifications) -> ControllerCheck:
    def per(fn):
        return np.array([fn(a) for a in analyses], dtype=float)

    if specs.bandwidth_measure == "crossover":
        bw = per(lambda a: min(ch.margins.crossover_rad_s for ch in a.channels))
        bw_name = "bandwidth (crossover of c_i)"
    else:
        bw = per(lambda a: min(ch.bandwidth_rad_s for ch in a.channels))
        bw_name = "bandwidth (-3 dB of c_i/(1+c_i))"
    pm = per(lambda a: min(ch.margins.pm_deg for ch in a.channels))
    gm = per(lambda a: min(loop_gain_margin_db(ch.margins) for ch in a.channels))
    kpm = per(lambda a: min(ch.kg_margins.pm_deg for ch in a.channels))
    kgm = per(lambda a: min(loop_gain_margin_db(ch.kg_margins) for ch in a.channels))
    cp = per(lambda a: a.coupling_peak_db)
    sgm = per(lambda a: min(ch.structural.gm_db for ch in a.channels))
    rows = []
    for name, vals, req, rel, unit in (
        (bw_name, bw, specs.bandwidth_rad_s, ">=", "rad/s"),
        ("phase margin of c_i", pm, specs.pm_deg, ">=", "deg"),
        ("gain margin of c_i", gm, specs.gm_db, ">=", "dB"),
        ("phase margin of k_i g_ii", kpm, specs.pm_deg, ">=", "deg"),
        ("gain margin of k_i g_ii", kgm, specs.gm_db, ">=", "dB"),
        ("coupling peak", cp, specs.coupling_db, "<=", "dB"),
        ("structural margin of gamma h_j", sgm, specs.structural_gm_db, ">=", "dB"),
    ):
        worst, at = _worst(vals, speeds, lower_is_worse=rel == ">=")
        met = worst >= req if rel == ">=" else worst <= req
        rows.append(SpecCheck(name, req, worst, at, rel, unit, bool(met)))
    cond = all(
        a.conditions.i and a.conditions.ii and a.conditions.iii and a.conditions.iv
        for a in analyses
    )
    stable = all(a.closed_loop_stable for a in analyses)
    b1 = all(a.b1 for a in analyses)
    b2 = all(a.b2 for a in analyses)
    rows.append(
        SpecCheck(
            "closed loop stable at every speed",
            1.0,
            float(stable and b1),
            math.nan,
            ">=",
            "",
            stable and b1,
        )
    )
    rows.append(
        SpecCheck("gamma h_j does not encircle (1, 0)", 1.0, float(b2), math.nan, ">=", "", b2)
    )
    return ControllerCheck(specs, np.asarray(speeds, float), tuple(rows), cond, stable, b1, b2)


# ---------------------------------------------------------------------------------------------
# proposing a controller


@dataclass(frozen=True)
class Candidate:
    """One member of the searched family: PI gain, PI zero and optional lag (zero a, poles with
    natural frequency w0 and damping zeta), with its screening score (smallest normalised
    slack over specs and speeds on the frequency grid; >= 0 means all specs met on the grid)."""

    structure: str
    gain: float
    pi_zero: float
    lag_zero: float | None
    lag_w0: float | None
    lag_zeta: float | None
    score: float

    def controller(self, name: str = "proposed") -> LTI:
        if self.lag_zero is None:
            return LTI.pi_lag(self.gain, self.pi_zero, [], [], name=name)
        wd = self.lag_w0 * math.sqrt(1.0 - self.lag_zeta**2)
        re = -self.lag_zeta * self.lag_w0
        return LTI.pi_lag(
            self.gain,
            self.pi_zero,
            [-self.lag_zero, -self.lag_zero],
            [complex(re, wd), complex(re, -wd)],
            name=name,
        )


@dataclass(frozen=True)
class Proposal:
    """A proposed diagonal controller k_1 = k_2 = ``controller`` and its full check."""

    controller: LTI
    candidate: Candidate
    check: ControllerCheck
    target_crossover_rad_s: float
    screened: int
    notes: tuple[str, ...] = field(default=())

    @property
    def met(self) -> tuple[str, ...]:
        return self.check.met

    @property
    def unmet(self) -> tuple[str, ...]:
        return self.check.unmet


PI_ZERO_RATIOS = (2.0, 3.3, 5.0, 10.0)  # w_c / z: the PI zero a factor below the crossover
LAG_W0 = (0.4, 0.55, 0.7, 0.85)  # lag pole natural frequency / w_r,max
LAG_ZERO_RATIO = (1.5, 2.0, 2.5)  # lag zero / lag pole natural frequency
LAG_ZETA = (0.15, 0.25, 0.4)


def _sign_change(x: np.ndarray) -> np.ndarray:
    return (np.sign(x[..., :-1]) * np.sign(x[..., 1:])) < 0


def _grid_gm(L: np.ndarray) -> np.ndarray:
    """Smallest |gain change| in dB to reach -1 from the negative-real-axis crossings (grid)."""
    cross = _sign_change(L.imag) & (L.real[..., :-1] < 0)
    with np.errstate(divide="ignore"):
        m = np.abs(20.0 * np.log10(np.abs(L.real[..., :-1])))
    return np.where(cross, m, np.inf).min(axis=-1)


def _grid_pm_crossover(L: np.ndarray, w: np.ndarray):
    """(highest crossover, phase margin there) on the grid, per leading index."""
    above = np.abs(L) >= 1.0
    idx = np.where(above, np.arange(L.shape[-1]), -1).max(axis=-1)
    ok = idx >= 0
    idx = np.clip(idx, 0, None)
    Lc = np.take_along_axis(L, idx[..., None], axis=-1)[..., 0]
    pm = np.degrees(np.angle(-Lc))  # angle from -1, wrapped to (-180, 180]
    pm = np.abs(pm)
    wc = np.where(ok, w[idx], np.nan)
    return wc, np.where(ok, pm, np.inf)


def _grid_structural(F: np.ndarray) -> np.ndarray:
    cross = _sign_change(F.imag) & (F.real[..., :-1] > 0)
    x = np.where(cross, F.real[..., :-1], 0.0).max(axis=-1)
    with np.errstate(divide="ignore"):
        return np.where(x > 0, -20.0 * np.log10(np.where(x > 0, x, 1.0)), np.inf)


def _screen(G: np.ndarray, kv: np.ndarray, w: np.ndarray, specs: Specifications) -> np.ndarray:
    """Smallest normalised slack over specs and speeds for each candidate response kv (nc, nw)."""
    q = icad_quantities(G[None], kv[:, None, :], kv[:, None, :])  # (nc, ns, nw[, 2])
    c = np.moveaxis(q["c"], -1, -2)  # (nc, ns, 2, nw)
    kg = np.moveaxis(q["kg"], -1, -2)
    gh = np.moveaxis(q["gamma_h"], -1, -2)
    wc, pm = _grid_pm_crossover(c, w)
    if specs.bandwidth_measure == "crossover":
        bw = wc
    else:
        T = np.abs(np.moveaxis(q["T"], -1, -2))
        below = T < np.abs(T[..., :1]) / math.sqrt(2.0)
        first = np.where(below, np.arange(w.size), w.size).min(axis=-1)
        bw = np.where(first < w.size, w[np.clip(first, 0, w.size - 1)], np.nan)
    _, kpm = _grid_pm_crossover(kg, w)
    with np.errstate(divide="ignore"):
        cp = 20.0 * np.log10(np.abs(q["coupling"]).max(axis=-2))  # (nc, ns, 2)
    slacks = [
        (np.nan_to_num(bw, nan=0.0) - specs.bandwidth_rad_s) / specs.bandwidth_rad_s,
        (pm - specs.pm_deg) / max(specs.pm_deg, 1.0),
        (kpm - specs.pm_deg) / max(specs.pm_deg, 1.0),
        (_grid_gm(c) - specs.gm_db) / max(specs.gm_db, 1.0),
        (_grid_gm(kg) - specs.gm_db) / max(specs.gm_db, 1.0),
        (specs.coupling_db - cp) / max(abs(specs.coupling_db), 1.0),
        (_grid_structural(gh) - specs.structural_gm_db) / max(specs.structural_gm_db, 1.0),
    ]
    return np.min([s.reshape(s.shape[0], -1).min(axis=-1) for s in slacks], axis=0)


def _unit_controller_response(pi_zero, lag, s):
    k = (s + pi_zero) / s
    if lag is not None:
        a, w0, zeta = lag
        k = k * (s + a) ** 2 / (s**2 + 2 * zeta * w0 * s + w0**2)
    return k


@checked(
    plant=PLANT_FAMILY, speeds=Array((0, 1), optional=True), specs=Instance(Specifications),
    w=Array(1, low=0.0, optional=True), max_verify=COUNT,
)
def propose_controller(
    plant, speeds=None, specs: Specifications = PAPER_SPECS, *, w=None, max_verify: int = 3
) -> Proposal:
    """Propose a stable, minimum-phase k_1 = k_2 (PI, else PI x lag (22)) meeting ``specs``.

    Explainable search: (1) target crossover w_c from the bandwidth spec (5 % above it for
    ``crossover``, the spec / 1.3 for ``closed_loop``); (2) for each PI zero w_c / r and each
    lag (zero a, poles w0, zeta) on a small grid, the gain puts |k m(j w_c)| = 1 for the design
    model m = g_11 (1 - gamma) (h_2 = 1) at the speed needing the most gain; (3) every candidate
    is screened on the grid over all speeds (smallest normalised slack), the PI is preferred if
    it meets everything, otherwise the best-scoring candidate; (4) the choice is checked with
    the full ICAD (``check_controller``); if that check fails a spec the screen passed, the next
    candidates are tried (up to ``max_verify``). The result reports which specs are met.
    """
    if not isinstance(specs, Specifications):
        raise InputError("specs", f"must be Specifications, got {type(specs).__name__}")
    family = plant_family(plant)
    speeds = specs.speeds() if speeds is None else _check_speeds(speeds)
    plants = [family(float(s)) for s in speeds]
    A, B, C, D, _ = stack_plants(plants)
    w_c = specs.bandwidth_rad_s * (1.05 if specs.bandwidth_measure == "crossover" else 1 / 1.3)
    w_r_max = float(np.max(np.abs(speeds)))
    lag_scale = w_r_max if w_r_max > 0 else w_c / 10.0
    if w is None:
        w = np.logspace(math.log10(min(1.0, lag_scale / 100.0)), math.log10(100.0 * w_c), 800)
    G = evaluate_ss(A, B, C, D, 1j * w)  # (ns, nw, 2, 2)
    Gc = evaluate_ss(A, B, C, D, np.array([1j * w_c]))[:, 0]  # (ns, 2, 2)
    model_c = (Gc[:, 0, 0] * Gc[:, 1, 1] - Gc[:, 0, 1] * Gc[:, 1, 0]) / Gc[:, 1, 1]
    lags = [None] + [
        (r * w0 * lag_scale, w0 * lag_scale, z)
        for w0 in LAG_W0
        for r in LAG_ZERO_RATIO
        for z in LAG_ZETA
    ]
    cands = []
    responses = []
    for lag in lags:
        for ratio in PI_ZERO_RATIOS:
            z = w_c / ratio
            unit_c = _unit_controller_response(z, lag, 1j * w_c)
            gain = float(np.max(1.0 / np.abs(unit_c * model_c)))
            responses.append(gain * _unit_controller_response(z, lag, 1j * w))
            cands.append((lag, z, gain))
    kv = np.array(responses)
    scores = np.concatenate([_screen(G, kv[i : i + 16], w, specs) for i in range(0, len(kv), 16)])
    candidates = [
        Candidate(
            "PI" if lag is None else "PI x lag",
            gain,
            z,
            None if lag is None else lag[0],
            None if lag is None else lag[1],
            None if lag is None else lag[2],
            float(sc),
        )
        for (lag, z, gain), sc in zip(cands, scores)
    ]
    n_pi = len(PI_ZERO_RATIOS)
    pi_best = max(candidates[:n_pi], key=lambda c: c.score)
    order = sorted(candidates, key=lambda c: -c.score)
    if pi_best.score >= 0.0:
        order = [pi_best] + [c for c in order if c is not pi_best]
    notes = []
    first = None
    for cand in order[: max(1, max_verify)]:
        k = cand.controller()
        check = check_controller(family, k, k, specs, speeds=speeds)
        proposal = Proposal(k, cand, check, w_c, len(candidates), tuple(notes))
        if first is None:
            first = proposal
        if check.met_all:
            return proposal
        notes.append(f"{cand.structure} (score {cand.score:.3f}) failed: {', '.join(check.unmet)}")
    return Proposal(
        first.controller, first.candidate, first.check, w_c, len(candidates), tuple(notes)
    )


@checked(plant=PLANT, K_I=NONNEGATIVE, w_c=POSITIVE, lo=POSITIVE, hi=POSITIVE)
def pi_gain_for_crossover(
    plant, K_I: float, w_c: float, lo: float = 1e-3, hi: float = 1e5
) -> float:
    """K_P such that the individual channel c_1 (Amezquita-Brooks (7)) of ``plant`` with the PI
    K_P + K_I / s on both loops crosses 0 dB at ``w_c`` [rad/s] (the PI family of equal
    crossover of sec. VII, Fig. 17), found by bisection (brentq) on [``lo``, ``hi``]; an
    InputError names ``w_c`` if the magnitude of c_1(j w_c) does not cross 1 over that range."""
    plant = as_plant(plant)
    K_I = require_nonnegative("K_I", K_I)
    w_c = require_positive("w_c", w_c)
    w = np.array([w_c])
    G = evaluate_ss(plant.A, plant.B, plant.C, plant.D, 1j * w)

    def excess(k_p: float) -> float:
        k = LTI.pi(k_p, K_I).freqresp(w)
        return float(abs(icad_quantities(G, k, k)["c"][0, 0])) - 1.0

    if excess(lo) * excess(hi) > 0:
        raise InputError("w_c", f"no K_P in [{lo:g}, {hi:g}] puts the crossover at {w_c:g} rad/s")
    return float(brentq(excess, lo, hi, xtol=1e-9))
