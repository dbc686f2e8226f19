"""The benchmark suite (``acdrive bench``): its matched acdrive system against an independent
solution of the same equations, its JSON and verdicts, and a missing peer. Fast: no network, no
virtualenv is made, short model times; speed targets are judged by the suite, never here."""

from __future__ import annotations

import io
import json
import sys
from contextlib import redirect_stderr, redirect_stdout

import numpy as np
import pytest

from acdrive._bench import gem_dfim, venvs
from acdrive._bench.reference import accuracy, error_verdicts
from acdrive._bench.suite import TARGETS, summarise


@pytest.fixture(scope="module")
def gem_run():
    """acdrive's side of the GEM case over 0.05 s (500 control periods)."""
    n = 500
    v_s, v_r = gem_dfim.acdrive_voltages(gem_dfim.actions(n))
    system, p = gem_dfim.build_system(v_s, v_r)
    ports = [p["dfim"].out.i_s, p["dfim"].out.i_r, p["shaft"].out.w, p["shaft"].out.theta]
    raw = system.compile().run(n * gem_dfim.T_S, gem_dfim.T_S, substeps=1, log=ports)
    states = gem_dfim.acdrive_states(raw, system, p)
    seg = {
        "t": raw.t.copy(),
        "counts": np.ones(n, dtype=np.int64),
        "dt": np.full(n, gem_dfim.T_S),
        "v_s": v_s,
        "v_r": v_r,
    }
    return states, seg, n


def test_gem_matched_system_agrees_with_scipy(gem_run):
    """The DFIM + shaft assembled from parts, fed the held voltage sequences, follows the same
    equations written independently in numpy (rotor voltage held in rotor coordinates) and
    solved by scipy's Radau at rtol 1e-10."""
    states, seg, n = gem_run
    assert np.max(np.abs(states[:, 0] + 1j * states[:, 1])) > 1.0  # the machine is excited
    err = accuracy(states, seg, n, gem_dfim.DFIMEquations("rotor"), extended_substeps=0)
    assert err["reference"]["current_rel_peak"] < 1e-9
    assert err["reference"]["speed_abs_rad_s"] < 1e-9
    assert err["reference"]["rotor_flux_rel_peak"] < 1e-9


def test_gem_rotor_voltage_convention_is_a_different_ode(gem_run):
    """GEM's rotor voltage held in the stator frame over each step is a different ODE: the
    rotor-frame solution is measurably far from it (so the suite keeps the two references)."""
    states, seg, n = gem_run
    err = accuracy(
        states, seg, n, gem_dfim.DFIMEquations("stator_at_step_start"), extended_substeps=0
    )
    assert err["reference"]["current_rel_peak"] > 1e-8


def test_actions_stay_inside_gems_bridge_limits():
    a = gem_dfim.actions(round(gem_dfim.DURATION / gem_dfim.T_S))
    assert np.max(np.abs(a)) < 1.0  # no clipping in GEM's bridges, none in acdrive


def _bench_json(*args) -> dict:
    from acdrive.cli import main

    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        code = main(["bench", "--json", *args])
    assert code == 0, err.getvalue()
    return json.loads(out.getvalue())


def test_bench_json_quick_no_peers(gem_run, monkeypatch):
    monkeypatch.setattr(sys, "argv", ["acdrive", "bench"])
    r = _bench_json("--quick", "--no-peers", "--only", "gem_dfim")
    for key in (
        "ratio_vs_motulator",
        "ratio_vs_motulator_pwm",
        "ratio_vs_gem",
        "icad_ms",
        "targets",
        "target_checks",
        "targets_met",
        "errors",
        "acdrive_steps_per_s",
        "peer_steps_per_s",
        "host",
        "versions",
        "peers",
    ):
        assert key in r, key
    assert r["ratio_vs_gem"] is None and r["ratio_vs_motulator"] is None
    gem = r["peers"]["gym-electric-motor"]
    assert gem["available"] is False and gem["reason"]
    assert r["acdrive_steps_per_s"]["gem_dfim"] > 0
    assert r["errors"]["gem_dfim"]["acdrive"]["radau_rtol_1e-10"]["current_rel_peak"] < 1e-9
    assert r["target_checks"] == {
        "ratio_vs_gem_at_least_300": None,
        "gem_dfim_error_not_larger": None,
    }
    assert r["targets_met"] is False
    assert r["host"]["load_average_at_start"] is not None


