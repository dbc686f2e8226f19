"""Peer run for ``acdrive bench``: motulator-export 0.11's native C simulation of the same drive.

motulator-export ports motulator's control system to C and simulates the drive natively, with
motulator's interface (``motulator_export.native.Simulation``). It runs in its own virtualenv
(motulator-export 0.11 installs motulator 0.18 and needs Python >= 3.12; ``acdrive bench``
makes it, see ``acdrive._bench.venvs``), never with acdrive on the path:

    python motulator_export_im.py --converter {averaged,pwm} --loop {c,callbacks} [--seconds 1.5]
    python motulator_export_im.py --serve

The case is ``motulator_im.py``'s (imported from beside this file: the same machine, converter,
controller and configuration, built by motulator's own classes), simulated by motulator-export
in two ways:

* ``--loop callbacks``: ``native.Simulation(mdl, ctrl).simulate`` with the case's speed
  reference and load torque as the Python functions of ``motulator_im.py``, which the C loop
  calls at every evaluation, and the results assembled into motulator's time series after the
  run (what a motulator user gets by swapping the ``Simulation`` class);
* ``--loop c``: the native system alone (``Simulation``'s native system, made and started
  untimed, then one ``run`` to the end time timed), with the speed reference as a
  ``StepSignal`` at the same instant and the load ramp as a ``StepSignal`` staircase that the
  C loop evaluates without Python: ``LOAD_STAIRS`` equal steps, one at the middle of each of the
  ramp's samples (the same torque impulse per sample as the ramp); no Python runs in the timed
  call and nothing is converted to motulator's time series.

Commands (``--serve``, see ``_serve.py``): ``about``; ``window`` (``runs`` timed runs in this
process's CPU time, ``loop`` as above); ``record`` (one run of ``loop``, the model state at
every sampling instant and at the end saved to ``out`` in the layout of ``motulator_im.py``'s
record, without the segments).
"""

from __future__ import annotations

import argparse
import json
import platform
from importlib.metadata import version

import numpy as np
from _serve import cpu_window, serve
from motulator_export import StepSignal, native
from motulator_im import DURATION, LOAD_RAMP, T_LOAD, T_S, T_STEP, U_DC, W_REF, build, nom

LOOPS = ("c", "callbacks")
#: steps of the load staircase of the ``c`` loop, one per sample of the 1 ms ramp
LOAD_STAIRS = round(LOAD_RAMP / T_S)


def load_staircase() -> StepSignal:
    """The load ramp as ``LOAD_STAIRS`` steps of nom.tau / LOAD_STAIRS, each at the middle of
    one of the ramp's samples (away from the sampling instants)."""
    times = [T_LOAD + (k + 0.5) * LOAD_RAMP / LOAD_STAIRS for k in range(LOAD_STAIRS)]
    levels = [nom.tau * (k + 1) / LOAD_STAIRS for k in range(LOAD_STAIRS)]
    return StepSignal(times, levels)


def build_native(pwm: bool, loop: str):
    """motulator's model and control system of the case and the native ``Simulation`` of them;
    for the ``c`` loop the reference and the load replaced by step signals (module docstring)."""
    if loop not in LOOPS:
        raise ValueError(f"loop must be one of {LOOPS}, got {loop!r}")
    sim = build(pwm)
    if loop == "c":
        sim.ctrl.set_speed_ref(StepSignal(T_STEP, W_REF))
        sim.mdl.mechanics.set_external_load_torque(load_staircase())
    return native.Simulation(sim.mdl, sim.ctrl, show_progress=False)


def started_system(nsim):
    """The native system of ``nsim`` made, started and given its signals, as ``simulate`` does
    on its first call (motulator-export 0.11's ``Simulation``), ready for ``run``."""
    mdl, ctrl = nsim.mdl, nsim.ctrl
    system = nsim._system_type(mdl, ctrl)
    system.start(mdl, nsim._t_start, ctrl.t, nsim._solver_cfg)
    system.set_signals(mdl, ctrl)
    system.set_enable(ctrl)
    return system


