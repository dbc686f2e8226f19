"""Identification of a machine from logged tests (issue 23, first stage: the cage IM at
standstill).

``StandstillPlan`` describes the DC-step and multisine-injection tests on the inverter-fed,
locked-rotor cage IM; ``dc_test`` and ``injection_test`` run them on acdrive's parts and return
their logs; ``read_log`` / ``write_log`` read and write a log (CSV or Parquet, unit-checked
columns). ``fit_dc_steps`` gives R_s and the inverter's voltage error, ``fit_impedance`` the
inverse-Gamma parameters, ``identify_standstill`` both and a T-circuit under a stated leakage
split; every estimate carries its 95 % intervals (Jacobian covariance and bootstrap).
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
        "Coverage": "._coverage",
        "coverage": "._coverage",
    },
)
