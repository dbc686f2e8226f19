"""Analysis: individual channel analysis (ICAD) of 2x2 plants, the machines' current-subsystem
plants, controller design checks, and the whole-drive stability of the DFIM drive."""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "analyse": "._icad",
        "icad_response": "._icad",
        "structure_conditions": "._icad",
        "invariant_zeros": "._icad",
        "sweep": "._icad",
        "ICADAnalysis": "._icad",
        "ICADResponse": "._icad",
        "Plant2x2": "._plants",
        "as_plant": "._plants",
        "plant_for": "._plants",
        "plants_for": "._plants",
        "plant_from_params": "._plants",
        "DriveModel": "._drive_stability",
        "OperatingPoint": "._drive_stability",
        "linearize": "._drive_stability",
        "stability_map": "._drive_stability",
        "max_stable_bandwidth": "._drive_stability",
    },
)
