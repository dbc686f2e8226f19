"""The ICAD analysis in the benchmark suite: the whole ``acdrive reproduce icad`` command (an
empty-cache run, then warm runs on that cache) and the point path, and their verdicts computed
from the numbers. Child processes are faked here; speed is judged by the suite, never here."""

from __future__ import annotations

import os

from acdrive._bench import reproduce_icad
from acdrive._bench.children import ChildFailed
from acdrive._bench.suite import TARGETS, summarise


def fake_runs(monkeypatch, cpu_s: list[float]) -> list[dict]:
    """Replace the child runner: each call takes the next CPU time and records the command,
    its cache folder and its output folder (which must exist while it runs)."""
    calls: list[dict] = []

    def run_child(cmd, env, cwd=None):
        out = cmd[cmd.index("--out") + 1]
        assert os.path.isdir(out) and not os.listdir(out)
        calls.append({"cmd": cmd, "cache": env["XDG_CACHE_HOME"], "out": out, "cwd": cwd,
                      "cache_files": sorted(os.listdir(env["XDG_CACHE_HOME"]))})  # fmt: skip
        cache = os.path.join(env["XDG_CACHE_HOME"], f"run{len(calls)}")
        open(cache, "w").close()  # what a run leaves in its cache folder
        t = cpu_s[len(calls) - 1]
        return {"cpu_s": t, "user_s": t, "system_s": 0.0, "wall_s": t / 2}

    monkeypatch.setattr(reproduce_icad, "run_child", run_child)
    return calls


def test_an_empty_cache_run_then_warm_runs_on_that_cache(monkeypatch):
    calls = fake_runs(monkeypatch, [40.0, 15.0, 13.0, 17.0])
    got = reproduce_icad.reproduce_icad(3)
    assert len(calls) == 4
    assert all(c["cmd"][-4:-1] == ["reproduce", "icad", "--out"] for c in calls)
    assert calls[0]["cache_files"] == []  # the first run's cache is empty
    assert len({c["cache"] for c in calls}) == 1  # the warm runs use the cache it filled
    assert calls[1]["cache_files"] == ["run1"]
    assert len({c["out"] for c in calls}) == 4  # a fresh output folder each run
    assert got["empty_cache"]["cpu_s"] == 40.0
    assert got["warm_cpu_s"] == {"min": 13.0, "median": 15.0, "max": 17.0, "n": 3}
    # everything the measurement made is removed
    assert not os.path.exists(calls[0]["cwd"])


def test_a_failing_reproduction_is_reported_not_measured(monkeypatch):
    def run_child(cmd, env, cwd=None):
        raise ChildFailed("acdrive reproduce icad exited with 70: boom")

    monkeypatch.setattr(reproduce_icad, "run_child", run_child)
    got = reproduce_icad.reproduce_icad(2)
    assert got == {"not_measured": "acdrive reproduce icad exited with 70: boom"}


def _report(**cases) -> dict:
    report = {"cases": cases}
    summarise(report)
    return report


def test_the_icad_verdicts_follow_the_numbers():
    point_limit = TARGETS["icad_point_cpu_us_max"]
    command_limit = TARGETS["reproduce_icad_cpu_s_max"]
    assert command_limit == 20.0  # issue 36: `acdrive reproduce icad` in at most 20 CPU-s

    def cases(point_us, warm_s):
        return {
            "icad": {"icad_ms": 15.0, "points": {"cpu_us_per_point": {"median": point_us}}},
            "reproduce_icad": {"warm_cpu_s": {"median": warm_s}, "empty_cache": {"cpu_s": 30.0}},
        }

    point_key = f"icad_point_at_most_{point_limit:g}_cpu_us"
    command_key = f"reproduce_icad_at_most_{command_limit:g}_cpu_s"
    slow = _report(**cases(22_000.0, 131.0))  # a parallel region started per point
    assert slow["icad_point_cpu_us"] == 22_000.0 and slow["reproduce_icad_cpu_s"] == 131.0
    assert slow["target_checks"][point_key] is False
    assert slow["target_checks"][command_key] is False
    assert slow["targets_met"] is False
    at_bounds = _report(**cases(point_limit, command_limit))["target_checks"]
    assert at_bounds[point_key] is True and at_bounds[command_key] is True
    unmeasured = _report(reproduce_icad={"not_measured": "no os.wait4"})
    assert unmeasured["reproduce_icad_cpu_s"] is None
    assert unmeasured["target_checks"][command_key] is None
    assert command_key in unmeasured["targets_unmeasured"]
