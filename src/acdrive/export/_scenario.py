"""A scenario's controller chains: the drive built from the scenario (``Drive.build``), its C
export, and the comparison of the C controller in the loop against acdrive's own run."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from acdrive.errors import InputError
from acdrive.sim._ccode._c_source import CExport, to_c
from acdrive.sim._ccode._prelude import FLOAT_NO_LIMIT

#: double build against acdrive (ACDRIVE_STRICT_MATH=1): each logged signal's largest
#: difference over the run, as a fraction of that signal's peak (the issue's bound)
DOUBLE_TOLERANCE = 1e-12
#: float build: its worst ratio may be at most FLOAT_MARGIN times the worst ratio of the double
#: build run with its inputs rounded to float32 at every sample (``float_bound``)
FLOAT_MARGIN = 100.0
#: float32's unit roundoff 2^-24: the bound is at least FLOAT_MARGIN of it
FLOAT_UNIT_ROUNDOFF = 2.0**-24


def c_name(scenario_name: str) -> str:
    """A scenario name as a C identifier prefix: bodson-ramp -> bodson_ramp."""
    name = scenario_name.replace("-", "_").lower()
    return name if name[:1].isalpha() else f"chain_{name}"


def built(setup):
    """(drive, initial, held) of one setup (``Drive.build``; a setup comparing several runs,
    such as both DFIM modes, is refused by its drive with an InputError)."""
    from acdrive.drives import for_setup

    runs = for_setup(setup).runs(setup)
    if runs > 1:
        raise InputError(
            "scenario",
            f"{setup.name} compares {runs} runs; the export takes a scenario of one run (one "
            "mode, one controller)",
        )
    drive = for_setup(setup).build(setup)
    initial, held = drive.initial()
    return drive, initial, held


def export_setup(setup, name: str | None = None) -> CExport:
    drive, initial, held = built(setup)
    return to_c(drive.system, setup.sample_time, initial, held, name=name or c_name(setup.name),
                description=f"scenario {setup.name}")  # fmt: skip


def shortened(setup, duration: float | None, field: str = "duration"):
    """``setup`` with its run cut to ``duration`` seconds (None: unchanged); an error names
    ``field``."""
    if duration is None:
        return setup
    if isinstance(duration, bool) or not (math.isfinite(duration) and duration > 0):
        raise InputError(field, "must be a finite number of seconds > 0")
    if duration > setup.duration:
        raise InputError(field, f"must not exceed the scenario's ({setup.duration:g} s)")
    return dataclasses.replace(setup, duration=float(duration))


def _worst(reference, other, no_limit: float | None = None) -> tuple[dict, str]:
    from acdrive.export._sil import deviation

    signals = {}
    for column, (difference, peak) in deviation(reference, other, no_limit).items():
        ratio = difference / peak if peak > 0 else (0.0 if difference == 0 else math.inf)
        signals[column] = {"max_difference": difference, "peak": peak, "ratio": ratio}
    return signals, max(signals, key=lambda c: signals[c]["ratio"])


def event_differences(reference, other, event_names) -> list[dict]:
    """Each event whose per-sample record differs between two runs of one system: its name
    (``part.event``), the samples on which each run raised it and the first logged time [s] at
    which the records differ (``event_names``: ``System.event_names()``, the order of the
    runs' ``event_log`` columns and bits), in the order of that time."""
    out = []
    for i, (part, names) in enumerate(event_names):
        for bit, name in enumerate(names):
            mine = (reference.event_log[:, i] >> bit) & 1
            theirs = (other.event_log[:, i] >> bit) & 1
            differ = np.flatnonzero(mine != theirs)
            if differ.size or reference.events[part][name] != other.events[part][name]:
                first = float(reference.t[differ[0]]) if differ.size else None
                out.append({"event": f"{part}.{name}", "acdrive": reference.events[part][name],
                            "c": other.events[part][name], "first_difference_s": first})  # fmt: skip
    return sorted(out, key=lambda d: math.inf if d["first_difference_s"] is None
                  else d["first_difference_s"])  # fmt: skip


def float_bound(input_rounding_ratio: float) -> float:
    """The bound of the float build's worst ratio (docs/guide/export.md, "The float bound").

    The float build rounds its inputs to float32 and then every operation of its step, each
    rounding of the same relative size (2^-24). ``input_rounding_ratio`` is what the first of
    those roundings alone does to the closed loop: the worst ratio of the double build whose
    inputs are rounded to float32 at every sample, against acdrive's run. A stable loop maps a
    perturbation in proportion to its size, and n roundings in sequence add at most about n
    times one (Higham's gamma_n = n u / (1 - n u)); the chains' steps do on the order of a
    hundred float operations (their instruction counts on the Cortex-M4, ``export m4``), hence
    FLOAT_MARGIN = 100. An engineering bound, stated, not a theorem: a float build beyond it
    has a numerical weakness the double build hides. Never below FLOAT_MARGIN * 2^-24."""
    return FLOAT_MARGIN * max(input_rounding_ratio, FLOAT_UNIT_ROUNDOFF)


def compare_in_loop(setup, real: str = "double") -> dict:
    """Run ``setup`` with acdrive's compiled loop and with its exported C controller in the loop
    (``export._sil``), every output logged at every sample; per signal the largest difference
    and the peak, the event counts of both, and the worst ratio. For ``real="float"`` also the
    double build with float32-rounded inputs (``input_rounding_ratio``), the bound derived from
    it (``float_bound``) and whether the float build is within it; beyond it an InputError
    naming the bound (the issue's bad-input rule, exit 2)."""
    from acdrive._jit import STRICT_MATH
    from acdrive.export._sil import find_compiler, run_in_loop

    find_compiler()  # before any work
    drive, initial, held = built(setup)
    export = to_c(drive.system, setup.sample_time, initial, held, name=c_name(setup.name))
    compiled = drive.system.compile()
    kwargs = {"initial": initial, "held": held}
    reference = compiled.run(setup.duration, setup.sample_time, setup.substeps, **kwargs)
    in_loop = run_in_loop(compiled, export, setup.duration, setup.sample_time, setup.substeps,
                          real=real, **kwargs)  # fmt: skip
    # the float build's stand-in as it holds it: 1e38 rounded to float32 (just below 1e38)
    no_limit = float(np.float32(FLOAT_NO_LIMIT)) if real == "float" else None
    signals, worst = _worst(reference, in_loop, no_limit)
    report = {
        "scenario": setup.name,
        "duration": setup.duration,
        "real": real,
        "strict_math": STRICT_MATH,
        "chains": [m.chain.name for m in export.chains],
        "signals": signals,
        "worst_signal": worst,
        "worst_ratio": signals[worst]["ratio"],
        "events_acdrive": reference.events,
        "events_c": in_loop.events,
        "events_differing": event_differences(reference, in_loop, drive.system.event_names()),
    }
    report["events_equal"] = not report["events_differing"]
    if real == "float":
        # the modulators' outputs switch: a carrier comparison that flips one sample earlier
        # moves a switched voltage by its full swing (an event, counted apart), so the bound is
        # on every other signal
        modulated = tuple(f"{m.name}." for m in drive.system.modulators)
        rounded = run_in_loop(compiled, export, setup.duration, setup.sample_time,
                              setup.substeps, real="double", float_inputs=True, **kwargs)  # fmt: skip
        rounded_signals, _ = _worst(reference, rounded, no_limit)
        rounded_worst = _worst_of(rounded_signals, modulated)
        input_rounding = rounded_signals[rounded_worst]["ratio"]
        bound = float_bound(input_rounding)
        bounded = _worst_of(signals, modulated)
        ratio = signals[bounded]["ratio"]
        report.update(input_rounding_ratio=input_rounding, input_rounding_signal=rounded_worst,
                      float_bound=bound, float_margin=FLOAT_MARGIN,
                      bounded_worst_signal=bounded, bounded_worst_ratio=ratio,
                      modulator_signals_left_out=[m.name for m in drive.system.modulators],
                      within_float_bound=ratio <= bound)  # fmt: skip
        if not report["within_float_bound"]:
            raise InputError(
                "float build",
                f"{bounded} deviates by {ratio:.3e} of its peak, beyond the float bound "
                f"{bound:.3e} ({FLOAT_MARGIN:g} x the {input_rounding:.3e} of the double build "
                "with float32-rounded inputs)",
            )
    return report


def _worst_of(signals: dict, left_out: tuple[str, ...]) -> str:
    """The signal of largest ratio among those whose name starts with none of ``left_out``."""
    kept = [c for c in signals if not c.startswith(left_out)] or list(signals)
    return max(kept, key=lambda c: signals[c]["ratio"])
