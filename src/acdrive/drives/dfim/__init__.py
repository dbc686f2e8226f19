"""The DFIM speed drive (Bodson et al.): setup, parts, result, outcome of a scenario."""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "DriveSetup": "._setup",
        "simulate": "._setup",
        "DFIMDrive": "._drive",
        "simulate_slow": "._drive",
        "DriveResult": "._result",
        "ScenarioOutcome": "._outcome",
        "run_scenario": "._outcome",
        "DRIVE": "._plugin",
    },
)
