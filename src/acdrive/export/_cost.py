"""Cost of the papers' controller chains on a Cortex-M4F (issue 22, item 3): each case's float
build cross-compiled, sized, and run on QEMU's board model over the inputs it saw in a short
acdrive run (``acdrive export m4``; the method in ``export._target``).

The inputs are replayed, not invented: the scenario runs (shortened) with the exported C chain
(double build) in acdrive's loop (``export._sil.run_in_loop``), every sample's inputs struct is
logged, rounded to float32 and replayed on the board into the float build, whose state evolves
from its own ``_reset``. The branches the step takes on the board are those of a real run (the
transient, limits, the load step), open loop on the board.
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from acdrive._arguments import (
    COUNT,
    PATH,
    POSITIVE,
    TEXT,
    Instance,
    Items,
    Table,
    checked,
    optional,
)
from acdrive.errors import InputError

#: the core the papers' rates are read against: a 168 MHz Cortex-M4F, one instruction per cycle
#: (an idealisation: the count is of instructions, not cycles)
CORE_CLOCK_HZ = 168e6
#: Bodson's sample rate (5 kHz) and a 10 kHz control period
PAPER_RATES_HZ = (5e3, 10e3)
#: at most this many replayed samples (their inputs go into the board's 4 MB code memory)
MAX_SAMPLES = 20_000
#: a scenario that is not one of CASES is replayed over its first DEFAULT_SECONDS
DEFAULT_SECONDS = 0.1


@dataclass(frozen=True)
class Case:
    scenario: str
    run: str | None  # the run of a scenario that compares runs (a mode, a controller)
    duration: float  # seconds of the scenario replayed
    what: str


CASES = {
    "dfim-voltage": Case("bodson-step", "voltage", 0.3,
                         "DFIM speed drive, voltage command (Bodson (20)-(25)), step at 0.1 s"),
    "dfim-current": Case("bodson-step", "current", 0.3,
                         "DFIM speed drive, current command (Bodson (43)-(49)), step at 0.1 s"),
    "ifoc-20": Case("im-foc-speed", None, 0.1,
                    "cage IM: IFOC, speed PI, controller (20) (Amezquita-Brooks), step at 0.05 s"),
    "ifoc-pi": Case("im-icad-vs-pi", "pi", 0.1,
                    "cage IM: IFOC, saturated P speed loop (21), stationary PI"),
    "pm-foc": Case("pm-bly171d-svpwm", None, 0.15,
                   "PMSM FOC: speed PI, MTPA/field weakening, rotor-frame PIs, load at 0.1 s"),
}  # fmt: skip


def period_fraction(instructions: float, rate_hz: float) -> float:
    """Fraction of one period at ``rate_hz`` that ``instructions`` take on a CORE_CLOCK_HZ core
    at one instruction per cycle."""
    return instructions / CORE_CLOCK_HZ * rate_hz


def one_run(setup, run: str | None):
    """The setup of one run of ``setup``: a DFIM mode of ``compare_modes`` or a label of
    ``compare_controllers`` (None: the setup itself)."""
    if run is None:
        return setup
    if run in getattr(setup, "compare_modes", ()):
        return setup.with_mode(run)
    if hasattr(setup, "runs"):
        runs = dict(setup.runs())
        if run in runs:
            return runs[run]
    raise InputError("run", f"{setup.name} has no run {run!r}")


def _case_setup(target: str, duration: float | None):
    from acdrive.export._scenario import shortened
    from acdrive.scenarios._loader import load_scenario

    case = CASES.get(target)
    if case is None:
        setup = load_scenario(target)
        what = getattr(setup, "description", "") or f"scenario {setup.name}"
        case = Case(setup.name, None, min(setup.duration, DEFAULT_SECONDS), what)
    else:
        setup = one_run(load_scenario(case.scenario), case.run)
    return case, shortened(setup, duration if duration is not None else case.duration)


def as_float32(replay: bytes) -> bytes:
    """Double inputs structs (all members real) as the float build's: each value rounded."""
    return np.frombuffer(replay, dtype=np.float64).astype(np.float32).tobytes()


