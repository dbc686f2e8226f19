"""Size bounds of a PM run, checked on its setup before any part is built.

The compiled loop refuses a run beyond its bounds (``sim._compiled``: the memory of the logs,
the integration steps of about half an hour, the substeps per segment) only once the system is
built, naming its own arguments; a PM setup checks the same bounds first, naming its fields
(``duration``, ``substeps``), which the scenario loader turns into ``simulation.<field>``. The
log is counted at ``LOG_COLUMNS`` columns, more than a PM run logs (signals and limit events),
so this check is met first.
"""

from __future__ import annotations

import math

from acdrive.errors import InputError
from acdrive.sim._compiled import LOG_BUDGET_BYTES, MAX_SUBSTEPS, MAX_WORK

#: an upper bound on the columns a PM run logs (module docstring)
LOG_COLUMNS = 40


def check_run_size(duration: float, sample_time: float, substeps: int, log_every: int = 1,
                   runs: int = 1) -> float:  # fmt: skip
    """Refuse ``runs`` runs of ``duration`` [s] at ``sample_time`` [s] (both checked > 0 before)
    whose log or integration steps exceed the compiled loop's bounds; returns the samples per
    run."""
    if substeps > MAX_SUBSTEPS:
        raise InputError("substeps", f"must be at most {MAX_SUBSTEPS}, got {substeps}")
    steps = duration / sample_time
    what = (
        f"{duration:g} s at a sample time of {sample_time:g} s is {steps:.3g} samples"
        + (f" x {runs} runs" if runs > 1 else "")
    )
    rows = math.ceil(steps / log_every) if math.isfinite(steps) else math.inf
    log_bytes = rows * LOG_COLUMNS * 8.0 * runs
    if log_bytes > LOG_BUDGET_BYTES:
        raise InputError(
            "duration", f"{what}; its log would need about {log_bytes / 1024**3:.3g} GB (limit "
            f"{LOG_BUDGET_BYTES / 1024**3:g} GB): shorten the run or log every k-th sample"
        )  # fmt: skip
    work = steps * substeps * runs
    if work > MAX_WORK:
        raise InputError(
            "duration", f"{what} with {substeps} substeps: {work:.3g} integration steps (limit "
            f"{MAX_WORK:.0e}, about half an hour): shorten the run or lengthen the sample time"
        )  # fmt: skip
    return steps
