"""The DFIM speed drive of Bodson et al. as a registered drive kind (``acdrive.drives``): what the
command line, batches and sweeps ask of it, each answered by the module that computes it."""

from __future__ import annotations

from acdrive.drives._registry import Drive
from acdrive.drives.dfim._setup import DriveSetup
from acdrive.errors import InputError
from acdrive.machines._dfim import DFIMParams


class DFIMDriveKind(Drive):
    """Doubly-fed induction motors on one supply, speed-controlled through their rotor
    converters (Bodson); scenarios without ``drive`` are of this kind."""

    kind = "dfim"
    setup_types = (DriveSetup,)
    default_machine = "bodson-dfim"

    def load(self, data: dict) -> DriveSetup:
        from acdrive.drives.dfim._schema import build_dfim_setup

        return build_dfim_setup(data)

    def runs(self, setup: DriveSetup) -> int:
        return len(setup.compare_modes) or 1

    def run(self, setup: DriveSetup, on_run=None):
        from acdrive.drives.dfim._outcome import run_scenario

        def announce(mode):
            if on_run is not None:
                on_run(f"{mode} command")

        return run_scenario(setup, on_run=announce)

    def write(self, outcome, folder, figures: bool = True, fmt: str = "parquet") -> dict:
        from acdrive.drives.dfim._outputs import write_outcome

        return write_outcome(outcome, folder, figures=figures, fmt=fmt)

    def figures(self, outcome, folder) -> list:
        from acdrive.drives.dfim._outputs import write_figures

        return write_figures(outcome, folder)

    def headline(self, outcome, summary: dict):
        from acdrive.drives.dfim._headline import headline

        return headline(outcome, summary)

    def build(self, setup: DriveSetup):
        from acdrive.drives.dfim._drive import DFIMDrive

        if setup.compare_modes:
            raise InputError("compare_modes", "a batch runs one mode per variant: no comparisons")
        return DFIMDrive(setup)

    def log_width(self, setup: DriveSetup) -> tuple[int, int]:
        from acdrive.drives.dfim._drive import DFIMDrive

        drive = DFIMDrive(setup)
        return len(drive.system.log_columns(drive.log_ports())), len(drive.system.event_names())

    def reducers(self, setup: DriveSetup) -> list:
        from acdrive.drives.dfim._reducers import dfim_reducers

        return dfim_reducers(setup)

    def verdict(self, setup: DriveSetup, row: dict) -> bool | None:
        from acdrive.drives.dfim._reducers import verdict

        return verdict(row)

    def params_fields(self, machine) -> tuple[str, ...] | None:
        from acdrive.drives.dfim._schema import PARAMS_FIELDS

        return PARAMS_FIELDS if isinstance(machine, DFIMParams) else None

    def crosscheck(self, setup: DriveSetup, lower: float, upper: float) -> dict:
        from acdrive.drives.dfim._crosscheck import linearised_tolerated_bandwidth

        return linearised_tolerated_bandwidth(setup, lower, upper)

    def robustness(self):
        from acdrive.drives.dfim._robustness import SEAM

        return SEAM

    def linearisation(self):
        from acdrive.drives.dfim import _linearisation

        return _linearisation


DRIVE = DFIMDriveKind()
