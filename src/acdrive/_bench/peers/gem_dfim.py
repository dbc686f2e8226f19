"""Peer run for ``acdrive bench``: gym-electric-motor 3.0.3's doubly-fed induction motor, open loop.

Runs in GEM's own virtualenv (made by ``acdrive._bench.venvs``), never with acdrive on the path:

    python gem_dfim.py --case case.json --actions actions.npy [--out run.npz] [--repeats 1]
    python gem_dfim.py --serve

``case.json`` (written by ``acdrive._bench.gem_dfim``) holds the machine, load, supply and control
period; ``actions.npy`` the action of every control step, shape (n, 6): GEM's normalised duty
commands in [-1, 1] of the stator bridge (phases a, b, c) then the rotor bridge (phases d, e, f,
rotor coordinates). The environment is ``Cont-SC-DFIM-v0`` built headless with those values,
GEM's default solver (scipy ``ode`` dopri5 with its default tolerances) and a viscous
``PolynomialStaticLoad``; its limits are set wide so that no constraint ends an episode.

Three kinds of run, each from a fresh environment:

* ``env.step`` over all actions (how GEM's users run it: physical system, reference generator,
  reward and constraint monitor);
* ``physical_system.simulate`` alone over the same actions (the simulator without the
  reinforcement-learning wrapper);
* with ``--out``: one more ``env.step`` run recording, at every step, GEM's ODE state at the
  step's start (load then motor states: omega, i_salpha, i_sbeta, psi_ralpha, psi_rbeta,
  epsilon, peak-value scaling) and the stator and rotor voltages GEM handed to its solver for
  that step (stationary frame), plus the final state.

The timed kinds (``window``) time only the loop over the actions, in this process's CPU time
(``_serve.cpu_window``), ``--repeats`` runs each. Alone, the script prints one JSON line; with
``--serve`` it answers the suite's commands (``about``, ``load``, ``window``, ``record``; see
``_serve.py``), so that the suite interleaves these windows with acdrive's.
"""

from __future__ import annotations

import argparse
import json
import platform
from importlib.metadata import version

import gym_electric_motor as gem
import numpy as np
from _serve import cpu_window, serve
from gym_electric_motor.physical_systems import PolynomialStaticLoad

ENV_ID = "Cont-SC-DFIM-v0"


def make_env(case: dict):
    """The DFIM environment of ``case`` (see the module docstring)."""
    m = case["machine"]
    motor_parameter = {
        "p": m["n_p"],
        "r_s": m["R_s"],
        "r_r": m["R_r"],
        "l_m": m["M"],
        "l_sigs": m["L_s"] - m["M"],
        "l_sigr": m["L_r"] - m["M"],
        "j_rotor": case["J"] - case["j_load"],
    }
    wide = case["limits"]
    motor = {
        "motor_parameter": motor_parameter,
        "limit_values": {"i": wide["i"], "u": case["u_sup"], "omega": wide["omega"]},
        "nominal_values": {"i": wide["i"], "u": case["u_sup"], "omega": wide["omega"]},
    }
    load = PolynomialStaticLoad(
        load_parameter={"a": 0.0, "b": case["B"], "c": 0.0, "j_load": case["j_load"]},
        limits={"omega": wide["omega"]},
    )
    return gem.make(
        ENV_ID,
        tau=case["tau"],
        supply={"u_nominal": case["u_sup"]},
        motor=motor,
        load=load,
        visualization=(),
    )


def prepared(case: dict):
    """A fresh environment of ``case``, reset (untimed: building the model)."""
    env = make_env(case)
    env.reset(seed=0)
    return env


def env_steps(env, actions: np.ndarray, ended: list) -> int:
    """``env.step`` over all actions (reset where an episode ends, counted in ``ended``)."""
    for action in actions:
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            ended.append(1)
            env.reset()
    return len(actions)


def physical_steps(env, actions: np.ndarray) -> int:
    """``physical_system.simulate`` alone over all actions."""
    simulate = env.unwrapped.physical_system.simulate
    for action in actions:
        simulate(action)
    return len(actions)


