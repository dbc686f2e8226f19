"""The cage induction motor drive of Amezquita-Brooks et al. as a registered drive kind
(``acdrive.drives``, ``drive = "cage-im"``): what the command line, batches and sweeps ask of
it, each answered by the module that computes it."""

from __future__ import annotations

from acdrive.drives._registry import Drive
from acdrive.drives.cage_im._setup import IMDriveSetup
from acdrive.errors import InputError
from acdrive.machines._induction import IMParams


class CageIMDriveKind(Drive):
    """A cage induction motor on a voltage-source inverter with stationary-frame current
    control, optionally under indirect field orientation and a speed or position loop."""

    kind = "cage-im"
    setup_types = (IMDriveSetup,)
    default_machine = "delorenzo-im"

    def load(self, data: dict) -> IMDriveSetup:
        from acdrive.drives.cage_im._schema import build_im_setup

        return build_im_setup(data)

    def run(self, setup: IMDriveSetup, on_run=None):
        from acdrive.drives.cage_im._outcome import run_im_scenario

        if on_run is not None:
            n = len(list(setup.runs()))
            on_run(f"{n} run{'s' * (n > 1)}")
        return run_im_scenario(setup)

    def write(self, outcome, folder, figures: bool = True, fmt: str = "parquet") -> dict:
        from acdrive.drives.cage_im._outputs import write_im_outcome

        return write_im_outcome(outcome, folder, figures=figures, fmt=fmt)

    def figures(self, outcome, folder) -> list:
        from acdrive.drives.cage_im._outputs import write_figures

        return write_figures(outcome, folder)

    def headline(self, outcome, summary: dict):
        from acdrive.drives.cage_im._headline import headline

        return headline(outcome, summary)

    def build(self, setup: IMDriveSetup):
        from acdrive.drives.cage_im._drive import IMDrive

        if setup.runs() and len(setup.runs()) > 1:
            raise InputError("compare", "a batch runs one controller per variant: no comparisons")
        return IMDrive(setup)

    def log_width(self, setup: IMDriveSetup) -> tuple[int, int]:
        from acdrive.drives.cage_im._drive import IMDrive

        drive = IMDrive(setup)
        ports = list(drive.log_ports().values())
        return len(drive.system.log_columns(ports)), len(drive.system.event_names())

    def reducers(self, setup: IMDriveSetup) -> list:
        from acdrive.drives.cage_im._reducers import im_reducers

        return im_reducers(setup)

    def robustness(self):
        from acdrive.drives.cage_im._robustness import SEAM

        return SEAM

    def params_fields(self, machine) -> tuple[str, ...] | None:
        from acdrive.drives.cage_im._schema import PARAMS_FIELDS

        return PARAMS_FIELDS if isinstance(machine, IMParams) else None


DRIVE = CageIMDriveKind()
