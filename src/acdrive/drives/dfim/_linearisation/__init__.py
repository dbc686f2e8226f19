"""The DFIM drive's linearisation (Bodson's closed speed loop at an operating point): what
``Drive.linearisation()`` of the DFIM drive returns, and through it ``acdrive.analysis``'s
``linearize``, ``OperatingPoint``, ``DriveModel``, ``stability_map`` and ``max_stable_bandwidth``
and the ``acdrive stability`` command.

What it reads of the setup is ``_view``, the loops ``_loops``, one linearisation ``_stability``,
the studies over many (maps, tolerated bandwidth, bench candidates) ``_studies``, the
``StateSpace`` of a result ``_control``.
"""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "DriveModel": "._stability",
        "StabilityResult": "._stability",
        "linearize": "._stability",
        "check_point": "._stability",
        "OperatingPoint": "._view",
        "RAD_S_PER_RPM": "._view",
        "stability_map": "._studies",
        "max_stable_bandwidth": "._studies",
        "default_grid": "._studies",
        "bench_candidates": "._studies",
        "evaluate_candidate": "._studies",
        "stabilising_thresholds": "._studies",
    },
)
