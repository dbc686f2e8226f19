"""Sweep files (TOML): reading and validating every field, named by its path on error.

Schema (units as in the scenario files; every table optional except ``[[vary]]``)::

    name = "my-sweep"               # output folder name (safe file name)
    description = "..."
    base = "bodson-ramp"            # built-in scenario, or a TOML path (relative to this file)
    chunk = 50                      # variants per chunk (one Parquet file each)
    integrator = "rk4"              # optional: "rk4" | "rk6" for every variant
    substeps = 4                    # optional: substeps per sample for every variant

    [fixed]                         # overrides applied to every variant (dotted scenario fields,
    "simulation.duration" = 2.0     #  "part:<part>.<param>" or "initial:<part>.<state>")

    [sampling]
    method = "grid"                 # "grid" (every combination) or "random"
    samples = 100                   # random: number of variants
    seed = 1                        # random: the generator's seed

    [[vary]]                        # one per varied field
    field = "motor[0].load_torque"
    values = [0.0, 0.05]            # grid or random (drawn uniformly among them), or:
    low = 0.0                       # bounds (uniform draw; grid: `points` values, linear, or
    high = 0.1                      #  geometric with log = true), or:
    relative = 0.5                  # base value x (1 +- 0.5)
    points = 3                      # grid with bounds or relative
    log = false

    [metrics]
    default = true                  # the drive's own on-line metrics (its Drive.reducers)
    summary = ["speed_oscillation_rms_rpm"]   # summary.json keys (a full single run per variant)
    [[metrics.reducer]]             # more on-line metrics (acdrive.batch.Reducer)
    name = "peak_speed_rpm"
    kind = "peak"                   # peak | mean | rms | exceed | final | oscillation
    signal = "shaft0.w"             # "part.output"
    reference = "reference0.w_ref"  # optional, subtracted from the signal
    start = 0.0                     # window [s]; stop optional
    limit = 0.0                     # exceed: threshold in the signal's unit
    scale = 9.549                   # multiplies the value (e.g. rad/s -> rpm)

    [traces]                        # optional decimated traces of a few signals
    signals = ["shaft0.w"]
    every = 50                      # samples between rows

    [report]
    worst = "speed_rms_error_tracking_rpm"   # metric whose largest values are the worst cases
    count = 5

    [limits]                        # checked before the sweep starts
    max_variants = 1000000
    max_table_mb = 1024
    max_memory_mb = 1024

    [crosscheck]                    # optional: tolerated speed-loop bandwidth against the
    bandwidth_field = "motor[0].controller.speed_bandwidth"   # linearised sampled drive
    tolerance = 1                   # grid steps by which the two may differ

Every error is an ``InputError("<path.to.field>", "<rule>")``: one line naming the field.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

from acdrive._arguments import (
    COUNT,
    COUNT0,
    FLAG,
    NONNEGATIVE,
    PATH,
    SEED,
    TEXT,
    Instance,
    Items,
    Table,
    Text,
    checked,
    optional,
)
from acdrive._toml import Section
from acdrive.errors import InputError, require_safe_name

METHODS = ("grid", "random")
DEFAULT_CHUNK = 50
MAX_CHUNK = 5000
LIMIT_DEFAULTS = {"max_variants": 1_000_000, "max_table_mb": 1024.0, "max_memory_mb": 1024.0}


@checked()
def builtin_sweeps() -> list[str]:
    folder = resources.files("acdrive.sweep") / "builtin"
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))


class _Table(Section):
    """One TOML table under validation (``acdrive._toml.Section``: every key read is recorded,
    unknown keys refused), with the sweep file's own rules for numbers, integers and text."""

    def __init__(self, data, path: str):
        if not isinstance(data, dict):
            raise InputError(path or "sweep", "must be a table")
        super().__init__(data, path)

    def name(self, key: str) -> str:
        return self.field(key)

    def number(self, key, default=None, minimum=None, positive=False):
        value = self.get(key, default)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise InputError(self.name(key), "must be a number")
        if not math.isfinite(value):
            raise InputError(self.name(key), "must be finite")
        if positive and value <= 0:
            raise InputError(self.name(key), f"must be > 0, got {value:g}")
        if minimum is not None and value < minimum:
            raise InputError(self.name(key), f"must be >= {minimum:g}, got {value:g}")
        return float(value)

    def integer(self, key, default=None, minimum=1, maximum=None):
        value = self.get(key, default)
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            raise InputError(self.name(key), f"must be an integer >= {minimum}")
        if maximum is not None and value > maximum:
            raise InputError(self.name(key), f"must be an integer <= {maximum}")
        return value

    def text(self, key, default=None, choices=None):
        value = self.get(key, default)
        if not isinstance(value, str) or not value:
            raise InputError(self.name(key), "must be a non-empty string")
        if choices is not None and value not in choices:
            raise InputError(self.name(key), f"must be one of {', '.join(choices)}")
        return value

    def strings(self, key):
        value = self.get(key, [])
        if not isinstance(value, list) or not all(isinstance(v, str) and v for v in value):
            raise InputError(self.name(key), "must be a list of strings")
        return list(value)


