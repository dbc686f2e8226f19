"""
Locked-rotor current tracking: ICAD controller (20) against the PI (Amezquita-Brooks et al., Fig. 11)
=====================================================================================================

The cage IM held at standstill, fed by the two-level SVPWM inverter, follows sinusoidal current
references at 300 rad/s with the stationary-frame controllers. The built-in scenario runs both
controllers; the summary gives each one's RMS tracking error.
"""

import matplotlib.pyplot as plt

from acdrive.drives import run_im_scenario
from acdrive.scenarios import load_scenario

outcome = run_im_scenario(load_scenario("im-locked-rotor"))

fig, ax = plt.subplots(figsize=(7, 3.5))
for label, result in outcome.results.items():
    error = result.current_rms_error()
    ax.plot(
        result.t, result.phase_peak("i_s").real, lw=0.7, label=f"{label} (RMS error {error:.3g} A)"
    )
ax.set_xlabel("time [s]")
ax.set_ylabel("i_alpha [A, phase peak]")
ax.legend()
fig.tight_layout()
