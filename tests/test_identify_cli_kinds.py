"""``acdrive identify --kind pm | dfim | mechanics`` on measured logs (here written from acdrive's
simulated tests in CSV, Parquet and .mat): the table and a parameter file whose estimates hold
the machine's values within their intervals, and every misuse refused in one line naming the
option (exit 2)."""

import math
import re
import tomllib

import pytest

from acdrive.cli import main
from acdrive.drives.pm import BLY171D
from acdrive.identify import (
    MechanicsPlan,
    SpinPlan,
    StandstillPlan,
    axis_test,
    dc_test,
    dfim_test,
    speed_step_test,
    spin_test,
    write_log,
    write_mechanics_log,
    write_spin_log,
)
from acdrive.machines import BODSON_DFIM

pytestmark = pytest.mark.slow

BLY_PLAN = StandstillPlan(dc_levels=(0.3, 0.6, 0.9), dc_step=0.5, base_frequency=2.0,
                          tone_amplitude=0.15, settle=0.5, v_dc=24.0)  # fmt: skip
DFIM_PLAN = StandstillPlan(tone_amplitude=0.3, v_dc=30.0)


def covered(entry, truth):
    low, high = entry["ci95_jacobian"]
    return low <= truth <= high


def test_pm_logs_give_r_s_l_d_l_q_psi_m_and_a_pm_machine_table(tmp_path, capsys):
    d = write_log(axis_test(BLY171D, BLY_PLAN, "d").log, tmp_path / "d.csv")
    q = write_log(axis_test(BLY171D, BLY_PLAN, "q", seed=2).log, tmp_path / "q.parquet")
    dc = write_log(dc_test(BLY171D, BLY_PLAN, seed=0), tmp_path / "dc.csv")
    spin = write_spin_log(spin_test(BLY171D, SpinPlan()).log, tmp_path / "spin.mat")
    out = tmp_path / "pm.toml"
    argv = ["identify", str(d), "--kind", "pm", "--q-log", str(q), "--spin-log", str(spin),
            "--dc-log", str(dc),
            "--pole-pairs", "4", "--base-frequency-hz", "2", "--settle-s", "0.5", "--out",
            str(out)]  # fmt: skip
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "pm_standstill.L_q" in text and "spin.psi_m" in text and "95% CI (bootstrap)" in text
    data = tomllib.loads(out.read_text())
    params = data["machine"]["params"]
    assert params["n_p"] == 4
    found = data["identification"]
    misses = sum(not covered(found["pm_standstill"][n], getattr(BLY171D, n))
                 for n in ("R_s", "L_d", "L_q"))  # fmt: skip
    misses += not covered(found["spin"]["psi_m"], BLY171D.psi_m)
    assert misses <= 1
    assert params["psi_m"] == found["spin"]["psi_m"]["value"]
    assert main([*argv[:3], "pm", "--pole-pairs", "4", "--out", str(out)]) == 2
    assert re.search(r"--q-log: is required for --kind pm", capsys.readouterr().err)


def test_pm_logs_with_dead_time_are_compensated_given_the_pwm_units_dead_time(tmp_path):
    """A 2 us dead time and 1 V device drops (U_err = 1.65 V): with --dc-log and --dead-time-s
    the standstill estimates hold the machine's values (identify._impedance); the tones of 0.9 V
    and the DC levels raised by U_err so the injection is not drowned by it."""
    import dataclasses

    U = 4.0 / 3.0 * (2e-6 * 5000.0 * 24.0 + 1.0)
    plan = dataclasses.replace(BLY_PLAN, t_d=2e-6, v_drop=1.0, tone_amplitude=0.9,
                               dc_levels=tuple(v + U for v in BLY_PLAN.dc_levels))  # fmt: skip
    d = write_log(axis_test(BLY171D, plan, "d").log, tmp_path / "d.csv")
    q = write_log(axis_test(BLY171D, plan, "q", seed=2).log, tmp_path / "q.csv")
    dc = write_log(dc_test(BLY171D, plan, seed=0), tmp_path / "dc.csv")
    out = tmp_path / "pm.toml"
    assert main(["identify", str(d), "--kind", "pm", "--q-log", str(q), "--dc-log", str(dc),
                 "--dead-time-s", "2e-6", "--pole-pairs", "4", "--base-frequency-hz", "2",
                 "--settle-s", "0.5", "--out", str(out)]) == 0  # fmt: skip
    found = tomllib.loads(out.read_text())["identification"]
    for name in ("R_s", "L_d", "L_q"):
        assert covered(found["pm_standstill"][name], getattr(BLY171D, name)), name
    assert found["dc_steps"]["U_err"]["value"] == pytest.approx(U, rel=0.02)


