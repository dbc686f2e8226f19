"""A scenario's FMUs: built (``scenario_fmus``) and checked against acdrive's own run
(``compare_fmus``) with fmpy (docs/guide/fmu.md).

The checks, each on the same run of acdrive's compiled loop with every output logged at every
sample (rows k = 0 .. n-1 at t_k = k T_s):

* **controller, open loop**: ``fmpy.simulate_fmu`` of the controller FMU with the logged plant
  outputs as its inputs (at t_k the values of row k), one communication step per period; its
  output after the step from t_k (recorded at t_{k+1}) is the command of sample k, compared with
  row k of acdrive's log.
* **plant, open loop**: ``simulate_fmu`` of the plant FMU with the logged commands as its inputs
  (discrete: held from t_k); its outputs at t_k against row k (a modulator's output, the voltage
  applied over the period before, against row k - 1, where acdrive logs the one applied from t_k;
  a controller reading a modulator's output reads that one too). The output of a switching
  modulator (several segments per period) changes within the period: acdrive logs its first
  segment, the FMU shows the last, so those columns are listed as not compared; the plant's
  own outputs, driven by every segment, are.
* **closed loop**: both FMUs stepped by a small master (``fmpy.fmi2.FMU2Slave``): at each t_k
  the plant's outputs are given to the controller, the controller steps, its commands are given
  to the plant, the plant steps. This is acdrive's order within a sample (the controller reads
  the plant at t_k, its command is applied from t_k), so with both FMUs equal to acdrive's parts
  the closed loop is acdrive's closed loop to rounding: the bound applied is the plant's,
  ``PLANT_TOLERANCE`` of each signal's peak. (A Jacobi master, stepping both with the values of
  the last communication point, would apply each command one period late: another system.)

Per check and signal: the largest difference over the run and the peak of acdrive's signal.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np

from acdrive.errors import InputError
from acdrive.export._fmu import build_fmu, controller_model, plant_model
from acdrive.export._scenario import built, c_name
from acdrive.sim._ccode._c_source import to_c
from acdrive.sim._ccode._plant_source import to_plant_c

#: plant FMU against acdrive, open and closed loop: each signal's largest difference as a
#: fraction of its peak (the issue's bound for the plant at the same step)
PLANT_TOLERANCE = 1e-9
PARTS = ("controller", "plant")


def scenario_fmus(setup, parts, folder: Path, name: str | None = None,
                  version: int = 2) -> dict[str, Path]:  # fmt: skip
    """Build the FMI ``version`` (2 or 3) FMUs ``parts`` (of ``PARTS``) of ``setup`` into
    ``folder``: part -> path. Every error (a part without C, feedthrough, no compiler, no
    fmpy) comes before any file."""
    from acdrive.export._fmu import fmi_headers
    from acdrive.export._sil import find_compiler

    for part in parts:
        if part not in PARTS:
            raise InputError("--part", f"must be one of {', '.join(PARTS)} (got {part!r})")
    find_compiler("gcc", "building an FMU's binary")
    fmi_headers()
    drive, initial, held = built(setup)
    base = name or c_name(setup.name)
    models = {}
    what = f"scenario {setup.name}"
    if "controller" in parts:
        export = to_c(drive.system, setup.sample_time, initial, held, name=f"{base}_controller",
                      description=what)  # fmt: skip
        models["controller"] = controller_model(export, setup.sample_time, setup.duration,
                                                f"controller chains of {what}")  # fmt: skip
    if "plant" in parts:
        export = to_plant_c(drive.system, setup.sample_time, setup.substeps, initial, held,
                            name=f"{base}_plant", description=what)  # fmt: skip
        models["plant"] = plant_model(export, drive.system, held, setup.sample_time,
                                      setup.duration, f"plant of {what}")  # fmt: skip
    return {part: build_fmu(m, Path(folder) / f"{m.identifier}.fmu", version)
            for part, m in models.items()}  # fmt: skip


def _signals(names, reference: dict, other: dict) -> dict:
    """Per column: the largest difference of ``other`` from ``reference`` over their common
    rows, the peak of ``reference`` and their ratio."""
    out = {}
    for column in names:
        a, b = reference[column], other[column]
        rows = min(len(a), len(b))
        a, b = a[:rows], b[:rows]
        difference = float(np.max(np.abs(a - b)))
        peak = float(np.max(np.abs(reference[column])))
        ratio = difference / peak if peak > 0 else (0.0 if difference == 0 else math.inf)
        out[column] = {"max_difference": difference, "peak": peak, "ratio": ratio}
    return out


def _worst(signals: dict) -> dict:
    worst = max(signals, key=lambda c: signals[c]["ratio"])
    return {"signals": signals, "worst_signal": worst, "worst_ratio": signals[worst]["ratio"]}


def _inputs(names, times, log) -> np.ndarray:
    rows = np.zeros(len(times), dtype=[("time", np.float64)] + [(n, np.float64) for n in names])
    rows["time"] = times
    for n in names:
        rows[n] = log[n]
    return rows


def _variables(fmu: Path, causality: str) -> list:
    from fmpy import read_model_description

    return [v for v in read_model_description(str(fmu)).modelVariables
            if v.causality == causality and v.type == "Real"]  # fmt: skip


def _closed_loop(paths: dict, n: int, T_s: float) -> dict:
    """Both FMUs stepped by a Gauss-Seidel master (module docstring); plant outputs at t_k and
    controller outputs of sample k, k = 0 .. n-1."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    slaves, described = {}, {}
    for part, path in paths.items():
        md = read_model_description(str(path))
        slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path)),
                          modelIdentifier=md.coSimulation.modelIdentifier, instanceName=part)  # fmt: skip
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        slaves[part], described[part] = slave, md
    controller, plant = slaves["controller"], slaves["plant"]
    c_in = _variables(paths["controller"], "input")
    c_out = _variables(paths["controller"], "output")
    p_in = _variables(paths["plant"], "input")
    p_out = _variables(paths["plant"], "output")
    p_vr = {v.name: v.valueReference for v in p_out}
    c_vr = {v.name: v.valueReference for v in c_out}
    log = {v.name: np.zeros(n) for v in (*p_out, *c_out)}
    try:
        for k in range(n):
            t = k * T_s
            y = dict(zip(p_vr, plant.getReal(list(p_vr.values())), strict=True))
            controller.setReal([v.valueReference for v in c_in], [y[v.name] for v in c_in])
            controller.doStep(t, T_s)
            u = dict(zip(c_vr, controller.getReal(list(c_vr.values())), strict=True))
            plant.setReal([v.valueReference for v in p_in], [u[v.name] for v in p_in])
            for name in p_vr:
                log[name][k] = y[name]
            for name in c_vr:
                log[name][k] = u[name]
            plant.doStep(t, T_s)
    finally:
        for slave in slaves.values():
            slave.terminate()
            slave.freeInstance()
    return log


