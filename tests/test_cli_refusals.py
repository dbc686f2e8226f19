"""Every count bounded before it is built, every option acting or refused, every error naming what
the user typed: one table of command lines, each refused with exit code 2 and one line
``acdrive: error: <what was typed>: <rule>``, the rule's words checked.

Each row is (id, the command line, the field the line must name, words of the rule). A command
line may name files the ``files`` fixture writes (``{name}`` in an argument); a row whose refusal
must come before an allocation or a run trips a wire if that work starts (``WIRES``).
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from acdrive.cli import main
from acdrive.identify import StandstillLog, write_log
from acdrive.identify._mechanics import MechanicsLog, write_mechanics_log
from acdrive.scenarios._loader import builtin_text


def _pm(base: str, *changes: tuple[str, str]) -> str:
    """The built-in PM scenario ``base`` with each (old, new) text replaced once."""
    text = builtin_text(base)
    for old, new in changes:
        assert old in text, old
        text = text.replace(old, new, 1)
    return text


PM_MACHINE_PARAMS = """load_torque = 0.0
[machine.params]
R_s = 3.6
L_d = 0.036
L_q = 0.051
psi_m = 0.545
n_p = 1e6
J = 0.015
"""
PM_LOAD = "load_torque_profile = [[0.0, 0.0], [0.3, 0.0], [0.3, 14.0], [1.0, 14.0]]\n"
SWEEP = """name = "refusals"
base = "bodson-ramp"
[fixed]
"simulation.duration" = 0.01
[sampling]
method = "grid"
[[vary]]
field = "simulation.substeps"
values = {values}
"""


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> dict:
    """Name -> path of every file the table's command lines use."""
    folder = tmp_path_factory.mktemp("refusals")
    texts = {
        "pm-pole-pairs.toml": _pm("pm-ipmsm-speed",
                                  ('machine = "ipmsm-2.2kw"\n', PM_MACHINE_PARAMS),
                                  (PM_LOAD, "")),  # fmt: skip
        "pm-encoder.toml": _pm("pm-ipmsm-speed", ("[simulation]", "[sensors]\n"
                               "encoder_counts_per_rev = 1e30\n\n[simulation]")),  # fmt: skip
        "pm-pwm.toml": _pm("pm-ipmsm-speed", ('model = "averaged"',
                           'model = "switching"\npwm_frequency_hz = 1e12')),  # fmt: skip
        "pm-duration.toml": _pm("pm-ipmsm-speed", ("duration = 0.6", "duration = 1e12")),
        "pm-step-duration.toml": _pm("pm-pmsg-2mw-icad-coupling",
                                     ("duration = 1.5", "duration = 1e12")),  # fmt: skip
        "pm-step-substeps.toml": _pm("pm-pmsg-2mw-icad-coupling",
                                     ("sample_time = 2e-5", "sample_time = 2e-5\nsubsteps = "
                                      "1000000000")),  # fmt: skip
        "pm-step-frequencies.toml": _pm("pm-pmsg-2mw-icad-coupling",
                                        ("frequencies_rad_s = [", "frequencies_rad_s = ["
                                         + "1.0, " * 100_000)),  # fmt: skip
        "dfim-encoder.toml": builtin_text("bodson-ramp").replace(
            'machine = "bodson-dfim"\n',
            'machine = "bodson-dfim"\nencoder_counts_per_rev = 1099511627776\n', 1),
        "sweep-type.toml": SWEEP.format(values='["fast"]'),
        "sweep-invalid.toml": SWEEP.format(values="[0, -1]"),
        "sweep-unknown.toml": SWEEP.format(values="[1]").replace("simulation.substeps",
                                                                 "motor[0].compare_modes"),
    }
    paths = {}
    for name, text in texts.items():
        paths[name] = folder / name
        paths[name].write_text(text)
    # a standstill log whose voltage column is zero: it excites no tone (4 s at 5 kHz)
    t = np.arange(20_000) * 2e-4
    current = 0.1 * np.sin(2.0 * np.pi * t)
    paths["zero-voltage.csv"] = write_log(StandstillLog(t, np.zeros_like(t), current),
                                          folder / "zero-voltage.csv")  # fmt: skip
    # a speed-step log held at one speed: no acceleration, one plateau
    t = np.arange(4000) * 1e-3
    noise = 0.01 * np.random.default_rng(2).standard_normal(t.size)
    paths["constant-speed.csv"] = write_mechanics_log(
        MechanicsLog(t, 0.5 + noise, np.full(t.size, 100.0), "constant"),
        folder / "constant-speed.csv",
    )
    paths["out"] = folder / "out"
    paths["params.toml"] = folder / "identified.toml"
    return paths


def _trip(what: str):
    def wire(*args, **kwargs):
        raise AssertionError(f"{what} started before the refusal")

    return wire


