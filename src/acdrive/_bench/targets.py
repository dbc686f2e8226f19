"""Issue 21's speed targets as measured numbers: ``acdrive bench --json``'s ``targets`` section.

Every target has one entry (``target_entry``): its ``value`` as measured in this run, the
``target``, the ``unit``, how the two compare (``at most`` / ``at least``) and ``met``, computed
from them (``is_met``); or ``"not measured"`` with the reason (a case not run, a feature this
branch does not have yet, a missing peer or baseline). ``TARGETS`` lists them; each is read
from the number one small measuring function produced:

* ``whole_command``: ``acdrive run bodson-ramp`` as a whole process (``_bench.children``) with an
  empty cache (its wall and CPU time: the first run after install) and then warm, with and
  without figures, interleaved, in the child's CPU time;
* ``compile_free_first_result``: a topology never compiled on this cache, built from part kinds
  that were (``motulator_im.matched_acdrive_system(encoder=False)`` after the matched case with
  its encoder): its first result's CPU time over the same topology's warm one;
* ``batch_speed``: ``acdrive.batch.simulate_batch`` over N ``bodson-ramp`` variants, steps per
  second and per CPU second, single-lane and, where the batch has a lockstep (SIMD) option
  (``lockstep_option``), across lanes;
* ``first_result``: the race against motulator (``_bench.first_result``);
* ``ratio_vs_motulator_export_c``: acdrive over motulator-export's pure C loop on the matched
  averaged cage-IM case (``_bench.motulator_im``, issue 39);
* ``loop_speed``: the specialised loop's steps per CPU second against a baseline source tree
  given with ``--baseline-src`` (``_bench.loop_speed``).

The speed targets are judged here, never in a timed test.
"""

from __future__ import annotations

import inspect
import os
import shutil
import sys
import tempfile
from pathlib import Path

from acdrive._bench.children import ChildFailed, can_time_children, child_env, run_child
from acdrive._bench.windows import Clock, spread

#: the scenario of the whole-command and batch targets
SCENARIO = "bodson-ramp"

#: name -> (what, target, unit, comparison): the issue's numbers, and where it gives none (the
#: compile-free ratio, the 3 % of the loop) the bound chosen in docs/speed.md, "Speed targets"
TARGETS = {
    "whole_command_warm_cpu_s": (
        f"warm `acdrive run {SCENARIO}` (data, summary, figures), whole process",
        1.0, "CPU-s", "at most",
    ),
    "whole_command_warm_no_figures_cpu_s": (
        f"warm `acdrive run {SCENARIO} --no-figures`, whole process",
        0.6, "CPU-s", "at most",
    ),
    "first_run_empty_cache_s": (
        f"first `acdrive run {SCENARIO}` after install (empty cache), wall time (idle machine)",
        6.0, "s", "at most",
    ),
    "compile_free_first_result_ratio": (
        ("first result of a new topology built from cached part kinds, whole-process CPU time "
         "over the same topology's warm first result (no per-topology compile)"),
        1.5, "x", "at most",
    ),
    "simd_batch_steps_per_s": (
        (f"1,000 `{SCENARIO}` variants in the lockstep (SIMD) batch, control steps per wall "
         "second on the 2-core machine (idle)"),
        6e6, "steps/s", "at least",
    ),
    "simd_batch_vs_single_lane": (
        "lockstep batch over the single-lane batch, control steps per CPU second, same run",
        3.0, "x", "at least",
    ),
    "first_result_empty_cache_time_ratio": (
        ("first-result race, acdrive with an empty cache: its whole-process CPU time over "
         "motulator 0.18's (median over interleaved rounds)"),
        1.0, "x", "at most",
    ),
    "first_result_warm_speedup": (
        ("first-result race, acdrive with a warm cache: motulator 0.18's whole-process CPU "
         "time over acdrive's (median over interleaved rounds)"),
        10.0, "x", "at least",
    ),
    "loop_steps_per_cpu_s_bodson_ramp_vs_baseline": (
        ("specialised loop, `bodson-ramp`: steps per CPU second over the baseline tree's, "
         "interleaved in the same run"),
        0.97, "x", "at least",
    ),
    "ratio_vs_motulator_export_c": (
        ("matched cage-IM case (averaged converter): acdrive's control steps per CPU second over "
         "motulator-export 0.11's pure C loop, interleaved (median over the rounds)"),
        10.0, "x", "at least",
    ),
    "loop_steps_per_cpu_s_im_foc_speed_vs_baseline": (
        ("specialised loop, `im-foc-speed`: steps per CPU second over the baseline tree's, "
         "interleaved in the same run"),
        0.97, "x", "at least",
    ),
}  # fmt: skip


