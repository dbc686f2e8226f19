"""The PM drive's setup refuses invalid input with one line naming the field, before any work."""

import pytest

from acdrive.drives.pm import BLY171D, PMDriveSetup, build
from acdrive.errors import InputError
from acdrive.machines import PMSGParams

GOOD = {
    "machine": BLY171D,
    "V_dc": 24.0,
    "i_max_peak": 1.8,
    "speed_reference": 100.0,
    "duration": 0.01,
    "sample_time": 5e-5,
    "current_bandwidth": 2000.0,
    "speed_bandwidth": 100.0,
}


@pytest.mark.parametrize(
    "change, field",
    [
        ({"V_dc": -1.0}, "V_dc"),
        ({"i_max_peak": float("nan")}, "i_max_peak"),
        ({"converter": "matrix"}, "converter"),
        ({"converter": "switching"}, "f_pwm"),
        ({"voltage_margin": 1.5}, "voltage_margin"),
        ({"K_F": 2.0}, "K_F"),
        ({"speed_reference": [[0, 1], [-1, 2]]}, "speed_reference"),
        ({"load": [1, 2, 3]}, "load"),
        ({"substeps": 0}, "substeps"),
        ({"machine": PMSGParams(R_s=0.75, L_d=1e-3, L_q=1e-3, psi_m=0.0052, n_p=4)}, "J"),
        (
            {"estimates": PMSGParams(R_s=0.75, L_d=2e-3, L_q=1e-3, psi_m=0.0052, n_p=4)},
            "estimates.L_q",
        ),
        ({"i_max_peak": 100.0}, "voltage_margin"),  # R_s i_max beyond the voltage budget
    ],
)
def test_invalid_setup_names_the_field(change, field):
    with pytest.raises(InputError) as err:
        PMDriveSetup(**{**GOOD, **change})
    assert err.value.field == field
    assert "\n" not in str(err.value)


def test_build_wires_every_input_and_logs_declared_ports():
    built = build(PMDriveSetup(**GOOD))
    names = {p.name for p in built.system.parts}
    assert {
        "machine",
        "shaft",
        "encoder",
        "speed",
        "speed_pi",
        "torque_reference",
        "current",
        "converter",
    } <= names
    assert built.log["i_s"].path == "machine.i_s"
    switching = build(PMDriveSetup(**{**GOOD, "converter": "switching", "f_pwm": 20000.0}))
    assert type(switching.system.part("converter")).__name__ == "Inverter"
