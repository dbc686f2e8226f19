"""Simulation: systems from parts and their compiled loop, the DFIM and cage-IM drives, and
running scenarios."""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "System": ".system",
        "CompiledSystem": ".system",
        "SystemResult": ".system",
        "INTEGRATORS": ".system",
        "DriveSetup": ".setup",
        "simulate": ".setup",
        "DFIMDrive": ".dfim_drive",
        "DriveResult": ".result",
        "IMDrive": ".im_drive",
        "IMDriveSetup": ".im_drive",
        "IMDriveResult": ".im_drive",
        "run_im_scenario": ".im_drive",
        "run_scenario": ".outcome",
    },
)
