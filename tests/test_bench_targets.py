"""The benchmark's issue-21 parts without running a peer or timing anything that is asserted:
the first-result race's order and statistics on fake processes, the targets' ``met`` flags,
the reference cache's key and its recovery from a corrupt entry, and the child-process timer's
plumbing. A test that needs motulator is skipped when its virtualenv is absent."""

from __future__ import annotations

import io
import json
import os
import sys
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import numpy as np
import pytest

from acdrive._bench import children, first_result, refcache, targets
from acdrive._bench.windows import Clock


# --- the race on fake processes ----------------------------------------------------------------
class FakeProcesses:
    """Stands in for ``children.run_child``: the CPU time of a run depends on which side it is
    (motulator's script, acdrive with a cache folder holding nothing yet, or one filled before)."""

    def __init__(self, empty_s, motulator_s, warm_s):
        self.costs = {"empty": list(empty_s), "motulator": list(motulator_s), "warm": list(warm_s)}
        self.calls: list[tuple[str, str | None]] = []
        self.filled: set[str] = set()

    def __call__(self, cmd, env, cwd=None):
        home = env.get("XDG_CACHE_HOME")
        if "--first-result" in cmd:
            side = "motulator"
        else:
            assert home is not None and os.path.isdir(home)  # the race made it
            side = "warm" if home in self.filled else "empty"
            self.filled.add(home)
        self.calls.append((side, home))
        costs = self.costs[side]
        cpu = costs.pop(0) if len(costs) > 1 else costs[0]
        return {"cpu_s": cpu, "wall_s": cpu, "max_rss_mb": 1.0, "stdout_last": "12000"}


def _quiet_clock():
    t = [0.0]
    return Clock(cpu=lambda: t[0], wall=lambda: t[0], busy=lambda: None, load=lambda: 0.5, cores=2)


def test_race_interleaves_and_gives_ratios_per_round(monkeypatch):
    """Rounds run empty cache, motulator, warm cache; every empty-cache run gets its own fresh
    cache folder, deleted after it; the warm runs share the folder filled before the rounds;
    per round acdrive's time over motulator's, and the verdicts come from the medians."""
    # warm-up runs first: the cache fill (an empty-cache run of the warm folder) and motulator
    fake = FakeProcesses(empty_s=[12.0, 9.0, 15.0], motulator_s=[6.0, 6.0, 5.0, 6.0],
                         warm_s=[1.2, 1.0, 1.5])  # fmt: skip
    fake.costs["empty"].insert(0, 10.0)  # the warm cache's fill
    monkeypatch.setattr(first_result, "run_child", fake)
    peer = {"available": True, "python": sys.executable}
    r = first_result.run_race(peer, 3, 1.5, clock=_quiet_clock())
    sides = [w["side"] for w in r["windows"]]
    assert sides == ["acdrive_empty_cache", "motulator", "acdrive_warm_cache"] * 3
    kinds = [side for side, _ in fake.calls]
    assert kinds == ["empty", "motulator"] + ["empty", "motulator", "warm"] * 3
    homes = [home for side, home in fake.calls if side == "empty"]
    warm_home = homes[0]
    assert len(set(homes[1:])) == 3 and warm_home not in homes[1:]
    assert all(home == warm_home for side, home in fake.calls if side == "warm")
    assert not any(os.path.exists(h) for h in homes)  # the race's folders are gone
    ratio = r["time_ratio"]["empty_cache"]
    assert ratio["per_round"] == pytest.approx([12.0 / 6.0, 9.0 / 5.0, 15.0 / 6.0])
    assert (ratio["min"], ratio["median"], ratio["max"]) == pytest.approx((1.8, 2.0, 2.5))
    speedup = r["speedup"]["warm_cache"]
    assert speedup["per_round"] == pytest.approx([6.0 / 1.2, 5.0 / 1.0, 6.0 / 1.5])
    assert speedup["median"] == pytest.approx(5.0)
    assert r["cpu_s"]["motulator"]["median"] == 6.0
    assert r["verdicts"] == {
        "empty_cache_at_most_1x_motulator": False,
        "warm_cache_at_least_10x_faster": False,
    }
    assert r["results"]["acdrive_warm_cache"]["control_steps"] == ["12000"]
    assert r["warm_up_cpu_s"] == {"acdrive_fill_warm_cache": 10.0, "motulator": 6.0}


