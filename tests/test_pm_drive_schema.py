"""Scenario tables of the PM drive (``drives/pm/_schema.py``): the built-in scenarios load, and
a bad field is refused with one line naming it."""

import copy
import tomllib

import pytest

from acdrive.drives.pm import BLY171D
from acdrive.drives.pm._schema import SCENARIO_DIR, builtin, builtin_names, load
from acdrive.errors import InputError


def base():
    return tomllib.loads((SCENARIO_DIR / "pm-bly171d-speed.toml").read_text())


def test_builtin_scenarios_load():
    assert builtin_names() == [
        "pm-bly171d-speed",
        "pm-bly171d-svpwm",
        "pm-ipmsm-field-weakening",
        "pm-ipmsm-speed",
        "pm-pmsg-2mw-icad-coupling",
    ]
    speed, svpwm = builtin("pm-bly171d-speed"), builtin("pm-bly171d-svpwm")
    assert speed.machine == BLY171D and speed.J == BLY171D.J
    assert (svpwm.converter, svpwm.f_pwm) == ("switching", 20000.0)
    assert speed.name == "pm-bly171d-speed"


def test_machine_params_table():
    data = base()
    data["machine"] = {"params": {"R_s": 0.1, "L_d": 1e-3, "L_q": 2e-3, "psi_m": 0.05,
                                  "n_p": 3, "J": 0.01}}  # fmt: skip
    setup = load(data)
    assert (setup.machine.L_q, setup.J) == (2e-3, 0.01)
    del data["machine"]["params"]["J"]
    with pytest.raises(InputError, match=r"^machine\.J: must be given"):
        load(data)


def edit(path, value):
    data = copy.deepcopy(base())
    *tables, key = path.split(".")
    node = data
    for t in tables:
        node = node.setdefault(t, {})
    if value is None:
        del node[key]
    else:
        node[key] = value
    return data


@pytest.mark.parametrize(
    "path, value, field",
    [
        ("machine.colour", "red", "machine.colour"),
        ("machine.J", 0.0, "machine.J"),
        ("machine.machine", "prius", "machine.machine"),
        ("converter.model", "matrix", "converter.model"),
        ("converter.dc_link_voltage", None, "converter.dc_link_voltage"),
        ("converter.pwm_frequency_hz", 5000.0, "converter.pwm_frequency_hz"),
        ("control.current_limit_pk_a", -1.0, "control.current_limit_pk_a"),
        ("control.current_limit_pk_a", 50.0, "control.voltage_margin"),
        ("control.K_F", 3.0, "control.K_F"),
        ("reference.speed_rad_s", 100.0, "reference.speed_rad_s"),
        ("reference.speed_rad_s_profile", [[0.0, 1.0], [0.1]], "reference.speed_rad_s_profile[1]"),
        ("simulation.sample_time", 0.0, "simulation.sample_time"),
        ("simulation.substeps", 1.5, "simulation.substeps"),
        ("drive", "dfim", "drive"),
    ],
)  # fmt: skip
def test_bad_field_is_named(path, value, field):
    with pytest.raises(InputError) as err:
        load(edit(path, value))
    assert err.value.field == field
    assert "\n" not in str(err.value)
