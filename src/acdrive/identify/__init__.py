"""Identification of a machine from logged tests (issue 23): the cage IM and the PM machine at
standstill, the shaft's mechanics from speed steps.

``StandstillPlan`` describes the DC-step and multisine-injection tests on the inverter-fed,
locked-rotor cage IM; ``dc_test`` and ``injection_test`` run them on acdrive's parts and return
their logs; ``read_log`` / ``write_log`` read and write a log (CSV or Parquet, unit-checked
columns). ``fit_dc_steps`` gives R_s and the inverter's voltage error, ``fit_impedance`` the
inverse-Gamma parameters, ``identify_standstill`` both and a T-circuit under a stated leakage
split; every estimate carries its 95 % intervals (Jacobian covariance and bootstrap).
``axis_test`` / ``identify_pm_standstill`` give a PM machine's R_s, L_d, L_q (rotor locked with
its d, then its q axis on phase a); ``no_load_test`` / ``fit_no_load`` a cage IM's L_M at the
flux of a no-load run; ``dfim_test`` / ``identify_dfim`` a DFIM's
rotor-side parameters from its rotor converter with the stator open and shorted;
``spin_test`` / ``fit_spin`` its magnet flux
from a short-circuit spin test; ``speed_step_test`` / ``fit_mechanics`` the inertia, viscous
and Coulomb friction from speed steps of a running drive. Logs may be CSV, Parquet or .mat; a
no-load log may add its DC-link voltage (``link_voltage``). ``builtin_names`` / ``builtin_bench``
give the benches ``acdrive identify NAME --kind`` simulates for the built-in machines.
"""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "InverseGamma": "._circuit",
        "inverse_gamma": "._circuit",
        "t_circuit": "._circuit",
        "standstill_impedance": "._circuit",
        "sampled_admittance": "._circuit",
        "StandstillPlan": "._experiment",
        "CurrentSensor": "._experiment",
        "StandstillLog": "._experiment",
        "dc_test": "._experiment",
        "injection_test": "._experiment",
        "read_log": "._log",
        "write_log": "._log",
        "Estimate": "._fit",
        "FitNotConverged": "._fit",
        "fit_dc_steps": "._dc",
        "fit_impedance": "._impedance",
        "identify_standstill": "._standstill",
        "identifiability": "._standstill",
        "AdmittanceModel": "._impedance",
        "AxisTest": "._pm",
        "PMStandstillIdentification": "._pm",
        "axis_test": "._pm",
        "rl_admittance": "._pm",
        "identify_pm_standstill": "._pm",
        "pm_identifiability": "._pm",
        "MECHANICS_COLUMNS": "._mechanics",
        "MechanicsLog": "._mechanics",
        "MechanicsPlan": "._mechanics",
        "MechanicsFit": "._mechanics",
        "SpeedSensor": "._mechanics",
        "speed_step_test": "._mechanics",
        "predicted_speed": "._mechanics",
        "fit_mechanics": "._mechanics",
        "mechanics_identifiability": "._mechanics",
        "read_mechanics_log": "._mechanics",
        "write_mechanics_log": "._mechanics",
        "NO_LOAD_COLUMNS": "._no_load",
        "NoLoadLog": "._no_load",
        "NoLoadPlan": "._no_load",
        "NoLoadFit": "._no_load",
        "no_load_test": "._no_load",
        "running_admittance": "._no_load",
        "fit_no_load": "._no_load",
        "read_no_load_log": "._no_load",
        "write_no_load_log": "._no_load",
        "NO_LOAD_OPTIONAL": "._no_load",
        "link_voltage": "._no_load",
        "builtin_names": "._builtin",
        "builtin_bench": "._builtin",
        "SPIN_COLUMNS": "._spin",
        "SpinPlan": "._spin",
        "SpinLog": "._spin",
        "SpinTest": "._spin",
        "SpinFit": "._spin",
        "spin_test": "._spin",
        "short_circuit_gain": "._spin",
        "fit_spin": "._spin",
        "read_spin_log": "._spin",
        "write_spin_log": "._spin",
        "DFIMIdentification": "._dfim",
        "dfim_test": "._dfim",
        "identify_dfim": "._dfim",
        "dfim_identifiability": "._dfim",
        "Coverage": "._coverage",
        "coverage": "._coverage",
    },
)
