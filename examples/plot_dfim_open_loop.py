"""
An open-loop machine test built from parts
==========================================

Switch the DFIM's stator onto the grid with its rotor short-circuited, from a de-energised start:
the machine runs up as a cage motor. Built directly from parts (supply, relay, machine, shaft, a
zero rotor-voltage program) and compiled once for this topology.
"""

import matplotlib.pyplot as plt
import numpy as np

from acdrive.control import ComplexProgram
from acdrive.machines import BODSON_DFIM, DoublyFedMachine
from acdrive.plant import RelayCommand, Shaft, ThreePhaseSource
from acdrive.sim import System

grid = ThreePhaseSource("grid", V_pk=11.1, f=60.0)
relay = RelayCommand("relay", close_at=0.0)
dfim = DoublyFedMachine.from_params("dfim", BODSON_DFIM)
shaft = Shaft("shaft", J=BODSON_DFIM.J)
rotor = ComplexProgram("rotor")  # rotor voltage 0: short-circuited
system = System(
    [grid, relay, dfim, shaft, rotor],
    [
        (grid.out.v, dfim.inp.v_s),
        (relay.out.closed, dfim.inp.connected),
        (rotor.out.v_ref, dfim.inp.v_r),
        (dfim.out.tau_e, shaft.inp.tau_e),
        (shaft.out.w, dfim.inp.w),
    ],
)
result = system.compile().run(duration=1.0, sample_time=1e-4)

i_s = result.signal(dfim.out.i_s)
fig, axes = plt.subplots(3, 1, sharex=True, figsize=(7, 6))
axes[0].plot(result.t, np.abs(i_s), lw=0.6)
axes[0].set_ylabel("|i_S| [A]")
axes[1].plot(result.t, result.signal(dfim.out.tau_e), lw=0.6)
axes[1].set_ylabel("torque [N m]")
axes[2].plot(result.t, result.signal(shaft.out.w) * 30 / np.pi)
axes[2].set_ylabel("speed [rpm]")
axes[2].set_xlabel("time [s]")
fig.tight_layout()

# %%
# Without load the machine runs up towards synchronous speed, 60 f / n_p: the final speed beside it.
synchronous_rpm = 60.0 * 60.0 / BODSON_DFIM.n_p
final_rpm = result.signal(shaft.out.w)[-1] * 30 / np.pi
print(f"final speed {final_rpm:.1f} rpm, synchronous speed {synchronous_rpm:.0f} rpm")
