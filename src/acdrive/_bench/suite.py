"""The benchmark suite behind ``acdrive bench``: every matched case in one run, one JSON document.

Cases (``CASES``; ``--only`` picks some):

* ``motulator_averaged``: the 2.2 kW cage-IM speed drive against motulator 0.18 with an averaged
  converter (``_bench.motulator_im``) -> ``ratio_vs_motulator``;
* ``motulator_pwm``: the same drive with switching PWM -> ``ratio_vs_motulator_pwm``;
* ``gem_dfim``: the open-loop DFIM against gym-electric-motor 3.0.3 (``_bench.gem_dfim``) ->
  ``ratio_vs_gem``;
* ``icad``: the full ICAD over 100 speeds x 2,000 frequencies (``_bench.icad``) -> ``icad_ms``.

Each ratio is acdrive's control steps per second over the peer's, both measured in this run on
this machine, the peer in its own virtualenv (``_bench.venvs``); each simulator's error is taken
against references of the same equations (``_bench.reference``), so that speed is never bought
with error. The verdicts (``target_checks``) are computed from those numbers: ``None`` where a
number is missing (a peer that could not be installed, ``--no-reference``), and ``targets_met``
is true only if every check is true.
"""

from __future__ import annotations

import os
import platform
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from acdrive._bench.common import load_average, package_version

CASES = ("motulator_averaged", "motulator_pwm", "gem_dfim", "icad")

#: the issue's targets (the pwm one is the matched pwm case's earlier target)
TARGETS = {
    "ratio_vs_motulator_min": 1000.0,
    "ratio_vs_motulator_pwm_min": 300.0,
    "ratio_vs_gem_min": 300.0,
    "icad_ms_max": 20.0,
    "errors": "acdrive's current and speed errors no larger than the peer's in every matched "
    "case, against the tightest reference computed for both (the extended-precision one when "
    "present, else Radau rtol 1e-10 within its own resolution)",
}

#: model times and repeats: the full run and ``--quick`` (short model times, for a smoke test)
FULL = {
    "im_s": 1.5,
    "gem_s": 1.0,
    "repeats": 5,
    "motulator_repeats": 2,
    "gem_repeats": 3,
    "icad_repeat": 7,
    "extended_substeps": 4,
}
QUICK = {
    "im_s": 0.05,
    "gem_s": 0.05,
    "repeats": 2,
    "motulator_repeats": 1,
    "gem_repeats": 1,
    "icad_repeat": 3,
    "extended_substeps": 4,
}


@dataclass
class Options:
    """What to run: ``quick`` (short model times), ``peers`` (make/use the peers' venvs),
    ``reference`` (accuracy references), ``only`` (case names), ``peers_dir`` (venv cache)."""

    quick: bool = False
    peers: bool = True
    reference: bool = True
    only: tuple[str, ...] = CASES
    peers_dir: Path | None = None
    log: object = field(default=None, repr=False)


def _say(options: Options):
    start = time.perf_counter()

    def say(message: str) -> None:
        if options.log is not None:
            options.log(f"[{time.perf_counter() - start:7.1f} s] {message}")

    return say


def _peer(spec, options: Options, say) -> dict:
    from acdrive._bench.venvs import default_peers_dir, ensure_venv

    if not options.peers:
        return {"available": False, "reason": "--no-peers"}
    return ensure_venv(spec, options.peers_dir or default_peers_dir(), say)


def run_suite(options: Options) -> dict:
    """Run the selected cases and return the report (JSON-ready but for numpy scalars)."""
    from acdrive._bench import venvs

    say = _say(options)
    settings = QUICK if options.quick else FULL
    report: dict = {
        "benchmark": "acdrive bench",
        "date": time.strftime("%Y-%m-%d %H:%M:%S"),
        "command": " ".join(["acdrive", *sys.argv[1:]]) if sys.argv else "acdrive bench",
        "quick": options.quick,
        "settings": settings,
        "host": {
            "cpus": os.cpu_count(),
            "machine": platform.machine(),
            "load_average_at_start": load_average(),
        },
        "versions": {
            "python": platform.python_version(),
            "acdrive": package_version("acdrive"),
            "numba": package_version("numba"),
            "numpy": package_version("numpy"),
            "scipy": package_version("scipy"),
        },
        "peers_dir": str(options.peers_dir or venvs.default_peers_dir()),
        "peers": {},
        "cases": {},
    }
    only = [c for c in CASES if c in options.only]
    ref = options.reference
    if any(c.startswith("motulator") for c in only):
        report["peers"]["motulator"] = _peer(venvs.MOTULATOR, options, say)
    if "gem_dfim" in only:
        report["peers"]["gym-electric-motor"] = _peer(venvs.GEM, options, say)
    for name in only:
        say(f"case {name}")
        report["host"][f"load_average_before_{name}"] = load_average()
        if name.startswith("motulator"):
            from acdrive._bench.motulator_im import run_case

            report["cases"][name] = run_case(
                name.split("_", 1)[1],
                report["peers"]["motulator"],
                settings["repeats"],
                settings["im_s"],
                ref,
                settings["extended_substeps"],
                settings["motulator_repeats"],
                say,
            )
        elif name == "gem_dfim":
            from acdrive._bench.gem_dfim import run_case

            report["cases"][name] = run_case(
                report["peers"]["gym-electric-motor"],
                settings["repeats"],
                settings["gem_s"],
                ref,
                settings["extended_substeps"],
                settings["gem_repeats"],
                say,
            )
        elif name == "icad":
            from acdrive._bench.icad import run_icad

            report["cases"][name] = run_icad(settings["icad_repeat"])
    report["host"]["load_average_at_end"] = load_average()
    summarise(report)
    say("done")
    return report