def compare_fmus(setup, duration: float | None = None, parts=PARTS) -> dict:
    """Build the FMUs ``parts`` of ``setup`` in a scratch folder and compare them with acdrive's
    run (module docstring): per check, per signal (max |difference|, peak, ratio). The closed
    loop needs both; a check not run is None."""
    from fmpy import simulate_fmu

    from acdrive._jit import STRICT_MATH
    from acdrive.export._scenario import shortened

    setup = shortened(setup, duration, "--duration")
    drive, initial, held = built(setup)
    system, T_s = drive.system, setup.sample_time
    compiled = system.compile()
    result = compiled.run(setup.duration, T_s, setup.substeps, initial=initial, held=held)
    log = {c: result.data[:, j] for j, c in enumerate(result.columns)}
    n = result.data.shape[0]
    times = np.arange(n) * T_s

    def columns(parts):
        return {f"{q.path}{s}" for m in parts for q in m.out for s in ("", ".re", ".im")}

    modulated = columns(system.modulators)
    # a switching modulator's output changes within a period: acdrive logs its first segment
    # (just after t_k), the FMU shows the last one (just before t_{k+1}), so it is not compared
    switching = columns([m for m in system.modulators if m.MAX_SEGMENTS > 1])
    # acdrive logs a modulator's output of t_k after modulating at t_k; what the controller read
    # at t_k, and what the plant FMU shows at t_k, is the one before (the held value at t_0)
    Y0 = system.pack_held(held)
    before = {c: np.concatenate(([Y0[slot]], log[c][:-1]))
              for c, _, slot in system.log_columns() if c in modulated}  # fmt: skip
    report = {"scenario": setup.name, "duration": setup.duration, "samples": n,
              "strict_math": STRICT_MATH, "plant_tolerance": PLANT_TOLERANCE,
              "controller": None, "plant": None, "closed_loop": None,
              "not_compared": sorted(c for c, _, _ in system.log_columns() if c in switching)}  # fmt: skip
    kw = {"start_time": 0.0, "stop_time": (n - 1) * T_s, "output_interval": T_s}
    with tempfile.TemporaryDirectory(prefix="acdrive-fmu-") as scratch:
        paths = scenario_fmus(setup, parts, Path(scratch))
        names = {(part, causality): [v.name for v in _variables(path, causality)]
                 for part, path in paths.items() for causality in ("input", "output")}  # fmt: skip
        if "controller" in paths:
            c_in, c_out = names[("controller", "input")], names[("controller", "output")]
            if switching & set(c_in):
                raise InputError("scenario", "its controller reads a switching modulator's "
                                 "output, which acdrive's log holds only per sample: not "
                                 "checkable against the log")  # fmt: skip
            c_run = simulate_fmu(str(paths["controller"]),
                                 input=_inputs(c_in, times, {**log, **before}), output=c_out, **kw)  # fmt: skip
            # the command of sample k is the output after the step from t_k, at t_{k+1}
            controller = {c: c_run[c][1:] for c in c_out}
            report["controller"] = _worst(_signals(c_out, log, controller))
        if "plant" in paths:
            p_in = names[("plant", "input")]
            p_out = [c for c in names[("plant", "output")] if c not in switching]
            p_run = simulate_fmu(str(paths["plant"]), input=_inputs(p_in, times, log),
                                 output=p_out, **kw)  # fmt: skip
            reference = {**log, **before}
            report["plant"] = _worst(_signals(p_out, reference, p_run))
        if len(paths) == 2:
            closed = _closed_loop(paths, n, T_s)
            both = [c for c in (*names[("plant", "output")], *names[("controller", "output")])
                    if c not in switching]  # fmt: skip
            report["closed_loop"] = _worst(_signals(both, {**log, **before}, closed))
    return report