#: row id -> (module, attribute) that must not run before that row's refusal
WIRES = {
    "robustness-grid-product": ("acdrive.robustness._map.MapSpec", "points_of"),
    "bench-peers-dir": ("acdrive._bench.suite", "run_suite"),
    "bench-reference-cache": ("acdrive._bench.suite", "run_suite"),
    "bench-baseline": ("acdrive._bench.suite", "run_suite"),
    **{
        f"run-log-every-{case}": ("acdrive.drives.dfim._outcome", "run_scenario")
        for case in ("zero", "text", "fraction", "too-large")
    },
}

ROWS = [
    # item 2: every count bounded before it is built
    ("robustness-grid-product", ["robustness", "bodson-ramp", "--points", "1000000000"],
     "--points", ["1000000000", "limit 100000"]),
    ("pm-pole-pairs", ["run", "{pm-pole-pairs.toml}"], "machine.params.n_p",
     ["at most 1000 pole pairs", "1e+06"]),
    ("pm-encoder", ["run", "{pm-encoder.toml}"], "sensors.encoder_counts_per_rev",
     ["4294967296", "1e+30"]),
    ("dfim-encoder", ["run", "{dfim-encoder.toml}"], "motor[0].encoder_counts_per_rev",
     ["<= 4294967296", "1099511627776"]),
    ("pm-pwm", ["run", "{pm-pwm.toml}"], "converter.pwm_frequency_hz",
     ["1e-12 s", "whole number", "at most 10000 Hz"]),
    ("pm-duration", ["run", "{pm-duration.toml}"], "simulation.duration",
     ["1e+12 s", "limit 1e+09"]),  # the default log keeps 100,000 samples: the work is the bound
    ("pm-step-duration", ["run", "{pm-step-duration.toml}"], "simulation.duration",
     ["1e+12 s", "limit 2 GB"]),
    ("pm-step-substeps", ["run", "{pm-step-substeps.toml}"], "simulation.substeps",
     ["at most 1000", "1000000000"]),
    ("pm-step-frequencies", ["run", "{pm-step-frequencies.toml}"],
     "comparison.frequencies_rad_s", ["at most 1000 frequencies", "100007"]),
    # item 3: every option acts or is refused, naming both options
    ("stability-map-scenario", ["stability", "--map", "--scenario", "pm-ipmsm-speed"],
     "--scenario", ["--map"]),
    ("stability-scenario-bandwidth", ["stability", "--scenario", "bodson-ramp", "--bandwidth",
                                      "100"], "--bandwidth", ["--scenario"]),  # fmt: skip
    ("stability-bench-mode", ["stability", "--bench", "--mode", "current"], "--mode",
     ["--bench"]),
    ("stability-point-grid", ["stability", "--speed-rpm", "900", "--grid", "3", "3"], "--grid",
     ["--speed-rpm", "--map"]),
    ("robustness-estimates-points", ["robustness", "bodson-ramp", "--estimates", "x.toml",
                                     "--points", "3"], "--points", ["--estimates"]),  # fmt: skip
    ("robustness-grid-seed", ["robustness", "bodson-ramp", "--seed", "3"], "--seed",
     ["--map grid", "--map monte-carlo"]),
    ("robustness-monte-carlo-points", ["robustness", "bodson-ramp", "--map", "monte-carlo",
                                       "--points", "3"], "--points", ["--map monte-carlo"]),  # fmt: skip
    ("icad-bandwidth-paper", ["icad", "ugalde-im-300w", "--speed", "100", "--bandwidth", "5"],
     "--bandwidth", ["--controller", "paper-20"]),
    ("icad-point-out", ["icad", "pmsg-2mw", "--speed", "100", "--out", "{out}"], "--out",
     ["--speed", "--sweep"]),
    ("sweep-timeout", ["sweep", "dfim-bandwidth", "--timeout", "5"], "--timeout",
     ["--scheduler"]),
    ("sweep-list-out", ["sweep", "--list", "--out", "{out}"], "--out", ["--list"]),
    ("identify-no-load-frequency", ["identify", "{zero-voltage.csv}", "--pole-pairs", "2",
                                    "--no-load-frequency-hz", "50"], "--no-load-frequency-hz",
     ["--no-load-log"]),  # fmt: skip
    ("identify-spin-settle", ["identify", "{zero-voltage.csv}", "--kind", "pm", "--q-log",
                              "{zero-voltage.csv}", "--pole-pairs", "2", "--spin-settle-s",
                              "0.1"], "--spin-settle-s", ["--spin-log"]),  # fmt: skip
    ("identify-resistance-std", ["identify", "{zero-voltage.csv}", "--kind", "dfim",
                                 "--shorted-log", "{zero-voltage.csv}",
                                 "--stator-resistance-std-ohm", "0.1"],
     "--stator-resistance-std-ohm", ["--stator-resistance-ohm"]),  # fmt: skip
    ("bench-peers-dir", ["bench", "--no-peers", "--peers-dir", "{out}"], "--peers-dir",
     ["--no-peers"]),
    ("bench-reference-cache", ["bench", "--no-reference", "--no-reference-cache"],
     "--no-reference-cache", ["--no-reference"]),
    ("bench-baseline", ["bench", "--only", "icad", "--baseline-src", "{out}"], "--baseline-src",
     ["--only", "loop_speed"]),
    # item 4: errors name what the user typed
    ("robustness-duration", ["robustness", "bodson-ramp", "--duration", "-1"], "--duration",
     ["> 0", "-1"]),
    ("robustness-estimates", ["robustness", "bodson-ramp", "--estimates", "/no/such.toml"],
     "--estimates", ["/no/such.toml", "not a file"]),
    ("stability-scenario", ["stability", "--scenario", "no-such-scenario"], "--scenario",
     ["no-such-scenario"]),
    ("identify-zero-voltage", ["identify", "{zero-voltage.csv}", "--pole-pairs", "2"],
     "TEST_FILE_OR_SCENARIO: column 'v_a'", ["found 0", "the column is zero"]),
    ("identify-base-frequency", ["identify", "{zero-voltage.csv}", "--pole-pairs", "2",
                                 "--base-frequency-hz", "0.3"], "--base-frequency-hz",
     ["0.3 Hz", "whole number of samples"]),  # fmt: skip
    ("identify-seed", ["identify", "delorenzo-im", "--seed", "-1", "--out", "{params.toml}"],
     "--seed",
     [">= 0", "-1"]),
    ("robustness-seed", ["robustness", "bodson-ramp", "--map", "monte-carlo", "--seed", "-1"],
     "--seed", [">= 0", "-1"]),
    ("identify-constant-speed", ["identify", "{constant-speed.csv}", "--kind", "mechanics",
                                 "--out", "{params.toml}"], "TEST_FILE_OR_SCENARIO: column 'w'",
     ["never changes", "100 rad/s", "two levels"]),  # fmt: skip
    ("run-log-every-zero", ["run", "bodson-ramp", "--log-every", "0"], "--log-every",
     [">= 1", "'0'"]),
    ("run-log-every-text", ["run", "bodson-ramp", "--log-every", "often"], "--log-every",
     ["integer", "'often'"]),
    ("run-log-every-fraction", ["run", "bodson-ramp", "--log-every", "2.5"], "--log-every",
     ["integer", "'2.5'"]),
    ("run-log-every-too-large", ["run", "bodson-ramp", "--log-every", "70001"], "--log-every",
     ["70000 control samples", "70001"]),
    # sweeps: a value of the wrong type is refused at load; a sweep with no valid variant fails
    ("sweep-wrong-type", ["sweep", "{sweep-type.toml}", "--out", "{out}", "--quiet"],
     "vary[0].values[0]", ["'fast'", "simulation.substeps", "must be an integer"]),
    ("sweep-unknown-field", ["sweep", "{sweep-unknown.toml}", "--out", "{out}", "--quiet"],
     "vary[0].field", ["motor[0].compare_modes", "unknown key"]),
    ("sweep-all-invalid", ["sweep", "{sweep-invalid.toml}", "--out", "{out}", "--quiet",
                           "--no-report"], "sweep", ["none of the 2 variants",
                                                     "simulation.substeps"]),  # fmt: skip
]


