"""The PM drive's scenario kinds behind one set of entry functions (what a registry entry
delegates to, one call each): the speed drive (``PMDriveSetup``: ``_build``, summary
``_metrics``) and seed 001's current-step run (``CurrentStepSetup``: ``_icad_step``, its two runs
and its comparison with ICAD's (10)).

* ``build_scenario(setup)``: the system of parts of one run (``_build.Built``: system, initial
  states, held outputs, logged ports);
* ``run(setup, compiled)``: simulate a speed-drive setup and summarise it (``_metrics``);
* ``runs(setup)``: how many simulations ``run_outcome`` makes;
* ``run_scenario(setup)``: (result, summary) of one scenario;
* ``run_outcome(setup, on_run)``: a ``PMOutcome`` (``results`` by label with their wall time,
  ``summary``);
* ``write(outcome, folder, figures, fmt)``: each result's table (``SystemResult.save``), a figure
  of its signals (``write_figures``), and ``summary.json``; returns the summary written;
* ``headline(outcome, summary)``: the first line and the (label, text) rows a command prints,
  every number read from the summary.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from acdrive._output import strict_json
from acdrive.drives._outcome import Outcome
from acdrive.drives.pm import _build, _icad_step, _metrics
from acdrive.drives.pm._icad_step import CurrentStepSetup
from acdrive.drives.pm._setup import PMDriveSetup
from acdrive.sim._step_response import headline_rows
from acdrive.sim._timing import run_timing, simulated_in

#: labels of the results of one scenario, by kind
SPEED_LABELS = ("run",)
STEP_LABELS = ("step", "base")


def _check(setup, function: str, types: tuple[type, ...] = (PMDriveSetup, CurrentStepSetup)):
    """An ``InputError`` on ``setup`` unless it is one of ``types``, naming ``function`` (another
    drive's setup is pointed to ``acdrive.drives.run_scenario``)."""
    from acdrive.drives._registry import require_setup

    require_setup(setup, types, function)


def build_scenario(setup) -> _build.Built:
    """The system of parts of either kind of setup (for a current-step setup: the run with the
    step; ``run_outcome`` runs it together with the run without)."""
    _check(setup, "acdrive.drives.pm.build_scenario")
    if isinstance(setup, CurrentStepSetup):
        return _icad_step.build(setup)
    return _build.build(setup)


def run(setup: PMDriveSetup, compiled=None):
    """Simulate ``setup``: (the engine's ``SystemResult`` with ``summary(setup, result)``
    attached as its ``summary``, that summary). ``compiled`` reuses a ``System.compile()`` of
    the same topology."""
    _check(setup, "acdrive.drives.pm.run", (PMDriveSetup,))
    built = _build.build(setup)
    compiled = compiled or built.system.compile()
    result = compiled.run(
        setup.duration,
        setup.sample_time,
        substeps=setup.substeps,
        initial=built.initial,
        held=built.held,
        log=list(built.log.values()),
        log_every=setup.log_every,
    )
    result.summary = _metrics.summary(setup, result, built.log)
    return result, result.summary


def runs(setup) -> int:
    """Simulations per scenario: 2 for a current step (with and without the step), else 1."""
    _check(setup, "acdrive.drives.pm._entry.runs")
    return len(STEP_LABELS if isinstance(setup, CurrentStepSetup) else SPEED_LABELS)


@dataclass
class PMOutcome(Outcome):
    """The PM drive's ``Outcome``: one scenario's results by label (``SystemResult``, each with
    ``wall_time``) and summary."""

    setup: PMDriveSetup | CurrentStepSetup
    results: dict
    summary: dict


def run_outcome(setup, on_run=None) -> PMOutcome:
    """Simulate ``setup``; ``on_run(label)`` is called before (the runs of a current step are
    one batch: one call names both)."""
    _check(setup, "acdrive.drives.pm._entry.run_outcome")
    if isinstance(setup, CurrentStepSetup):
        if on_run is not None:
            on_run(" and ".join(STEP_LABELS))
        out = _icad_step.run(setup)
        results = dict(zip(STEP_LABELS, out.runs, strict=True))
        return PMOutcome(setup, results, {**out.summary, **run_timing(results.values())})
    if on_run is not None:
        on_run(SPEED_LABELS[0])
    result, summary = run(setup)
    return PMOutcome(setup, {SPEED_LABELS[0]: result}, {**summary, **run_timing([result])})


def run_scenario(setup, compiled=None):
    """(the result of the run, its summary): for a current-step setup, the run with the step
    (``CurrentStepResult.runs[0]``) and the comparison's summary."""
    _check(setup, "acdrive.drives.pm.run_scenario")
    if isinstance(setup, CurrentStepSetup):
        out = _icad_step.run(setup, compiled)
        return out.runs[0], out.summary
    return run(setup, compiled)


def write_figures(outcome: PMOutcome, folder) -> list[Path]:
    """A figure of each result's signals (``signals.png``, in ``folder/<label>/`` when there are
    several); returns their paths."""
    folder = Path(folder)
    paths = []
    for label, result in outcome.results.items():
        where = folder / label if len(outcome.results) > 1 else folder
        where.mkdir(parents=True, exist_ok=True)
        # matplotlib only here, on the Agg canvas without pyplot
        result.plot(pyplot=False).savefig(where / "signals.png", dpi=100)
        paths.append(where / "signals.png")
    return paths


def write(outcome: PMOutcome, folder, figures: bool = True, fmt: str = "parquet") -> dict:
    """Each result's table (in ``folder/<label>/`` when there are several), its figure
    (``write_figures``) and ``summary.json`` (strict JSON: a non-finite number as null); returns
    the summary written."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for label, result in outcome.results.items():
        where = folder / label if len(outcome.results) > 1 else folder
        where.mkdir(parents=True, exist_ok=True)
        result.save(where, fmt)
    if figures:
        write_figures(outcome, folder)
    summary = outcome.summary
    (folder / "summary.json").write_text(strict_json(summary, indent=2) + "\n", encoding="utf-8")
    return summary


def headline(outcome: PMOutcome, summary: dict) -> tuple[str, list[tuple[str, str]]]:
    """What ``acdrive run`` prints: a first line and (label, text) rows from ``summary``."""
    name = outcome.setup.name
    timing = (
        "simulation",
        f"{outcome.setup.duration:g} s {simulated_in(outcome.results.values())}",
    )
    if isinstance(outcome.setup, CurrentStepSetup):
        first, rows = _step_headline(name, summary)
        return first, [*rows, timing]
    first = (
        f"{name}: final speed {summary['speed_final_rad_s']:.5g} rad/s = "
        f"{summary['speed_final_to_base_ratio']:.3g} x base speed "
        f"({summary['base_speed_rad_s']:.5g} rad/s, steady-state voltage equation)"
    )
    bound = (
        f"{summary['voltage_bound_speed_rad_s']:.5g} rad/s (the drive's conservative voltage "
        "bound: its references leave MTPA at full current there)"
    )
    d_current = (
        f"final {summary['i_d_final_a']:.4g} A; least over the run {summary['i_d_min_a']:.4g} A "
        + _when(summary, "i_d_min_time_s")
    )
    voltage_use = (
        f"final {summary['voltage_use_final']:.3g}; largest over the run "
        f"{summary['voltage_use_max']:.3g} " + _when(summary, "voltage_use_max_time_s")
    )
    current = (
        f"{summary['current_peak_a']:.4g} A (limit {summary['current_limit_peak_a']:.4g} A, "
        "phase peak)"
    )
    rows = [
        ("MTPA at full current until", bound),
        *headline_rows(summary["step_response"], "rad_s"),
        ("speed error, final", f"{summary['speed_error_final_rad_s']:.3g} rad/s"),
        ("current peak", current),
        ("d current (phase peak)", d_current),
        ("voltage command / m V_dc / sqrt(2)", voltage_use),
        ("torque, final", f"{summary['torque_final_n_m']:.4g} N m"),
        ("voltage command's margin, least", f"{summary['voltage_margin_min']:.3g}"),
        (
            "current controller at the link",
            f"{summary['current_controller_limited_samples']} samples",
        ),
        ("references on the voltage limit", f"{summary['voltage_limited_samples']} samples"),
        timing,
    ]
    return first, rows


def _when(summary: dict, key: str) -> str:
    """Where an extreme of the run lies: a transient's (before the final window) or the final
    window's, with its instant."""
    t = summary[key]
    where = "transient" if t < summary["final_window_from_s"] else "in the final window"
    return f"({where}, t = {t:.4g} s)"


def _step_headline(name: str, summary: dict) -> tuple[str, list[tuple[str, str]]]:
    verdict = "matches" if summary["coupling_matches_icad"] else "does NOT match"
    first = f"{name}: the coupling r_d -> i_q measured from the step {verdict} ICAD's (10)"
    icad = (
        f"{summary['relative_error_max']:.3%} up to {_icad_step.ICAD_W_MAX:g} rad/s "
        f"(allowed {_icad_step.ICAD_REL_TOL:.0%})"
    )
    delayed = (
        f"{summary['relative_error_delayed_max']:.3%} (allowed {_icad_step.DELAYED_REL_TOL:.1%})"
    )
    rows = [
        ("controller", summary["controller"]),
        ("largest error vs (10)", icad),
        ("vs (10) with the hold", delayed),
    ]
    for r in summary["rows"]:
        text = f"measured {r['measured_db']:.2f} dB, (10) {r['icad_db']:.2f} dB"
        rows.append((f"{r['frequency_rad_s']:g} rad/s", text))
    return first, rows
