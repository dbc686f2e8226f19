"""
A sweep: the tolerated speed-loop bandwidth across load
=======================================================

Vary the speed-loop bandwidth a_D,VEL of Bodson's voltage-command DFIM drive and its load
torque, run every variant in the compiled batch loop on all cores, and read the on-line metrics:
the band-limited speed oscillation at the end of each run says which bandwidths the drive
tolerates. (``acdrive sweep dfim-bandwidth`` is the full version, with converter losses, a
resumable Parquet table, a report and the cross-check against the linearised drive.)
"""

import matplotlib.pyplot as plt
import numpy as np

from acdrive.batch import simulate_batch

bandwidths = np.geomspace(100.0, 800.0, 7)  # rad/s
loads = (0.0, 0.1)  # N m
fixed = {
    "simulation.duration": 1.5,
    "motor[0].speed_reference_rpm": [[0.0, 0.0], [0.1, 0.0], [1.1, 950.0], [1.5, 950.0]],
}
variants = [
    {**fixed, "motor[0].controller.speed_bandwidth": float(bw), "motor[0].load_torque": tl}
    for tl in loads
    for bw in bandwidths
]
batch = simulate_batch("bodson-ramp-ideal", variants)
table = batch.to_dataframe()
print(f"{len(table)} variants, {batch.steps} control steps in {batch.wall_time:.2f} s")

fig, ax = plt.subplots(figsize=(7, 3.5))
for k, tl in enumerate(loads):
    rows = table.iloc[k * len(bandwidths) : (k + 1) * len(bandwidths)]
    ax.semilogx(bandwidths, rows["speed_oscillation_late_rpm"], "o-", label=f"load {tl:g} N m")
ax.set_xlabel("speed-loop bandwidth a_D,VEL [rad/s]")
ax.set_ylabel("late speed oscillation [rpm RMS]")
ax.legend()
fig.tight_layout()
print(
    table[["stable", "speed_oscillation_late_rpm"]].assign(
        bandwidth=[v["motor[0].controller.speed_bandwidth"] for v in variants]
    )
)
