"""The files of one DFIM scenario run: data (Parquet, CSV or .mat) with columns.md, figures and
summary.json."""

from __future__ import annotations

from pathlib import Path

from acdrive._output import strict_json
from acdrive.columns import DEFAULT_FORMAT
from acdrive.drives.dfim import _converter_effect as converter_effect
from acdrive.drives.dfim._outcome import ScenarioOutcome, synchronous_rpm


def write_outcome(
    outcome: ScenarioOutcome, folder: Path, figures: bool = True, fmt: str = DEFAULT_FORMAT
) -> dict:
    """Write every result of ``outcome`` (one sub-folder per compared mode) into ``folder``: the
    data as ``fmt`` (``acdrive.columns.FORMATS``) with columns.md, figures, summary.json;
    returns the summary written.

    summary.json is the outcome's summary plus, where a rotor converter has dead time or device
    drops, ``converter_side_effect``: the steady-state stator reactive power and torque-command
    offset that converter causes (``acdrive.drives.dfim._converter_effect``)."""
    folder = Path(folder)
    setup = outcome.setup
    if figures:
        from acdrive.drives.dfim._figures import (
            current_limits,
            write_comparison_figures,
            write_drive_figures,
            write_sync_figure,
        )
    for label, result in outcome.results.items():
        sub = folder if len(outcome.results) == 1 else folder / label
        sub.mkdir(parents=True, exist_ok=True)
        result.save(sub, fmt)
        if figures:
            write_drive_figures(result, sub, synchronous_rpm(setup), current_limits(setup))
            if setup.motors[0].controller.sync.enabled:
                write_sync_figure(result, sub)
    if figures and len(outcome.results) > 1:
        limit = setup.motors[0].controller.rotor_current_limit_pk
        write_comparison_figures(outcome.results, folder, limit)
    summary = dict(outcome.summary)
    side_effect = converter_effect.summary(outcome)  # None with ideal converters
    if side_effect is not None:
        summary["converter_side_effect"] = side_effect
    # strict JSON: a non-finite figure (e.g. an RMS over no samples) is written as null
    (folder / "summary.json").write_text(strict_json(summary, indent=2) + "\n")
    return summary
