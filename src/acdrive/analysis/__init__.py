"""Analysis: individual channel analysis (ICAD) of 2x2 plants, the machines' current-subsystem
plants, controller design checks, and the whole-drive stability of the DFIM drive."""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "analyse": ".icad",
        "icad_response": ".icad",
        "structure_conditions": ".icad",
        "invariant_zeros": ".icad",
        "sweep": ".icad",
        "ICADAnalysis": ".icad",
        "ICADResponse": ".icad",
        "Plant2x2": ".plants",
        "as_plant": ".plants",
        "plant_for": ".plants",
        "plants_for": ".plants",
        "plant_from_params": ".plants",
        "DriveModel": ".drive_stability",
        "OperatingPoint": ".drive_stability",
        "linearize": ".drive_stability",
        "stability_map": ".drive_stability",
        "max_stable_bandwidth": ".drive_stability",
    },
)