@dataclass(frozen=True)
class Vary:
    """One varied field: explicit ``values``, or bounds ``low``/``high``, or ``relative`` to the
    base value; ``points`` values on a grid (geometric with ``log``)."""

    field: str
    values: tuple | None = None
    low: float | None = None
    high: float | None = None
    relative: float | None = None
    points: int | None = None
    log: bool = False

    @property
    def length(self) -> int | None:
        """Values of this field on a grid (counted, never materialised); None for a random draw
        between bounds."""
        return len(self.values) if self.values is not None else self.points


@checked(
    name=TEXT, description=Text(empty=True), base=TEXT, base_data=Table(), method=Text(METHODS),
    samples=COUNT0, seed=SEED, chunk=COUNT, vary=Items(Instance(Vary), empty=True),
    fixed=Table(empty=True), integrator=Text(("rk4", "rk6"), optional=True),
    substeps=optional(COUNT), default_metrics=FLAG,
    reducers=Items(Instance("acdrive.batch:Reducer"), empty=True), summary=Items(TEXT, empty=True),
    traces=Items(TEXT, empty=True), trace_every=COUNT0, worst=Text(optional=True),
    worst_count=COUNT0, limits=Table(NONNEGATIVE, empty=True),
    crosscheck=Table(empty=True, optional=True),
)
@dataclass(frozen=True)
class SweepSpec:
    name: str
    description: str
    base: str  # what the file said (for the report)
    base_data: dict  # the parsed base scenario
    method: str
    samples: int
    seed: int
    chunk: int
    vary: tuple[Vary, ...]
    fixed: dict
    integrator: str | None
    substeps: int | None
    default_metrics: bool
    reducers: tuple = ()
    summary: tuple[str, ...] = ()
    traces: tuple[str, ...] = ()
    trace_every: int = 0
    worst: str | None = None
    worst_count: int = 5
    limits: dict = field(default_factory=lambda: dict(LIMIT_DEFAULTS))
    crosscheck: dict | None = None

    def to_payload(self) -> dict:
        """Everything a worker needs, as plain data (JSON-serialisable, picklable)."""
        from dataclasses import asdict

        out = asdict(self)
        out["reducers"] = [asdict(r) for r in self.reducers]
        return out

    def digest(self) -> str:
        """A hash of everything that decides the variants and their results: a resumed sweep
        must have the same."""
        payload = self.to_payload()
        for key in ("chunk", "description", "worst", "worst_count", "limits"):
            payload.pop(key)  # presentation and chunking do not change a variant's result
        text = json.dumps(payload, sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def spec_from_payload(payload: dict) -> SweepSpec:
    from acdrive.batch import Reducer

    data = dict(payload)
    data["vary"] = tuple(Vary(**v) for v in data["vary"])
    data["reducers"] = tuple(
        Reducer(**{**r, "band_hz": tuple(r["band_hz"])}) for r in data["reducers"]
    )
    for key in ("summary", "traces"):
        data[key] = tuple(data[key])
    return SweepSpec(**data)


def read_sweep_text(source: str) -> tuple[str, Path | None]:
    """(TOML text, folder that relative paths start from) of a built-in name or a file."""
    if source in builtin_sweeps():
        text = (resources.files("acdrive.sweep") / "builtin" / f"{source}.toml").read_text()
        return text, None
    path = Path(source)
    if not path.is_file():
        raise InputError(
            "sweep", f"'{source}' is neither a built-in sweep ({', '.join(builtin_sweeps())}) "
            "nor a file"
        )  # fmt: skip
    try:
        return path.read_text(encoding="utf-8"), path.resolve().parent
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError("sweep", f"cannot read {path} ({exc})") from None


@checked(source=PATH)
def load_sweep(source: str) -> SweepSpec:
    """Read and validate a sweep file (or built-in sweep name)."""
    from acdrive._toml import parse_toml

    text, folder = read_sweep_text(str(source))
    return build_spec(parse_toml(text, str(source), "sweep"), folder)


def _base(top: _Table, folder: Path | None) -> tuple[str, dict]:
    from acdrive.scenarios._files import builtin_names, read_scenario

    base = top.text("base", "bodson-ramp")
    if base in builtin_names():
        return base, read_scenario(base)
    path = Path(base)
    if not path.is_absolute() and folder is not None:
        path = folder / path
    if not path.is_file():
        raise InputError("base", f"'{base}' is neither a built-in scenario nor a file")
    try:
        return base, read_scenario(str(path))
    except InputError as exc:
        raise InputError("base", exc.rule) from None


def _vary(raw, index: int, method: str, base_data: dict) -> Vary:
    from acdrive.batch import get_field

    t = _Table(raw, f"vary[{index}]")
    name = t.text("field")
    where = t.name("field")
    if not name.startswith(("part:", "initial:")):
        try:
            from acdrive.batch import _segments

            _segments(name)
        except InputError as exc:
            raise InputError(where, exc.rule) from None
    forms = [k for k in ("values", "low", "relative") if t.has(k)]
    if len(forms) != 1:
        raise InputError(
            t.name("values"), "give exactly one of: values, low and high, relative"
        )  # fmt: skip
    values = low = high = relative = points = None
    log = t.boolean("log", False)
    if t.has("values"):
        raw_values = t.get("values")
        if not isinstance(raw_values, list) or not raw_values:
            raise InputError(t.name("values"), "must be a non-empty list")
        for j, v in enumerate(raw_values):
            if isinstance(v, bool) or not isinstance(v, (int, float, str)):
                raise InputError(f"{t.name('values')}[{j}]", "must be a number or a string")
            if isinstance(v, float) and not math.isfinite(v):
                raise InputError(f"{t.name('values')}[{j}]", "must be finite")
        values = tuple(raw_values)
    elif t.has("low"):
        low, high = t.number("low"), t.number("high")
        if not high > low:
            raise InputError(t.name("high"), "must be greater than low")
        if log and low <= 0:
            raise InputError(t.name("low"), "must be > 0 with log = true")
    else:
        relative = t.number("relative", positive=True)
        if name.startswith(("part:", "initial:")):
            raise InputError(t.name("relative"), "needs a scenario field (use low and high)")
        value = get_field(base_data, name)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise InputError(
                t.name("relative"),
                f"needs a number at {name} in the base scenario (give low and high instead)",
            )
        low, high = value * (1 - relative), value * (1 + relative)
        if low > high:
            low, high = high, low
        if low == high:
            raise InputError(t.name("relative"), f"the base value of {name} is zero")
    if method == "grid" and values is None:
        points = t.integer("points", minimum=2)
    elif t.has("points"):
        raise InputError(t.name("points"), "is for grids with bounds (not values or random)")
    t.done()
    return Vary(name, values, low, high, relative, points, log)


def _reducers(metrics: _Table) -> tuple:
    from acdrive.batch import Reducer, check_reducer

    raw = metrics.get("reducer", [])
    if not isinstance(raw, list):
        raise InputError(metrics.name("reducer"), "must be an array of tables [[metrics.reducer]]")
    out = []
    for i, item in enumerate(raw):
        t = _Table(item, f"{metrics.name('reducer')}[{i}]")
        band = t.get("band_hz", [20.0, 200.0])
        if not (isinstance(band, list) and len(band) == 2):
            raise InputError(t.name("band_hz"), "must be [low, high] in Hz")
        r = Reducer(
            name=t.text("name"),
            kind=t.text("kind"),
            signal=t.text("signal"),
            reference=t.get("reference"),
            start=t.number("start", 0.0, minimum=0.0),
            stop=t.number("stop") if t.has("stop") else None,
            limit=t.number("limit", 0.0, minimum=0.0),
            scale=t.number("scale", 1.0),
            band_hz=(band[0], band[1]),
            window=t.number("window", 0.25, positive=True),
        )
        t.done()
        if r.reference is not None and not isinstance(r.reference, str):
            raise InputError(t.name("reference"), 'must name an output as "part.output"')
        out.append(check_reducer(r, t.path))
    names = [c for r in out for c in r.columns()]
    for n in names:
        if names.count(n) > 1:
            raise InputError(metrics.name("reducer"), f"two metrics are named {n}")
    return tuple(out)


def _check_count(method: str, samples: int, vary: tuple[Vary, ...], limit: int) -> None:
    """Refuse more than ``limit`` variants, counted as the product of the grid's axis lengths
    (nothing is materialised: ``points = 1000000000`` is refused at once)."""
    if method == "random":
        if samples > limit:
            raise InputError(
                "sampling.samples", f"{samples:.4g} variants exceed limits.max_variants = {limit}"
            )
        return
    n = math.prod(v.length for v in vary)
    if n <= limit:
        return
    i = max(range(len(vary)), key=lambda j: vary[j].length)
    longest = vary[i]
    where = f"vary[{i}]." + ("values" if longest.values is not None else "points")
    field = where if longest.length > limit else "vary"
    raise InputError(
        field, f"the grid has {n:.4g} variants (the product of the axes' lengths, "
        f"{' x '.join(str(v.length) for v in vary)}), more than limits.max_variants = {limit}"
    )  # fmt: skip


#: the loaders' rules that say a value has the wrong type (not a wrong size): such a value is a
#: mistake in the sweep file, refused at load; a value of the right type that breaks a rule of
#: its field or of a combination is an invalid variant, kept as a row with its reason
_TYPE_RULES = (
    "must be a number",
    "must be a real number",
    "must be an integer,",
    "must be a string",
    "must be true or false",
    "must be a table",
    "must be a non-empty list",
    "must be a list",
    "must be a [time_s, value] pair",
    "must be one of",
)


def _kind(value) -> str:
    if isinstance(value, bool):
        return "true or false"
    if isinstance(value, (int, float)):
        return "a number"
    if isinstance(value, str):
        return "a string"
    return type(value).__name__


def _check_value(field: str, where: str, value, base_data: dict, fixed: dict,
                 field_where: str | None = None) -> None:  # fmt: skip
    """Refuse ``value`` for ``field`` (named ``where``) if the base scenario's loader refuses it
    for its type: the variant with that value alone is built, and an error naming ``field`` with
    a type rule is raised on ``where``; a ``field`` the loader does not know (an unknown key) is
    refused on ``field_where`` (default ``where``), the entry that names it."""
    from acdrive.batch import apply_overrides, build_variant_setup

    if field.startswith(("part:", "initial:")):
        if _kind(value) != "a number":
            raise InputError(where, f"{field} is a part's parameter or state: must be a number")
        return
    try:
        build_variant_setup(apply_overrides(base_data, {**fixed, field: value}))
    except InputError as exc:
        if exc.field == field and exc.rule.startswith(_TYPE_RULES):
            raise InputError(where, f"{value!r} for {field}: {exc.rule}") from None
        if exc.field == field and exc.rule.startswith("unknown key"):
            raise InputError(field_where or where, f"{field} is not a field of the base "
                             f"scenario (its loader: {exc.rule})") from None  # fmt: skip


def _check_values(vary: tuple[Vary, ...], fixed: dict, base_data: dict) -> None:
    """Every varied and fixed field exists in the base scenario (an index such as motor[3] on a
    one-motor base is refused), each ``values`` list holds one kind of value (one table column
    has one type), and a value of the wrong type for its field is refused before anything runs
    (one variant per kind of value is built; see :func:`_check_value`)."""
    from acdrive.batch import get_field

    scenario_fixed = {k: v for k, v in fixed.items() if not k.startswith(("part:", "initial:"))}
    for key, value in fixed.items():
        if not key.startswith(("part:", "initial:")):
            try:
                get_field(base_data, key)
            except InputError as exc:
                raise InputError(f"fixed.{key}", exc.rule) from None
        _check_value(key, f"fixed.{key}", value, base_data, {})
    for i, v in enumerate(vary):
        if not v.field.startswith(("part:", "initial:")):
            try:
                get_field(base_data, v.field)
            except InputError as exc:
                raise InputError(f"vary[{i}].field", exc.rule) from None
        if v.values is None:
            _check_value(v.field, f"vary[{i}].low", v.low, base_data, scenario_fixed,
                         f"vary[{i}].field")  # fmt: skip
            continue
        kinds: dict[str, int] = {}
        for j, value in enumerate(v.values):
            kinds.setdefault(_kind(value), j)
        for j in kinds.values():
            _check_value(v.field, f"vary[{i}].values[{j}]", v.values[j], base_data, scenario_fixed,
                         f"vary[{i}].field")  # fmt: skip
        if len(kinds) > 1:
            j = sorted(kinds.values())[1]
            raise InputError(
                f"vary[{i}].values[{j}]", f"must be {_kind(v.values[0])} like values[0] (one "
                f"field's values share one type), got {v.values[j]!r}"
            )  # fmt: skip


def build_spec(data: dict, folder: Path | None = None) -> SweepSpec:
    """Validate a parsed sweep file (``folder``: where relative paths start)."""
    top = _Table(data, "")
    name = require_safe_name("name", top.get("name", "sweep"))
    description = top.get("description", "")
    if not isinstance(description, str):
        raise InputError("description", "must be a string")
    base, base_data = _base(top, folder)
    chunk = top.integer("chunk", DEFAULT_CHUNK, maximum=MAX_CHUNK)
    integrator = top.text("integrator", choices=("rk4", "rk6")) if top.has("integrator") else None
    substeps = top.integer("substeps", maximum=1000) if top.has("substeps") else None

    fixed = top.get("fixed", {})
    if not isinstance(fixed, dict):
        raise InputError("fixed", 'must be a table of "field" = value')
    for key, value in fixed.items():
        if isinstance(value, dict):
            raise InputError(f"fixed.{key}", 'write the dotted field in quotes: "a.b" = value')

    sampling = _Table(top.get("sampling", {}), "sampling")
    method = sampling.text("method", "grid", choices=METHODS)
    samples = seed = 0
    if method == "random":
        samples = sampling.integer("samples")
        seed = sampling.integer("seed", 0, minimum=0)
    sampling.done()

    raw_vary = top.get("vary")
    if not isinstance(raw_vary, list) or not raw_vary:
        raise InputError("vary", "at least one [[vary]] table is required")
    vary = tuple(_vary(v, i, method, base_data) for i, v in enumerate(raw_vary))
    fields = [v.field for v in vary]
    for f in fields:
        if fields.count(f) > 1:
            raise InputError("vary", f"{f} is varied twice")

    metrics = _Table(top.get("metrics", {}), "metrics")
    default_metrics = metrics.boolean("default", True)
    summary = tuple(metrics.strings("summary"))
    reducers = _reducers(metrics)
    metrics.done()
    from acdrive.batch import _segments

    for i, key in enumerate(summary):
        try:
            _segments(key)
        except InputError:
            raise InputError(f"metrics.summary[{i}]", "must be a dotted summary.json key") from None
    direct = [f for f in (*fields, *fixed) if f.startswith(("part:", "initial:"))]
    if summary and direct:
        raise InputError(
            "metrics.summary", f"needs a full scenario run, which cannot apply {direct[0]}"
        )
    if not default_metrics and not reducers and not summary:
        raise InputError("metrics", "keeps nothing: set default = true or list metrics")

    traces = _Table(top.get("traces", {}), "traces")
    signals = tuple(traces.strings("signals"))
    every = traces.integer("every", 50) if signals else 0
    traces.done()

    report = _Table(top.get("report", {}), "report")
    worst = report.text("worst") if report.has("worst") else None
    count = report.integer("count", 5)
    report.done()

    limits_t = _Table(top.get("limits", {}), "limits")
    limits = {
        "max_variants": limits_t.integer("max_variants", LIMIT_DEFAULTS["max_variants"]),
        "max_table_mb": limits_t.number("max_table_mb", LIMIT_DEFAULTS["max_table_mb"],
                                        positive=True),
        "max_memory_mb": limits_t.number("max_memory_mb", LIMIT_DEFAULTS["max_memory_mb"],
                                         positive=True),
    }  # fmt: skip
    limits_t.done()
    _check_count(method, samples, vary, limits["max_variants"])
    _check_values(vary, dict(fixed), base_data)

    crosscheck = None
    if top.has("crosscheck"):
        cc = _Table(top.get("crosscheck"), "crosscheck")
        crosscheck = {
            "bandwidth_field": cc.text("bandwidth_field"),
            "tolerance": cc.integer("tolerance", 1, minimum=0),
        }
        cc.done()
        if crosscheck["bandwidth_field"] not in fields:
            raise InputError("crosscheck.bandwidth_field", "must be one of the varied fields")
        if method != "grid":
            raise InputError("crosscheck", "needs sampling.method = grid")
    top.done()
    return SweepSpec(
        name=name,
        description=description,
        base=base,
        base_data=base_data,
        method=method,
        samples=samples,
        seed=seed,
        chunk=chunk,
        vary=vary,
        fixed=dict(fixed),
        integrator=integrator,
        substeps=substeps,
        default_metrics=default_metrics,
        reducers=reducers,
        summary=summary,
        traces=signals,
        trace_every=every,
        worst=worst,
        worst_count=count,
        limits=limits,
        crosscheck=crosscheck,
    )
