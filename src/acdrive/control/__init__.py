"""Controllers: linear controllers and their discretisation, and the sampled controller parts of
the three papers' drives (stationary-frame current control, indirect FOC, speed and position
control, Bodson's DFIM controller)."""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "LTI": ".lti",
        "LTIMatrix": ".lti",
        "DiscreteLTI": ".lti",
        "discretise": ".lti",
        "builtin": ".lti",
        "as_lti": ".lti",
        "PAPER_20": ".lti",
        "PAPER_PI": ".lti",
        "FIG17_PI_FAMILY": ".lti",
        "FIG18_PI": ".lti",
        "StationaryCurrentController": ".current",
        "CurrentProgram": ".current",
        "IndirectFOC": ".foc",
        "SaturatedSpeedP": ".foc",
        "SpeedPI": ".foc",
        "PositionP": ".foc",
        "ComputationDelay": ".delay",
        "SpeedReference": ".speed",
        "VoltageProgram": ".open_loop",
        "ComplexProgram": ".open_loop",
        "SpeedController": ".bodson",
        "SpeedEstimator": ".bodson",
        "SupplyFrequencyEstimator": ".bodson",
        "Synchroniser": ".bodson",
    },
)
