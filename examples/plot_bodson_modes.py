"""
Voltage command against current command (Bodson, Figs. 8-11)
============================================================

The same DFIM drive and speed steps, once with the open-loop voltage-command law and once with
rotor-current feedback. ``DriveSetup.with_mode`` switches every controller of a scenario.
"""

import matplotlib.pyplot as plt

from acdrive.drives import simulate
from acdrive.scenarios import load_scenario

setup = load_scenario("bodson-step")
fig, ax = plt.subplots(figsize=(7, 3.5))
for mode in ("voltage", "current"):
    result = simulate(setup.with_mode(mode))
    ax.plot(result.t, result.speed_rpm(), lw=0.8, label=f"{mode} command")
ax.plot(result.t, result.reference_rpm(), "k--", lw=0.8, label="reference")
ax.set_xlabel("time [s]")
ax.set_ylabel("speed [rpm]")
ax.legend()
fig.tight_layout()