def test_dfim_logs_with_a_stator_resistance_give_a_dfim_machine_table(tmp_path):
    m = BODSON_DFIM
    opened = write_log(dfim_test(m, DFIM_PLAN, "open", "injection"), tmp_path / "open.csv")
    shorted = write_log(dfim_test(m, DFIM_PLAN, "shorted", "injection", seed=2),
                        tmp_path / "shorted.csv")  # fmt: skip
    out = tmp_path / "dfim.toml"
    assert main(["identify", str(opened), "--kind", "dfim", "--shorted-log", str(shorted),
                 "--stator-resistance-ohm", str(m.R_s), "--stator-resistance-std-ohm", "0.0066",
                 "--pole-pairs", "2", "--out", str(out)]) == 0  # fmt: skip
    data = tomllib.loads(out.read_text())
    params = data["machine"]["params"]
    for name in ("R_r", "L_r", "L_s", "M"):
        assert params[name] == pytest.approx(getattr(m, name), rel=0.02), name
    assert abs(data["identification"]["consistency_l_r_sigmas"]) < 3.0


def test_a_speed_step_log_gives_j_b_and_tau_c(tmp_path):
    scenario = {
        "drive": "pm",
        "machine": {"machine": "bly171d", "viscous_friction": 1.1604e-5},
        "converter": {"model": "switching", "pwm_frequency_hz": 20000.0, "dc_link_voltage": 24.0},
        "control": {"current_limit_pk_a": 1.8, "current_bandwidth_rad_s": 2 * math.pi * 400,
                    "speed_bandwidth_rad_s": 200.0},
        "simulation": {"sample_time": 5e-5},
    }  # fmt: skip
    log = write_mechanics_log(speed_step_test(scenario, MechanicsPlan(tau_c=2e-3)),
                              tmp_path / "steps.csv")  # fmt: skip
    out = tmp_path / "mech.toml"
    assert main(["identify", str(log), "--kind", "mechanics", "--out", str(out)]) == 0
    found = tomllib.loads(out.read_text())["identification"]["mechanics"]
    assert found["J"]["value"] == pytest.approx(BLY171D.J, rel=0.01)
    assert found["tau_c"]["value"] == pytest.approx(2e-3, rel=0.01)


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--kind", "mechanics", "--q-log", "q.csv"], r"--q-log: is for --kind pm only"),
        (["--kind", "pm", "--shorted-log", "s.csv"], r"--shorted-log: is for --kind dfim only"),
        (["--no-load-log", "n.csv", "--kind", "dfim"], r"--no-load-log: is for --kind cage-im only"),
        (["--kind", "mechanics", "--pole-pairs", "2"], r"--pole-pairs: is not used by --kind mechanics"),
        (["--kind", "mechanics", "--dead-time-s", "2e-6"], r"--dead-time-s: is not used by --kind mechanics"),
        (["--kind", "pm", "--dead-time-s", "-1e-6"], r"^acdrive: error: --dead-time-s: "),
        (["--kind", "dfim", "--device-drop-v", "1"], r"--device-drop-v: is for a simulated test only"),
    ],
)  # fmt: skip
def test_an_option_of_another_kind_is_refused_in_one_line(tmp_path, capsys, extra, message):
    source = tmp_path / "log.csv"
    source.write_text("time [s],tau_e [N m],w [rad/s]\n")
    assert main(["identify", str(source), *extra, "--out", str(tmp_path / "x.toml")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and re.search(message, err), err