def is_met(value: float, target: float, comparison: str) -> bool:
    """``value`` against ``target``: ``at most`` is value <= target, ``at least`` value >= it."""
    if comparison == "at most":
        return bool(value <= target)
    if comparison == "at least":
        return bool(value >= target)
    raise ValueError(f"comparison must be 'at most' or 'at least', got {comparison!r}")


def target_entry(name: str, value=None, reason: str | None = None, **detail) -> dict:
    """The entry of target ``name``: value, target, unit, comparison and the computed ``met``;
    with no value, ``"not measured"`` gives ``reason`` and ``met`` is None."""
    what, target, unit, comparison = TARGETS[name]
    entry = {"what": what, "target": target, "unit": unit, "comparison": comparison}
    if value is None:
        entry.update(value=None, met=None)
        entry["not measured"] = reason or "not measured in this run"
    else:
        entry.update(value=value, met=is_met(value, target, comparison))
    entry.update(detail)
    return entry


# --- the whole command -------------------------------------------------------------------------
def acdrive_command() -> list[str]:
    """The installed ``acdrive`` command beside this interpreter, else ``python -c`` its main."""
    script = Path(sys.executable).parent / "acdrive"
    if script.exists():
        return [str(script)]
    return [sys.executable, "-c", "import sys; from acdrive.cli import main; sys.exit(main())"]


def run_command_once(args: list[str], cache_home: str, work: str) -> dict:
    """One whole ``acdrive run`` process writing into a fresh folder under ``work`` (deleted
    after): ``run_child``'s answer."""
    out = tempfile.mkdtemp(prefix="out-", dir=work)
    try:
        cmd = [*acdrive_command(), "run", *args, "--out", out]
        return run_child(cmd, child_env(dict(os.environ), cache_home), cwd=work)
    finally:
        shutil.rmtree(out, ignore_errors=True)  # made just above for this run


def whole_command(rounds: int, log=None, scenario: str = SCENARIO) -> dict:
    """``acdrive run <scenario>`` as whole processes: first with an empty cache (a fresh
    ``XDG_CACHE_HOME``: wall and CPU time), then ``rounds`` rounds of warm runs alternating with
    and without figures on that cache (CPU time, min / median / max, load average)."""
    say = log or (lambda _m: None)
    if not can_time_children():
        return {"not_measured": "this platform has no os.wait4 (a child's own CPU time)"}
    work = tempfile.mkdtemp(prefix="acdrive_command_")
    try:
        home = os.path.join(work, "cache")
        os.mkdir(home)
        say(f"whole command: acdrive run {scenario} with an empty cache")
        load0 = _load()
        first = run_command_once([scenario], home, work)
        out = {
            "scenario": scenario,
            "empty_cache": {**first, "load_average_1min": [load0, _load()]},
        }
        runs: dict[str, list] = {"figures": [], "no_figures": []}
        loads = []
        for r in range(rounds):
            for kind, extra in (("figures", []), ("no_figures", ["--no-figures"])):
                say(f"whole command, round {r + 1}/{rounds}: warm, {kind.replace('_', ' ')}")
                runs[kind].append(run_command_once([scenario, *extra], home, work))
                loads.append(_load())
    except ChildFailed as exc:
        return {"not_measured": str(exc)}
    finally:
        shutil.rmtree(work, ignore_errors=True)  # this measurement's own folder (mkdtemp)
    for kind, got in runs.items():
        out[f"warm_{kind}"] = {
            "cpu_s": spread(g["cpu_s"] for g in got),
            "wall_s": spread(g["wall_s"] for g in got),
        }
    out["warm_load_average_1min"] = spread(loads)
    out["method"] = (
        "whole processes of the installed command, each timed by its own CPU time (os.wait4), "
        "output to a fresh folder; the empty-cache run first (its cache then serves the warm "
        f"runs), then {rounds} rounds alternating warm with and without figures"
    )
    # with PYTHONDONTWRITEBYTECODE set, an editable install compiles every imported module of
    # acdrive from source in every process (about 0.1 CPU-s of this command); a wheel's modules
    # are compiled by pip at install, and an editable install's on first import otherwise
    out["python_writes_bytecode"] = not os.environ.get("PYTHONDONTWRITEBYTECODE")
    return out