def case_export(target: str, duration: float | None = None):
    """(setup, drive, initial, held, export) of a case or a scenario of one run, shortened."""
    from acdrive.export._scenario import built, c_name
    from acdrive.sim._ccode._c_source import to_c

    case, setup = _case_setup(target, duration)
    drive, initial, held = built(setup)
    name = c_name(target if target in CASES else setup.name)
    export = to_c(drive.system, setup.sample_time, initial, held, name=name,
                  description=f"scenario {setup.name}")  # fmt: skip
    return case, setup, drive, initial, held, export


@checked(
    compiled=Instance("acdrive.sim._compiled:CompiledSystem"),
    export=Instance("acdrive.sim._ccode._c_source:CExport"), duration=POSITIVE,
    sample_time=POSITIVE, substeps=COUNT,
    initial=Table(Table(empty=True), empty=True, optional=True),
    held=Table(Table(empty=True), empty=True, optional=True), folder=optional(PATH),
)
def board_cost(compiled, export, duration: float, sample_time: float, substeps: int = 4,
               initial=None, held=None, folder: Path | None = None) -> list[dict]:  # fmt: skip
    """Per chain of ``export``: the float build's sizes and instructions per step on the
    Cortex-M4 board model, over the inputs each chain sees when ``compiled`` runs ``duration``
    seconds with the C chain (double) in the loop (the arguments of ``run_in_loop``), and the
    fraction of a 5 kHz, a 10 kHz and its own period a CORE_CLOCK_HZ core would use at one
    instruction per cycle. Needs gcc and the cross tools (``scripts/install-cross-tools.sh``):
    a missing one is an InputError naming it, before any work. ``folder``: where the files are
    built (default: a temporary folder)."""
    from acdrive.export._sil import find_compiler
    from acdrive.export._target import chain_on_board, find_cross_tools

    find_compiler()
    tools = find_cross_tools()
    samples = round(duration / sample_time)
    if samples > MAX_SAMPLES:
        raise InputError("duration", f"gives {samples} samples; at most {MAX_SAMPLES} replay")
    replays = [[] for _ in export.chains]

    def log(chain_index, inputs):
        replays[chain_index].append(bytes(inputs))

    for model in export.chains:
        for member in model.inputs:
            if member.spec not in ("real", "complex"):
                raise InputError(model.chain.name, f"input {member.name} is not a real or complex")
    from acdrive.export._sil import run_in_loop

    run_in_loop(compiled, export, duration, sample_time, substeps, initial=initial, held=held,
                on_inputs=log)  # fmt: skip
    samples = len(replays[0])
    chains = []
    with tempfile.TemporaryDirectory(prefix="acdrive-m4-") as scratch:
        where = Path(folder) if folder is not None else Path(scratch)
        for model, rows in zip(export.chains, replays, strict=True):
            replay = as_float32(b"".join(rows))
            chains.append(chain_on_board(export, model, replay, samples, where, tools))
    rate = 1.0 / sample_time
    for row in chains:
        n = row["instructions_per_step"]
        row["fraction_of_period"] = {f"{r:g}": period_fraction(n, r) for r in PAPER_RATES_HZ}
        row["fraction_of_own_period"] = period_fraction(n, rate)
        row["samples"] = samples
    return chains


def measure_case(target: str, duration: float | None = None, folder: Path | None = None) -> dict:
    """Instructions per step and sizes of one case (a name of CASES or a scenario of one run)
    on the board model; the files are built in ``folder`` (default: a temporary folder)."""
    from acdrive.export._sil import find_compiler
    from acdrive.export._target import find_cross_tools

    find_compiler()
    find_cross_tools()
    case, setup, drive, initial, held, export = case_export(target, duration)
    if round(setup.duration / setup.sample_time) > MAX_SAMPLES:
        samples = round(setup.duration / setup.sample_time)
        raise InputError("duration", f"gives {samples} samples; at most {MAX_SAMPLES} replay")
    chains = board_cost(drive.system.compile(), export, setup.duration, setup.sample_time,
                        setup.substeps, initial, held, folder)  # fmt: skip
    samples = chains[0]["samples"]
    rate = 1.0 / setup.sample_time
    return {
        "case": target,
        "what": case.what,
        "scenario": setup.name,
        "run": case.run,
        "duration": setup.duration,
        "sample_rate_hz": rate,
        "samples": samples,
        "chains": chains,
    }