LOADED: dict = {}


def load(case: str, actions: str) -> dict:
    """Read the case (JSON) and the actions (.npy) that the next commands use."""
    with open(case, encoding="utf-8") as f:
        LOADED["case"] = json.load(f)
    LOADED["actions"] = np.load(actions)
    return {"control_steps": len(LOADED["actions"])}


def window(kind: str, runs: int = 1) -> dict:
    """``runs`` timed runs over the loaded actions (``_serve.cpu_window``, this process's CPU
    time): ``kind`` "physical" (``physical_system.simulate``) or "env" (``env.step``)."""
    case, actions = LOADED["case"], LOADED["actions"]
    ended: list = []
    if kind == "physical":
        out = cpu_window(lambda: prepared(case), lambda env: physical_steps(env, actions), runs)
    elif kind == "env":
        out = cpu_window(lambda: prepared(case), lambda env: env_steps(env, actions, ended), runs)
        out["episodes_ended_early"] = len(ended)
    else:
        raise ValueError(f"kind must be physical or env, got {kind!r}")
    return out


def save_record(out: str) -> dict:
    """One recorded ``env.step`` run over the loaded actions (``record``), saved to ``out``."""
    rec = record(LOADED["case"], LOADED["actions"])
    np.savez(out, **{k: v for k, v in rec.items() if k != "ended"})
    return {"recorded_episodes_ended_early": rec["ended"]}


def about() -> dict:
    return {
        "peer": "gym-electric-motor",
        "version": version("gym-electric-motor"),
        "env": ENV_ID,
        "python": platform.python_version(),
        "numpy": version("numpy"),
        "scipy": version("scipy"),
        "gymnasium": version("gymnasium"),
    }


def record(case: dict, actions: np.ndarray) -> dict:
    """States at each step start and the voltages GEM integrated (module docstring)."""
    env = make_env(case)
    env.reset(seed=0)
    ps = env.unwrapped.physical_system
    solver = ps._ode_solver
    applied = []
    set_f_params = solver.set_f_params

    def recording(*args):
        applied.append(np.array(args[0], dtype=float))
        return set_f_params(*args)

    solver.set_f_params = recording
    states = []
    ended = 0
    for action in actions:
        states.append(np.array(solver.y, dtype=float))
        before = len(applied)
        _, _, terminated, truncated, _ = env.step(action)
        if len(applied) - before != 1:
            raise RuntimeError("GEM integrated a step in more than one segment")
        ended += int(terminated or truncated)
    states.append(np.array(solver.y, dtype=float))
    u = np.array(applied)  # (n, 2, 2): [stator (alpha, beta), rotor (alpha, beta)]
    return {
        "t": np.arange(len(actions)) * case["tau"],
        "states": np.array(states),
        "u_s": u[:, 0, 0] + 1j * u[:, 0, 1],
        "u_r": u[:, 1, 0] + 1j * u[:, 1, 1],
        "ended": ended,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--serve", action="store_true", help="answer the suite's commands")
    parser.add_argument("--case", help="case description (JSON)")
    parser.add_argument("--actions", help="actions, shape (n, 6) (.npy)")
    parser.add_argument("--out", help="save the recorded run (.npz)")
    parser.add_argument("--repeats", type=int, default=1, help="timed runs per kind")
    args = parser.parse_args()
    if args.serve:
        serve({"about": about, "load": load, "window": window, "record": save_record})
        return
    if not (args.case and args.actions):
        parser.error("--case and --actions are needed without --serve")
    out = {**about(), **load(args.case, args.actions)}
    for kind in ("env", "physical"):
        w = window(kind, args.repeats)
        out[kind] = {**w, "steps_per_cpu_s": w["steps_per_run"] * w["runs"] / w["cpu_s"]}
    if args.out:
        out.update(save_record(args.out))
    print(json.dumps(out))


if __name__ == "__main__":
    main()
