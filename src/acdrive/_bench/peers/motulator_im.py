"""Peer run for ``acdrive bench``: motulator 0.18's 2.2 kW cage-IM speed drive.

Runs in motulator's own virtualenv (motulator 0.18 needs Python >= 3.12; ``acdrive bench`` makes
it, see ``acdrive._bench.venvs``), never with acdrive on the path:

    python motulator_im.py --converter {averaged,pwm} [--seconds 1.5] [--out run.npz]
    python motulator_im.py --serve
    python motulator_im.py --first-result [--converter averaged] [--seconds 1.5]

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

Two kinds of run of the same case: timed windows (``window``: ``--repeats`` runs, only
``Simulation.simulate`` timed, in this process's CPU time, no progress bar, nothing recorded);
and one that records (``save_record``), at every sampling instant, the model state and the
switching sequence that ``Drive.modulate`` hands to the simulation loop (interval lengths and
switching states, or duty ratios with the averaged converter), which ``--out`` saves for the
suite's accuracy reference (``acdrive._bench.motulator_im``). ``--first-result`` is the
first-result race's process (``acdrive._bench.first_result``): build the case, simulate it once,
keep the result in memory and print its control steps, nothing timed or recorded (the suite takes
this whole process's CPU time). Alone, the script prints one JSON
line; with ``--serve`` it answers the suite's commands (``about``, ``window``, ``record``; see
``_serve.py``), so that the suite interleaves its windows with acdrive's.
"""

from __future__ import annotations

import argparse
import json
import platform
from importlib.metadata import version

import motulator.drive.control.im as control
import numpy as np
from _serve import cpu_window, serve
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


class ClampingSpeedPI(control.PIController):
    """acdrive's speed PI law (``control._speed.speed_pi`` with K_F = 1) in motulator's speed
    controller slot, for the ``clamping_speed_pi`` variant: tau = k_p e + k_i int(e) clipped to
    [-tau_max, tau_max], the integral advancing (forward Euler) only while unclipped, whatever
    torque the current limit then realises (motulator's own PI instead integrates towards the
    realised torque, anti-windup by back-calculation)."""

    def __init__(self, k_p: float, k_i: float, tau_max: float) -> None:
        super().__init__(k_p=k_p, k_i=k_i)
        self.k_i, self.tau_max = k_i, tau_max
        self.e_int, self._step = 0.0, 0.0

    def compute_output(self, y_ref: float, y: float, u_ff: float = 0.0) -> float:
        e = y_ref - y
        tau = self.k_p * e + self.k_i * self.e_int + u_ff
        self._step = 0.0 if abs(tau) > self.tau_max else e
        return min(max(tau, -self.tau_max), self.tau_max)

    def update(self, T_s: float, u: float) -> None:
        self.e_int += T_s * self._step


class FixedLimitSpeedPI(control.PIController):
    """motulator's speed PI (back-calculation on the realised torque) with its output clipped at
    a fixed ``tau_max`` before the current limit, for the ``fixed_limit_speed_pi`` variant: the
    integral then follows the fixed limit rather than the flux-dependent torque the current
    limit realises."""

    def __init__(self, k_p: float, k_i: float, tau_max: float) -> None:
        super().__init__(k_p=k_p, k_i=k_i)
        self.tau_max, self._u = tau_max, 0.0

    def compute_output(self, y_ref: float, y: float, u_ff: float = 0.0) -> float:
        u = super().compute_output(y_ref, y, u_ff)
        self._u = min(max(u, -self.tau_max), self.tau_max)
        return self._u

    def update(self, T_s: float, u: float) -> None:
        super().update(T_s, self._u)


#: the example as it is, with acdrive's speed PI, and with its own PI held to acdrive's fixed
#: torque limit, for the measured account of the remaining differences
#: (benchmarks/bench_matched_im.py)
VARIANTS = ("example", "clamping_speed_pi", "fixed_limit_speed_pi")
SPEED_PIS = {"clamping_speed_pi": ClampingSpeedPI, "fixed_limit_speed_pi": FixedLimitSpeedPI}


