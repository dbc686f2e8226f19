"""
Design a current controller with ICAD, then run it on the switching inverter
============================================================================

Choose a stationary-frame PI for the DeLorenzo cage IM at standstill from a family of candidates
by its individual-channel margins, then run the chosen controller, the very object the analysis
took, in a time-domain simulation: 310 V DC link, two-level SVPWM at 5 kHz, 50 kHz control,
rotor locked, a 300 rad/s sinusoidal current reference.
"""

import matplotlib.pyplot as plt
import numpy as np

from acdrive.analysis import analyse, plant_for
from acdrive.control import FIG17_PI_FAMILY, PAPER_PI, CurrentProgram, StationaryCurrentController
from acdrive.machines import CageInductionMachine, machine_params
from acdrive.plant import DCSource, Inverter, PrescribedSpeed
from acdrive.sim import System

# %%
# The analysis: phase margin and bandwidth of channel 1 for every candidate.
plant = plant_for("delorenzo-im", 0.0)
candidates = (PAPER_PI, *FIG17_PI_FAMILY)
rows = []
for k in candidates:
    channel = analyse(plant, k, k).channels[0]
    rows.append((k, channel.margins.pm_deg, channel.bandwidth_rad_s))
    print(
        f"{k.name:>16}: phase margin {channel.margins.pm_deg:6.1f} deg, "
        f"bandwidth {channel.bandwidth_rad_s:8.0f} rad/s"
    )
# the widest bandwidth among the candidates with at least 60 degrees of phase margin
chosen = max((r for r in rows if r[1] >= 60.0), key=lambda r: r[2])[0]
print("chosen:", chosen.name)

# %%
# The simulation, built from parts around the chosen controller.
T_s, duration, amplitude, w_ref = 2e-5, 0.06, 2.0, 300.0
times = np.arange(0.0, duration + T_s, T_s)
reference = CurrentProgram.from_function(
    "reference", lambda t: amplitude * np.sqrt(1.5) * np.exp(1j * w_ref * t), times
)
dc = DCSource("dc", V=310.0)
machine = CageInductionMachine.from_params("machine", machine_params("delorenzo-im"))
rotor = PrescribedSpeed("rotor", w=0.0)
current = StationaryCurrentController("current", chosen, T_s, "tustin", v_dc_input=True)
inverter = Inverter("inverter", f_pwm=5000.0)
system = System(
    [dc, machine, rotor, reference, current, inverter],
    [
        (rotor.out.w, machine.inp.w),
        (machine.out.i_s, current.inp.i_meas),
        (reference.out.i, current.inp.i_ref),
        (dc.out.v_dc, current.inp.v_dc),
        (dc.out.v_dc, inverter.inp.v_dc),
        (current.out.v_ref, inverter.inp.v_ref),
        (machine.out.i_s, inverter.inp.i_s),
        (inverter.out.v, machine.inp.v_s),
    ],
)
result = system.compile().run(duration, T_s, substeps=4, log=[machine.out.i_s, reference.out.i])
i_s = result.signal(machine.out.i_s) / np.sqrt(1.5)  # phase peak
i_ref = result.signal(reference.out.i) / np.sqrt(1.5)

fig, ax = plt.subplots(figsize=(7, 3.5))
ax.plot(result.t, i_ref.real, "k--", lw=0.8, label="reference")
ax.plot(result.t, i_s.real, lw=0.7, label=f"i_alpha with {chosen.name}")
ax.set_xlabel("time [s]")
ax.set_ylabel("phase current [A, peak]")
ax.legend()
fig.tight_layout()
late = result.t > duration / 2
print(f"RMS tracking error (second half): {np.sqrt(np.mean(np.abs(i_ref - i_s)[late] ** 2)):.3f} A")
