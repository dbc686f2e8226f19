"""Coverage of the cage IM's standstill identification on another simulator's logs: motulator 0.18's
2.2 kW cage IM behind motulator's own PWM inverter with dead time and device drops, read by a
current sensor with an offset; prints JSON.

    python benchmarks/coverage_motulator.py [--repetitions 50] [--bootstrap 50]
        [--amplitudes 15] [--offsets 0 0.05 0.2] [--peers-dir DIR] [--logs-dir DIR]

**The logs.** motulator runs in its own virtualenv (``acdrive._bench.venvs.ensure_venv``, as
``acdrive bench`` makes it); the peer script ``src/acdrive/_bench/peers/motulator_standstill.py``
(motulator only, never acdrive) simulates the locked-rotor DC-step test (a 0.2 s rest at zero
command, then 12, 24, 36 V for 2 s each) and the multisine injection (acdrive's default tones,
1 to 160 Hz at f_0 = 1 Hz, 2 s settling and two periods) at each tone amplitude of
``--amplitudes`` [V], on a 540 V link at 5 kHz with a 2 us dead time and 1 V device drops
(U_err = 4/3 (t_d f_pwm u_dc + u_th) = 8.53 V), and writes acdrive's CSV logs, one per
current-sensor offset of ``--offsets`` [A] (motulator's ``Sensor``). One motulator run per test
and amplitude; the logs are kept in ``--logs-dir`` (default
``$XDG_CACHE_HOME/acdrive/motulator-standstill``) under a key of the peer script's text and its
arguments, and reused.

**The sensor's noise** is drawn here, per repetition r (seeds 2r for the DC log, 2r + 1 for the
injection): Gaussian of ``--noise-a`` [A], then a 12-bit converter over +-``--adc-range-a`` [A]
(rounded to its step and clipped to its range; the JSON counts clipped samples).

**The fit** is what the identification guide documents for a real bench
(``acdrive identify injection.csv --dc-log dc.csv --dead-time-s 2e-6 --pole-pairs 2``):
``identify_standstill`` with the DC-step log (U_err, the sensor's offset) and the programmed dead
time. Each case is fitted twice: with the DC log as logged (its rest gives the offset) and with
its rest cut off (``no rest``: the offset then comes from the injection's mean jointly with the
parameters, ``identify._offset``).

Per case and inverse-Gamma parameter: the fraction of accepted fits whose Jacobian and bootstrap
95 % intervals hold motulator's value, the mean relative error and the mean relative half-width
of the Jacobian interval; the same for the offset; fits refused (``InputError``,
``FitNotConverged``) are counted by their message's cause and left out of the fractions; fits
that warn are counted with their first warning's cause.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import subprocess
import sys
from collections import Counter
from pathlib import Path

import numpy as np

PEER = "motulator_standstill.py"
TRUTH = {"R_s": 3.7, "L_sigma": 0.021, "R_R": 2.1, "L_M": 0.224}  # the peer's PAR
N_P = 2
DEAD_TIME = 2e-6
BASE_FREQUENCY, SETTLE = 1.0, 2.0  # acdrive's default plan (identify._experiment)


def logs_dir_default() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "acdrive" / "motulator-standstill"


def peer_logs(python: str, args: list[str], logs_dir: Path, say) -> dict:
    """The peer's answer for ``args`` (its logs), run once and kept under a key of the peer
    script's text and the arguments."""
    from acdrive._bench.venvs import PEER_SCRIPTS, clean_env

    script = PEER_SCRIPTS / PEER
    key = hashlib.sha256(script.read_bytes() + json.dumps(args).encode()).hexdigest()[:16]
    folder = logs_dir / key
    answer = folder / "answer.json"
    if answer.exists():
        return json.loads(answer.read_text())
    folder.mkdir(parents=True, exist_ok=True)
    say(f"motulator: {' '.join(args)}")
    run = subprocess.run([python, str(script), *args, "--out-dir", str(folder)], check=False,
                         capture_output=True, text=True, env=clean_env())  # fmt: skip
    if run.returncode != 0:
        raise SystemExit(f"{PEER} failed: {run.stderr.strip().splitlines()[-3:]}")
    answer.write_text(run.stdout.strip().splitlines()[-1])
    return json.loads(answer.read_text())


def adc(current: np.ndarray, noise: float, full_scale: float, rng) -> tuple[np.ndarray, int]:
    """The 12-bit converter's reading of ``current`` with Gaussian ``noise`` [A], and how many
    samples it clipped."""
    step = 2.0 * full_scale / 4096
    reading = np.round((current + noise * rng.standard_normal(current.shape)) / step) * step
    clipped = int(np.count_nonzero(np.abs(reading) > full_scale))
    return np.clip(reading, -full_scale, full_scale - step), clipped


def without_rest(log):
    """``log`` from its first nonzero command on (the rest cut off)."""
    from acdrive.identify import StandstillLog

    first = int(np.flatnonzero(log.v_a != 0.0)[0])
    return StandstillLog(log.time[first:] - log.time[first], log.v_a[first:], log.i_a[first:],
                         log.source + " (rest cut off)")  # fmt: skip


def cause(message: str) -> str:
    """A refusal's or warning's message with its numbers as '#' (so that one cause counts once),
    cut to 160 characters (the cause comes first)."""
    message = re.sub(r"[-+]?\d+(\.\d+)?(e[-+]?\d+)?", "#", message)
    return message if len(message) <= 160 else message[:157] + "..."