def _load():
    try:
        return round(os.getloadavg()[0], 2)
    except (AttributeError, OSError):
        return None


# --- the compile-free first result -------------------------------------------------------------
#: a topology of the matched case's part kinds, without the encoder; argv[1]: "1" with it
TOPOLOGY_CHILD = """\
import sys
from acdrive._bench.motulator_im import SUBSTEPS, T_S, log_ports, matched_acdrive_system
system, parts = matched_acdrive_system("averaged", encoder=sys.argv[1] == "1")
result = system.compile().run(float(sys.argv[2]), T_S, substeps=SUBSTEPS, log=log_ports(parts))
print(result.steps)
"""


def compile_free_first_result(model_time_s: float, rounds: int = 3, log=None) -> dict:
    """The matched case on a fresh cache (its part kinds now cached); then, ``rounds`` times, a
    copy of that cache in which the same kinds in another topology (the IFOC reading the shaft
    angle, no encoder) were never run: its first result (``new``) and, right after, its first
    result with its own topology cached (``warm``). The ratio new / warm is taken per round
    (the two runs of a round are adjacent, A B A B); the target reads its median."""
    say = log or (lambda _m: None)
    if not can_time_children():
        return {"not_measured": "this platform has no os.wait4 (a child's own CPU time)"}
    work = tempfile.mkdtemp(prefix="acdrive_topology_")
    try:

        def run(encoder: bool, cache: str) -> dict:
            cmd = [sys.executable, "-c", TOPOLOGY_CHILD, "1" if encoder else "0",
                   repr(model_time_s)]  # fmt: skip
            return run_child(cmd, child_env(dict(os.environ), cache), cwd=work)

        kinds_cache = os.path.join(work, "kinds")
        say("compile-free first result: the matched case on a fresh cache (part kinds)")
        kinds = run(True, kinds_cache)
        new, warm = [], []
        for r in range(rounds):
            say(
                f"compile-free first result, round {r + 1}/{rounds}: a new topology, first and warm"
            )
            cache = os.path.join(work, f"round{r}")
            shutil.copytree(kinds_cache, cache)
            new.append(run(False, cache)["cpu_s"])
            warm.append(run(False, cache)["cpu_s"])
    except ChildFailed as exc:
        return {"not_measured": str(exc)}
    finally:
        shutil.rmtree(work, ignore_errors=True)  # this measurement's own folder (mkdtemp)
    ratios = [a / b for a, b in zip(new, warm, strict=True)]
    return {
        "model_time_s": model_time_s,
        "rounds": rounds,
        "kinds_cached_by_cpu_s": kinds["cpu_s"],
        "new_topology_cpu_s": spread(new),
        "warm_cpu_s": spread(warm),
        "ratio": {"per_round": ratios, **spread(ratios)},
        "per_topology_cost_cpu_s": spread(a - b for a, b in zip(new, warm, strict=True)),
    }


# --- the batch ---------------------------------------------------------------------------------
#: names a lockstep (SIMD) switch of ``simulate_batch`` may have, when the batch has one
LOCKSTEP_NAMES = ("lockstep", "lanes", "simd")


def lockstep_option(simulate_batch) -> str | None:
    """The name of ``simulate_batch``'s lockstep (SIMD) parameter, None if it has none."""
    params = inspect.signature(simulate_batch).parameters
    return next((n for n in LOCKSTEP_NAMES if n in params), None)