def test_race_without_motulator_still_times_acdrive(monkeypatch):
    fake = FakeProcesses(empty_s=[8.0], motulator_s=[1.0], warm_s=[1.0])
    monkeypatch.setattr(first_result, "run_child", fake)
    r = first_result.run_race(
        {"available": False, "reason": "--no-peers"}, 2, 1.5, clock=_quiet_clock()
    )
    assert [w["side"] for w in r["windows"]] == ["acdrive_empty_cache", "acdrive_warm_cache"] * 2
    assert r["motulator"] == {"available": False, "reason": "--no-peers"}
    assert r["time_ratio"] == {} and r["speedup"] == {}
    assert r["verdicts"] == {
        "empty_cache_at_most_1x_motulator": None,
        "warm_cache_at_least_10x_faster": None,
    }
    section = targets.targets_section({"first_result": r}, {})
    entry = section["first_result_warm_speedup"]
    assert entry["met"] is None and entry["not measured"] == "--no-peers"


def test_a_failing_child_ends_the_race_with_the_reason(monkeypatch):
    def failing(cmd, env, cwd=None):
        raise children.ChildFailed("python -c exited with 1: ImportError: no acdrive")

    monkeypatch.setattr(first_result, "run_child", failing)
    r = first_result.run_race({"available": False}, 2, 1.5, clock=_quiet_clock())
    assert "ImportError" in r["not_measured"]
    assert r["verdicts"]["warm_cache_at_least_10x_faster"] is None


def test_race_verdicts_at_the_bounds():
    v = first_result.verdicts
    assert v(1.0, 10.0) == {
        "empty_cache_at_most_1x_motulator": True,
        "warm_cache_at_least_10x_faster": True,
    }
    assert v(1.0001, 9.999) == {
        "empty_cache_at_most_1x_motulator": False,
        "warm_cache_at_least_10x_faster": False,
    }
    assert set(v(None, None).values()) == {None}


def test_warm_cache_with_two_numba_folders_is_flagged(tmp_path):
    (tmp_path / "acdrive" / "numba-aaaa").mkdir(parents=True)
    assert first_result.warm_cache_warnings(str(tmp_path)) == []
    (tmp_path / "acdrive" / "numba-bbbb").mkdir()
    (w,) = first_result.warm_cache_warnings(str(tmp_path))
    assert "numba-aaaa, numba-bbbb" in w and "compiled again" in w


# --- the targets -------------------------------------------------------------------------------
def test_met_is_computed_from_value_target_and_comparison():
    assert targets.is_met(1.0, 1.0, "at most") is True
    assert targets.is_met(1.01, 1.0, "at most") is False
    assert targets.is_met(3.0, 3.0, "at least") is True
    assert targets.is_met(2.99, 3.0, "at least") is False
    with pytest.raises(ValueError):
        targets.is_met(1.0, 1.0, "about")
    e = targets.target_entry("whole_command_warm_cpu_s", 2.2)
    assert (e["value"], e["target"], e["unit"], e["met"]) == (2.2, 1.0, "CPU-s", False)
    e = targets.target_entry("simd_batch_steps_per_s", None, "no lockstep batch")
    assert e["met"] is None and e["not measured"] == "no lockstep batch"


def _spread(median):
    return {"min": median, "median": median, "max": median, "n": 1}


