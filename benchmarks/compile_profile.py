"""Where the compile of a topology's specialised loop goes, and what the native loop costs
instead (``acdrive.sim._tier``).

    python benchmarks/compile_profile.py [scenario | im4 ...]

For each scenario (or ``im4``: the 4-part hand-built cage-IM system of tests/test_system.py), in
a fresh process: the topology's own cache entries are removed (its generated module and numba's
files of it; acdrive's helpers stay cached, as on a machine that ran other drives), the
specialised loop is compiled with numba's event recorders listening, and the exclusive thread
CPU time of every compiler stage is summed (type inference, numba-IR inlining of the
``inline="always"`` kernels, lowering to LLVM IR, LLVM's optimisation and code generation). Then
the native loop's first result of the same topology is timed: its C generated from the kernels,
compiled by the C compiler (or loaded), the run; and both tiers' run in thread CPU time. Prints
JSON.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

SCENARIOS = ("bodson-ramp", "im-foc-speed", "im4")

WORKER = r"""
import collections, json, os, re, sys, time, warnings
warnings.simplefilter("ignore")
from numba.core import event

name = sys.argv[1]


def build(name):
    if name == "im4":
        from acdrive.control._open_loop import VoltageProgram
        from acdrive.machines._cage_part import CageInductionMachine
        from acdrive.machines._induction import UGALDE_IM_300W
        from acdrive.plant._converter import AveragedConverter
        from acdrive.plant._mechanics import Shaft
        from acdrive.sim._system import System

        im = CageInductionMachine.from_params("im", UGALDE_IM_300W)
        shaft = Shaft("shaft", J=UGALDE_IM_300W.J, B=1e-5)
        program = VoltageProgram("program", V_pk=100.0, f=50.0)
        inverter = AveragedConverter("inverter", V_dc=310.0)
        wires = [(program.out.v_ref, inverter.inp.v_ref), (inverter.out.v, im.inp.v_s),
                 (shaft.out.w, im.inp.w), (im.out.tau_e, shaft.inp.tau_e)]
        system = System([im, shaft, program, inverter], wires)
        return system, dict(duration=1.0, sample_time=1e-4, substeps=4, log=[im.out.i_s])
    from acdrive.scenarios import load_scenario

    setup = load_scenario(name)
    setup = setup.runs()[0][1] if hasattr(setup, "runs") and setup.runs() else setup
    from acdrive.drives.dfim._drive import DFIMDrive
    from acdrive.drives.cage_im._drive import IMDrive
    inner = DFIMDrive(setup) if hasattr(setup, "motors") else IMDrive(setup)
    initial, held = inner.initial()
    ports = inner.log_ports()
    ports = list(ports.values()) if isinstance(ports, dict) else ports
    return inner.system, dict(duration=setup.duration, sample_time=setup.sample_time,
                              substeps=setup.substeps, initial=initial, held=held, log=ports)


system, run = build(name)
from acdrive.sim import _codegen as codegen

if sys.argv[2] == "specialised":
    path = codegen.module_path(system.source())
    module = codegen.load_module(system.source())
    index = module.run._cache._cache_file._index_path
    folder = os.path.dirname(index)
    stem = path.stem
    for f in os.listdir(folder):
        if f.startswith(stem + "."):
            os.remove(os.path.join(folder, f))
    os.environ["ACDRIVE_LOOP_TIER"] = "specialised"
    stages = collections.Counter()

    class Listener(event.Listener):
        def __init__(self):
            self.stack = []

        def on_start(self, ev):
            label = ev.kind
            if ev.kind == "numba:run_pass":
                label = re.sub(r" \[.*\]$", "", ev.data["name"])
            self.stack.append([label, time.thread_time(), 0.0])

        def on_end(self, ev):
            label, start, child = self.stack.pop()
            total = time.thread_time() - start
            stages[label] += total - child
            if self.stack:
                self.stack[-1][2] += total

    listener = Listener()
    for kind in ("numba:compile", "numba:llvm_lock", "numba:run_pass"):
        event.register(kind, listener)
    t0, c0 = time.perf_counter(), time.thread_time()
    compiled = system.compile()
    wall, cpu = time.perf_counter() - t0, time.thread_time() - c0
    for kind in ("numba:compile", "numba:llvm_lock", "numba:run_pass"):
        event.unregister(kind, listener)
    groups = {"type inference": ("nopython_type_inference",),
              "numba-IR inlining": ("inline_inlinables", "inline_closure_likes", "inline_overloads"),
              "lowering to LLVM IR": ("native_lowering",),
              "LLVM optimisation and code generation": ("numba:llvm_lock",)}
    out = {g: round(sum(stages[k] for k in keys), 3) for g, keys in groups.items()}
    grouped = {k for keys in groups.values() for k in keys}
    out["other numba passes"] = round(sum(v for k, v in stages.items() if k not in grouped), 3)
    result = {"compile_wall_s": round(wall, 3), "compile_thread_cpu_s": round(cpu, 3),
              "stages_thread_cpu_s": out, "parts": len(system.parts)}
else:
    os.environ["ACDRIVE_LOOP_TIER"] = "native"
    t0 = time.perf_counter()
    compiled = system.compile()
    result = {"native_prepare_s": round(time.perf_counter() - t0, 3),
              "compiled_now": compiled.compiled_now, "parts": len(system.parts)}
c0 = time.thread_time()
r = compiled.run(**run)
result["run_thread_cpu_s"] = round(time.thread_time() - c0, 3)
result["steps"] = r.steps
print(json.dumps(result))
"""


def _measure(name: str, tier: str) -> dict:
    out = subprocess.run([sys.executable, "-c", WORKER, name, tier], check=True,
                         capture_output=True, text=True, env=dict(os.environ)).stdout  # fmt: skip
    return json.loads(out.strip().splitlines()[-1])


def main(argv: list[str]) -> int:
    report = {}
    for name in argv or SCENARIOS:
        report[name] = {"specialised": _measure(name, "specialised"),
                        "native": _measure(name, "native")}  # fmt: skip
    print(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