def batch_variants(n: int, seed: int = 1) -> list[dict]:
    """``n`` variants of ``bodson-ramp``: load torque and speed bandwidth drawn with a seed."""
    import numpy as np

    rng = np.random.default_rng(seed)
    return [
        {"motor[0].load_torque": float(rng.uniform(0.0, 0.1)),
         "motor[0].controller.speed_bandwidth": float(rng.uniform(150.0, 400.0))}
        for _ in range(n)
    ]  # fmt: skip


def time_batch(simulate_batch, variants, clock: Clock, **options) -> dict:
    """One batch run: control steps, wall and CPU time (all threads of this process and the
    workers it forked to prepare the variants), both rates."""
    c0, w0 = clock.cpu() + clock.children(), clock.wall()
    result = simulate_batch(SCENARIO, variants, **options)
    cpu, wall = clock.cpu() + clock.children() - c0, clock.wall() - w0
    return {
        "steps": result.steps,
        "wall_s": wall,
        "cpu_s": cpu,
        "steps_per_s": result.steps / wall if wall > 0.0 else None,
        "steps_per_cpu_s": result.steps / cpu if cpu > 0.0 else None,
        "all_ok": all(r.get("status") == "ok" for r in result.rows),
    }


def batch_speed(n_variants: int, rounds: int, log=None, clock: Clock | None = None) -> dict:
    """The single-lane batch and, if the batch has a lockstep option, the lockstep one, each
    warmed up on 2 variants, then alternated for ``rounds`` rounds over ``n_variants``; the
    lockstep one's steps per CPU second over the single-lane one's in each round."""
    from acdrive.batch import simulate_batch

    clock = clock or Clock()
    say = log or (lambda _m: None)
    option = lockstep_option(simulate_batch)
    modes = {"single_lane": {}}
    if option is not None:
        modes = {"single_lane": {option: False}, "lockstep": {option: True}}
    vs = batch_variants(n_variants)
    for name, opts in modes.items():
        say(f"batch: warm-up ({name})")
        simulate_batch(SCENARIO, vs[:2], **opts)
    got: dict[str, list] = {name: [] for name in modes}
    for r in range(rounds):
        for name, opts in modes.items():
            say(f"batch, round {r + 1}/{rounds}: {n_variants} variants, {name}")
            got[name].append(time_batch(simulate_batch, vs, clock, **opts))
    out = {"scenario": SCENARIO, "variants": n_variants, "rounds": rounds, "cpus": os.cpu_count()}
    out["lockstep_option"] = option
    for name, runs in got.items():
        out[name] = {
            "steps_per_s": spread(g["steps_per_s"] for g in runs),
            "steps_per_cpu_s": spread(g["steps_per_cpu_s"] for g in runs),
            "all_ok": all(g["all_ok"] for g in runs),
        }
    if option is not None:
        ratios = [
            lock["steps_per_cpu_s"] / single["steps_per_cpu_s"]
            for lock, single in zip(got["lockstep"], got["single_lane"], strict=True)
            if lock["steps_per_cpu_s"] and single["steps_per_cpu_s"]
        ]
        out["lockstep_vs_single_lane_per_cpu_s"] = {"per_round": ratios, **spread(ratios)}
    return out


