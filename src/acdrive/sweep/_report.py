"""The report of a sweep: ``report.md`` and ``figures/*.png`` (matplotlib, Agg).

Sections: what ran (variants, valid, ok, diverged); for a grid sweep, every metric against the
swept parameters (``sweep._grid_figures``: lines, or heat maps); the distribution of every metric
(count, min, 5th percentile, median, 95th percentile, max; a histogram per metric); the worst cases
(largest ``report.worst``); the invalid variants with their reasons; the variants beyond a
limit (any ``*_over_limit`` count > 0: samples more than ``OVER_LIMIT_TOLERANCE``, 1 %, above
the limit, the tolerance stated in the report) and, apart from them, the variants in which a
limiter acted (a ``limit`` / ``saturat`` event counted on at least one sample: a controller or
converter holding its command at its limit, as designed, no excursion); the unstable variants
(``stable`` false: diverged, or late speed oscillation above
``OSCILLATION_FINDING_RPM``, ``acdrive.batch``); and, for a sweep with ``[crosscheck]``, the tolerated
speed-loop bandwidth per combination of the other varied fields, simulated against the
linearised sampled drive (``analysis.max_stable_bandwidth``), with the verdict. Grid values in
the tables are written to their grid's resolution (``sweep._grid_figures.grid_labels``).

**Cross-check verdict.** The bandwidth grid b_0 < b_1 < ... is the varied field. Simulated
tolerance: the largest b_i such that every variant with bandwidth <= b_i is stable. Linearised
tolerance: ``max_stable_bandwidth`` (bisection to 1 rad/s) at the variant's final reference
speed, load torque and converter fundamental loss, sampled model with the scenario's sample
time and substeps. They *agree* if the linearised value falls in the grid interval
[b_(i - tol), b_(i + 1 + tol)) where tol is ``crosscheck.tolerance`` grid steps (default 1):
a grid cannot place a boundary more finely than one step, and near the boundary the simulated
oscillation grows slowly, so it may stay below the 1 rpm threshold for the run's length.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from acdrive._arguments import PATH, Instance, checked
from acdrive._reducer_parts import OVER_LIMIT_TOLERANCE
from acdrive.sweep._grid_figures import sweep_labels, write_grid_figures
from acdrive.sweep._spec import SweepSpec

MAX_FIGURES = 16
MAX_LISTED = 30
LIMIT_WORDS = ("limit", "saturat")


def metric_columns(table) -> list[str]:
    import pandas as pd

    out = []
    for name in table.columns:
        if name in ("variant",) or name.startswith(("vary.", "events.")):
            continue
        if pd.api.types.is_numeric_dtype(table[name]) and not pd.api.types.is_bool_dtype(
            table[name]
        ):
            out.append(name)
    return out


def beyond_limit(table):
    """Boolean array: the variant went beyond a limit (an ``*_over_limit`` count > 0: samples
    more than OVER_LIMIT_TOLERANCE above it)."""
    flags = np.zeros(len(table), dtype=bool)
    for name in table.columns:
        if name.endswith("_over_limit"):
            flags |= table[name].fillna(0).to_numpy() > 0
    return flags


def limiter_acted(table) -> tuple[np.ndarray, list[str]]:
    """(Boolean array: a limiter acted in the variant, the event columns that count it): a
    ``limit`` / ``saturat`` event counted on at least one sample."""
    flags = np.zeros(len(table), dtype=bool)
    names = []
    for name in table.columns:
        if name.startswith("events.") and any(w in name for w in LIMIT_WORDS):
            hit = table[name].fillna(0).to_numpy() > 0
            flags |= hit
            if hit.any():
                names.append(name.removeprefix("events."))
    return flags, names


def _fmt(x) -> str:
    if isinstance(x, (float, np.floating)):
        return "nan" if not math.isfinite(x) else f"{x:.4g}"
    return str(x)


def _md_table(header: list[str], rows: list[list], labels: dict | None = None) -> list[str]:
    """A Markdown table; ``labels``: column name -> {value: text} (a grid's rounded values)."""
    labels = labels or {}

    def cell(name, value):
        text = labels.get(name, {}).get(value) if name in labels else None
        return (text if text is not None else _fmt(value)).replace("|", "/")

    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += [
        "| " + " | ".join(cell(name, v) for name, v in zip(header, r, strict=True)) + " |"
        for r in rows
    ]
    return lines


def _figures(table, metrics, folder: Path) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = []
    figures = folder / "figures"
    figures.mkdir(exist_ok=True)
    for name in metrics[:MAX_FIGURES]:
        values = table[name].to_numpy(dtype=float)
        values = values[np.isfinite(values)]
        if values.size == 0:
            continue
        fig, ax = plt.subplots(figsize=(5, 3.2))
        ax.hist(values, bins=min(40, max(5, values.size // 3)))
        ax.set_xlabel(name)
        ax.set_ylabel("variants")
        fig.tight_layout()
        file = f"hist-{name.replace('/', '_')}.png"
        fig.savefig(figures / file, dpi=90)
        plt.close(fig)
        out.append(file)
    return out


def crosscheck(spec: SweepSpec, table) -> tuple[list[dict], bool | None]:
    """Per combination of the other varied fields: the simulated and the linearised tolerated
    bandwidth and whether they agree (module docstring). Returns (rows, all agree)."""
    from acdrive.batch import apply_overrides, build_variant_setup
    from acdrive.drives import for_setup

    cc = spec.crosscheck
    bw = f"vary.{cc['bandwidth_field']}"
    others = [f"vary.{v.field}" for v in spec.vary if v.field != cc["bandwidth_field"]]
    grid = sorted({float(b) for b in table[bw]})
    rows = []
    keys = [()] if not others else sorted({tuple(r) for r in table[others].itertuples(index=False)})
    for key in keys:
        sel = np.ones(len(table), dtype=bool)
        for name, value in zip(others, key, strict=True):
            sel &= (table[name] == value).to_numpy()
        part = table[sel].sort_values(bw)
        stable_at = {float(b): bool(s) for b, s in zip(part[bw], part["stable"].fillna(False),
                                                        strict=True)}  # fmt: skip
        i_sim = -1
        for i, b in enumerate(grid):
            if not stable_at.get(b, False):
                break
            i_sim = i
        fields = {**spec.fixed, **dict(zip([o[5:] for o in others], key, strict=True))}
        fields[cc["bandwidth_field"]] = grid[0]
        setup = build_variant_setup(apply_overrides(spec.base_data, fields))
        point = for_setup(setup).crosscheck(setup, min(grid) / 2, max(grid) * 2)
        linear = point["linearised_tolerated"]
        j_lin = sum(1 for b in grid if b <= linear) - 1
        tol = cc["tolerance"]
        agree = abs(j_lin - i_sim) <= tol
        rows.append({
            **{o[5:]: v for o, v in zip(others, key, strict=True)},
            "speed_rpm": point["speed_rpm"], "load_nm": point["load_nm"],
            "converter_loss_v": point["converter_loss_v"],
            "simulated_tolerated": grid[i_sim] if i_sim >= 0 else 0.0,
            "simulated_first_unstable": grid[i_sim + 1] if i_sim + 1 < len(grid) else math.inf,
            "linearised_tolerated": linear, "grid_step_difference": j_lin - i_sim,
            "agree": agree,
        })  # fmt: skip
    return rows, (all(r["agree"] for r in rows) if rows else None)


@checked(
    spec=Instance("acdrive.sweep._spec:SweepSpec"), folder=PATH, table=Instance("pandas:DataFrame"),
)
def write_report(spec: SweepSpec, folder: Path, table) -> Path:
    """Write ``report.md`` and its figures into the sweep folder ``folder`` (one acdrive wrote:
    its marker, else InputError naming ``folder``); returns the report's path."""
    from acdrive._output import is_acdrive_folder, not_ours

    folder = Path(folder)
    if not is_acdrive_folder(folder):
        raise not_ours("folder", folder)
    lines = [f"# Sweep {spec.name}", ""]
    if spec.description:
        lines += [spec.description, ""]
    n = len(table)
    valid = table["valid"].to_numpy(dtype=bool) if n else np.zeros(0, dtype=bool)
    ok = (table["status"] == "ok").to_numpy() if n else valid
    lines += [
        (
            f"Base scenario: `{spec.base}`; {spec.method} of {n} variants "
            f"({', '.join(v.field for v in spec.vary)}); valid {int(valid.sum())}, ran to the "
            f"end {int(ok.sum())}, diverged {int((valid & ~ok).sum())}, invalid "
            f"{int((~valid).sum())}."
        ),
        "",
    ]
    metrics = metric_columns(table) if n else []
    labels = sweep_labels(spec)
    if metrics and spec.method == "grid":
        files = write_grid_figures(spec, table, metrics, folder, MAX_FIGURES)
        if files:
            lines += ["## Metrics against the swept parameters", ""]
            lines += [f"![{f}](figures/{f})" for f in files] + [""]
    if metrics:
        lines += ["## Distributions", ""]
        rows = []
        for name in metrics:
            v = table[name].to_numpy(dtype=float)
            v = v[np.isfinite(v)]
            if v.size == 0:
                rows.append([name, 0, *["nan"] * 5])
                continue
            q = np.percentile(v, [5, 50, 95])
            rows.append([name, v.size, v.min(), q[0], q[1], q[2], v.max()])
        lines += _md_table(["metric", "n", "min", "p5", "median", "p95", "max"], rows) + [""]
        files = _figures(table, metrics, folder)
        lines += [f"![{f}](figures/{f})" for f in files] + [""]
    worst = spec.worst or next(
        (m for m in metrics if m.startswith("speed_rms_error_tracking")), None
    )
    worst = worst or (metrics[0] if metrics else None)
    if worst is not None and worst in table:
        lines += [f"## Worst cases (largest {worst})", ""]
        top = table[np.isfinite(table[worst].to_numpy(dtype=float))]
        top = top.sort_values(worst, ascending=False).head(spec.worst_count)
        cols = ["variant_id", *[c for c in table.columns if c.startswith("vary.")], worst]
        lines += _md_table(cols, top[cols].values.tolist(), labels) + [""]
    lines += ["## Invalid variants", ""]
    bad = table[~valid] if n else table
    if len(bad):
        lines += [f"{len(bad)} variants were not run:", ""]
        lines += [f"- `{r.variant_id}`: {r.reason}" for r in bad.head(MAX_LISTED).itertuples()]
    else:
        lines.append("None.")
    lines += ["", "## Variants beyond a limit", ""]
    trip = beyond_limit(table) if n else np.zeros(0, dtype=bool)
    lines.append(
        f"{int(trip.sum())} of {n} (an `*_over_limit` count > 0: samples more than "
        f"{100 * OVER_LIMIT_TOLERANCE:g} % above the limit)" + (":" if trip.any() else ".")
    )
    if trip.any():
        lines += [""] + [f"- `{v}`" for v in table["variant_id"][trip].head(MAX_LISTED)]
    acted, events = limiter_acted(table) if n else (np.zeros(0, dtype=bool), [])
    lines += [
        "",
        f"A limiter acted (held its command at its limit, as designed; no excursion) in "
        f"{int(acted.sum())} of {n}" + (f": {', '.join(f'`{e}`' for e in events)}." if events
                                       else "."),
    ]  # fmt: skip
    lines += ["", "## Unstable variants", ""]
    if "stable" in table:
        unstable = table["stable"].eq(False).fillna(False).to_numpy(dtype=bool)
        lines.append(
            f"{int(unstable.sum())} of {n} (diverged, or late speed oscillation above 1 rpm RMS "
            "in 20-200 Hz)" + (":" if unstable.any() else ".")
        )
        osc = [c for c in table.columns if c.startswith("speed_oscillation_late_rpm")]
        for _, r in table[unstable].head(MAX_LISTED).iterrows():
            values = ", ".join(f"{c} = {_fmt(r[c])}" for c in osc)
            lines.append(f"- `{r['variant_id']}`: {r['status']}" + (f"; {values}" if osc else ""))
    if spec.crosscheck and n:
        rows, agree = crosscheck(spec, table)
        lines += ["", "## Cross-check: tolerated bandwidth, simulation against linearisation", ""]
        if rows:
            header = list(rows[0])
            bandwidth = labels.get(f"vary.{spec.crosscheck['bandwidth_field']}", {})
            named = {name[5:]: values for name, values in labels.items()}
            named |= {"simulated_tolerated": bandwidth, "simulated_first_unstable": bandwidth}
            lines += _md_table(header, [list(r.values()) for r in rows], named)
        verdict = "AGREE" if agree else "DISAGREE"
        lines += [
            "",
            (
                f"Verdict: **{verdict}** (tolerance: {spec.crosscheck['tolerance']} grid step(s) "
                "of the bandwidth grid; method in `acdrive.sweep._report`)."
            ),
        ]
    path = folder / "report.md"
    tmp = folder / ".report.md.tmp"
    tmp.write_text("\n".join(lines) + "\n")
    tmp.replace(path)
    return path
