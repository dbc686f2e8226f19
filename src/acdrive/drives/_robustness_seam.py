"""What a drive tells a robustness map (``Drive.robustness``): where its plant-only perturbation
table is, which reducers measure it, the criteria a run is judged by and the linearised
prediction of its stability.

A ``Criterion`` is one stated tolerance on one batch-row figure: the run passes it when
``row[column] <= limit`` (a figure that is NaN, or a run that did not finish, fails). The
stability criterion is the row's ``stable`` flag (``Drive.verdict`` and a finite state), with
``column = "stable"``.
"""

from __future__ import annotations

from acdrive._arguments import (
    NONNEGATIVE,
    POSITIVE,
    REAL,
    TEXT,
    Function,
    Items,
    Table,
    Text,
    checked,
    optional,
)

import math
from collections.abc import Callable
from dataclasses import dataclass

#: the criteria every map reports, in the order a report lists them
CRITERIA = ("tracking", "current_limit", "stability")


@checked(name=TEXT, column=TEXT, limit=REAL, unit=Text(empty=True), rule=TEXT)
@dataclass(frozen=True)
class Criterion:
    """One stated tolerance: ``name`` (one of ``CRITERIA``), ``column`` of the batch row,
    ``limit`` in ``unit`` (the figure must be <= it), and ``rule``: the sentence a report
    prints (what is measured, over which window, against what)."""

    name: str
    column: str
    limit: float
    unit: str
    rule: str

    def passes(self, row: dict) -> bool:
        """True if the finished run ``row`` meets the tolerance (module docstring)."""
        if row.get("status") != "ok":
            return False
        value = row.get(self.column)
        if self.column == "stable":
            return value is True
        if value is None or not math.isfinite(value):
            return False
        return bool(value <= self.limit)


#: the stability criterion of a drive without a late-oscillation verdict: the run finished
#: with a finite state (``finished_finite``)
FINITE_RUN = Criterion("stability", "stable", 0.0, "", "the run finished with a finite state")


def finished_finite(row: dict, prefixes: tuple[str, ...]) -> dict:
    """The ``stable`` flag of ``FINITE_RUN`` for a batch row: the run finished and every float
    figure whose name starts with one of ``prefixes`` is finite."""
    return {"stable": row.get("status") == "ok" and all(
        math.isfinite(v) for k, v in row.items()
        if isinstance(v, float) and k.startswith(prefixes))}  # fmt: skip


@checked(
    table=TEXT, fields=Table(TEXT), reducers=Function(), criteria=Function(),
    derived=Function(optional=True), linear=Function(optional=True), linear_rule=Text(empty=True),
    design_table=Text(empty=True), design_fields=Items(TEXT, empty=True),
    design_aliases=Table(TEXT, empty=True, optional=True), design_figures=Function(optional=True),
    point_analysis=Function(optional=True),
)
@dataclass(frozen=True)
class RobustnessSeam:
    """A drive's answers to a robustness map.

    ``table``: the dotted scenario path of its plant-only perturbation table (e.g.
    ``motor[0].perturbation``); ``fields``: the map's parameter names -> the table's keys (the
    map says ``L_m`` for the magnetising inductance whatever the drive calls it);
    ``reducers(setup)``: the on-line metrics of a variant; ``criteria(setup, tolerances)``: its
    ``Criterion`` list from the stated tolerances (``Tolerances``); ``derived(setup, row)``: the
    figures a criterion reads that are computed from the row (e.g. a peak over its limit);
    ``linear(setup)``: the
    linearised prediction ``{"predicted_stable": bool, <figure>: value}`` or None where the
    drive has none; ``design_table``: the dotted path of its ``[design]`` table (controllers
    designed on estimates, ``_toml.design_machine``), ``design_fields`` / ``design_aliases`` the
    parameters it takes, ``design_figures(setup)`` the design quantities of a setup (gains,
    estimates) as the drive computes them; ``point_analysis(setup, factors)``: an analysis of one
    perturbed plant too costly for every variant (the cage IM: ICAD of Amezquita-Brooks et al.'s
    Figs. 21-22), run on the paper's point.
    """

    table: str
    fields: dict
    reducers: Callable
    criteria: Callable
    derived: Callable | None = None
    linear: Callable | None = None
    linear_rule: str = ""
    design_table: str = ""
    design_fields: tuple = ()
    design_aliases: dict | None = None
    design_figures: Callable | None = None
    point_analysis: Callable | None = None


@checked(tracking=optional(POSITIVE), current=NONNEGATIVE)
@dataclass(frozen=True)
class Tolerances:
    """The stated tolerances of a map: ``tracking`` (the RMS tracking error as a fraction of the
    reference's scale, which the drive names; None: the drive's default), ``current`` (the
    fraction by which a peak current may exceed its limit)."""

    tracking: float | None = None
    current: float = 0.05
