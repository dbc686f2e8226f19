"""A measured no-load run's DC-link voltage (identify._no_load.link_voltage): given as
``--link-voltage-v`` or as the log's ``v_dc [V]`` column, ``acdrive identify`` fits L_M with the
PWM pulses' second-order term exactly as ``fit_no_load(..., v_dc=)`` does in-process; without
either it fits the held-voltage model, whose bias is larger and grows as the square of the
switching period; the two given and disagreeing, or a link that varies, is one line (exit 2)."""

import dataclasses
import json
import re
import types

import numpy as np
import pytest

from acdrive.cli import main
from acdrive.identify import (
    NoLoadPlan,
    StandstillPlan,
    dc_test,
    fit_no_load,
    identify_standstill,
    injection_test,
    inverse_gamma,
    no_load_test,
    read_log,
    read_no_load_log,
    write_log,
    write_no_load_log,
)
from acdrive.identify._experiment import CurrentSensor
from acdrive.machines import DELORENZO_IM

M = DELORENZO_IM
PLAN = StandstillPlan()
RUN = NoLoadPlan(slip=0.02)


def with_link(log, v_dc):
    """The log with a v_dc column: the bench's DC source is ideal, so the link sensor reads
    its voltage at every sample."""
    return dataclasses.replace(log, v_dc=np.full(log.time.size, float(v_dc)))


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("link")
    run = no_load_test(M, RUN, seed=3)
    return {
        "injection": write_log(injection_test(M, PLAN, seed=1), folder / "injection.csv"),
        "dc": write_log(dc_test(M, PLAN, seed=0), folder / "dc.csv"),
        "plain": write_no_load_log(run, folder / "run.csv"),
        "column": write_no_load_log(with_link(run, RUN.v_dc), folder / "run-vdc.csv"),
    }


def cli_no_load(capsys, logs, run, *extra):
    argv = ["identify", str(logs["injection"]), "--dc-log", str(logs["dc"]), "--no-load-log",
            str(logs[run]), "--pole-pairs", str(M.n_p), "--json", *extra]  # fmt: skip
    assert main([*argv, "--out", str(logs["injection"].with_name(f"{run}.toml"))]) == 0
    return json.loads(capsys.readouterr().out)["no_load"]


def test_the_column_or_the_option_give_the_in_process_fit_with_the_link_voltage(logs, capsys):
    # in-process: the same logs read back, the command's seeds (standstill seed 0, no-load 2)
    standstill = identify_standstill(read_log(logs["injection"]), PLAN.base_frequency,
                                     PLAN.settle, dc=read_log(logs["dc"]), n_p=M.n_p, seed=0)  # fmt: skip
    run = read_no_load_log(logs["plain"])
    assert run.v_dc is None

    def in_process(v_dc):
        return fit_no_load(run, RUN.frequency, RUN.settle, M.n_p, standstill.impedance, seed=2,
                           v_dc=v_dc).L_M.value  # fmt: skip

    modelled, held = in_process(RUN.v_dc), in_process(None)
    column = cli_no_load(capsys, logs, "column")
    assert column["link_voltage_v"] == RUN.v_dc
    assert column["L_M"]["value"] == pytest.approx(modelled, rel=1e-12)
    option = cli_no_load(capsys, logs, "plain", "--link-voltage-v", repr(RUN.v_dc))
    assert option["L_M"]["value"] == pytest.approx(modelled, rel=1e-12)
    neither = cli_no_load(capsys, logs, "plain")
    assert neither["link_voltage_v"] is None
    assert neither["L_M"]["value"] == pytest.approx(held, rel=1e-12)
    assert neither["L_M"]["value"] != modelled


def one_line_error(capsys, argv, pattern):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and re.search(pattern, err), err


def test_a_link_voltage_given_twice_and_different_or_varying_is_one_line(logs, tmp_path, capsys):
    base = ["identify", str(logs["injection"]), "--pole-pairs", str(M.n_p), "--out",
            str(tmp_path / "x.toml")]  # fmt: skip
    one_line_error(capsys, [*base, "--no-load-log", str(logs["column"]), "--link-voltage-v",
                            repr(0.8 * RUN.v_dc)],
                   r"--link-voltage-v and --no-load-log: column 'v_dc': must agree within 5%")  # fmt: skip
    run = read_no_load_log(logs["plain"])
    ripple = dataclasses.replace(run, v_dc=RUN.v_dc * (1 + 0.1 * np.sin(2 * np.pi * run.time)))
    varying = write_no_load_log(ripple, tmp_path / "varying.csv")
    one_line_error(capsys, [*base, "--no-load-log", str(varying)],
                   r"--no-load-log: column 'v_dc': must stay within 5% of its mean")  # fmt: skip
    bad_unit = tmp_path / "kv.csv"
    bad_unit.write_text(logs["column"].read_text().replace("v_dc [V]", "v_dc [kV]", 1))
    one_line_error(capsys, [*base, "--no-load-log", str(bad_unit)],
                   r"--no-load-log: column 'v_dc': must be in V, got 'kV'")  # fmt: skip
    one_line_error(capsys, [*base, "--link-voltage-v", "310"],
                   r"--link-voltage-v: needs --no-load-log")  # fmt: skip
    one_line_error(capsys, ["identify", "delorenzo-im", "--link-voltage-v", "310", "--out",
                            str(tmp_path / "x.toml")], r"--link-voltage-v: is for a measured")  # fmt: skip


def test_without_the_link_voltage_the_bias_is_larger_and_grows_as_the_period_squared(tmp_path):
    """Noise-free runs with the true standstill parameters: the held-voltage model reads L_M
    high by a bias that falls fourfold when the carrier doubles (the pulses' second moment about
    the period's centre, v_dc T^3 (d^3 - d) / 12 per leg, over a period T: relative to the
    mean's effect, T^2); the column's link voltage, read from a CSV log, removes it."""
    truth = inverse_gamma(M)
    standstill = types.SimpleNamespace(params=truth, cov=np.zeros((4, 4)),
                                       draws=np.empty((0, 4)))  # fmt: skip
    quiet = CurrentSensor(noise_std=0.0, lsb=0.0)
    held, modelled = {}, {}
    for f_pwm in (5000.0, 10000.0):
        run = dataclasses.replace(RUN, f_pwm=f_pwm, sensor=quiet)
        log = no_load_test(M, run)
        path = write_no_load_log(with_link(log, run.v_dc), tmp_path / f"run-{f_pwm:g}.csv")

        def error(log, v_dc=None, run=run):
            fit = fit_no_load(log, run.frequency, run.settle, M.n_p, standstill, bootstrap=5,
                              v_dc=v_dc)  # fmt: skip
            return fit.L_M.value / truth.L_M - 1.0

        held[f_pwm], modelled[f_pwm] = error(log), error(read_no_load_log(path))
        # a link voltage 5 % off (the column's tolerance) moves the estimate by a fraction of
        # the term it models
        assert abs(error(log, 1.05 * run.v_dc) - modelled[f_pwm]) < 0.25 * held[f_pwm]
    assert held[5000.0] > 0.0 and held[10000.0] > 0.0  # the held model reads L_M high
    assert held[5000.0] / held[10000.0] == pytest.approx(4.0, rel=0.1)  # as T^2
    for f_pwm, bias in held.items():
        assert abs(modelled[f_pwm]) < 0.01 * bias
