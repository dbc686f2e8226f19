"""Robustness of a drive to what was not estimated well (issue 23, items 4 and 5).

``robustness_map`` runs a grid or Monte Carlo map of plant-parameter errors (``MapSpec``) on a
scenario in the compiled batch loop and judges every variant by the drive's stated criteria
(tracking, current limit, stability), with the linearised prediction beside the simulation where
the drive has one; ``PAPER_PERTURBATION`` is Amezquita-Brooks et al.'s sec. VIII perturbation.
``write_map_report`` writes its report and figure. ``design_comparison`` runs a scenario with
the controllers designed on estimated parameters against the same scenario designed on the truth.
"""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "Criterion": "acdrive.drives._robustness_seam",
        "RobustnessSeam": "acdrive.drives._robustness_seam",
        "Tolerances": "acdrive.drives._robustness_seam",
        "DesignComparison": "._design",
        "design_comparison": "._design",
        "MapSpec": "._map",
        "RobustnessMap": "._map",
        "PAPER_PERTURBATION": "._map",
        "paper_factors": "._map",
        "robustness_map": "._map",
        "write_map_report": "._report",
    },
)
