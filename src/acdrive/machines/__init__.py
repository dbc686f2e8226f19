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
        "PMSMParams": "._pmsm",
        "PMSG_2MW": "._pmsm",
        "DoublyFedMachine": "._dfim_part",
        "CageInductionMachine": "._cage_part",
        "PermanentMagnetMachine": "._pmsm_part",
        "SynchronousMachine": "._synchronous_part",
        "SynchronousMachineParams": "._synchronous",
        "FluxMapSynchronousMachine": "._flux_map_part",
        "FluxMap": "._flux_map",
        "read_flux_map_csv": "._flux_map",
        "write_flux_map_csv": "._flux_map",
        "read_syre_mat": "._flux_map",
        "SYRM_6_7KW": "._synchronous",
        "machine_params": "._registry",
        "machine_part": "._registry",
        "names": "._registry",
        "stator_current_ss": "._induction",
        "params_from_stationary_matrix": "._induction",
        "machine_vector": "._dfim",
        "impedances": "._dfim",
        "steady_state_currents": "._dfim",
        "rotor_voltage_for": "._dfim",
        "rotor_current_for": "._dfim",
        "electromagnetic_torque": "._dfim",
        "stator_current_lossless": "._dfim",
        "lossless_law_torque": "._dfim",
        "delta_z_coefficients": "._dfim",
        "shifted_delta_z_coefficients": "._dfim",
        "electrical_poles": "._dfim",
        "stator_current_per_rotor_voltage": "._dfim",
        "torque_limits_case1": "._dfim",
        "torque_limit_case2": "._dfim",
        "torque_window": "._dfim",
        "abc_to_complex": "acdrive._frames",
        "complex_to_abc": "acdrive._frames",
        "rotor_abc_to_complex": "acdrive._frames",
        "complex_to_rotor_abc": "acdrive._frames",
        "complex_power": "acdrive._frames",
    },
)