def run_c(system, seconds: float) -> int:
    """One run of the native loop to the first sampling instant after ``seconds``; the control
    steps it ran."""
    status = system.run(float(seconds), 0)
    if status != 0:
        raise RuntimeError(f"motulator-export's native loop stopped with status {status}")
    t_end, _ = system.state()
    return round(t_end / T_S)


def run_callbacks(nsim, seconds: float) -> int:
    res = nsim.simulate(t_stop=seconds)
    if not res.success:
        raise RuntimeError("motulator-export's native simulation reported failure")
    nsim.last_result = res
    return len(res.ctrl.t)


def window(converter: str, seconds: float, runs: int = 1, loop: str = "c") -> dict:
    """``runs`` timed runs of ``loop`` (``_serve.cpu_window``: building untimed)."""
    pwm = converter == "pwm"
    if loop == "c":
        out = cpu_window(
            lambda: started_system(build_native(pwm, "c")), lambda s: run_c(s, seconds), runs
        )
    else:
        out = cpu_window(
            lambda: build_native(pwm, "callbacks"), lambda s: run_callbacks(s, seconds), runs
        )
    out["loop"] = loop
    return out


def save_record(converter: str, seconds: float, out: str, loop: str = "c") -> dict:
    """One run of ``loop`` through ``Simulation.simulate`` (the same native loop, the signals of
    ``loop``), then the model state at every sampling instant (the first output row at or after
    it) and at the end, saved to ``out`` (.npz)."""
    nsim = build_native(converter == "pwm", loop)
    res = nsim.simulate(t_stop=seconds)
    mdl = nsim.mdl
    t_mdl = np.asarray(res.mdl.t)
    t_ctrl = np.asarray(res.ctrl.t)
    rows = np.searchsorted(t_mdl, t_ctrl - 1e-9 * T_S)
    np.savez(
        out,
        t=t_ctrl,
        psi_s=np.asarray(res.mdl.machine.psi_s_ab)[rows],
        psi_r=np.asarray(res.mdl.machine.psi_r_ab)[rows],
        w_M=np.real(np.asarray(res.mdl.mechanics.w_M))[rows],
        final_t=mdl.t0,
        final_psi_s=complex(mdl.machine.state.psi_s_ab),
        final_psi_r=complex(mdl.machine.state.psi_r_ab),
        final_w_M=float(np.real(mdl.mechanics.state.w_M)),
        u_dc=U_DC,
        T_s=T_S,
    )
    return {
        "recorded_loop": loop,
        "recorded_control_steps": len(t_ctrl),
        "recorded_final_speed_rad_s": float(np.real(mdl.mechanics.state.w_M)),
    }


def about() -> dict:
    from motulator_export.native._build import FLAGS

    return {
        "peer": "motulator-export",
        "version": version("motulator-export"),
        "motulator": version("motulator"),
        "python": platform.python_version(),
        "numpy": version("numpy"),
        "c_flags": FLAGS,
        "load_stairs_of_c_loop": LOAD_STAIRS,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--serve", action="store_true", help="answer the suite's commands")
    parser.add_argument("--converter", choices=("averaged", "pwm"), default="averaged")
    parser.add_argument("--loop", choices=LOOPS, default="c")
    parser.add_argument("--seconds", type=float, default=DURATION, help="model time [s]")
    parser.add_argument("--repeats", type=int, default=1, help="timed runs (one window)")
    args = parser.parse_args()
    if args.serve:
        serve({"about": about, "window": window, "record": save_record})
        return
    out = {**about(), "converter": args.converter}
    w = window(args.converter, args.seconds, args.repeats, args.loop)
    out.update(w)
    out["steps_per_cpu_s"] = w["steps_per_run"] * w["runs"] / w["cpu_s"]
    print(json.dumps(out))


if __name__ == "__main__":
    main()