def _measured_cases(**scale):
    """Every case behind the targets with the given numbers (defaults: all targets met)."""
    s = {"warm": 0.8, "no_fig": 0.5, "first": 5.0, "topo": 1.2, "simd": 7e6, "lanes": 4.0,
         "empty": 0.9, "speedup": 12.0, "loop": 0.99, "export_c": 12.0, **scale}  # fmt: skip
    return {
        "command": {
            "warm_figures": {"cpu_s": _spread(s["warm"])},
            "warm_no_figures": {"cpu_s": _spread(s["no_fig"])},
            "empty_cache": {"wall_s": s["first"], "cpu_s": 4.0, "load_average_1min": [0.1, 0.2]},
        },
        "compile_free": {
            "ratio": _spread(s["topo"]),
            "new_topology_cpu_s": _spread(1.2),
            "warm_cpu_s": _spread(1.0),
        },
        "batch": {
            "variants": 1000,
            "lockstep_option": "lanes",
            "single_lane": {"steps_per_s": _spread(2e6), "steps_per_cpu_s": _spread(1e6)},
            "lockstep": {"steps_per_s": _spread(s["simd"]), "steps_per_cpu_s": _spread(4e6)},
            "lockstep_vs_single_lane_per_cpu_s": _spread(s["lanes"]),
        },
        "first_result": {
            "time_ratio": {"empty_cache": _spread(s["empty"])},
            "speedup": {"warm_cache": _spread(s["speedup"])},
        },
        "motulator_averaged": {
            "motulator_export": {
                "available": True,
                "sides": {
                    "motulator_export_c": {
                        "acdrive_ratio": s["export_c"],
                        "acdrive_ratio_spread": _spread(s["export_c"]),
                    }
                },
            }
        },
        "loop_speed": {
            "scenarios": {
                name: {"loop": {"ratio_after_before_median": s["loop"]}}
                for name in ("bodson-ramp", "im-foc-speed")
            }
        },
    }


def test_every_target_has_an_entry_and_its_flag_follows_its_number():
    section = targets.targets_section(_measured_cases(), {})
    assert set(section) == set(targets.TARGETS)
    assert all(e["met"] is True for e in section.values())
    missed = targets.targets_section(
        _measured_cases(speedup=9.0, warm=1.1, loop=0.96, export_c=3.9), {}
    )
    assert targets.summary(missed)["missed"] == [
        "whole_command_warm_cpu_s",
        "first_result_warm_speedup",
        "ratio_vs_motulator_export_c",
        "loop_steps_per_cpu_s_bodson_ramp_vs_baseline",
        "loop_steps_per_cpu_s_im_foc_speed_vs_baseline",
    ]
    assert missed["first_result_warm_speedup"]["value"] == 9.0


def test_unmeasured_targets_say_why():
    cases = _measured_cases()
    batch = cases["batch"]
    batch["lockstep_option"] = None
    del batch["lockstep"], batch["lockstep_vs_single_lane_per_cpu_s"]
    del cases["compile_free"], cases["loop_speed"]
    section = targets.targets_section(cases, {"loop_speed": "needs --baseline-src DIR"})
    simd = section["simd_batch_steps_per_s"]
    assert simd["met"] is None and "no lockstep (SIMD) batch" in simd["not measured"]
    assert "2,000,000 steps/s" in simd["not measured"]  # the single-lane figure, for context
    assert "--only compile_free" in section["compile_free_first_result_ratio"]["not measured"]
    loop = section["loop_steps_per_cpu_s_im_foc_speed_vs_baseline"]
    assert loop["not measured"] == "needs --baseline-src DIR"
    assert section["whole_command_warm_cpu_s"]["met"] is True
    summary = targets.summary(section)
    assert len(summary["not_measured"]) == 5 and summary["missed"] == []