def test_unknown_case_is_an_input_error():
    from acdrive.cli import main

    err = io.StringIO()
    with redirect_stderr(err):
        assert main(["bench", "--json", "--only", "nonsense"]) == 2
    assert "--only" in err.getvalue()


def _report(**cases) -> dict:
    report = {"cases": cases}
    summarise(report)
    return report


def _case(ratio, a_err, p_err, peer="motulator"):
    def summary(e):
        return {"reference": {"current_rel_peak": e, "speed_abs_rad_s": e}}

    return {
        "acdrive": {"steps_per_s": 1e6},
        peer: {"steps_per_s": 1e6 / ratio},
        "ratio": ratio,
        "error_verdicts": error_verdicts(summary(a_err), summary(p_err)),
    }


def test_verdicts_follow_the_numbers():
    r = _report(
        motulator_averaged=_case(1200.0, 1e-13, 1e-12),
        motulator_pwm=_case(250.0, 1e-13, 1e-12),
        gem_dfim=_case(400.0, 1e-11, 1e-12, peer="gym-electric-motor"),
        icad={"icad_ms": 15.0},
    )
    checks = r["target_checks"]
    assert r["ratio_vs_motulator"] == 1200.0
    assert checks["ratio_vs_motulator_at_least_1000"] is True
    assert checks["motulator_averaged_error_not_larger"] is True
    assert checks["ratio_vs_motulator_pwm_at_least_300"] is False
    assert checks["ratio_vs_gem_at_least_300"] is True
    assert checks["gem_dfim_error_not_larger"] is False
    assert checks[f"icad_at_most_{TARGETS['icad_ms_max']:g}_ms"] is True
    assert r["targets_met"] is False
    good = _report(motulator_averaged=_case(1200.0, 1e-13, 1e-12))
    assert good["targets_met"] is True and good["targets_unmeasured"] == []


def test_error_verdicts_use_the_radau_resolution():
    """An error below the Radau reference's own resolution counts as equal to it."""
    a = {
        "reference": {"current_rel_peak": 2e-12, "speed_abs_rad_s": 0.0},
        "reference_resolution": {"current_rel_peak": 5e-12, "speed_abs_rad_s": 0.0},
    }
    m = {
        "reference": {"current_rel_peak": 1e-12, "speed_abs_rad_s": 0.0},
        "reference_resolution": {"current_rel_peak": 5e-12, "speed_abs_rad_s": 0.0},
    }
    v = error_verdicts(a, m)
    assert v["current_error_not_larger"] is True
    assert v["decisive"] == ["current_error_not_larger", "speed_error_not_larger"]


def test_missing_peer_is_reported_not_raised(tmp_path):
    """No interpreter the peer accepts: ``available: false`` with the reason, no venv made."""
    spec = venvs.PeerSpec(
        "nothing",
        "nothing",
        "nothing==1.0",
        "1.0",
        "nothing-1.0",
        lambda: [sys.executable],
        ((2, 7),),
    )
    got = venvs.ensure_venv(spec, tmp_path / "peers")
    assert got["available"] is False
    assert "no Python" in got["reason"] and sys.executable in got["reason"]
    assert not (tmp_path / "peers").exists()
    none = venvs.PeerSpec(
        "nothing", "nothing", "nothing==1.0", "1.0", "nothing-1.0", list, ((3, 12),)
    )
    assert "tried: none" in venvs.ensure_venv(none, tmp_path / "peers")["reason"]


def test_missing_peer_case_still_measures_acdrive(monkeypatch):
    """A peer that is not available: the case says why and acdrive is still timed."""
    r = gem_dfim.run_case({"available": False, "reason": "no venv here"}, 1, 0.01, False)
    assert r["gym-electric-motor"] == {"available": False, "reason": "no venv here"}
    assert r["acdrive"]["steps_per_s"] > 0 and "ratio" not in r


def test_default_peers_dir_is_a_cache(monkeypatch, tmp_path):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert venvs.default_peers_dir() == tmp_path / "acdrive" / "peers"
    monkeypatch.delenv("XDG_CACHE_HOME")
    assert venvs.default_peers_dir().parts[-3:] == (".cache", "acdrive", "peers")
