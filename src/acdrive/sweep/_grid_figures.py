"""A grid sweep's metrics against its swept parameters, and grid values written to their resolution.

**Labels.** A grid value is written to the resolution of its own grid (:func:`grid_labels`): with
``step`` the distance to its nearest neighbour on the grid, it is rounded to
``max(ceil(-log10(step)) + 1, 0)`` decimals, one digit finer than the step so that a step of
0.25 keeps its 0.25 and ``np.linspace(0.1, 0.5, 5)``'s 0.30000000000000004 reads 0.3; a
geometric grid is rounded value by value (its steps grow with the value). Should two values of
a grid round to the same text, every label gets one more decimal until all are distinct. Text
values are written as they are.

**Figures** (:func:`grid_plot`, :func:`draw`). The swept parameters are the varied fields with
more than one value in the table. The x axis is the one with the most values (the first in the
file on a tie), on a log scale if the file made it geometric. With the other swept parameters
taking at most :data:`MAX_LINES` combinations, each combination is one line (a single line when
only one parameter is swept); beyond that the metric is a heat map over the x parameter and the
other parameter with the most values, one panel per combination of any further ones (the first
:data:`MAX_PANELS`, said in the title). A variant that was invalid or diverged has no value: a
gap in its line, a blank cell in a heat map.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from acdrive.sweep._spec import SweepSpec, Vary

MAX_LINES = 8
MAX_PANELS = 6
#: At most this many labelled ticks on an axis (every k-th grid value beyond).
MAX_TICKS = 12


def _is_number(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
        value, (bool, np.bool_)
    )


def _label(value: float, decimals: int) -> str:
    if value == 0 or not math.isfinite(value):
        return "0" if value == 0 else str(value)
    significant = max(math.floor(math.log10(abs(value))) + 1 + decimals, 1)
    return f"{round(value, decimals):.{significant}g}"


def grid_labels(values) -> dict:
    """Each value of one grid -> its text, rounded to the grid's resolution (module docstring)."""
    numbers = sorted({float(v) for v in values if _is_number(v) and math.isfinite(float(v))})
    labels = {v: str(v) for v in values if not _is_number(v) or not math.isfinite(float(v))}
    if len(numbers) == 1:
        return {**labels, **{v: f"{float(v):.6g}" for v in values if _is_number(v)}}
    decimals = {}
    for i, value in enumerate(numbers):
        gaps = [abs(value - numbers[j]) for j in (i - 1, i + 1) if 0 <= j < len(numbers)]
        step = min(gaps)
        decimals[value] = max(math.ceil(-math.log10(step) - 1e-9) + 1, 0)
    for extra in range(17):
        text = {v: _label(v, d + extra) for v, d in decimals.items()}
        if len(set(text.values())) == len(text):
            break
    return {**labels, **{v: text[float(v)] for v in values if _is_number(v)}}


def sweep_labels(spec: SweepSpec) -> dict[str, dict]:
    """``vary.<field>`` -> {value: label} for every varied field of a grid sweep ({} for a
    random sweep: its values are draws, not a grid, and keep their 4 significant digits)."""
    from acdrive.sweep._variants import grid_values

    if spec.method != "grid":
        return {}
    return {f"vary.{v.field}": grid_labels(grid_values(v)) for v in spec.vary}


@dataclass
class GridPlot:
    """One metric against the swept parameters, as drawn by :func:`draw`.

    ``kind`` "lines": ``lines`` holds (label, y over ``x_values``); "heatmap": ``panels`` holds
    (title, array of shape (len(y_values), len(x_values))). ``labels``: field -> {value: text}.
    """

    metric: str
    kind: str
    x_field: str
    x_values: list
    x_log: bool
    labels: dict
    lines: list = field(default_factory=list)
    y_field: str | None = None
    y_values: list = field(default_factory=list)
    panels: list = field(default_factory=list)
    panels_left_out: int = 0


def _ordered(v: Vary, present: set) -> list:
    from acdrive.sweep._variants import grid_values

    values = [x for x in dict.fromkeys(grid_values(v)) if x in present]
    return sorted(values) if all(_is_number(x) for x in values) else values