@pytest.mark.parametrize(("argv", "field", "words"), [row[1:] for row in ROWS],
                         ids=[row[0] for row in ROWS])  # fmt: skip
def test_refused_with_one_line_naming_what_was_typed(request, files, monkeypatch, capsys,
                                                     tmp_path, argv, field, words):  # fmt: skip
    monkeypatch.chdir(tmp_path)  # a command that is not refused writes its default output here
    row = request.node.callspec.id
    if row in WIRES:
        module, name = WIRES[row]
        monkeypatch.setattr(f"{module}.{name}", _trip(f"{module}.{name}"))
    argv = [re.sub(r"\{(.+)\}", lambda m: str(files[m.group(1)]), a) for a in argv]
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if not line.startswith("acdrive: note:")]
    assert code == 2, err
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"acdrive: error: {field}: "), err
    for word in words:
        assert word in lines[0], (word, err)


def test_a_sweep_is_refused_only_when_no_variant_is_valid(files, tmp_path, capsys):
    """The refusal counts valid rows: one valid variant among invalid ones runs (exit 0), the
    same sweep without it is refused (exit 2) and keeps its folder, whose table lists each
    variant's reason."""
    import pandas as pd

    outcomes = {}
    for values in ("[0, 1]", "[0, -1]"):
        path = tmp_path / "sweep.toml"
        path.write_text(SWEEP.format(values=values))
        out = tmp_path / values.strip("[]").replace(", ", "_")
        outcomes[values] = main(["sweep", str(path), "--out", str(out), "--quiet", "--no-report"])
        table = pd.read_parquet(out / "refusals" / "table")
        assert len(table) == 2 and not table["valid"].iloc[0]
    assert outcomes == {"[0, 1]": 0, "[0, -1]": 2}, capsys.readouterr().err
