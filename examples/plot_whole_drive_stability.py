"""
Whole-drive stability of the DFIM speed drive
=============================================

Linearise the complete voltage-command DFIM drive (machine, controller law, speed PI) with an
ideal converter at one operating point, for a slow speed loop and for the paper's a_D,VEL = 314
rad/s, and plot the eigenvalues. The verdicts printed and in the legend are computed from the
largest real part (the stability theory page explains the lightly damped stator-flux mode).
"""

import matplotlib.pyplot as plt

from acdrive.analysis import DriveModel, OperatingPoint, linearize

point = OperatingPoint(speed=150.0, load_torque=0.05)  # rad/s, N m
fig, ax = plt.subplots(figsize=(6, 4))
for bandwidth, marker in ((100.0, "o"), (314.0, "x")):
    result = linearize(DriveModel(mode="voltage", speed_bandwidth=bandwidth), point)
    verdict = "stable" if result.stable else "unstable"
    ax.plot(
        result.eigenvalues.real,
        result.eigenvalues.imag,
        marker,
        ls="",
        label=f"a_D,VEL = {bandwidth:g} rad/s: {verdict}",
    )
    print(f"a_D,VEL = {bandwidth:g}: largest real part {result.max_real_part:.2f} 1/s ({verdict})")
ax.axvline(0.0, color="k", lw=0.6)
ax.set_xlim(-400, 100)
ax.set_ylim(-600, 600)
ax.set_xlabel("real part [1/s]")
ax.set_ylabel("imaginary part [rad/s]")
ax.legend()
fig.tight_layout()