def grid_plot(spec: SweepSpec, table, metric: str) -> GridPlot | None:
    """The layout and values of ``metric``'s figure (module docstring), or None when no field
    takes more than one value in ``table``."""
    if spec.method != "grid" or not len(table):
        return None
    axes = {}
    for v in spec.vary:
        values = _ordered(v, set(table[f"vary.{v.field}"]))
        if len(values) > 1:
            axes[v.field] = (v, values)
    if not axes:
        return None
    x_field = max(axes, key=lambda f: len(axes[f][1]))  # the first of the longest
    x_vary, x_values = axes[x_field]
    others = [f for f in axes if f != x_field]
    labels = {f: grid_labels(values) for f, (_, values) in axes.items()}
    cells = {}
    columns = [f"vary.{f}" for f in axes]
    for *key, y in table[[*columns, metric]].itertuples(index=False):
        cells[tuple(key)] = float(y) if y is not None else math.nan
    order = list(axes)

    def value_at(assignment: dict) -> float:
        return cells.get(tuple(assignment[f] for f in order), math.nan)

    numeric_x = all(_is_number(x) for x in x_values)
    plot = GridPlot(metric, "lines", x_field, x_values, bool(x_vary.log and numeric_x), labels)
    combos = list(itertools.product(*(axes[f][1] for f in others)))
    if len(combos) <= MAX_LINES:
        for combo in combos:
            fixed = dict(zip(others, combo, strict=True))
            y = np.array([value_at({x_field: x, **fixed}) for x in x_values])
            text = ", ".join(f"{f} = {labels[f][v]}" for f, v in fixed.items())
            plot.lines.append((text, y))
        return plot
    y_field = max(others, key=lambda f: len(axes[f][1]))
    rest = [f for f in others if f != y_field]
    plot.kind, plot.y_field, plot.y_values = "heatmap", y_field, axes[y_field][1]
    panels = list(itertools.product(*(axes[f][1] for f in rest)))
    plot.panels_left_out = max(len(panels) - MAX_PANELS, 0)
    for combo in panels[:MAX_PANELS]:
        fixed = dict(zip(rest, combo, strict=True))
        grid = np.array(
            [[value_at({x_field: x, y_field: y, **fixed}) for x in x_values] for y in plot.y_values]
        )
        text = ", ".join(f"{f} = {labels[f][v]}" for f, v in fixed.items())
        plot.panels.append((text, grid))
    return plot


def _ticks(positions, labels) -> tuple[list, list]:
    """Every k-th of ``positions`` and ``labels``, at most :data:`MAX_TICKS` of them."""
    k = max(math.ceil(len(labels) / MAX_TICKS), 1)
    return list(positions)[::k], list(labels)[::k]


def draw(plot: GridPlot):
    """The matplotlib figure of ``plot`` (Agg); tick and legend texts are the grid labels."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x_labels = [plot.labels[plot.x_field][x] for x in plot.x_values]
    numeric = all(_is_number(x) for x in plot.x_values)
    if plot.kind == "lines":
        fig, ax = plt.subplots(figsize=(6, 3.6))
        x = np.asarray(plot.x_values, dtype=float) if numeric else np.arange(len(x_labels))
        for text, y in plot.lines:
            ax.plot(x, y, marker="o", label=text or None)
        if plot.x_log:
            ax.set_xscale("log")
            ax.minorticks_off()
        ax.set_xticks(*_ticks(x, x_labels))
        if len(x_labels) > 6:
            plt.setp(ax.get_xticklabels(), rotation=45, ha="right")
        ax.set_xlabel(plot.x_field)
        ax.set_ylabel(plot.metric)
        if any(text for text, _ in plot.lines):
            ax.legend(fontsize="small")
        ax.grid(True, alpha=0.3)
    else:
        n = len(plot.panels)
        fig, axes = plt.subplots(1, n, figsize=(3.6 * n + 1.6, 3.8), squeeze=False,
                                 sharey=True, layout="constrained")  # fmt: skip
        finite = [g[np.isfinite(g)] for _, g in plot.panels]
        values = np.concatenate(finite) if finite else np.zeros(0)
        low, high = (values.min(), values.max()) if values.size else (0.0, 1.0)
        cmap = matplotlib.colormaps["viridis"].with_extremes(bad="white")  # no value: blank
        y_labels = [plot.labels[plot.y_field][y] for y in plot.y_values]
        for ax, (text, grid) in zip(axes[0], plot.panels, strict=True):
            image = ax.imshow(np.ma.masked_invalid(grid), origin="lower", aspect="auto",
                              cmap=cmap, vmin=low, vmax=high)  # fmt: skip
            ax.set_xticks(*_ticks(range(len(x_labels)), x_labels), rotation=45, ha="right")
            ax.set_yticks(*_ticks(range(len(y_labels)), y_labels))
            ax.set_xlabel(plot.x_field)
            if ax is axes[0][0]:
                ax.set_ylabel(plot.y_field)
            if text:
                ax.set_title(text, fontsize="small")
        fig.colorbar(image, ax=list(axes[0]), label=plot.metric)
        if plot.panels_left_out:
            fig.suptitle(f"first {n} of {n + plot.panels_left_out} combinations", fontsize="small")
    if plot.kind == "lines":
        fig.tight_layout()
    return fig


def write_grid_figures(spec: SweepSpec, table, metrics: list[str], folder: Path,
                       limit: int) -> list[str]:  # fmt: skip
    """Draw each metric's :class:`GridPlot` (at most ``limit``) into ``folder/figures``; returns
    the file names (relative to ``figures``)."""
    import matplotlib.pyplot as plt

    figures = Path(folder) / "figures"
    figures.mkdir(exist_ok=True)
    files = []
    for metric in metrics:
        if len(files) >= limit:
            break
        plot = grid_plot(spec, table, metric)
        if plot is None:
            break
        if all(not np.isfinite(y).any() for _, y in plot.lines + plot.panels):
            continue
        fig = draw(plot)
        name = f"grid-{metric.replace('/', '_')}.png"
        fig.savefig(figures / name, dpi=90)
        plt.close(fig)
        files.append(name)
    return files