def build(pwm: bool, variant: str = "example", tau_max: float | None = None) -> model.Simulation:
    """The case; ``variant`` (``VARIANTS``): ``clamping_speed_pi`` replaces the speed PI by
    ``ClampingSpeedPI`` at ``tau_max`` [N m], ``fixed_limit_speed_pi`` by
    ``FixedLimitSpeedPI``."""
    if variant not in VARIANTS:
        raise ValueError(f"variant must be one of {VARIANTS}, got {variant!r}")
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
    if variant == "example":
        speed_ctrl = control.PIController(k_p=1, k_i=10)
    else:
        speed_ctrl = SPEED_PIS[variant](k_p=1, k_i=10, tau_max=tau_max)
    ctrl = control.VectorControlSystem(vector_ctrl, speed_ctrl)
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


def simulate(sim: model.Simulation, seconds: float) -> int:
    """Run ``sim`` for ``seconds`` of model time; the control-system calls it made (the loop runs
    to the first sample after ``seconds``)."""
    res = sim.simulate(t_stop=seconds)
    if not res.success:
        raise RuntimeError("motulator's solver reported failure")
    sim.last_result = res
    return len(res.ctrl.t)


def window(converter: str, seconds: float, runs: int = 1) -> dict:
    """``runs`` timed runs of the case (``_serve.cpu_window``: only ``Simulation.simulate`` is
    timed, in this process's CPU time) and the last run's final speed and peak current."""
    pwm = converter == "pwm"
    sims = []

    def prepare():
        sims.append(build(pwm))
        return sims[-1]

    out = cpu_window(prepare, lambda sim: simulate(sim, seconds), runs)
    res = sims[-1].last_result
    out["final_speed_rad_s"] = float(np.real(res.mdl.mechanics.w_M)[-1])
    out["peak_current_a"] = float(np.max(np.abs(np.asarray(res.mdl.machine.i_s_ab))))
    out["model_time_s"] = float(res.ctrl.t[-1] + T_S)
    return out


def save_record(
    converter: str, seconds: float, out: str, variant: str = "example", tau_max=None
) -> dict:
    """One more run recording the state and the segments at every sampling instant (``record``),
    saved to ``out`` (.npz) for the suite's accuracy reference and trajectory comparison;
    ``variant`` and ``tau_max``: ``build``'s."""
    sim = build(converter == "pwm", variant, tau_max)
    rec = record(sim)
    res = sim.simulate(t_stop=seconds)
    mdl = sim.mdl
    np.savez(
        out,
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
    return {
        "recorded_control_steps": len(res.ctrl.t),
        "recorded_final_speed_rad_s": float(np.real(res.mdl.mechanics.w_M)[-1]),
    }


def about() -> dict:
    return {
        "peer": "motulator",
        "version": version("motulator"),
        "python": platform.python_version(),
        "numpy": version("numpy"),
        "scipy": version("scipy"),
        "base": {"w_M": float(base.w_M), "psi": float(base.psi), "i": float(base.i)},
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--serve", action="store_true", help="answer the suite's commands")
    parser.add_argument("--out", help="save the recorded run (.npz) for the accuracy reference")
    parser.add_argument("--converter", choices=("averaged", "pwm"), default="pwm")
    parser.add_argument("--seconds", type=float, default=DURATION, help="model time [s]")
    parser.add_argument("--repeats", type=int, default=1, help="timed runs (one window)")
    parser.add_argument(
        "--first-result", action="store_true", help="build, simulate once, print the steps"
    )
    args = parser.parse_args()
    if args.first_result:
        sim = build(args.converter == "pwm")
        print(json.dumps({"steps": simulate(sim, args.seconds)}))
        return
    if args.serve:
        serve({"about": about, "window": window, "record": save_record})
        return
    out = {**about(), "converter": args.converter}
    w = window(args.converter, args.seconds, args.repeats)
    out.update(w)
    out["steps_per_cpu_s"] = w["steps_per_run"] * w["runs"] / w["cpu_s"]
    if args.out:
        out.update(save_record(args.converter, args.seconds, args.out))
    print(json.dumps(out))


if __name__ == "__main__":
    main()
