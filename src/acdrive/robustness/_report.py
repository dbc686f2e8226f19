"""The report of a robustness map: ``map.json`` (every row and the findings), ``report.md`` (the
findings as sentences, each read from ``RobustnessMap.summary``) and ``map.png`` (grid: each
criterion's figure against the factor, one line per parameter, the tolerance dashed; Monte
Carlo: the tracking figure against the largest |ln f| of each variant)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from acdrive._arguments import PATH, Instance, Text, checked
from acdrive._output import REPORT_STAMP, strict_json
from acdrive.robustness._map import PAPER, RobustnessMap


def _fmt(value) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "none"
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def _pair(passes: float, breaks: float) -> tuple[str, str]:
    """The two ends of a boundary with digits enough to tell them apart."""
    width = abs(math.log(breaks / passes)) if passes > 0 < breaks else abs(breaks - passes)
    digits = max(4, 2 + math.ceil(-math.log10(max(width, 1e-15))))
    return f"{passes:.{digits}g}", f"{breaks:.{digits}g}"


def _side(axis: dict, side: str, criterion: str) -> str:
    """One side of a boundary cell: ``passes -> breaks`` where the map refined it, else the
    first breaking grid value (or none)."""
    b = axis[f"boundary_{side}"][criterion]
    if b is not None:
        passes, breaks = _pair(b["passes"], b["breaks"])
        return f"{passes} -> {breaks}"
    return _fmt(axis[f"first_break_{side}"][criterion])


def report_lines(m: RobustnessMap) -> list[str]:
    """The report's Markdown, every number read from ``m.summary`` or ``m.criteria``."""
    s = m.summary
    lines = [f"<!-- {REPORT_STAMP}robustness` -->",
             f"# Robustness map of `{m.scenario}` ({m.spec.kind}, {len(m.rows)} variants)", "",
             (f"Factor f on a parameter: the simulated plant has f x the nominal value in "
             f"`{m.table}`; the controllers keep the nominal design (their estimate is 1/f x "
             "the truth)."), "", "## Criteria (stated tolerances)", ""]  # fmt: skip
    for c in m.criteria:
        lines.append(f"- **{c.name}** (`{c.column}`): {c.rule}")
    nominal = s["nominal"]
    lines += ["", "## Nominal run", "",
              f"status {nominal['status']}; " + "; ".join(
                  f"{c.name} {'passes' if nominal['verdicts'][c.name] else 'BREAKS'} "
                  f"({c.column} = {_fmt(nominal.get(c.column))})" for c in m.criteria), "",
              (f"{s['valid_variants']} variants ran, {s['refused_variants']} were refused by the "
              "scenario's checks (not a machine, or a pre-check; reasons in map.json)."), ""]  # fmt: skip
    if m.spec.kind == "grid":
        lines += ["## Where each criterion breaks", "",
                  ("A boundary is the pair passes -> breaks of the two nearest variants on "
                   "either side of it (the grid refined by bisection"
                   + (f" to {m.spec.resolution:g} in |ln f| or severity" if m.spec.resolution
                      else ", here not refined") + "); a single value is a grid point."), "",
                  "| axis | valid range | " + " | ".join(f"{c.name} below / above" for c in m.criteria) + " |",
                  "| --- | --- |" + " --- |" * len(m.criteria)]  # fmt: skip
        for axis, a in s["axes"].items():
            rng = (
                "none"
                if a["valid_range"] is None
                else f"{_fmt(a['valid_range'][0])} to {_fmt(a['valid_range'][1])}"
            )
            cells = [f"{_side(a, 'below', c.name)} / {_side(a, 'above', c.name)}"
                     for c in m.criteria]  # fmt: skip
            label = "paper (severity s)" if axis == PAPER else axis
            lines.append(f"| {label} | {rng} | " + " | ".join(cells) + " |")
        lines += [
            "",
            (
                "Refused nearest the nominal (the scenario's own checks; such a plant is not "
                "simulated):"
            ),
            "",
        ]
        for axis, a in s["axes"].items():
            for side in ("first_refused_below", "first_refused_above"):
                r = a[side]
                if r is not None:
                    lines.append(f"- {axis} at {_fmt(r['value'])}: {r['reason']}")
        lines.append("")
        for c in m.criteria:
            f = s["first_to_break"][c.name]
            if f is None:
                lines.append(f"- {c.name}: no single-parameter error in the map breaks it")
                continue
            at = _fmt(f["factor"])
            if f.get("passes_at") is not None:
                passes, at = _pair(f["passes_at"], f["factor"])
                at += f" (passes at {passes})"
            lines.append(f"- {c.name}: breaks first on {f['parameter']} at f = {at}, nearest the "
                         "nominal in |ln f|")  # fmt: skip
        if "paper_point" in s:
            p = s["paper_point"]
            verdicts = ", ".join(f"{k} {'passes' if v else 'breaks' if v is False else 'refused'}"
                                 for k, v in p["verdicts"].items())  # fmt: skip
            lines += ["", "## Amezquita-Brooks et al. sec. VIII (severity 1)", "",
                      f"factors {p['factors']}: {verdicts}; "
                      + ", ".join(f"{c.column} = {_fmt(p.get(c.column))}" for c in m.criteria)]  # fmt: skip
            a = p.get("analysis")
            if a is not None:
                speeds = ", ".join(_fmt(w) for w in a["speeds_rad_s"])
                lines += ["", (f"ICAD of the continuous current loop on this plant (Figs. 21-22) at "
                          f"electrical rotor speeds {speeds} rad/s: conditions i-iv "
                          f"{'hold' if a['conditions_hold'] else 'FAIL'}, worst structural gain "
                          f"margin {_fmt(a['worst_structural_gm_db'])} dB, worst channel phase "
                          f"margin {_fmt(a['worst_channel_pm_deg'])} deg.")]  # fmt: skip
    else:
        lines += ["## Broken fraction (95 % Wilson interval)", ""]
        for c in m.criteria:
            b = s["broken"][c.name]
            lines.append(f"- {c.name}: {b['broken']} of {b['of']} "
                         f"({_fmt(b['fraction'])}, [{_fmt(b['ci95'][0])}, {_fmt(b['ci95'][1])}])")  # fmt: skip
        lines += ["", "Median |ln f| of each parameter among broken / passing variants:", "",
                  "| parameter | " + " | ".join(c.name for c in m.criteria) + " |",
                  "| --- |" + " --- |" * len(m.criteria)]  # fmt: skip
        for p in m.spec.params:
            cells = [f"{_fmt(s['parameters'][c.name][p]['median_abs_log_factor_broken'])} / "
                     f"{_fmt(s['parameters'][c.name][p]['median_abs_log_factor_passing'])}"
                     for c in m.criteria]  # fmt: skip
            lines.append(f"| {p} | " + " | ".join(cells) + " |")
    if "linear_vs_simulation" in s:
        lv = s["linear_vs_simulation"]
        lines += ["", "## Linearised prediction beside the simulation", "", m.linear_rule + ".", "",
                  (f"{lv['agree']} of {lv['compared']} compared variants agree; predicted stable "
                  f"but simulated unstable {lv['predicted_stable_simulated_unstable']}, predicted "
                  f"unstable but simulated stable {lv['predicted_unstable_simulated_stable']}; "
                  f"no prediction {lv['no_prediction']}.")]  # fmt: skip
    lines += ["", (f"Wall time {m.wall_time:.3g} s (compiled batch loop {m.batch_wall_time:.3g} s, "
              f"linearisations {m.linear_time:.3g} s)."), ""]  # fmt: skip
    return lines


