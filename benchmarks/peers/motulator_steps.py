"""Peer benchmark: control steps per second of a motulator induction-machine speed drive.

Run under the peer virtualenv (see requirements.txt), never with acdrive on the path:

    /tmp/peer/bin/python benchmarks/peers/motulator_steps.py [--seconds 2.0]

The drive is a cage induction machine with the electrical parameters of Bodson's DFIM (acdrive's
default machine, Bodson section IV-A: R_s = 0.66, R_r = 0.94, L_s = 13.1 mH, L_r = 9.8 mH,
M = 9.7 mH, n_p = 2, J = 3.5e-4) seen as a T-model with the rotor short-circuited, fed by an
averaged two-level converter on a 30 V DC link, under motulator's sensored current-vector control
with its speed controller, sampled at T_s = 200 us. The speed reference ramps from 0 to 1500 rpm
and then holds. Only ``Simulation.simulate`` is timed; one JSON line is printed.
"""

import argparse
import json
import math
import time
from importlib.metadata import version

import motulator.drive.control.im as im_control
from motulator.drive import model
from motulator.drive.utils import InductionMachineInvGammaPars, InductionMachinePars

T_S = 200e-6  # sampling period [s] (5 kHz control)

# Bodson IV-A machine, T-model values [ohm, H, kg m^2]
R_S, R_R, L_S, L_R, M, N_P, J = 0.66, 0.94, 13.1e-3, 9.8e-3, 9.7e-3, 2, 3.5e-4
U_DC = 30.0  # DC-link voltage [V]
NOM_U_S = 11.1  # nominal stator voltage, peak phase [V] (Bodson's supply)
NOM_F = 60.0  # nominal frequency [Hz]
MAX_I_S = 6.0  # stator current limit, peak [A]
B_L = 6e-4  # viscous load [Nm/(rad/s)]: about 0.1 Nm at 1500 rpm
SPEED_RPM = 1500.0  # end of the speed ramp


def inverse_gamma_parameters() -> InductionMachineInvGammaPars:
    """Inverse-Gamma equivalent of the T-model: L_M = M^2/L_r, L_sgm = L_s - L_M, R_R = (M/L_r)^2 R_r."""
    k_r = M / L_R
    L_M = k_r * M
    return InductionMachineInvGammaPars(
        n_p=N_P, R_s=R_S, R_R=k_r**2 * R_R, L_sgm=L_S - L_M, L_M=L_M
    )


def speed_reference(seconds: float):
    """Electrical rotor speed reference [rad/s]: ramp over the first 60 % of the run, then hold."""
    t_0, t_1 = 0.05 * seconds, 0.65 * seconds
    w_end = N_P * SPEED_RPM * 2.0 * math.pi / 60.0

    def w_m(t: float) -> float:
        return w_end * min(max((t - t_0) / (t_1 - t_0), 0.0), 1.0)

    return w_m


def build(seconds: float) -> model.Simulation:
    par = inverse_gamma_parameters()
    machine = model.InductionMachine(InductionMachinePars.from_inv_gamma_model_pars(par))
    mechanics = model.StiffMechanicalSystem(J=J, B_L=B_L)
    converter = model.VoltageSourceConverter(u_dc=U_DC)
    mdl = model.Drive(converter=converter, machine=machine, mechanics=mechanics)

    cfg = im_control.CurrentReferenceCfg(
        par, max_i_s=MAX_I_S, nom_u_s=NOM_U_S, nom_w_s=2.0 * math.pi * NOM_F
    )
    ctrl = im_control.CurrentVectorControl(par, cfg, J=J, T_s=T_S, sensorless=False)
    ctrl.ref.w_m = speed_reference(seconds)
    return model.Simulation(mdl, ctrl)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=2.0, help="model time to simulate [s]")
    args = parser.parse_args()

    sim = build(args.seconds)
    start = time.perf_counter()
    sim.simulate(t_stop=args.seconds)
    wall = time.perf_counter() - start

    steps = round(args.seconds / T_S)
    w_M_end = float(sim.mdl.mechanics.data.w_M[-1])
    print(
        json.dumps(
            {
                "peer": "motulator",
                "version": version("motulator"),
                "control_steps": steps,
                "wall_s": wall,
                "steps_per_s": steps / wall,
                "final_speed_rpm": w_M_end * 60.0 / (2.0 * math.pi),
            }
        )
    )


if __name__ == "__main__":
    main()