def _peer_of(case: str) -> str:
    return "gym-electric-motor" if case == "gem_dfim" else "motulator"


def summarise(report: dict) -> None:
    """The headline keys and the verdicts, computed from the cases' numbers."""
    cases = report["cases"]
    ratio_keys = {
        "motulator_averaged": "ratio_vs_motulator",
        "motulator_pwm": "ratio_vs_motulator_pwm",
        "gem_dfim": "ratio_vs_gem",
    }
    report["acdrive_steps_per_s"] = {}
    report["peer_steps_per_s"] = {}
    report["errors"] = {}
    for case, key in ratio_keys.items():
        c = cases.get(case)
        report[key] = c.get("ratio") if c else None
        if not c:
            continue
        report["acdrive_steps_per_s"][case] = c["acdrive"]["steps_per_s"]
        peer = c.get(_peer_of(case), {})
        report["peer_steps_per_s"][case] = peer.get("steps_per_s")
        if "error_summary" in c["acdrive"]:
            report["errors"][case] = {
                "acdrive": c["acdrive"]["error_summary"],
                _peer_of(case): peer.get("error_summary"),
                "verdicts": c.get("error_verdicts"),
            }
    if "gem_dfim" in cases:
        report["ratio_vs_gem_env_step"] = cases["gem_dfim"].get("ratio_env_step")
    report["icad_ms"] = cases["icad"]["icad_ms"] if "icad" in cases else None
    report["targets"] = TARGETS
    report["target_checks"] = target_checks(report)
    checks = report["target_checks"]
    report["targets_met"] = bool(checks) and all(v is True for v in checks.values())
    report["targets_unmeasured"] = [k for k, v in checks.items() if v is None]


def _at_least(value, bound):
    return None if value is None else bool(value >= bound)


def target_checks(report: dict) -> dict:
    """One boolean per target of the cases run (None where its number is missing)."""
    cases = report["cases"]
    out = {}
    for case, key, bound in (
        ("motulator_averaged", "ratio_vs_motulator", "ratio_vs_motulator_min"),
        ("motulator_pwm", "ratio_vs_motulator_pwm", "ratio_vs_motulator_pwm_min"),
        ("gem_dfim", "ratio_vs_gem", "ratio_vs_gem_min"),
    ):
        if case not in cases:
            continue
        limit = TARGETS[bound]
        out[f"{key}_at_least_{limit:g}"] = _at_least(report[key], limit)
        verdicts = cases[case].get("error_verdicts")
        out[f"{case}_error_not_larger"] = (
            None if verdicts is None else all(verdicts[k] for k in verdicts["decisive"])
        )
    if "icad" in cases:
        out[f"icad_at_most_{TARGETS['icad_ms_max']:g}_ms"] = bool(
            report["icad_ms"] <= TARGETS["icad_ms_max"]
        )
    return out


def table(report: dict) -> str:
    """A short human-readable summary of the report."""
    host = report["host"]
    kind = "quick" if report["quick"] else "full"
    load = f"{host['load_average_at_start']} -> {host['load_average_at_end']}"
    lines = [f"acdrive bench ({kind}), load average {load}"]
    lines.append(
        f"{'case':<20}{'acdrive steps/s':>17}{'peer steps/s':>14}{'ratio':>9}"
        f"{'acdrive err':>13}{'peer err':>11}"
    )
    for case in ("motulator_averaged", "motulator_pwm", "gem_dfim"):
        c = report["cases"].get(case)
        if not c:
            continue
        peer = c.get(_peer_of(case), {})
        a_err = _decisive_current(c["acdrive"].get("error_summary"))
        p_err = _decisive_current(peer.get("error_summary"))
        ratio = c.get("ratio")
        lines.append(
            f"{case:<20}{c['acdrive']['steps_per_s']:>17,.0f}"
            f"{peer['steps_per_s'] if peer.get('steps_per_s') else float('nan'):>14,.0f}"
            f"{ratio if ratio else float('nan'):>9.0f}{a_err:>13}{p_err:>11}"
        )
        if not peer.get("available"):
            lines.append(f"  {_peer_of(case)} not measured: {peer.get('reason')}")
    if report.get("icad_ms") is not None:
        lines.append(f"icad: {report['icad_ms']:.1f} ms (full ICAD, 100 x 2,000)")
    lines.append("current errors relative to the peak, against the tightest reference")
    for k, v in report["target_checks"].items():
        lines.append(f"  {k}: {'-' if v is None else ('yes' if v else 'NO')}")
    lines.append(f"targets met: {'yes' if report['targets_met'] else 'no'}")
    return "\n".join(lines)


def _decisive_current(summary) -> str:
    if not summary:
        return "-"
    for key in ("extended_precision", "radau_rtol_1e-10"):
        if key in summary:
            return f"{summary[key]['current_rel_peak']:.1e}"
    return "-"
