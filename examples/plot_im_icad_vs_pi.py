"""
Controller (20) against the PI under a saturated speed law (Amezquita-Brooks et al., Fig. 16)
=============================================================================================

The saturated proportional speed law (21) asks for the largest torque until the speed nears 376
rad/s, so the ideal response is a constant-torque ramp. The scenario runs it with the ICAD current
controller (20) and with the PI (no decoupling, no back-EMF compensation); the printed summary
gives both controllers' RMS speed error to the ideal ramp, the same metric for both.
"""

import matplotlib.pyplot as plt

from acdrive.drives import run_im_scenario
from acdrive.scenarios import load_scenario

outcome = run_im_scenario(load_scenario("im-icad-vs-pi"))

fig, ax = plt.subplots(figsize=(7, 3.5))
for label, result in outcome.results.items():
    ax.plot(result.t, result.signal("w"), lw=0.9, label=label)
ax.set_xlabel("time [s]")
ax.set_ylabel("speed [rad/s]")
ax.legend()
fig.tight_layout()
print({k: v for k, v in outcome.summary.items() if k.startswith("speed_ramp_error")})