@checked(targets=Items(TEXT), duration=optional(POSITIVE), folder=optional(PATH))
def target_report(targets: list[str], duration: float | None = None,
                  folder: Path | None = None) -> dict:  # fmt: skip
    """Every target measured, and the voltage-command chain's count against the current-command
    one's when both DFIM cases are among them."""
    from acdrive.export import _target as t

    t.find_cross_tools()  # before any work
    cases = []
    for target in targets:
        where = None if folder is None else Path(folder) / target
        if where is not None:
            where.mkdir(parents=True, exist_ok=True)
        cases.append(measure_case(target, duration, where))
    report = {
        "board": t.BOARD,
        "flags": list(t.M4_FLAGS),
        "method": (
            f"qemu-system-arm -icount shift=0 (1 ns of virtual time per instruction), "
            f"SysTick at the board's {t.BOARD_CLOCK_HZ / 1e6:g} MHz "
            f"({t.INSTRUCTIONS_PER_TICK} instructions per tick), the step over the "
            "replayed samples with and without the call"
        ),
        "core_clock_hz": CORE_CLOCK_HZ,
        "cases": cases,
    }
    by_case = {c["case"]: c["chains"][0]["instructions_per_step"] for c in cases}
    if "dfim-voltage" in by_case and "dfim-current" in by_case:
        v, i = by_case["dfim-voltage"], by_case["dfim-current"]
        report["voltage_vs_current"] = {
            "voltage_instructions": v,
            "current_instructions": i,
            "voltage_over_current": v / i,
            "voltage_cheaper_by": 1.0 - v / i,
        }
    return report


def report_lines(report: dict) -> list[str]:
    rates = ", ".join(f"{r / 1e3:g} kHz" for r in PAPER_RATES_HZ)
    lines = [
        f"Float build on QEMU {report['board']} (Cortex-M4F), {' '.join(report['flags'])}",
        f"counted: {report['method']}",
        (
            f"fractions: of a {rates} period on a {CORE_CLOCK_HZ / 1e6:g} MHz core at one "
            "instruction per cycle (an instruction count, not a cycle count)"
        ),
    ]
    for case in report["cases"]:
        lines.append(f"{case['case']}: {case['what']} ({case['scenario']}"
                     f"{', ' + case['run'] if case['run'] else ''}; {case['samples']} samples "
                     f"replayed at {case['sample_rate_hz'] / 1e3:g} kHz)")  # fmt: skip
        for row in case["chains"]:
            fractions = ", ".join(f"{100 * f:.2f} % at {float(r) / 1e3:g} kHz"
                                  for r, f in row["fraction_of_period"].items())  # fmt: skip
            size = row["object"]
            step = row["functions"].get(f"{row['chain']}_step", math.nan)
            lines.append(
                f"  {row['chain']}: {row['instructions_per_step']:.1f} instructions per step "
                f"(+-{row['resolution']:.2f}; longest {row['longest_step_window']}, "
                f"+-{row['window_resolution']}); {fractions}, "
                f"{100 * row['fraction_of_own_period']:.2f} % at its own rate"
            )
            lines.append(
                f"    size: object text {size['text']} B (step function {step} B), data "
                f"{size['data']} B, bss {size['bss']} B; linked image (with libm, libc, startup and "
                f"the measuring loop) code {row['image']['text']} B; structs "
                + ", ".join(f"{k} {v} B" for k, v in row["structs"].items())
            )
    vc = report.get("voltage_vs_current")
    if vc:
        lines.append(
            f"DFIM voltage command: {vc['voltage_instructions']:.1f} instructions per step, "
            f"current command {vc['current_instructions']:.1f}: the voltage mode needs "
            f"{100 * vc['voltage_cheaper_by']:.1f} % fewer instructions"
            if vc["voltage_cheaper_by"] >= 0
            else f"DFIM voltage command: {vc['voltage_instructions']:.1f} instructions per "
            f"step, current command {vc['current_instructions']:.1f}: the voltage mode needs "
            f"{100 * -vc['voltage_cheaper_by']:.1f} % more instructions"
        )
    return lines