# --- the table ---------------------------------------------------------------------------------
def targets_section(cases: dict, not_run: dict) -> dict:
    """One entry per target (``TARGETS``) from the measured cases: ``cases`` maps a case name
    (``command``, ``compile_free``, ``batch``, ``first_result``, ``loop_speed``) to its result;
    ``not_run`` maps a case name that was not run to the reason."""

    def missing(case: str) -> str | None:
        if case in not_run:
            return not_run[case]
        if case not in cases:
            return f"case {case} not run (acdrive bench --only {case})"
        return cases[case].get("not_measured")

    out = {}
    why = missing("command")
    c = cases.get("command", {})
    out["whole_command_warm_cpu_s"] = target_entry(
        "whole_command_warm_cpu_s",
        None if why else c["warm_figures"]["cpu_s"]["median"],
        why,
        **({} if why else {"spread": c["warm_figures"]["cpu_s"]}),
    )
    out["whole_command_warm_no_figures_cpu_s"] = target_entry(
        "whole_command_warm_no_figures_cpu_s",
        None if why else c["warm_no_figures"]["cpu_s"]["median"],
        why,
        **({} if why else {"spread": c["warm_no_figures"]["cpu_s"]}),
    )
    first = c.get("empty_cache", {})
    out["first_run_empty_cache_s"] = target_entry(
        "first_run_empty_cache_s",
        None if why else first["wall_s"],
        why,
        **({} if why else {"cpu_s": first["cpu_s"], "load_average_1min": first["load_average_1min"]}),
    )  # fmt: skip
    why = missing("compile_free")
    c = cases.get("compile_free", {})
    out["compile_free_first_result_ratio"] = target_entry(
        "compile_free_first_result_ratio",
        None if why else c["ratio"]["median"],
        why,
        **(
            {}
            if why
            else {"spread": c["ratio"], **{k: c[k] for k in ("new_topology_cpu_s", "warm_cpu_s")}}
        ),
    )
    why = missing("batch")
    c = cases.get("batch", {})
    if not why and c.get("lockstep_option") is None:
        why = (
            "no lockstep (SIMD) batch on this branch: simulate_batch has no "
            f"{' / '.join(LOCKSTEP_NAMES)} option; the single-lane batch ran at "
            f"{c['single_lane']['steps_per_s']['median']:,.0f} steps/s "
            f"({c['single_lane']['steps_per_cpu_s']['median']:,.0f} per CPU-s)"
        )
    out["simd_batch_steps_per_s"] = target_entry(
        "simd_batch_steps_per_s",
        None if why else c["lockstep"]["steps_per_s"]["median"],
        why,
        **({} if why else {"variants": c["variants"], "spread": c["lockstep"]["steps_per_s"]}),
    )
    out["simd_batch_vs_single_lane"] = target_entry(
        "simd_batch_vs_single_lane",
        None if why else c["lockstep_vs_single_lane_per_cpu_s"]["median"],
        why,
    )
    why = missing("first_result")
    c = cases.get("first_result", {})
    for name, group, key in (
        ("first_result_empty_cache_time_ratio", "time_ratio", "empty_cache"),
        ("first_result_warm_speedup", "speedup", "warm_cache"),
    ):
        r = c.get(group, {}).get(key)
        reason = why or (None if r else c.get("motulator", {}).get("reason", "no motulator"))
        out[name] = target_entry(
            name,
            None if reason else r["median"],
            reason,
            **({} if reason else {"spread": {k: r[k] for k in ("min", "median", "max", "n")}}),
        )
    why = missing("motulator_averaged")
    mex = cases.get("motulator_averaged", {}).get("motulator_export", {})
    side = mex.get("sides", {}).get("motulator_export_c")
    reason = why or (None if side else mex.get("reason", "motulator-export not measured"))
    out["ratio_vs_motulator_export_c"] = target_entry(
        "ratio_vs_motulator_export_c",
        None if reason else side["acdrive_ratio"],
        reason,
        **({} if reason else {"spread": side["acdrive_ratio_spread"]}),
    )
    why = missing("loop_speed")
    c = cases.get("loop_speed", {})
    for name, scenario in (
        ("loop_steps_per_cpu_s_bodson_ramp_vs_baseline", "bodson-ramp"),
        ("loop_steps_per_cpu_s_im_foc_speed_vs_baseline", "im-foc-speed"),
    ):
        s = c.get("scenarios", {}).get(scenario)
        reason = why or (None if s else f"{scenario} not measured")
        out[name] = target_entry(
            name,
            None if reason else s["loop"]["ratio_after_before_median"],
            reason,
            **({} if reason else {"steps_per_cpu_s": s["loop"]}),
        )
    return out


def summary(section: dict) -> dict:
    """How many targets were met, missed and not measured, and their names."""
    met = [k for k, v in section.items() if v["met"] is True]
    missed = [k for k, v in section.items() if v["met"] is False]
    unmeasured = [k for k, v in section.items() if v["met"] is None]
    return {"met": met, "missed": missed, "not_measured": unmeasured}