def test_motulator_export_target_says_why_when_the_peer_is_missing():
    cases = _measured_cases()
    cases["motulator_averaged"]["motulator_export"] = {
        "available": False,
        "reason": "no Python that motulator-export supports (3.12, 3.13) was found",
    }
    entry = targets.targets_section(cases, {})["ratio_vs_motulator_export_c"]
    assert entry["met"] is None and "motulator-export supports" in entry["not measured"]
    del cases["motulator_averaged"]
    entry = targets.targets_section(cases, {})["ratio_vs_motulator_export_c"]
    assert "--only motulator_averaged" in entry["not measured"]


def test_lockstep_option_is_read_from_the_batch_signature():
    def single(base, variants, *, log=None):
        pass

    def simd(base, variants, *, lanes=None):
        pass

    assert targets.lockstep_option(single) is None
    assert targets.lockstep_option(simd) == "lanes"


def _bench_json(*args) -> tuple[int, dict | None, str]:
    from acdrive.cli import main

    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        code = main(["bench", "--json", *args])
    return code, (json.loads(out.getvalue()) if code == 0 else None), err.getvalue()


def test_bench_json_prints_every_target(monkeypatch):
    """The cheapest run (loop_speed without a baseline measures nothing): every target has its
    entry, each unmeasured with the reason."""
    monkeypatch.setattr(sys, "argv", ["acdrive", "bench"])
    code, r, _ = _bench_json("--no-peers", "--only", "loop_speed")
    assert code == 0
    assert set(r["targets"]) == set(targets.TARGETS)
    assert (
        "--baseline-src"
        in r["targets"]["loop_steps_per_cpu_s_bodson_ramp_vs_baseline"]["not measured"]
    )
    assert r["targets_met"] is False
    assert set(r["targets_summary"]["not_measured"]) == set(targets.TARGETS)


def test_baseline_src_must_hold_acdrive(tmp_path):
    code, _, err = _bench_json("--only", "loop_speed", "--baseline-src", str(tmp_path))
    assert code == 2 and "--baseline-src" in err


# --- the reference cache -----------------------------------------------------------------------
class Decay:
    """dx/dt = -a x + v, v held per segment: a reference model with the ``accuracy`` interface."""

    def __init__(self, a=2.0):
        self.a = a

    def rhs(self, t, y, v):
        return -self.a * y + v

    def jac(self, t, y, v):
        return -self.a * np.eye(5)

    def rhs_ld(self, t, y, v):
        return -np.longdouble(self.a) * y + v

    def inputs(self, seg, extended):
        v = seg["v"]
        if extended:
            return lambda j, y: (np.longdouble(v[j]),)
        return lambda j, y: (float(v[j]),)


def _decay_run(n=20, h=0.01, a=2.0, v=1.0):
    """The exact solution of Decay at the sampling instants (and the end), and its segments: four
    components from 0 and the fifth from 1 (every error figure has a non-zero peak)."""
    t = np.arange(n) * h
    decay = np.exp(-a * np.append(t, n * h))
    x = (v / a) * (1.0 - decay)
    w = v / a + (1.0 - v / a) * decay
    states = np.column_stack([x, x, x, x, w])
    seg = {"t": t, "counts": np.ones(n, dtype=np.int64), "dt": np.full(n, h), "v": np.full(n, v)}
    return states, seg


def test_cache_key_changes_with_every_input():
    base = {"x": np.arange(3.0), "settings": {"rtol": 1e-10, "substeps": 4}, "who": "peer 0.18"}
    k = refcache.key(**base)
    assert k == refcache.key(**base)  # a pure function of its inputs
    changed = [
        {**base, "x": np.array([0.0, 1.0, 2.000000001])},
        {**base, "x": np.arange(3, dtype=np.float32)},
        {**base, "x": np.arange(3.0).reshape(3, 1)},
        {**base, "settings": {"rtol": 1e-9, "substeps": 4}},
        {**base, "settings": {"rtol": 1e-10, "substeps": 2}},
        {**base, "who": "peer 0.19"},
    ]
    keys = [refcache.key(**c) for c in changed]
    assert k not in keys and len(set(keys)) == len(keys)
    a, b = refcache.model_identity(Decay(2.0)), refcache.model_identity(Decay(3.0))
    assert a["class"] == "Decay" and "def rhs_ld" in a["module_source"]
    assert refcache.key(m=a) != refcache.key(m=b)


