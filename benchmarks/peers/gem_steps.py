"""Peer benchmark: control steps per second of a gym-electric-motor (GEM) DFIM environment.

Run under the peer virtualenv (see requirements.txt), never with acdrive on the path:

    /tmp/peer/bin/python benchmarks/peers/gem_steps.py [--seconds 2.0]

GEM 3.0.3 has a doubly-fed induction motor, so the environment is ``Cont-SC-DFIM-v0`` with
Bodson's DFIM parameters (acdrive's default machine, Bodson section IV-A: R_s = 0.66,
R_r = 0.94, L_s = 13.1 mH, L_r = 9.8 mH, M = 9.7 mH, n_p = 2, J = 3.5e-4), both windings fed by
GEM's averaged B6 bridges from a 30 V supply, control cycle tau = 200 us, GEM's default solver
(scipy ``ode`` dopri5). GEM's own controllers (gem_controllers) do not cover the DFIM and do not
import from a plain GEM 3.0.3 install, so the action sequence is a fixed open-loop policy
computed before the timed loop: rotor bridge at zero voltage (short-circuited rotor, i.e. the
machine runs as a cage motor) and a stator voltage vector rotating at a frequency that ramps from
0 to 60 Hz (1800 rpm synchronous; about 1500 rpm reached under the light load) with a
V/f-proportional amplitude plus an R_s boost.
Only the ``env.step`` loop is timed; one JSON line is printed.
"""

import argparse
import json
import math
import time
from importlib.metadata import version

import gym_electric_motor as gem
import numpy as np
from gym_electric_motor.physical_systems import PolynomialStaticLoad

TAU = 200e-6  # control cycle [s] (5 kHz control)
ENV_ID = "Cont-SC-DFIM-v0"

# Bodson IV-A machine in GEM's T-model terms [ohm, H, kg m^2]
R_S, R_R, L_S, L_R, M, N_P, J = 0.66, 0.94, 13.1e-3, 9.8e-3, 9.7e-3, 2, 3.5e-4
J_LOAD = 1e-5  # GEM needs a non-zero load inertia; J = j_rotor + j_load
U_SUP = 30.0  # DC supply of both bridges [V]; phase voltage = action * U_SUP / 2
NOM_U_S = 11.1  # stator voltage at NOM_F, peak phase [V] (Bodson's supply)
NOM_F = 60.0  # [Hz]
U_BOOST = 1.5  # low-frequency boost [V], about R_s times the magnetising current
B_L = 6e-4  # viscous load [Nm/(rad/s)]: about 0.1 Nm at 1500 rpm
F_END = 60.0  # end of the stator-frequency ramp [Hz]


def make_env():
    motor_parameter = {
        "p": N_P,
        "r_s": R_S,
        "r_r": R_R,
        "l_m": M,
        "l_sigs": L_S - M,
        "l_sigr": L_R - M,
        "j_rotor": J - J_LOAD,
    }
    motor = {
        "motor_parameter": motor_parameter,
        "limit_values": {"i": 10.0, "u": U_SUP, "omega": 300.0},
        "nominal_values": {"i": 6.0, "u": U_SUP, "omega": 200.0},
    }
    load = PolynomialStaticLoad(load_parameter={"a": 0.0, "b": B_L, "c": 0.0, "j_load": J_LOAD})
    return gem.make(
        ENV_ID,
        tau=TAU,
        supply={"u_nominal": U_SUP},
        motor=motor,
        load=load,
        visualization=(),  # headless: no dashboard collecting plot data every step
    )


def open_loop_actions(n_steps: int) -> np.ndarray:
    """Normalised bridge duty commands, shape (n_steps, 6): stator a, b, c, then rotor a, b, c."""
    t = np.arange(n_steps) * TAU
    seconds = n_steps * TAU
    t_0, t_1 = 0.05 * seconds, 0.65 * seconds
    f = F_END * np.clip((t - t_0) / (t_1 - t_0), 0.0, 1.0)
    theta = 2.0 * np.pi * np.cumsum(f) * TAU
    u_pk = U_BOOST + (NOM_U_S - U_BOOST) * f / NOM_F
    m = u_pk / (U_SUP / 2.0)
    actions = np.zeros((n_steps, 6))
    for k in range(3):
        actions[:, k] = m * np.cos(theta - 2.0 * np.pi * k / 3.0)
    return actions


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=2.0, help="model time to simulate [s]")
    args = parser.parse_args()

    n_steps = round(args.seconds / TAU)
    env = make_env()
    actions = open_loop_actions(n_steps)
    env.reset(seed=0)
    resets = 0
    start = time.perf_counter()
    for action in actions:
        (state, _), _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            resets += 1
            env.reset()
    wall = time.perf_counter() - start

    omega_limit = env.unwrapped.physical_system.limits[0]
    print(
        json.dumps(
            {
                "peer": "gym-electric-motor",
                "version": version("gym-electric-motor"),
                "env": ENV_ID,
                "control_steps": n_steps,
                "wall_s": wall,
                "steps_per_s": n_steps / wall,
                "final_speed_rpm": float(state[0] * omega_limit) * 30.0 / math.pi,
                "resets": resets,
            }
        )
    )


if __name__ == "__main__":
    main()
