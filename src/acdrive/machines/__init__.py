"""Machines: parameters (for analysis and design) and parts (for simulation).

Public names (imported on first use): the parameter classes and built-in machines, the machine
parts, and the registry of built-in machines by name.
"""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "DFIMParams": ".dfim",
        "BODSON_DFIM": ".dfim",
        "stator_current_command": ".dfim",
        "IMParams": ".induction",
        "DELORENZO_IM": ".induction",
        "DELORENZO_IM_13": ".induction",
        "UGALDE_IM_300W": ".induction",
        "PMSGParams": ".pmsm",
        "PMSG_2MW": ".pmsm",
        "DoublyFedMachine": ".dfim_part",
        "CageInductionMachine": ".cage_part",
        "PermanentMagnetMachine": ".pmsm_part",
        "machine_params": ".registry",
        "machine_part": ".registry",
        "names": ".registry",
    },
)
