"""Machines: parameters (for analysis and design) and parts (for simulation).

Public names (imported on first use): the parameter classes and built-in machines, the machine
parts, and the registry of built-in machines by name.
"""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "DFIMParams": "._dfim",
        "BODSON_DFIM": "._dfim",
        "stator_current_command": "._dfim",
        "IMParams": "._induction",
        "DELORENZO_IM": "._induction",
        "DELORENZO_IM_13": "._induction",
        "UGALDE_IM_300W": "._induction",
        "PMSGParams": "._pmsm",
        "PMSG_2MW": "._pmsm",
        "DoublyFedMachine": "._dfim_part",
        "CageInductionMachine": "._cage_part",
        "PermanentMagnetMachine": "._pmsm_part",
        "machine_params": "._registry",
        "machine_part": "._registry",
        "names": "._registry",
    },
)
