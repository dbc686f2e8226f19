"""``acdrive identify``: a measured log (written here from the exact sampled circuit) gives the
table with its intervals and a parameter file whose [machine] table a cage-IM scenario accepts;
bad input is one line with exit 2; a file of the user's is never replaced."""

import json
import re
import tomllib

import numpy as np
import pytest
from test_identify_estimators import HOLD, injection_log, sampled_response

from acdrive.cli import main
from acdrive.identify import StandstillLog, inverse_gamma, write_log
from acdrive.machines import DELORENZO_IM


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("logs")
    injection = write_log(injection_log(DELORENZO_IM, seed=21), folder / "injection.csv")
    t = np.arange(3 * 10000) * HOLD
    v = np.repeat((12.0, 24.0, 36.0), 10000)
    i = sampled_response(DELORENZO_IM, v) + 5e-3 * np.random.default_rng(22).standard_normal(t.size)
    dc = write_log(StandstillLog(t, v, i), folder / "dc.parquet")
    return injection, dc


def test_a_measured_log_gives_the_table_and_a_parameter_file_a_scenario_accepts(logs, tmp_path,
                                                                                capsys):  # fmt: skip
    from acdrive._toml import Section
    from acdrive.drives.cage_im._schema import _machine

    injection, dc = logs
    out = tmp_path / "machine.toml"
    code = main(["identify", str(injection), "--dc-log", str(dc), "--pole-pairs", "1",
                 "--out", str(out), "--json"])  # fmt: skip
    assert code == 0
    printed = json.loads(capsys.readouterr().out)
    truth = inverse_gamma(DELORENZO_IM)
    for name, true in zip(("R_s", "L_sigma", "R_R", "L_M"), truth.as_array(), strict=True):
        entry = printed["inverse_gamma"][name]
        low, high = entry["ci95_jacobian"]
        assert low <= true <= high, (name, entry)
    assert printed["dc_steps"]["R_s"]["ci95_jacobian"][0] <= DELORENZO_IM.R_s
    assert printed["dc_steps"]["R_s"]["ci95_jacobian"][1] >= DELORENZO_IM.R_s
    data = tomllib.loads(out.read_text())
    nominal = _machine(Section(data["machine"], "machine"))[0]  # the design machine
    np.testing.assert_allclose(inverse_gamma(nominal).as_array(),
                               [printed["inverse_gamma"][n]["value"]
                                for n in ("R_s", "L_sigma", "R_R", "L_M")], rtol=1e-12)  # fmt: skip
    assert data["identification"]["leakage_split"] == "equal"
    assert nominal.L_s == pytest.approx(nominal.L_r, rel=1e-12)  # the split assumed, L_ls = L_lr
    # the plain table: every quantity with its unit and both intervals; written again over its
    # own file (acdrive's mark), which is allowed
    assert main(["identify", str(injection), "--pole-pairs", "1", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "inverse_gamma.L_M" in text and "95% CI (bootstrap)" in text
    assert "not identifiable at standstill: the split of the leakage" in text


def one_line_error(capsys, argv, pattern):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert re.search(pattern, err), err


def test_bad_input_is_one_line_with_exit_2(logs, tmp_path, capsys):
    injection, _ = logs
    out = str(tmp_path / "m.toml")
    one_line_error(capsys, ["identify", str(injection), "--out", out],
                   r"--pole-pairs: is required for a measured log")  # fmt: skip
    one_line_error(capsys, ["identify", "no-such-machine", "--out", out],
                   r"TEST_FILE_OR_SCENARIO: neither a .csv / .parquet / .mat log nor a built-in "
                   "cage IM")  # fmt: skip
    one_line_error(capsys, ["identify", str(injection), "--pole-pairs", "1", "--out",
                            str(tmp_path / "m.txt")], r"--out: must name a .toml file")  # fmt: skip
    bad = tmp_path / "bad.csv"
    bad.write_text(injection.read_text().replace("i_a [A]", "i_a [mA]", 1))
    one_line_error(capsys, ["identify", str(bad), "--pole-pairs", "1", "--out", out],
                   r"TEST_FILE_OR_SCENARIO: column 'i_a': must be in A, got 'mA'")  # fmt: skip
    one_line_error(capsys, ["identify", str(injection), "--pole-pairs", "1", "--out", out,
                            "--base-frequency-hz", "0.3"], r"--base-frequency-hz: a period")  # fmt: skip
    one_line_error(capsys, ["identify", str(injection), "--pole-pairs", "1", "--out", out,
                            "--no-load-log", str(injection)],
                   r"--no-load-log: column 'w': is missing; a no-load log has")  # fmt: skip
    one_line_error(capsys, ["identify", "delorenzo-im", "--out", out, "--no-load-log",
                            str(injection)], r"--no-load-log: is for a measured test")  # fmt: skip


def test_a_file_of_the_users_is_never_replaced(logs, tmp_path, capsys):
    injection, _ = logs
    mine = tmp_path / "machine.toml"
    mine.write_text("[machine]\nmachine = 'delorenzo-im'\n")
    one_line_error(capsys, ["identify", str(injection), "--pole-pairs", "1", "--out", str(mine)],
                   r"--out: '.*machine.toml' exists and acdrive did not write it")  # fmt: skip
    assert mine.read_text() == "[machine]\nmachine = 'delorenzo-im'\n"


def test_a_fit_that_does_not_converge_says_so_with_its_residual_and_writes_nothing(
    logs, tmp_path, capsys, monkeypatch
):
    """The solver is made to stop after two evaluations: the command reports the failure with
    the residual reached, exit 1, and no parameter file."""
    import scipy.optimize

    injection, _ = logs
    original = scipy.optimize.least_squares

    def starved(*args, **kwargs):
        kwargs["max_nfev"] = 2
        return original(*args, **kwargs)

    monkeypatch.setattr(scipy.optimize, "least_squares", starved)
    out = tmp_path / "m.toml"
    assert main(["identify", str(injection), "--pole-pairs", "1", "--out", str(out)]) == 1
    err = capsys.readouterr().err.strip()
    assert re.fullmatch(r"acdrive: error: impedance: the fit did not converge \(.*\); residual "
                        r"[0-9.e+-]+ A \(rms of the tones' current error\); no parameters are "
                        r"returned", err), err  # fmt: skip
    assert not out.exists()