def draw_map(m: RobustnessMap, path: Path) -> None:
    """``map.png`` (module docstring)."""
    from acdrive._figures import new_figure, save_figure

    numeric = [c for c in m.criteria if c.column != "stable"]
    fig, axes = new_figure((6.5, 3.0 * len(numeric)), len(numeric), 1, squeeze=False)
    for ax, c in zip(axes[:, 0], numeric, strict=True):
        if m.spec.kind == "grid":
            for axis in m.spec.params:
                rows = sorted((r for r in m.rows if r["axis"] == axis and r["valid"]),
                              key=lambda r: r["value"])  # fmt: skip
                if axis == PAPER:  # severity s on the paper's path: plotted at its largest factor
                    x = [math.exp(r["log_distance"]) for r in rows]
                else:
                    x = [r["value"] for r in rows]
                ax.plot(x, [r.get(c.column, np.nan) for r in rows], marker=".", ms=3,
                        label="paper path (max f)" if axis == PAPER else axis)  # fmt: skip
            ax.set_xscale("log")
            ax.set_xlabel("factor f on the plant")
        else:
            rows = [r for r in m.rows if r["valid"]]
            ok = np.array([r["verdicts"][c.name] is True for r in rows])
            x = np.array([math.exp(r["log_distance"]) for r in rows])
            y = np.array([r.get(c.column, np.nan) for r in rows], dtype=float)
            ax.scatter(x[ok], y[ok], s=4, label="passes")
            ax.scatter(x[~ok], y[~ok], s=4, label="breaks")
            ax.set_xlabel("largest factor max(f, 1/f) of the variant")
        ax.axhline(c.limit, ls="--", color="k", lw=0.8, label="tolerance")
        ax.set_ylabel(f"{c.column} [{c.unit}]" if c.unit else c.column)
        ax.set_title(f"{c.name}", fontsize=9)
        ax.legend(fontsize=7)
    save_figure(path, fig)


@checked(m=Instance(RobustnessMap), out=PATH, name=Text(optional=True))
def write_map_report(m: RobustnessMap, out, name: str | None = None) -> Path:
    """Write map.json, report.md and map.png into ``out``/``name`` (default the scenario's name)
    through ``_output.OutputFolder`` (a folder acdrive did not write is never replaced)."""
    from acdrive._output import OutputFolder

    with OutputFolder(out, name or f"{m.scenario}-robustness", "out") as folder:
        write_into(m, folder.staging)
        return folder.publish()


def write_into(m: RobustnessMap, folder: Path) -> None:
    """map.json, report.md and map.png of ``m`` into ``folder`` (a staging folder)."""
    (folder / "map.json").write_text(strict_json(m.to_json(), indent=1))
    (folder / "report.md").write_text("\n".join(report_lines(m)))
    draw_map(m, folder / "map.png")
