"""The cage induction motor drive (Amezquita-Brooks et al.): setup, parts, result, outcome."""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "IMDrive": "._drive",
        "IMDriveSetup": "._setup",
        "IMDriveResult": "._result",
        "IMOutcome": "._outcome",
        "run_im_scenario": "._outcome",
        "DRIVE": "._plugin",
    },
)
