"""``acdrive identify NAME --kind pm | dfim | mechanics``: a built-in machine's name simulates that
kind's tests on its bench (identify._builtin) and prints the table and writes the parameter file
of a measured log; the estimates written are within a percent or two of the catalog machine's
own values and their 95 % intervals hold them (at most one miss where that has a probability of
a few percent; seed 0, the command's default). An unknown name is one line naming the argument and listing the kind's
built-in names (exit 2), before any work."""

import re
import tomllib

import pytest

from acdrive.cli import main
from acdrive.drives.pm import BLY171D, IPMSM_2KW2
from acdrive.drives.pm._machines import BLY171D_B
from acdrive.identify._builtin import builtin_bench, builtin_names
from acdrive.machines import BODSON_DFIM


def identified(tmp_path, capsys, argv):
    """Run the command (the plain table) and return (printed text, parameter file)."""
    out = tmp_path / "estimates.toml"
    assert main(["identify", *argv, "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "95% CI (Jacobian)" in text and "95% CI (bootstrap)" in text
    return text, tomllib.loads(out.read_text())


def misses(table, truth, rtol):
    """How many of the Jacobian intervals of ``table`` miss ``truth`` (name -> true value);
    every estimate within ``rtol`` of its true value and with a bootstrap interval."""
    count = 0
    for name, true in truth.items():
        entry = table[name]
        low, high = entry["ci95_jacobian"]
        count += not low <= true <= high
        assert abs(entry["value"] - true) < rtol * true, (name, true, entry)
        assert entry["ci95_bootstrap"][0] < entry["value"] < entry["ci95_bootstrap"][1], name
    return count


@pytest.mark.parametrize(("name", "machine"), [("bly171d", BLY171D), ("ipmsm-2.2kw", IPMSM_2KW2)])
def test_a_built_in_pm_machine_gives_r_s_l_d_l_q_psi_m_covering_its_values(
    tmp_path, capsys, name, machine
):
    text, data = identified(tmp_path, capsys, [name, "--kind", "pm"])
    found = data["identification"]
    missed = misses(found["pm_standstill"], {n: getattr(machine, n) for n in ("R_s", "L_d", "L_q")},
                    0.01)  # fmt: skip
    missed += misses(found["spin"], {"psi_m": machine.psi_m}, 0.005)
    # four 95 % intervals: two misses or more have probability 1.4 % if they are right
    assert missed <= 1
    assert found["kind"] == "pm" and "spin.psi_m" in text
    params = data["machine"]["params"]
    assert params["n_p"] == machine.n_p  # the built-in machine's, not asked for
    assert params["psi_m"] == found["spin"]["psi_m"]["value"]
    # the bench's lock holds n_p psi_pm i_q: a torque, reported for sizing a brake
    assert found["q_test_lock_torque_nm"] > 0.0


def test_the_built_in_dfim_gives_its_rotor_side_parameters_and_with_r_s_m_and_l_s(tmp_path,
                                                                                   capsys):  # fmt: skip
    m = BODSON_DFIM
    text, data = identified(tmp_path, capsys, ["bodson-dfim", "--kind", "dfim",
                                               "--stator-resistance-ohm", repr(m.R_s),
                                               "--stator-resistance-std-ohm",
                                               repr(0.01 * m.R_s)])  # fmt: skip
    truth = {
        "R_r": m.R_r,
        "L_r": m.L_r,
        "L_sigma_r": m.L_r - m.M**2 / m.L_s,
        "R_S": m.R_s * (m.M / m.L_s) ** 2,
        "L_M": m.M**2 / m.L_s,
        "M": m.M,
        "L_s": m.L_s,
    }
    # seven 95 % intervals: two misses or more have probability 4 % if they are right
    assert misses(data["identification"]["dfim"], truth, 0.02) <= 1
    assert abs(data["identification"]["consistency_l_r_sigmas"]) < 3.0
    assert data["machine"]["params"]["n_p"] == m.n_p
    assert "check: L_r (open)" in text


def test_the_built_in_speed_drive_gives_j_b_and_tau_c_covering_its_shaft(tmp_path, capsys):
    _, data = identified(tmp_path, capsys, ["bly171d", "--kind", "mechanics"])
    shaft = builtin_bench("mechanics", "bly171d")
    assert shaft.viscous_friction == BLY171D_B  # the scenario's, the catalog table's B
    truth = {"J": BLY171D.J, "B": BLY171D_B, "tau_c": shaft.plan.tau_c}
    # three 95 % intervals (conservative for the encoder's correlated error): none may miss
    assert misses(data["identification"]["mechanics"], truth, 0.01) == 0


def one_line_error(capsys, argv, pattern):
    assert main(argv) == 2
    captured = capsys.readouterr()
    err = captured.err.strip()
    assert len(err.splitlines()) == 1 and re.search(pattern, err), err
    assert captured.out == ""


@pytest.mark.parametrize("kind", ["pm", "dfim", "mechanics"])
def test_an_unknown_name_is_one_line_listing_the_kinds_names(tmp_path, capsys, kind):
    out = tmp_path / "x.toml"
    known = builtin_names(kind)
    assert known
    one_line_error(capsys, ["identify", "no-such-machine", "--kind", kind, "--out", str(out)],
                   r"^acdrive: error: TEST_FILE_OR_SCENARIO: neither a .csv / .parquet / .mat log "
                   rf"nor a built-in .*\(known for --kind {kind}: {re.escape(', '.join(known))}\)$")  # fmt: skip
    assert not out.exists()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["bly171d", "--kind", "pm", "--q-log", "q.csv"], r"--q-log: is for a measured test"),
        (["bodson-dfim", "--kind", "dfim", "--dc-log", "dc.csv"], r"--dc-log: is for a measured"),
        (["bly171d", "--kind", "mechanics", "--dead-time-s", "1e-6"],
         r"--dead-time-s: is not used by --kind mechanics"),
        (["bly171d", "--kind", "pm", "--spin-settle-s", "5"],
         r"--spin-settle-s: must be shorter than the built-in spin test's 1 s plateaus"),
        (["bly171d", "--kind", "pm", "--dead-time-s", "1e-3"], r"^acdrive: error: --dead-time-s: "),
    ],
)  # fmt: skip
def test_an_option_a_built_in_bench_cannot_take_is_one_line(tmp_path, capsys, argv, message):
    one_line_error(capsys, ["identify", *argv, "--out", str(tmp_path / "x.toml")], message)


@pytest.mark.parametrize("kind", ["cage-im", "pm", "dfim", "mechanics"])
def test_a_negative_seed_is_one_line_naming_it_before_any_work(tmp_path, capsys, kind):
    name = {"cage-im": "delorenzo-im", "pm": "bly171d", "dfim": "bodson-dfim"}.get(kind, "bly171d")
    out = tmp_path / "x.toml"
    one_line_error(capsys, ["identify", name, "--kind", kind, "--seed", "-1", "--out", str(out)],
                   r"^acdrive: error: --seed: must be an integer >= 0, got -1$")  # fmt: skip
    assert not out.exists()
