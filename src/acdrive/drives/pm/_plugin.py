"""The permanent-magnet synchronous motor drive as a registered drive kind (``acdrive.drives``):
what the command line, batches and sweeps ask of it, each answered by ``_entry`` (one call each)."""

from __future__ import annotations

from dataclasses import dataclass

from acdrive.drives._registry import Drive
from acdrive.drives.pm._icad_step import CurrentStepSetup
from acdrive.drives.pm._setup import PMDriveSetup
from acdrive.errors import InputError
from acdrive.machines._pmsm import PMSGParams


@dataclass(frozen=True)
class _BatchRun:
    """One run's system and its start, as a batch variant needs them."""

    system: object
    start: tuple

    def initial(self) -> tuple[dict, dict]:
        return self.start


class PMDriveKind(Drive):
    """Permanent-magnet synchronous machines: the field-oriented speed drive (MTPA, field
    weakening) and the current-step run of a current subsystem against ICAD."""

    kind = "pm"
    setup_types = (PMDriveSetup, CurrentStepSetup)
    default_machine = None

    def load(self, data: dict):
        from acdrive.drives.pm._schema import load

        return load(data)

    def runs(self, setup) -> int:
        from acdrive.drives.pm._entry import runs

        return runs(setup)

    def run(self, setup, on_run=None):
        from acdrive.drives.pm._entry import run_outcome

        return run_outcome(setup, on_run)

    def write(self, outcome, folder, figures: bool = True, fmt: str = "parquet") -> dict:
        from acdrive.drives.pm._entry import write

        return write(outcome, folder, figures=figures, fmt=fmt)

    def figures(self, outcome, folder) -> list:
        from acdrive.drives.pm._entry import write_figures

        return write_figures(outcome, folder)

    def headline(self, outcome, summary: dict):
        from acdrive.drives.pm._entry import headline

        return headline(outcome, summary)

    def build(self, setup):
        from acdrive.drives.pm._entry import build_scenario

        if isinstance(setup, CurrentStepSetup):
            raise InputError(
                "kind", "a current-step scenario compares two runs: not a batch variant"
            )
        built = build_scenario(setup)
        return _BatchRun(built.system, (built.initial, built.held))

    def log_width(self, setup) -> tuple[int, int] | None:
        from acdrive.drives.pm._entry import build_scenario

        if isinstance(setup, CurrentStepSetup):
            return None  # two runs of their own log (``_icad_step``)
        built = build_scenario(setup)
        return len(built.system.log_columns(list(built.log.values()))), len(
            built.system.event_names()
        )

    def reducers(self, setup) -> list:
        from acdrive.drives.pm._reducers import pm_reducers

        if isinstance(setup, CurrentStepSetup):
            return []  # not a batch variant (``build``)
        return pm_reducers(setup)

    def robustness(self):
        from acdrive.drives.pm._robustness import SEAM

        return SEAM

    def params_fields(self, machine) -> tuple[str, ...] | None:
        from acdrive.drives.pm._schema import MACHINE_FIELDS

        return MACHINE_FIELDS if isinstance(machine, PMSGParams) else None


DRIVE = PMDriveKind()
