"""Peer run for ``acdrive bench``: gym-electric-motor 3.0.3's doubly-fed induction motor, open loop.

Runs in GEM's own virtualenv (made by ``acdrive._bench.venvs``), never with acdrive on the path:

    python gem_dfim.py --case case.json --actions actions.npy [--out run.npz] [--repeats 3]

``case.json`` (written by ``acdrive._bench.gem_dfim``) holds the machine, load, supply and control
period; ``actions.npy`` the action of every control step, shape (n, 6): GEM's normalised duty
commands in [-1, 1] of the stator bridge (phases a, b, c) then the rotor bridge (phases d, e, f,
rotor coordinates). The environment is ``Cont-SC-DFIM-v0`` built headless with those values,
GEM's default solver (scipy ``ode`` dopri5 with its default tolerances) and a viscous
``PolynomialStaticLoad``; its limits are set wide so that no constraint ends an episode.

Three kinds of run, each from a fresh environment:

* ``env.step`` over all actions (how GEM's users run it: physical system, reference generator,
  reward and constraint monitor), best of ``--repeats``;
* ``physical_system.simulate`` alone over the same actions (the simulator without the
  reinforcement-learning wrapper), best of ``--repeats``;
* with ``--out``: one more ``env.step`` run recording, at every step, GEM's ODE state at the
  step's start (load then motor states: omega, i_salpha, i_sbeta, psi_ralpha, psi_rbeta,
  epsilon, peak-value scaling) and the stator and rotor voltages GEM handed to its solver for
  that step (stationary frame), plus the final state.

One JSON line is printed.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from importlib.metadata import version

import gym_electric_motor as gem
import numpy as np
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


def run_env(case: dict, actions: np.ndarray) -> tuple[float, int, np.ndarray]:
    """(wall time of the env.step loop, episodes ended early, final normalised state)."""
    env = make_env(case)
    env.reset(seed=0)
    ended = 0
    state = None
    start = time.perf_counter()
    for action in actions:
        (state, _), _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            ended += 1
            env.reset()
    return time.perf_counter() - start, ended, state


def run_physical(case: dict, actions: np.ndarray) -> float:
    """Wall time of ``physical_system.simulate`` over the actions, after a reset."""
    env = make_env(case)
    env.reset(seed=0)
    simulate = env.unwrapped.physical_system.simulate
    start = time.perf_counter()
    for action in actions:
        simulate(action)
    return time.perf_counter() - start


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
    parser.add_argument("--case", required=True, help="case description (JSON)")
    parser.add_argument("--actions", required=True, help="actions, shape (n, 6) (.npy)")
    parser.add_argument("--out", help="save the recorded run (.npz)")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    with open(args.case, encoding="utf-8") as f:
        case = json.load(f)
    actions = np.load(args.actions)
    n = len(actions)

    env_walls, ended = [], 0
    for _ in range(max(args.repeats, 1)):
        wall, k, _ = run_env(case, actions)
        env_walls.append(wall)
        ended = max(ended, k)
    phys_walls = [run_physical(case, actions) for _ in range(max(args.repeats, 1))]
    out = {
        "peer": "gym-electric-motor",
        "version": version("gym-electric-motor"),
        "env": ENV_ID,
        "python": platform.python_version(),
        "numpy": version("numpy"),
        "scipy": version("scipy"),
        "gymnasium": version("gymnasium"),
        "control_steps": n,
        "env_step_wall_s": min(env_walls),
        "env_step_steps_per_s": n / min(env_walls),
        "physical_system_wall_s": min(phys_walls),
        "physical_system_steps_per_s": n / min(phys_walls),
        "episodes_ended_early": ended,
    }
    if args.out:
        rec = record(case, actions)
        np.savez(args.out, **{k: v for k, v in rec.items() if k != "ended"})
        out["recorded_episodes_ended_early"] = rec["ended"]
    print(json.dumps(out))


if __name__ == "__main__":
    main()
