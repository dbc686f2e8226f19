"""Robustness maps: many runs of one scenario with the simulated machine's parameters off their
nominal values and the controllers kept on the nominal design, in the compiled batch loop.

The seam is the drive's plant-only perturbation table (``Drive.robustness().table``, e.g. the
cage IM's ``[machine.perturbation]``): a factor f on a parameter makes the simulated plant's value
f times the nominal one while every controller keeps the nominal value. Seen from the other
side, the controller's estimate is 1/f times the truth. Amezquita-Brooks et al. sec. VIII
perturb the plant this way (R_s, R_r x 2; L_s, L_r x 0.6; L_m x 0.59, ``PAPER_PERTURBATION``).

Two kinds of map (``MapSpec``):

* ``grid``: each parameter alone over ``points`` factors spaced evenly in log between ``low`` and
  ``high`` (the nominal factor 1 always added); the axis ``paper`` moves all five electrical
  parameters together along f_k = PAPER_k^s for a severity s from 0 to ``severity_max`` (s = 1 is
  the paper's perturbation exactly, always included);
* ``monte-carlo``: ``variants`` draws, every chosen parameter's factor log-uniform in
  [``low``, ``high``] (seeded).

Every variant is judged by the drive's criteria (``RobustnessSeam.criteria``: tracking, current
limit, stability, each a stated tolerance on a figure of the batch row) and, where the drive has
one, by its linearised prediction of stability beside the simulated verdict.

Where a grid's verdict changes between two neighbouring points (the last variant that passes a
criterion and the first valid one that breaks it, walking out from the nominal), the map bisects
that interval with further runs (in ln f; in severity on the paper axis) until the two are
``MapSpec.resolution`` apart, and reports the boundary as that pair (``_boundaries``): the
breaking factor with its resolution, not the first breaking grid point. Bisection finds one
crossing inside the grid interval; a criterion that passes again between two grid points (not
monotone there) may have others the grid cannot show.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import time
from dataclasses import dataclass, field

import numpy as np

from acdrive._arguments import (
    COUNT,
    NONNEGATIVE,
    PATH,
    POSITIVE,
    SEED,
    TEXT,
    Either,
    Flag,
    Instance,
    Items,
    Table,
    Text,
    checked,
    optional,
)
from acdrive.analysis._robustness import PAPER_PERTURBATION as _ICAD_PAPER
from acdrive.drives._robustness_seam import CRITERIA, Tolerances
from acdrive.errors import InputError, require_positive

#: Amezquita-Brooks et al. sec. VIII: the perturbed plant of Figs. 21-23 (factors on the plant),
#: the ICAD robustness study's ``analysis._robustness.PAPER_PERTURBATION`` as a dict
PAPER_PERTURBATION = {
    k: float(getattr(_ICAD_PAPER, k)) for k in ("R_s", "R_r", "L_s", "L_r", "L_m")
}
#: the single parameters a map varies (the map's names; ``RobustnessSeam.fields`` translates)
PARAMETERS = ("R_s", "R_r", "L_s", "L_r", "L_m", "L_d", "L_q", "psi_m", "J")
#: the default parameters of a map on an induction machine (a drive without some of them, as the
#: PM drive, gets those of ``PARAMETERS`` its seam has: ``MapSpec.for_fields``)
INDUCTION_PARAMETERS = ("R_s", "R_r", "L_s", "L_r", "L_m", "J")
#: the combined axis of a grid
PAPER = "paper"
KINDS = ("grid", "monte-carlo")
#: default points per grid axis: with 7 axes, 144 on each besides the nominal (the paper axis with
#: s = 1 inserted) and the nominal: 1,009 variants
DEFAULT_POINTS = 145
DEFAULT_VARIANTS = 1000
#: the most variants one map runs (memory of the rows, minutes of a 2-core machine)
MAX_VARIANTS = 100_000
#: default resolution of a grid's refined boundaries: 1e-3 in |ln f| (0.1 % of the factor), and
#: 1e-3 in severity on the paper axis
DEFAULT_RESOLUTION = 1e-3
#: the most bisection rounds of one map (a grid spacing of 1 refined to 1e-9 takes 30)
MAX_REFINEMENT_ROUNDS = 40
#: |ln f| below which a factor is the nominal one
_NOMINAL_TOL = 1e-12


@checked(
    kind=Text(KINDS), params=Items(TEXT, optional=True), points=COUNT, variants=COUNT, low=POSITIVE,
    high=POSITIVE, severity_max=POSITIVE, seed=SEED, resolution=optional(POSITIVE),
)
@dataclass(frozen=True)
class MapSpec:
    """What a map varies (module docstring); checked on construction, each error naming the
    field."""

    kind: str = "grid"
    params: tuple | None = None  # None: every parameter (and on a grid the paper axis)
    points: int = DEFAULT_POINTS
    variants: int = DEFAULT_VARIANTS
    low: float = 0.5
    high: float = 2.0
    severity_max: float = 2.0
    seed: int = 1
    #: a grid's boundaries are refined until the passing and the breaking variant are this close
    #: (in |ln f| on a parameter axis, in severity on the paper axis); None: the grid alone
    resolution: float | None = DEFAULT_RESOLUTION
    #: True when ``params`` was not given (the drive's own parameters are then used)
    defaulted: bool = field(default=False, init=False, compare=False)

    def __post_init__(self):
        if self.kind not in KINDS:
            raise InputError("kind", f"must be one of {', '.join(KINDS)}, got {self.kind!r}")
        if self.params is None:
            object.__setattr__(self, "defaulted", True)
            axes = INDUCTION_PARAMETERS
            object.__setattr__(self, "params", (*axes, PAPER) if self.kind == "grid" else axes)
        if isinstance(self.params, str) or not isinstance(self.params, (tuple, list)):
            raise InputError("params", f"must be a list of parameter names, got {self.params!r}")
        params = tuple(self.params)
        if not params:
            raise InputError("params", "must name at least one parameter")
        known = (*PARAMETERS, PAPER)
        for p in params:
            if p not in known:
                raise InputError("params", f"unknown parameter {p!r}; known: {', '.join(known)}")
        if len(set(params)) < len(params):
            raise InputError("params", "must name each parameter once")
        if self.kind == "monte-carlo" and PAPER in params:
            raise InputError(
                "params",
                f"{PAPER!r} is a grid axis (one path through the parameters), not a Monte Carlo "
                "dimension: draw the single parameters instead",
            )
        object.__setattr__(self, "params", params)
        for name, value in (("points", self.points), ("variants", self.variants)):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                raise InputError(name, f"must be an integer, got {value!r}")
        if self.points < 2:
            raise InputError("points", f"must be at least 2 grid points, got {self.points}")
        if self.variants < 1:
            raise InputError("variants", f"must be at least 1, got {self.variants}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)):
            raise InputError("seed", f"must be an integer, got {self.seed!r}")
        if self.seed < 0:
            raise InputError("seed", f"must be an integer >= 0, got {self.seed}")
        require_positive("low", self.low)
        require_positive("high", self.high)
        if not self.low < self.high:
            raise InputError(
                "high", f"must be larger than the lowest factor ({self.low:g}), got {self.high:g}"
            )
        require_positive("severity_max", self.severity_max)
        if self.resolution is not None:
            require_positive("resolution", self.resolution)
            if self.resolution < 1e-9:
                raise InputError(
                    "resolution", f"must be at least 1e-9 (a finer boundary is below the runs' "
                    f"own rounding), got {self.resolution:g}"
                )  # fmt: skip
        if self.kind == "grid" and 1 + len(params) * (self.points - 1) > MAX_VARIANTS:
            # counted before any axis is built: the nominal and points - 1 others per axis
            raise InputError(
                "points", f"asks for 1 + {len(params)} axes x ({self.points} - 1) = "
                f"{1 + len(params) * (self.points - 1)} variants (limit {MAX_VARIANTS})"
            )  # fmt: skip
        if self.size > MAX_VARIANTS:
            raise InputError(
                "points" if self.kind == "grid" else "variants",
                f"the map would run {self.size} variants (limit {MAX_VARIANTS})",
            )

    def for_fields(self, fields) -> MapSpec:
        """This spec for a drive whose perturbation table has ``fields`` (map names): a spec
        whose parameters were not given takes every one of ``PARAMETERS`` the drive has (and on
        a grid the paper axis, if the drive has all its parameters); a given one is unchanged."""
        if not self.defaulted:
            return self
        axes = tuple(p for p in PARAMETERS if p in fields)
        if self.kind == "grid" and all(k in fields for k in PAPER_PERTURBATION):
            axes = (*axes, PAPER)
        return dataclasses.replace(self, params=axes)

    @property
    def size(self) -> int:
        """The number of variants the map runs."""
        return len(self.points_of()) if self.kind == "grid" else int(self.variants)

    def points_of(self) -> list[tuple[str, float, dict]]:
        """(axis, axis value, factors on the map's parameter names) of every variant: the
        nominal first (axis "nominal", value 1), then each axis in ``params`` order."""
        out = [("nominal", 1.0, {})]
        if self.kind == "grid":
            for p in self.params:
                if p == PAPER:
                    axis = np.linspace(0.0, self.severity_max, self.points)
                    for s in _with(axis, 1.0, 0.0):
                        out.append((p, float(s), paper_factors(s)))
                else:
                    axis = np.exp(np.linspace(math.log(self.low), math.log(self.high), self.points))
                    for f in _with(axis, 1.0, 1.0):
                        out.append((p, float(f), {p: float(f)}))
            return out
        rng = np.random.default_rng(self.seed)
        draws = np.exp(rng.uniform(math.log(self.low), math.log(self.high),
                                   size=(self.variants - 1, len(self.params))))  # fmt: skip
        for row in draws:
            out.append(
                ("monte-carlo", math.nan, dict(zip(self.params, map(float, row), strict=True)))
            )
        return out


def _with(axis: np.ndarray, value: float, nominal: float) -> list[float]:
    """``axis`` with ``value`` in it (an axis point within 1e-12 of it becomes it, else it is
    inserted) and without the ``nominal`` point (the map's first row is the nominal run)."""
    points = {value if abs(x - value) < 1e-12 else float(x) for x in axis}
    points.add(value)
    return sorted(x for x in points if abs(x - nominal) >= 1e-12)


@checked(severity=NONNEGATIVE)
def paper_factors(severity: float) -> dict:
    """Factors PAPER_k ** s of the combined axis (s = 1: ``PAPER_PERTURBATION``; s = 0: none)."""
    if severity == 1.0:
        return dict(PAPER_PERTURBATION)
    return {k: float(f**severity) for k, f in PAPER_PERTURBATION.items()}


def _log_distance(axis: str, value: float, factors: dict) -> float:
    """How far a variant is from the nominal: the largest |ln f| of its factors."""
    return max((abs(math.log(f)) for f in factors.values()), default=0.0)


@checked(
    scenario=TEXT, spec=Instance(MapSpec), table=TEXT,
    criteria=Items(Instance("acdrive.drives._robustness_seam:Criterion"), empty=True),
    rows=Items(Table(), empty=True), linear_rule=Text(empty=True), wall_time=NONNEGATIVE,
    batch_wall_time=NONNEGATIVE, linear_time=NONNEGATIVE, summary=Table(empty=True),
)
@dataclass
class RobustnessMap:
    """The rows of a map (one per variant, nominal first) and what is computed from them.

    Each row: ``axis``, ``value`` (factor or severity), ``factors`` (map names), the batch
    row's figures, ``valid``/``reason``/``status``, ``verdicts`` (criterion -> True/False, None
    if the variant was refused), and with a prediction ``linear``. ``criteria`` are the stated
    tolerances; ``summary`` the findings (``summarise``)."""

    scenario: str
    spec: MapSpec
    table: str
    criteria: list
    rows: list
    linear_rule: str
    wall_time: float
    batch_wall_time: float
    linear_time: float
    summary: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        from acdrive._output import finite_or_null

        def clean(value):
            if isinstance(value, dict):
                return {k: clean(v) for k, v in value.items()}
            if isinstance(value, (list, tuple)):
                return [clean(v) for v in value]
            if isinstance(value, (float, np.floating)):
                return finite_or_null(float(value))
            if isinstance(value, np.integer):
                return int(value)
            return value

        return clean({
            "scenario": self.scenario,
            "map": self.spec.kind,
            "params": list(self.spec.params),
            "variants": len(self.rows),
            "perturbation_table": self.table,
            "meaning": "factor f: simulated plant = f x nominal; controllers keep the nominal "
                       "design (their estimate is 1/f x the truth)",
            "criteria": [{"name": c.name, "column": c.column, "limit": c.limit,
                          "unit": c.unit, "rule": c.rule} for c in self.criteria],
            "linear_rule": self.linear_rule,
            "wall_time_s": self.wall_time,
            "batch_wall_time_s": self.batch_wall_time,
            "linear_time_s": self.linear_time,
            "summary": self.summary,
            "rows": [{k: v for k, v in r.items()} for r in self.rows],
        })  # fmt: skip


def _seam_of(data: dict):
    from acdrive.drives import for_data

    return for_data(data).robustness()


def _table_value(seam, factors: dict) -> dict:
    return {seam.fields[k]: f for k, f in factors.items()}


@checked(
    scenario=Either(PATH, Table()), spec=Instance(MapSpec, optional=True),
    tracking_tolerance=optional(POSITIVE), current_tolerance=NONNEGATIVE,
    linear=Flag(optional=True), overrides=Table(empty=True, optional=True),
    lockstep=Flag(optional=True),
)
def robustness_map(scenario, spec: MapSpec | None = None, *, tracking_tolerance=None,
                   current_tolerance: float = 0.05, linear: bool | None = None,
                   overrides: dict | None = None, lockstep: bool | None = None) -> RobustnessMap:  # fmt: skip
    """Run the map ``spec`` (default: the full grid) on ``scenario`` (built-in name, TOML path
    or parsed dict) and judge every variant (module docstring).

    ``tracking_tolerance``: the tracking criterion's fraction (None: the drive's default);
    ``current_tolerance``: how far a peak current may exceed its limit (fraction);
    ``linear``: add the drive's linearised prediction to every valid variant (None: on a grid,
    off in Monte Carlo, where it would cost more than the simulations); ``overrides``: scenario
    fields set in every variant (e.g. ``{"simulation.duration": 2.0}``), as ``simulate_batch``.
    All input is checked before any simulation.
    """
    from acdrive.batch import _base_data, apply_overrides, build_variant_setup

    start = time.perf_counter()
    spec = spec if spec is not None else MapSpec()
    if not isinstance(spec, MapSpec):
        raise InputError("spec", "must be a MapSpec")
    if tracking_tolerance is not None:
        require_positive("tracking_tolerance", tracking_tolerance)
    if current_tolerance is None or current_tolerance < 0 or not math.isfinite(current_tolerance):
        raise InputError(
            "current_tolerance", f"must be a finite number >= 0, got {current_tolerance!r}"
        )
    tolerances = Tolerances(tracking=tracking_tolerance, current=float(current_tolerance))
    data, setup = _base_data(scenario)
    if data is None:
        raise InputError("scenario", "a robustness map needs a scenario (name, path or dict)")
    name = str(data.get("name", scenario if isinstance(scenario, str) else "custom"))
    seam = _seam_of(data)
    spec = spec.for_fields(seam.fields)
    missing = [p for p in spec.params if p != PAPER and p not in seam.fields]
    if missing:
        raise InputError("spec.params", f"the drive has no perturbation of {missing[0]!r}")
    if PAPER in spec.params:
        absent = [k for k in PAPER_PERTURBATION if k not in seam.fields]
        if absent:
            raise InputError("spec.params", f"{PAPER!r} needs {absent[0]!r}, which the drive lacks")
    base = apply_overrides(data, dict(overrides or {}))
    nominal = build_variant_setup(copy.deepcopy(base))  # a bad scenario fails here, before work
    from acdrive.drives import for_setup

    for_setup(nominal).build(nominal)  # a setup no batch can run (several runs) fails here
    criteria = seam.criteria(nominal, tolerances)
    linear = (spec.kind == "grid") if linear is None else bool(linear)
    judge = _Judge(base, seam, nominal, criteria, linear, lockstep)
    rows = judge.rows(spec.points_of(), refined=False)
    if spec.kind == "grid" and spec.resolution is not None:
        for _ in range(MAX_REFINEMENT_ROUNDS):
            points = _midpoints(rows, criteria, spec.resolution)
            if not points:
                break
            rows += judge.rows(points, refined=True, first_index=len(rows))
    m = RobustnessMap(
        scenario=name, spec=spec, table=seam.table, criteria=criteria, rows=rows,
        linear_rule=seam.linear_rule if linear else "", wall_time=0.0,
        batch_wall_time=judge.batch_wall_time, linear_time=judge.linear_time,
    )  # fmt: skip
    m.summary = summarise(m)
    point = m.summary.get("paper_point")
    if point is not None and point["valid"] and seam.point_analysis is not None:
        point["analysis"] = seam.point_analysis(nominal, dict(PAPER_PERTURBATION))
    m.wall_time = time.perf_counter() - start
    return m


class _Judge:
    """Runs map points in the batch loop and judges each row by the criteria (and, with
    ``linear``, adds the drive's prediction), keeping the time spent in each."""

    def __init__(self, base, seam, nominal, criteria, linear: bool, lockstep):
        self.base, self.seam, self.nominal, self.criteria = base, seam, nominal, criteria
        self.linear, self.lockstep = linear, lockstep
        self.batch_wall_time = self.linear_time = 0.0

    def rows(self, points: list, *, refined: bool, first_index: int = 0) -> list[dict]:
        """One judged row per (axis, value, factors) of ``points``; ``variant`` numbers the row
        in the map (``first_index`` on)."""
        from acdrive.batch import apply_overrides, build_variant_setup, simulate_batch

        seam = self.seam
        variants = [{seam.table: _table_value(seam, f)} for _, _, f in points]
        result = simulate_batch(self.base, variants, reducers=seam.reducers,
                                lockstep=self.lockstep)  # fmt: skip
        self.batch_wall_time += result.wall_time
        rows = []
        for (axis, value, factors), variant, row in zip(points, variants, result.rows,
                                                        strict=True):  # fmt: skip
            out = {"axis": axis, "value": value, "factors": factors,
                   "log_distance": _log_distance(axis, value, factors), **row,
                   "variant": first_index + row["variant"], "refined": refined}  # fmt: skip
            if row["valid"] and seam.derived is not None:
                out.update(seam.derived(self.nominal, row))
            out["verdicts"] = (
                {c.name: c.passes(out) for c in self.criteria}
                if row["valid"]
                else dict.fromkeys(CRITERIA)
            )
            if self.linear and row["valid"] and seam.linear is not None:
                t0 = time.perf_counter()
                setup = build_variant_setup(apply_overrides(self.base, variant))
                out["linear"] = seam.linear(setup)
                self.linear_time += time.perf_counter() - t0
            rows.append(out)
        return rows


# --- boundaries -------------------------------------------------------------------------------


def _coordinate(axis: str, value: float) -> float:
    """Where a grid value lies on its axis for bisection: ln f on a parameter axis, the
    severity itself on the paper axis (the nominal is 0 on both)."""
    return value if axis == PAPER else math.log(value)


def _value(axis: str, x: float) -> float:
    return x if axis == PAPER else math.exp(x)


def _boundaries(rows: list, axis: str, criterion: str) -> dict:
    """The boundary of ``criterion`` on each side of the nominal along ``axis`` (sides "below"
    and "above"; the paper axis has only "above"): walking out from the nominal over the axis's
    rows (grid and refined), the last variant that passes and the first that does not.

    Each side is ``{"passes": value, "breaks": value, "width": |x_breaks - x_passes|}`` (x as
    ``_coordinate``: the width is in ln f, or in severity) when the first variant that does not
    pass is a valid run that breaks the criterion; None when every variant on the side passes,
    when the nominal itself does not pass, or when the first that does not pass was refused (the
    scenario's checks end that side first: ``first_refused_*``)."""
    nominal = rows[0]
    out = {}
    for side in ("below", "above") if axis != PAPER else ("above",):
        mine = sorted(
            (r for r in rows if r["axis"] == axis
             and (_coordinate(axis, r["value"]) < 0) == (side == "below")),
            key=lambda r: abs(_coordinate(axis, r["value"])),
        )  # fmt: skip
        found = None
        last = {**nominal, "value": 0.0 if axis == PAPER else 1.0}
        for r in [last, *mine] if nominal["verdicts"].get(criterion) is True else []:
            if r["valid"] and r["verdicts"][criterion] is True:
                last = r
                continue
            if r["valid"] and r["verdicts"][criterion] is False:
                found = {"passes": last["value"], "breaks": r["value"],
                         "width": abs(_coordinate(axis, r["value"])
                                      - _coordinate(axis, last["value"]))}  # fmt: skip
            break
        out[side] = found
    return out


def _midpoints(rows: list, criteria: list, resolution: float) -> list[tuple[str, float, dict]]:
    """The next bisection points of every boundary wider than ``resolution`` (``_boundaries``),
    one per (axis, value): the mean of the two ends in ``_coordinate``."""
    axes = dict.fromkeys(r["axis"] for r in rows[1:])
    points = {}
    for axis in axes:
        for c in criteria:
            for b in _boundaries(rows, axis, c.name).values():
                if b is None or b["width"] <= resolution:
                    continue
                x = 0.5 * (_coordinate(axis, b["passes"]) + _coordinate(axis, b["breaks"]))
                value = _value(axis, x)
                if value in (b["passes"], b["breaks"]):
                    continue  # the two ends are adjacent floats
                factors = paper_factors(value) if axis == PAPER else {axis: value}
                points[(axis, value)] = (axis, value, factors)
    return list(points.values())


# --- findings ---------------------------------------------------------------------------------


def _first_break(rows: list, criterion: str, below: bool):
    """The axis value nearest the nominal (in |ln f|; on the ``paper`` axis the smallest
    severity, ``below`` None) that breaks ``criterion`` on one side of it
    (``below``: factors < 1), or None if none does."""
    side = [
        r
        for r in rows
        if r["log_distance"] > 0
        and r["verdicts"][criterion] is False
        and (below is None or (r["value"] < 1.0) == below)
    ]
    if not side:
        return None
    return min(side, key=lambda r: r["log_distance"])["value"]


def _first_refused(rows: list, below: bool | None):
    """{value, reason} of the refused variant nearest the nominal on one side (as
    ``_first_break``), or None: where the scenario's own checks refuse the plant (not a machine,
    or a pre-check such as an unstable sampled loop), with their one-line reason."""
    side = [r for r in rows if not r["valid"] and (below is None or (r["value"] < 1.0) == below)]
    if not side:
        return None
    r = min(side, key=lambda r: r["log_distance"])
    return {"value": r["value"], "reason": r["reason"]}


def _wilson(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """95 % Wilson score interval of a proportion k / n."""
    if n == 0:
        return (math.nan, math.nan)
    p = k / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return (max(0.0, c - h), min(1.0, c + h))


def summarise(m: RobustnessMap) -> dict:
    """The map's findings, every one computed from the rows here.

    ``nominal``: the nominal run's verdicts. Grid: per axis, per criterion, the breaking factor
    nearest the nominal below and above 1 (severity on the ``paper`` axis), the refined
    boundary on each side (``_boundaries``: the passing and the breaking value and their
    distance) and the refused variant nearest the nominal on each side with the scenario's
    reason; ``first_to_break``: per criterion, the single parameter whose break is nearest the
    nominal in |ln f| (the refined breaking factor where there is one, with the passing factor
    beside it). Monte Carlo: per criterion, the broken fraction of the valid variants with its
    95 % Wilson interval and, per parameter, the median |ln f| of the broken and of the passing
    variants (a parameter whose errors are larger where the criterion breaks drives it).
    Both: ``linear_vs_simulation``, the count of valid variants where the prediction and the
    simulated stability agree and where they differ. ``paper_point``: the verdicts of the
    paper's perturbation (severity 1), where the map has it."""
    rows = m.rows
    nominal = rows[0]
    out: dict = {"nominal": {"verdicts": nominal["verdicts"], "status": nominal["status"]}}
    for c in m.criteria:
        out["nominal"][c.column] = nominal.get(c.column)
    valid = [r for r in rows if r["valid"]]
    out["valid_variants"] = len(valid)
    out["refused_variants"] = len(rows) - len(valid)
    names = [c.name for c in m.criteria]
    if m.spec.kind == "grid":
        axes = {}
        for axis in m.spec.params:
            origin = {**nominal, "value": 0.0 if axis == PAPER else 1.0}
            mine = [r for r in rows if r["axis"] == axis] + [origin]
            ok = [r for r in mine if r["valid"]]
            refused = [r["value"] for r in mine if not r["valid"]]
            axes[axis] = {
                "valid_range": [min(r["value"] for r in ok), max(r["value"] for r in ok)] if ok else None,
                "refused": len(refused),
                "first_refused_below": None if axis == PAPER else _first_refused(mine, True),
                "first_refused_above": _first_refused(mine, None if axis == PAPER else False),
                "first_break_below": {n: None if axis == PAPER else _first_break(ok, n, True)
                                      for n in names},
                "first_break_above": {n: _first_break(ok, n, None if axis == PAPER else False)
                                      for n in names},
            }  # fmt: skip
            sides = {n: _boundaries(rows, axis, n) for n in names}
            axes[axis]["boundary_below"] = {n: sides[n].get("below") for n in names}
            axes[axis]["boundary_above"] = {n: sides[n]["above"] for n in names}
        out["axes"] = axes
        first = {}
        for n in names:
            best = None
            for axis, a in axes.items():
                if axis == PAPER:
                    continue
                for side in ("below", "above"):
                    b = a[f"boundary_{side}"][n]
                    v = a[f"first_break_{side}"][n] if b is None else b["breaks"]
                    if v is not None and (best is None or abs(math.log(v)) < best[2]):
                        best = (axis, v, abs(math.log(v)), b)
            first[n] = None if best is None else {
                "parameter": best[0], "factor": best[1],
                "passes_at": None if best[3] is None else best[3]["passes"],
            }  # fmt: skip
        out["first_to_break"] = first
        paper = [r for r in rows if r["axis"] == PAPER and r["value"] == 1.0]
        if paper:
            p = paper[0]
            out["paper_point"] = {"variant": p["variant"], "factors": p["factors"],
                                  "valid": p["valid"], "reason": p["reason"],
                                  "verdicts": p["verdicts"],
                                  **{c.column: p.get(c.column) for c in m.criteria}}  # fmt: skip
    else:
        rates, drivers = {}, {}
        for n in names:
            broken = [r for r in valid if r["verdicts"][n] is False]
            lo, hi = _wilson(len(broken), len(valid))
            rates[n] = {"broken": len(broken), "of": len(valid),
                        "fraction": len(broken) / len(valid) if valid else math.nan,
                        "ci95": [lo, hi]}  # fmt: skip
            passing = [r for r in valid if r["verdicts"][n] is True]
            per = {}
            for p in m.spec.params:

                def med(rs, p=p):
                    return (
                        float(np.median([abs(math.log(r["factors"].get(p, 1.0))) for r in rs]))
                        if rs
                        else None
                    )

                per[p] = {"median_abs_log_factor_broken": med(broken),
                          "median_abs_log_factor_passing": med(passing)}  # fmt: skip
            drivers[n] = per
        out["broken"] = rates
        out["parameters"] = drivers
    pairs = [(r["linear"].get("predicted_stable"), r["verdicts"]["stability"])
             for r in valid if "linear" in r]  # fmt: skip
    if pairs:
        known = [(a, b) for a, b in pairs if a is not None]
        out["linear_vs_simulation"] = {
            "compared": len(known),
            "agree": sum(a == b for a, b in known),
            "predicted_stable_simulated_unstable": sum(a and not b for a, b in known),
            "predicted_unstable_simulated_stable": sum(b and not a for a, b in known),
            "no_prediction": len(pairs) - len(known),
        }
    return out