def test_accuracy_reads_its_references_back_and_recomputes_a_corrupt_entry(tmp_path):
    """The references of a run come back from disk with the same errors; a changed input is a
    new entry; a corrupt entry is reported in one line, recomputed and rewritten."""
    from acdrive._bench.reference import accuracy

    states, seg = _decay_run()
    notes: list[str] = []
    first = accuracy(states, seg, 20, Decay(), extended_substeps=2, cache=tmp_path,
                     log=notes.append)  # fmt: skip
    assert first["cached_from_disk"] is False
    # the exact solution against the references: they agree to their own accuracy
    assert first["reference"]["current_rel_peak"] < 1e-8
    assert first["extended_reference"]["current_rel_peak"] < 1e-10
    assert first["extended_reference"]["speed_rel_peak"] < 1e-10
    (entry,) = tmp_path.glob("*.npz")
    assert entry.stem == first["reference_inputs_key"]
    again = accuracy(states, seg, 20, Decay(), extended_substeps=2, cache=tmp_path)
    assert again["cached_from_disk"] is True
    for k in ("reference", "extended_reference", "extended_resolution", "reference_resolution"):
        assert again[k] == first[k], k
    other = accuracy(states, {**seg, "v": seg["v"] * 1.001}, 20, Decay(), extended_substeps=2,
                     cache=tmp_path)  # fmt: skip
    assert other["cached_from_disk"] is False
    assert other["reference_inputs_key"] != first["reference_inputs_key"]
    entry.write_bytes(b"not a zip file")
    fixed = accuracy(states, seg, 20, Decay(), extended_substeps=2, cache=tmp_path,
                     log=notes.append)  # fmt: skip
    assert fixed["cached_from_disk"] is False
    assert len(notes) == 1 and "\n" not in notes[0] and "unreadable" in notes[0]
    assert fixed["reference"]["current_rel_peak"] == first["reference"]["current_rel_peak"]
    assert accuracy(states, seg, 20, Decay(), extended_substeps=2, cache=tmp_path)[
        "cached_from_disk"
    ]  # rewritten
    assert sorted(p.suffix for p in tmp_path.iterdir()) == [".npz", ".npz"]  # no temp files


def test_an_entry_under_another_name_is_not_trusted(tmp_path):
    refcache.store(tmp_path, "a" * 64, {"x": np.ones(2)})
    os.replace(tmp_path / f"{'a' * 64}.npz", tmp_path / f"{'b' * 64}.npz")
    notes: list[str] = []
    assert refcache.load(tmp_path, "b" * 64, notes.append) is None
    assert "stored key differs" in notes[0]
    calls = []
    got, hit = refcache.cached(tmp_path, "b" * 64, lambda: calls.append(1) or {"x": np.zeros(2)},
                               notes.append)  # fmt: skip
    assert hit is False and calls == [1] and np.array_equal(got["x"], np.zeros(2))
    got, hit = refcache.cached(tmp_path, "b" * 64, lambda: 1 / 0, notes.append)
    assert hit is True and np.array_equal(got["x"], np.zeros(2))


