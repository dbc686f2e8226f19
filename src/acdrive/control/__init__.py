"""Controllers: linear controllers and their discretisation, and the sampled controller parts of
the three papers' drives (stationary-frame current control, indirect FOC, speed and position
control, Bodson's DFIM controller)."""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "LTI": "._lti",
        "LTIMatrix": "._lti_matrix",
        "DiscreteLTI": "._discretise",
        "discretise": "._discretise",
        "builtin": "._lti",
        "as_lti": "._lti",
        "PAPER_20": "._lti",
        "PAPER_PI": "._lti",
        "FIG17_PI_FAMILY": "._lti",
        "FIG18_PI": "._lti",
        "StationaryCurrentController": "._current",
        "CurrentProgram": "._current",
        "IndirectFOC": "._foc",
        "SaturatedSpeedP": "._foc",
        "SpeedPI": "._foc",
        "PositionP": "._foc",
        "ComputationDelay": "._delay",
        "SpeedReference": "._speed",
        "SynchronousFluxObserver": "._flux_observer",
        "SpeedPIGains": "._speed",
        "VoltageProgram": "._open_loop",
        "ComplexProgram": "._open_loop",
        "SpeedController": "._bodson",
        "SpeedEstimator": "._bodson",
        "SupplyFrequencyEstimator": "._bodson",
        "Synchroniser": "._bodson",
        "PI_OF_22": "._lti",
        "FIG17_K_I": "._lti",
        "FIG17_K_P": "._lti",
        "current_loop_gains": "._dfim",
    },
)
