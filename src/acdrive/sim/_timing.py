"""A run's time as the headlines, summaries and reprs tell it: the simulation apart from the
compile or load of its loop (``sim._compiled``; the loop's tiers in ``sim._tier``). Plain Python,
so that a headline does not import the engine."""

from __future__ import annotations


def loop_time_text(seconds: float, compiled: bool, tiers) -> str:
    """The compile or load time of a run's loop, for a headline beside its simulation time:
    " (+ 12.15 s compiling the specialised loop)", " (+ 0.05 s loading the native loop)", or
    " (specialised loop)" when the loop was in memory already. ``tiers``: the tier names of the
    runs (``sim._tier``)."""
    names = " and ".join(sorted({t for t in tiers if t})) or "simulation"
    if seconds <= 0.0:
        return f" ({names} loop)"
    what = "compiling" if compiled else "loading"
    return f" (+ {seconds:.2f} s {what} the {names} loop)"


def run_timing(results) -> dict:
    """The time of ``results`` (objects with ``wall_time``, ``compile_time``, ``compiled_now``,
    ``tier``: one scenario's runs) as summary.json keeps it: the simulation alone
    (``wall_time_s``) apart from compiling or loading the loop before it (``compile_time_s``;
    ``loop_compiled``: a compile, not a load), and the loop's tier (``compiled_loop_tier``).
    Each key names time or the compile: a comparison of results leaves them out."""
    results = list(results)
    return {
        "wall_time_s": float(sum(r.wall_time for r in results)),
        "compile_time_s": float(sum(getattr(r, "compile_time", 0.0) for r in results)),
        "loop_compiled": any(getattr(r, "compiled_now", False) for r in results),
        "compiled_loop_tier": " and ".join(
            sorted({getattr(r, "tier", "") for r in results} - {""})
        ),
    }


def simulated_in(results) -> str:
    """ "simulated in 0.13 s (+ 12.15 s compiling the specialised loop)": a headline's timing of
    ``results`` (``run_timing``), the simulation and the loop's compile or load apart."""
    timing = run_timing(results)
    tiers = timing["compiled_loop_tier"].split(" and ")
    loop = loop_time_text(timing["compile_time_s"], timing["loop_compiled"], tiers)
    return f"simulated in {timing['wall_time_s']:.2f} s{loop}"