def test_without_a_cache_folder_nothing_is_written(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    got, hit = refcache.cached(None, "c" * 64, lambda: {"x": np.ones(1)}, print)
    assert hit is False and got["x"][0] == 1.0 and list(tmp_path.iterdir()) == []


def test_cache_dir_follows_xdg(monkeypatch, tmp_path):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert refcache.cache_dir() == tmp_path / "acdrive" / "bench-references"


# --- the child-process timer -------------------------------------------------------------------
@pytest.mark.skipif(not children.can_time_children(), reason="no os.wait4 on this platform")
def test_run_child_reads_output_and_reports_a_failure(tmp_path):
    got = children.run_child([sys.executable, "-c", "print('a'); print(12000)"], dict(os.environ))
    assert got["stdout_last"] == "12000"
    assert got["cpu_s"] == pytest.approx(got["user_s"] + got["system_s"])
    with pytest.raises(children.ChildFailed, match="exited with 3: broken"):
        children.run_child(
            [sys.executable, "-c", "import sys; sys.stderr.write('broken\\n'); sys.exit(3)"],
            dict(os.environ),
        )


def test_child_env_drops_the_suites_caches():
    base = {"PATH": "/bin", "NUMBA_CACHE_DIR": "/x", "ACDRIVE_NUMBA_CACHE_DIR": "/x",
            "XDG_CACHE_HOME": "/mine"}  # fmt: skip
    quiet = {"PATH": "/bin"}
    assert children.child_env(base, "/fresh") == {**quiet, "XDG_CACHE_HOME": "/fresh"}
    assert children.child_env(base, None) == quiet


# --- motulator, when its virtualenv is there ---------------------------------------------------
def _motulator_python() -> Path | None:
    from acdrive._bench.venvs import MOTULATOR, default_peers_dir

    python = default_peers_dir() / MOTULATOR.folder / "bin" / "python"
    return python if python.exists() else None


@pytest.mark.skipif(_motulator_python() is None, reason="motulator's virtualenv is absent")
def test_motulators_first_result_process_runs_the_matched_case():
    """The race's motulator process simulates the matched case: the control steps of 0.05 s at
    motulator's 125 us sampling (its loop runs to the first sample at or after the stop time)."""
    from acdrive._bench.motulator_im import T_S
    from acdrive._bench.venvs import clean_env

    peer = {"python": str(_motulator_python())}
    got = children.run_child(first_result.motulator_command(peer, 0.05), clean_env())
    steps = json.loads(got["stdout_last"])["steps"]
    assert abs(steps - round(0.05 / T_S)) <= 1


def test_the_table_prints_the_race_with_its_spread_and_every_target(monkeypatch):
    from acdrive._bench.suite import summarise, table

    fake = FakeProcesses(empty_s=[10.0, 12.0, 9.0, 15.0], motulator_s=[6.0, 6.0, 5.0, 6.0],
                         warm_s=[1.2, 1.0, 1.5])  # fmt: skip
    monkeypatch.setattr(first_result, "run_child", fake)
    race = first_result.run_race({"available": True, "python": "p"}, 3, 1.5, clock=_quiet_clock())
    report = {"cases": {"first_result": race}, "quick": False}
    report["host"] = {"load_average_at_start": 1, "load_average_at_end": 2, "cpus": 2}
    summarise(report)
    text = table(report)
    assert "acdrive empty cache: 2.00 (1.80-2.50) x motulator's time" in text
    assert "first_result_warm_speedup: 5 x (at least 10): NO" in text
    for name in targets.TARGETS:
        assert f"  {name}: " in text


def test_batch_speed_alternates_single_lane_and_lockstep(monkeypatch):
    """With a lockstep option the two batches alternate per round (after a warm-up of each on
    2 variants), the option is passed False / True, and each round gives lockstep over
    single-lane in steps per CPU second."""
    import acdrive.batch
    from acdrive.batch import BatchResult

    t = {"cpu": 0.0, "wall": 0.0}
    calls = []

    def fake_batch(base, variants, *, lanes=False):
        calls.append((len(variants), lanes))
        cost = len(variants) * (0.001 if lanes else 0.004)  # 4x cheaper per step in lockstep
        t["cpu"] += cost
        t["wall"] += cost / 2  # both cores busy
        rows = [{"status": "ok"} for _ in variants]
        return BatchResult(rows=rows, steps=1000 * len(variants))

    monkeypatch.setattr(acdrive.batch, "simulate_batch", fake_batch)
    clock = Clock(cpu=lambda: t["cpu"], wall=lambda: t["wall"], busy=lambda: None,
                  load=lambda: None, cores=2)  # fmt: skip
    r = targets.batch_speed(10, 2, clock=clock)
    assert calls == [(2, False), (2, True)] + [(10, False), (10, True)] * 2
    assert r["lockstep_option"] == "lanes"
    assert r["single_lane"]["steps_per_cpu_s"]["median"] == pytest.approx(250_000.0)
    assert r["lockstep"]["steps_per_s"]["median"] == pytest.approx(2_000_000.0)
    assert r["lockstep_vs_single_lane_per_cpu_s"]["per_round"] == pytest.approx([4.0, 4.0])
    section = targets.targets_section({"batch": r}, {})
    assert section["simd_batch_vs_single_lane"]["met"] is True  # 4 >= 3
    assert section["simd_batch_steps_per_s"]["met"] is False  # 2 M < 6 M


@pytest.mark.slow
def test_the_compile_free_topology_is_the_same_drive():
    """The compile-free target's new topology (the IFOC reading the shaft angle instead of the
    ideal encoder's sample of it) runs the same drive: the same speed and current over the speed
    step, bit for bit (the ideal encoder passes the angle on unchanged)."""
    from acdrive._bench.motulator_im import SUBSTEPS, T_S, log_ports, matched_acdrive_system

    runs = []
    for encoder in (True, False):
        system, parts = matched_acdrive_system("averaged", encoder=encoder)
        assert ("encoder" in parts) is encoder
        raw = system.compile().run(0.25, T_S, substeps=SUBSTEPS, log=log_ports(parts))
        runs.append((raw.signal(parts["shaft"].out.w), raw.signal(parts["im"].out.i_s)))
    (w_a, i_a), (w_b, i_b) = runs
    assert np.max(w_a) > 10.0  # the speed step at 0.2 s is inside the run
    assert np.array_equal(w_a, w_b) and np.array_equal(i_a, i_b)


def _export_python() -> Path | None:
    from acdrive._bench.venvs import MOTULATOR_EXPORT, default_peers_dir

    python = default_peers_dir() / MOTULATOR_EXPORT.folder / "bin" / "python"
    return python if python.exists() else None


@pytest.mark.skipif(
    _motulator_python() is None or _export_python() is None,
    reason="motulator's or motulator-export's virtualenv is absent",
)
def test_motulator_exports_recorded_states_are_motulators(tmp_path):
    """The peer records motulator-export's state at every sampling instant: run with the case's
    Python signals it is motulator's own run of the case (motulator-export ports the same
    control and solver), to rounding, at every sample of 0.25 s (past the speed step); the C
    loop's staircase load starts only at 0.75 s, so before it the two loops agree as well."""
    from acdrive._bench.motulator_im import export_states, motulator_states, state_difference
    from acdrive._bench.venvs import PeerProcess

    with PeerProcess(str(_motulator_python()), "motulator_im.py", cwd=str(tmp_path)) as p:
        p.ask("record", converter="averaged", seconds=0.25, out=str(tmp_path / "m.npz"))
    with PeerProcess(str(_export_python()), "motulator_export_im.py", cwd=str(tmp_path)) as p:
        for loop in ("callbacks", "c"):
            p.ask("record", converter="averaged", seconds=0.25, loop=loop,
                  out=str(tmp_path / f"{loop}.npz"))  # fmt: skip
    m_states, _ = motulator_states(dict(np.load(tmp_path / "m.npz")))
    for loop in ("callbacks", "c"):
        x_states = export_states(dict(np.load(tmp_path / f"{loop}.npz")))
        d = state_difference(x_states, m_states)
        assert d["compared_samples"] >= round(0.25 / 125e-6)
        assert d["speed_max_rel_to_peak"] < 1e-12 and d["current_max_rel_to_peak"] < 1e-12
