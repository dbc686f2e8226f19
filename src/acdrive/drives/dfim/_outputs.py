"""The files of one DFIM scenario run: data (Parquet, CSV or .mat) with columns.md, figures and
summary.json."""

from __future__ import annotations

from pathlib import Path

from acdrive._output import strict_json
from acdrive.columns import DEFAULT_FORMAT
from acdrive.drives.dfim._outcome import ScenarioOutcome, synchronous_rpm


def write_figures(outcome: ScenarioOutcome, folder: Path) -> list[Path]:
    """Draw every figure of ``outcome`` into ``folder`` (one sub-folder per compared mode, the
    comparison figures in ``folder``); returns their paths."""
    from acdrive.drives.dfim._figures import (
        current_limits,
        write_comparison_figures,
        write_drive_figures,
        write_sync_figure,
    )

    folder = Path(folder)
    setup = outcome.setup
    paths = []
    for label, result in outcome.results.items():
        sub = folder if len(outcome.results) == 1 else folder / label
        sub.mkdir(parents=True, exist_ok=True)
        paths += write_drive_figures(result, sub, synchronous_rpm(setup), current_limits(setup))
        if setup.motors[0].controller.sync.enabled:
            paths.append(write_sync_figure(result, sub))
    if len(outcome.results) > 1:
        limit = setup.motors[0].controller.rotor_current_limit_pk
        paths += write_comparison_figures(outcome.results, folder, limit)
    return paths


def write_outcome(
    outcome: ScenarioOutcome, folder: Path, figures: bool = True, fmt: str = DEFAULT_FORMAT
) -> dict:
    """Write every result of ``outcome`` (one sub-folder per compared mode) into ``folder``: the
    data as ``fmt`` (``acdrive.columns.FORMATS``) with columns.md, figures (``write_figures``)
    and summary.json, the outcome's summary; returns the summary written."""
    folder = Path(folder)
    for label, result in outcome.results.items():
        sub = folder if len(outcome.results) == 1 else folder / label
        sub.mkdir(parents=True, exist_ok=True)
        result.save(sub, fmt)
    if figures:
        write_figures(outcome, folder)
    summary = dict(outcome.summary)
    # strict JSON: a non-finite figure (e.g. an RMS over no samples) is written as null
    (folder / "summary.json").write_text(strict_json(summary, indent=2) + "\n")
    return summary
