"""Peer run for ``acdrive bench``: motulator 0.18's 2.2 kW cage-IM speed drive.

Runs in motulator's own virtualenv (motulator 0.18 needs Python >= 3.12; ``acdrive bench`` makes
it, see ``acdrive._bench.venvs``), never with acdrive on the path:

    python motulator_im.py --converter {averaged,pwm} [--seconds 1.5] [--out run.npz]

The case is motulator's example ``examples/drive/current_vector/plot_2kw_im_sat_cvc.py``
(2.2 kW, 400 V, 50 Hz, 2 pole pairs, J = 0.015 kg m^2, 540 V DC link, default sampling period
125 us, speed step to 0.5 p.u. at 0.2 s, rated load torque 14.6 N m from 0.75 s, 1.5 s) with:

* the converter: ``--converter averaged`` is the example's own ``model.Drive(..., pwm=False)``
  (the duty ratios held over each sampling period); ``--converter pwm`` is ``pwm=True``: carrier
  comparison with exact switching instants (duty ratios updated at every sampling instant, i.e.
  twice per carrier period of 2 T_s = 250 us, 4 kHz); one sampling period of computational
  delay in the control system either way;
* the example's own alternative, unsaturated machine: inverse-Gamma parameters R_s = 3.7 ohm,
  R_R = 2.1 ohm, L_sgm = 21 mH, L_M = 224 mH (the example's saturated Gamma model has no linear
  counterpart in acdrive);
* sensored control (``sensorless=False``: the observer takes the measured rotor speed), as
  acdrive's drive, which reads its encoder;
* the speed step at 0.2 s + T_s/2 (the first sample after 0.2 s on both sides, whatever the
  rounding of the accumulated sample times) and the load as a 1 ms ramp from 0.75 s instead of
  a step (both simulators then integrate the same continuous load; a step at a sample instant
  falls on one side or the other of it by rounding).

Everything else is the example's: current-vector control with psi_s_nom = 0.95 psi_base,
i_s_max = 1.5 i_base, the 2DOF complex PI current controller (alpha_c = 2 pi 200 rad/s), the
speed PI k_p = 1, k_i = 10, motulator's default solver (RK45, rtol 1e-3, atol 1e-6).

Two kinds of run of the same case: the timed ones (``--repeats``, the best kept; only
``Simulation.simulate`` is timed, no progress bar, nothing recorded); then one that records, at
every sampling instant, the model state and the switching sequence that ``Drive.modulate`` hands to the simulation loop (interval lengths and
switching states, or duty ratios with the averaged converter), which ``--out`` saves for the
suite's accuracy reference (``acdrive._bench.motulator_im``). One JSON line is printed.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import time
from importlib.metadata import version

import motulator.drive.control.im as control
import numpy as np
from motulator.drive import model, utils

T_S = 125e-6  # s, motulator's default sampling period of current-vector control
DURATION = 1.5  # s
J = 0.015  # kg m^2
U_DC = 540.0  # V
PAR = {"n_p": 2, "R_s": 3.7, "R_R": 2.1, "L_sgm": 0.021, "L_M": 0.224}  # inverse-Gamma [ohm, H]
T_STEP = 0.2 + 0.5 * T_S  # s, speed step (first sample after 0.2 s)
T_LOAD, LOAD_RAMP = 0.75, 1e-3  # s, load ramp start and length

nom = utils.NominalValues(U=400, I=5, f=50, P=2.2e3, tau=14.6)
base = utils.BaseValues.from_nominal(nom, n_p=2)
W_REF = 0.5 * base.w_M  # rad/s, mechanical


def speed_reference(t: float) -> float:
    return W_REF if t > T_STEP else 0.0


def load_torque(t: float) -> float:
    return nom.tau * min(max((t - T_LOAD) / LOAD_RAMP, 0.0), 1.0)


def build(pwm: bool) -> model.Simulation:
    par = model.InductionMachineInvGammaPars(**PAR)
    mdl = model.Drive(
        model.InductionMachine(par),
        model.MechanicalSystem(J=J),
        model.VoltageSourceConverter(u_dc=U_DC),
        pwm=pwm,
    )
    mdl.mechanics.set_external_load_torque(load_torque)
    cfg = control.CurrentVectorControllerCfg(
        psi_s_nom=0.95 * base.psi, i_s_max=1.5 * base.i, T_s=T_S, sensorless=False
    )
    vector_ctrl = control.CurrentVectorController(control.InductionMachineInvGammaPars(**PAR), cfg)
    ctrl = control.VectorControlSystem(vector_ctrl, control.PIController(k_p=1, k_i=10))
    ctrl.set_speed_ref(speed_reference)
    return model.Simulation(mdl, ctrl, show_progress=False)


def record(sim: model.Simulation) -> dict:
    """Wrap ``Drive.modulate`` (called once per sampling instant, after the control system) to
    keep the state at the instant and the intervals the loop will integrate."""
    mdl = sim.mdl
    rec = {"t": [], "psi_s": [], "psi_r": [], "w_M": [], "n": [], "dt": [], "q": []}
    modulate = mdl.modulate

    def recording_modulate(T_s, d_abc):
        t_steps, q_abc, b_abc = modulate(T_s, d_abc)
        rec["t"].append(mdl.t0)
        rec["psi_s"].append(complex(mdl.machine.state.psi_s_ab))
        rec["psi_r"].append(complex(mdl.machine.state.psi_r_ab))
        rec["w_M"].append(float(np.real(mdl.mechanics.state.w_M)))
        rec["n"].append(len(t_steps))
        rec["dt"].extend(float(x) for x in t_steps)
        rec["q"].extend(np.asarray(q_abc, dtype=float).tolist())
        return t_steps, q_abc, b_abc

    mdl.modulate = recording_modulate
    return rec


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", help="save the recorded run (.npz) for the accuracy reference")
    parser.add_argument("--converter", choices=("averaged", "pwm"), default="pwm")
    parser.add_argument("--seconds", type=float, default=DURATION, help="model time [s]")
    parser.add_argument("--repeats", type=int, default=1, help="timed runs (the best is kept)")
    args = parser.parse_args()

    pwm = args.converter == "pwm"
    walls = []
    for _ in range(max(args.repeats, 1)):
        sim = build(pwm)
        start = time.perf_counter()
        res = sim.simulate(t_stop=args.seconds)
        walls.append(time.perf_counter() - start)
    wall = min(walls)
    steps = len(res.ctrl.t)  # control-system calls (the loop runs to the first sample after t_stop)
    w_M = np.real(res.mdl.mechanics.w_M)
    i_s = np.asarray(res.mdl.machine.i_s_ab)
    out = {
        "peer": "motulator",
        "version": version("motulator"),
        "converter": args.converter,
        "python": platform.python_version(),
        "numpy": version("numpy"),
        "scipy": version("scipy"),
        "success": bool(res.success),
        "model_time_s": float(res.ctrl.t[-1] + T_S),
        "control_steps": steps,
        "wall_s": wall,
        "wall_s_all_runs": walls,
        "steps_per_s": steps / wall,
        "real_time_factor": steps * T_S / wall,
        "final_speed_rad_s": float(w_M[-1]),
        "peak_current_a": float(np.max(np.abs(i_s))),
        "base": {"w_M": float(base.w_M), "psi": float(base.psi), "i": float(base.i)},
    }
    if args.out:
        sim2 = build(pwm)
        rec = record(sim2)
        res2 = sim2.simulate(t_stop=args.seconds)
        mdl = sim2.mdl
        np.savez(
            args.out,
            t=np.array(rec["t"]),
            psi_s=np.array(rec["psi_s"]),
            psi_r=np.array(rec["psi_r"]),
            w_M=np.array(rec["w_M"]),
            n=np.array(rec["n"], dtype=np.int64),
            dt=np.array(rec["dt"]),
            q=np.array(rec["q"]),
            final_t=mdl.t0,
            final_psi_s=complex(mdl.machine.state.psi_s_ab),
            final_psi_r=complex(mdl.machine.state.psi_r_ab),
            final_w_M=float(np.real(mdl.mechanics.state.w_M)),
            u_dc=U_DC,
            T_s=T_S,
        )
        out["recorded_run_matches_timed_run"] = bool(
            len(res2.ctrl.t) == steps
            and math.isclose(
                float(np.real(res2.mdl.mechanics.w_M)[-1]), float(w_M[-1]), rel_tol=0.0, abs_tol=0.0
            )
        )
    print(json.dumps(out))


if __name__ == "__main__":
    main()
