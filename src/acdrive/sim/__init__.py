"""Simulation: systems from parts and their compiled loop, the DFIM and cage-IM drives, and
running scenarios."""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "System": "._system",
        "CompiledSystem": "._system",
        "SystemResult": "._system",
        "INTEGRATORS": "._system",
        "DriveSetup": "._setup",
        "simulate": "._setup",
        "DFIMDrive": "._dfim_drive",
        "DriveResult": "._result",
        "IMDrive": "._im_drive",
        "IMDriveSetup": "._im_drive",
        "IMDriveResult": "._im_drive",
        "run_im_scenario": "._im_drive",
        "run_scenario": "._outcome",
    },
)
