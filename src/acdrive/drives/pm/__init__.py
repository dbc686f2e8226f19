"""The permanent-magnet synchronous motor speed drive (issue 20, item 5): rotor-frame current
control with decoupling and anti-windup, speed PI, MTPA and field weakening, on the averaged
converter or the SVPWM inverter, with an encoder; and seed 001's PMSG current subsystem in the
time domain under ICAD's controller, its coupling measured beside ICAD's (10).

``build(setup)`` gives the system of parts, ``run(setup)`` simulates it and summarises it;
``_design`` holds the formulas, ``_control`` the sampled controller parts, ``_machines`` the
published machines (the BLY171D surface PMSM, motulator's 2.2-kW interior PMSM), ``_icad_step``
the current-step run and its comparison with (10), ``_schema`` the scenario tables (``load``)
and the built-in scenarios (``scenarios/*.toml``), ``_entry`` the functions a registry entry
delegates to (both scenario kinds: build, run, write, headline).
"""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "PMDriveSetup": "._setup",
        "build": "._build",
        "run": "._entry",
        "PMOutcome": "._entry",
        "Built": "._build",
        "controller_parts": "._build",
        "summary": "._metrics",
        "build_scenario": "._entry",
        "run_scenario": "._entry",
        "CurrentStepSetup": "._icad_step",
        "signals": "._metrics",
        "PMSpeedPI": "._control",
        "PMTorqueReference": "._control",
        "RotorFrameCurrentController": "._control",
        "CurrentPIGains": "._design",
        "torque": "._design",
        "mtpa_point": "._design",
        "mtpa_angle": "._design",
        "mtpa_current": "._design",
        "operating_point": "._design",
        "available_torque": "._design",
        "base_speed": "._design",
        "voltage_bound_speed": "._design",
        "magnet_flux": "._design",
        "BLY171D": "._machines",
        "IPMSM_2KW2": "._machines",
        "load": "._schema",
        "builtin": "._schema",
        "builtin_names": "._schema",
    },
)
