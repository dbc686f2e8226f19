"""Controllers designed on estimated parameters, the plant at the truth, beside the design on the
truth (issue 23, item 4).

``design_comparison(scenario, estimates)`` runs ``scenario`` twice in the compiled batch loop:
as it stands (every controller designed on the scenario's machine, which is also the simulated
plant) and with the drive's ``[design]`` table set to ``estimates`` (``_toml.design_machine``:
the controllers designed on the estimates, the scenario's machine still simulated). Both runs are
judged by the same criteria as a robustness map (``RobustnessSeam.criteria``: tracking, current
limit, stability) and carry the drive's design quantities (``RobustnessSeam.design_figures``:
for the DFIM Bodson's gains (25)-(27), (49) and the controller's estimates; for the cage IM the
IFOC's estimates, the speed PI and the sampled current loop's spectral radius). ``estimates`` is
a machine parameter file (``acdrive identify`` writes one), a machine parameter record or a dict
of parameters; parameters it does not give (the pole pairs, the inertia a standstill test cannot
measure) are the scenario's, and the result lists which came from the estimates.
"""

from __future__ import annotations

import copy
import os
from dataclasses import dataclass

from acdrive._arguments import (
    NONNEGATIVE,
    PATH,
    POSITIVE,
    TEXT,
    Either,
    Instance,
    Items,
    Number,
    Table,
    checked,
    optional,
)
from acdrive.drives._robustness_seam import Tolerances
from acdrive.errors import InputError
from acdrive.machines._registry import MACHINE_RECORD


@checked(
    scenario=TEXT,
    criteria=Items(Instance("acdrive.drives._robustness_seam:Criterion"), empty=True),
    rows=Table(Table()), from_estimates=Items(TEXT, empty=True), table=TEXT,
)
@dataclass
class DesignComparison:
    """``rows``: label ("truth", "estimates") -> {figures of the batch row, ``verdicts``,
    ``design``}; ``criteria``: the stated tolerances; ``from_estimates``: the parameters the
    estimates gave."""

    scenario: str
    criteria: list
    rows: dict
    from_estimates: tuple
    table: str

    def to_json(self) -> dict:
        from acdrive._output import finite_or_null

        def clean(v):
            if isinstance(v, dict):
                return {k: clean(x) for k, x in v.items()}
            if isinstance(v, (list, tuple)):
                return [clean(x) for x in v]
            return finite_or_null(v) if isinstance(v, float) else v

        return clean({
            "scenario": self.scenario,
            "design_table": self.table,
            "from_estimates": list(self.from_estimates),
            "criteria": [{"name": c.name, "column": c.column, "limit": c.limit, "unit": c.unit,
                          "rule": c.rule} for c in self.criteria],
            "runs": self.rows,
        })  # fmt: skip

    def lines(self) -> list[str]:
        """A side-by-side table of the figures the criteria read and of the designs."""
        t, e = self.rows["truth"], self.rows["estimates"]

        def fmt(v):
            return f"{v:.6g}" if isinstance(v, float) else str(v)

        out = [(f"{self.scenario}: controllers designed on the truth and on the estimates "
               f"({', '.join(self.from_estimates)} from the estimates), the plant the truth"),
               f"{'figure':<36} {'design on truth':>18} {'design on estimates':>20}"]  # fmt: skip
        for c in self.criteria:
            out.append(f"{c.column:<36} {fmt(t.get(c.column)):>18} {fmt(e.get(c.column)):>20}")
            out.append(f"  {c.name}: {c.rule}: truth {'passes' if t['verdicts'][c.name] else 'BREAKS'}, "
                       f"estimates {'passes' if e['verdicts'][c.name] else 'BREAKS'}")  # fmt: skip
        for k in t["design"]:
            a, b = t["design"][k], e["design"].get(k)
            if isinstance(a, str) and a == b and len(a) > 18:  # a statement: once, in full
                out.append(f"{k}: {a}")
            else:
                out.append(f"{k:<36} {fmt(a):>18} {fmt(b):>20}")
        return out


def _estimates_table(estimates, seam) -> dict:
    """The ``[design]`` table of ``estimates`` (module docstring)."""
    if isinstance(estimates, (str, os.PathLike)):
        return {"machine_file": os.fspath(estimates)}
    if isinstance(estimates, dict):
        return {"params": dict(estimates)}
    names = [*seam.design_fields, *(seam.design_aliases or {}).values()]
    values = {k: getattr(estimates, k) for k in names if getattr(estimates, k, None) is not None}
    if not values:
        raise InputError(
            "estimates", "must be a parameter file, a machine record or a dict of parameters"
        )
    if seam.design_aliases:  # a record has one name per parameter: keep the drive's own
        for key, alias in seam.design_aliases.items():
            if key in values and alias in values:
                values.pop(alias)
    return {"params": {k: float(v) if k != "n_p" else int(v) for k, v in values.items()}}


@checked(
    scenario=Either(PATH, Table()),
    estimates=Either(PATH, Table(Number()), MACHINE_RECORD),
    tracking_tolerance=optional(POSITIVE), current_tolerance=NONNEGATIVE,
    overrides=Table(empty=True, optional=True),
)
def design_comparison(scenario, estimates, *, tracking_tolerance=None,
                      current_tolerance: float = 0.05, overrides: dict | None = None) -> DesignComparison:  # fmt: skip
    """Run ``scenario`` designed on the truth and on ``estimates`` (module docstring)."""
    from acdrive.batch import _base_data, apply_overrides, build_variant_setup, simulate_batch
    from acdrive.drives import for_data
    from acdrive.errors import require_positive

    if tracking_tolerance is not None:
        require_positive("tracking_tolerance", tracking_tolerance)
    data, _ = _base_data(scenario)
    if data is None:
        raise InputError("scenario", "a design comparison needs a scenario (name, path or dict)")
    seam = for_data(data).robustness()
    base = apply_overrides(data, dict(overrides or {}))
    table = _estimates_table(estimates, seam)
    truth_setup = build_variant_setup(copy.deepcopy(base))
    est_data = apply_overrides(base, {seam.design_table: table})
    est_setup = build_variant_setup(copy.deepcopy(est_data))  # a bad estimate fails here
    taken = _given(table, seam)
    criteria = seam.criteria(truth_setup, Tolerances(tracking_tolerance, float(current_tolerance)))
    result = simulate_batch(base, [{}, {seam.design_table: table}], reducers=seam.reducers)
    rows = {}
    for label, setup, row in (("truth", truth_setup, result.rows[0]),
                              ("estimates", est_setup, result.rows[1])):  # fmt: skip
        if not row["valid"]:
            raise InputError("estimates", row["reason"])
        out = dict(row)
        if seam.derived is not None:
            out.update(seam.derived(truth_setup, row))
        out["verdicts"] = {c.name: c.passes(out) for c in criteria}
        out["design"] = seam.design_figures(setup) if seam.design_figures else {}
        rows[label] = out
    name = str(data.get("name", "custom"))
    return DesignComparison(name, criteria, rows, taken, seam.design_table)


def _given(table: dict, seam) -> tuple:
    """The parameters the ``[design]`` table gives (the file's were checked by the loader)."""
    from pathlib import Path

    from acdrive._toml import parse_toml

    if "machine_file" in table:
        path = Path(table["machine_file"])
        given = parse_toml(path.read_text(encoding="utf-8"), str(path), "estimates")["machine"][
            "params"
        ]
    else:
        given = table["params"]
    aliases = seam.design_aliases or {}
    return tuple(k for k in seam.design_fields if k in given or aliases.get(k) in given)