def study(injection, dc, offset: float, repetitions: int, bootstrap: int, noise: float,
          full_scale: float) -> dict:  # fmt: skip
    """The coverage of one case (module docstring)."""
    from acdrive.errors import InputError
    from acdrive.identify import FitNotConverged, StandstillLog, identify_standstill

    rows = {name: {"jacobian": 0, "bootstrap": 0, "error": 0.0, "width": 0.0,
                   } for name in [*TRUTH, "i_a_offset"]}  # fmt: skip
    refused, warned, clipped, accepted = Counter(), Counter(), 0, 0
    ratios = []
    for r in range(repetitions):
        rng_dc, rng_inj = np.random.default_rng(2 * r), np.random.default_rng(2 * r + 1)
        i_dc, c_dc = adc(dc.i_a, noise, full_scale, rng_dc)
        i_inj, c_inj = adc(injection.i_a, noise, full_scale, rng_inj)
        clipped += c_dc + c_inj
        try:
            result = identify_standstill(
                StandstillLog(injection.time, injection.v_a, i_inj, injection.source),
                BASE_FREQUENCY, SETTLE, dc=StandstillLog(dc.time, dc.v_a, i_dc, dc.source),
                n_p=N_P, seed=r, bootstrap=bootstrap, dead_time=DEAD_TIME,
            )  # fmt: skip
        except (InputError, FitNotConverged) as exc:
            refused[cause(str(exc))] += 1
            continue
        accepted += 1
        ratios.append(result.impedance.residual_ratio)
        if result.warnings:
            warned[cause(result.warnings[0])] += 1
        estimates = {e.name: e for e in result.impedance.estimates}
        estimates["i_a_offset"] = result.current_offset
        for name, row in rows.items():
            truth = TRUTH.get(name, offset)
            e = estimates[name]
            row["jacobian"] += e.covers(truth)
            row["bootstrap"] += e.covers(truth, "bootstrap") if bootstrap else 0
            scale = abs(truth) if truth != 0.0 else 1.0  # the offset's 0 A case: absolute [A]
            low, high = e.jacobian
            row["error"] += (e.value - truth) / scale
            row["width"] += 0.5 * (high - low) / scale
    out = {"repetitions": repetitions, "accepted": accepted,
           "refused": sum(refused.values()), "refusals": dict(refused),
           "warned": sum(warned.values()), "warnings": dict(warned),
           "clipped_samples": clipped,
           "residual_over_noise_floor_median": float(np.median(ratios)) if ratios
           else None}  # fmt: skip
    for name, row in rows.items():
        n = max(accepted, 1)
        truth = TRUTH.get(name, offset)
        relative = name in TRUTH or truth != 0.0
        out[name] = {
            "jacobian_coverage": row["jacobian"] / n if accepted else None,
            "bootstrap_coverage": (row["bootstrap"] / n if accepted else None) if bootstrap
            else None,
            ("mean_relative_error" if relative else "mean_error_a"): row["error"] / n,
            ("mean_relative_half_width" if relative else "mean_half_width_a"): row["width"] / n,
        }
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repetitions", type=int, default=50)
    parser.add_argument("--bootstrap", type=int, default=50)
    parser.add_argument("--amplitudes", type=float, nargs="+", default=[15.0],
                        help="tone amplitudes [V] (acdrive's default plan: 15)")  # fmt: skip
    parser.add_argument("--offsets", type=float, nargs="+", default=[0.0, 0.05, 0.2])
    parser.add_argument("--noise-a", type=float, default=0.01, help="sensor noise [A]")
    parser.add_argument("--adc-range-a", type=float, default=25.0, help="+- full scale [A]")
    parser.add_argument("--peers-dir", default=None)
    parser.add_argument("--logs-dir", default=None)
    args = parser.parse_args(argv)

    from acdrive._bench.venvs import MOTULATOR, default_peers_dir, ensure_venv
    from acdrive.identify import read_log

    def say(line: str) -> None:
        print(line, file=sys.stderr, flush=True)

    peers = Path(args.peers_dir) if args.peers_dir else default_peers_dir()
    venv = ensure_venv(MOTULATOR, peers, log=say)
    if not venv["available"]:
        print(json.dumps({"available": False, "reason": venv["reason"]}))
        return 1
    logs_dir = Path(args.logs_dir) if args.logs_dir else logs_dir_default()
    offsets = ["--offsets", *[repr(c) for c in args.offsets]]
    dc_answer = peer_logs(venv["python"], ["--test", "dc", *offsets], logs_dir, say)
    dc_logs = {entry["offset_a"]: read_log(entry["path"], "dc") for entry in dc_answer["logs"]}
    out = {"motulator": venv["version"], "dc_test": {k: v for k, v in dc_answer.items()
                                                      if k != "logs"},  # fmt: skip
           "sensor": {"noise_a": args.noise_a, "adc_bits": 12, "adc_range_a": args.adc_range_a},
           "fit": {"dead_time_s": DEAD_TIME, "base_frequency_hz": BASE_FREQUENCY,
                   "settle_s": SETTLE, "bootstrap": args.bootstrap},
           "truth": TRUTH, "cases": {}}  # fmt: skip
    for amplitude in args.amplitudes:
        answer = peer_logs(venv["python"], ["--test", "injection", "--tone-amplitude",
                                            repr(amplitude), *offsets], logs_dir, say)  # fmt: skip
        out.setdefault("injection_peak_current_a", {})[f"{amplitude:g} V"] = answer[
            "peak_current_a"]
        for entry in answer["logs"]:
            offset = entry["offset_a"]
            injection = read_log(entry["path"], "injection")
            variants = (("rest", dc_logs[offset]), ("no rest", without_rest(dc_logs[offset])))
            for variant, dc in variants:
                name = f"tones {amplitude:g} V, offset {offset:g} A, DC log {variant}"
                say(name)
                out["cases"][name] = study(injection, dc, offset, args.repetitions, args.bootstrap,
                                           args.noise_a, args.adc_range_a)  # fmt: skip
    print(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
