"""
Indirect field-oriented speed control of the cage IM (Amezquita-Brooks et al., Fig. 13)
=======================================================================================

The DeLorenzo IM with controller (20) in the stationary frame inside an indirect FOC and a speed
PI: a speed step to 150 rad/s, then a load-torque step. Two-level SVPWM inverter at 5 kHz, 50 kHz
control.
"""

import matplotlib.pyplot as plt

from acdrive.drives import run_im_scenario
from acdrive.scenarios import load_scenario

outcome = run_im_scenario(load_scenario("im-foc-speed"))
result = outcome.main

fig, (ax_w, ax_i) = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
ax_w.plot(result.t, result.signal("w_ref"), "k--", lw=0.8, label="reference")
ax_w.plot(result.t, result.signal("w"), lw=0.8, label="speed")
ax_w.set_ylabel("speed [rad/s]")
ax_w.legend()
ax_i.plot(result.t, result.phase_peak("i_s").real, lw=0.4)
ax_i.set_ylabel("i_alpha [A, phase peak]")
ax_i.set_xlabel("time [s]")
fig.tight_layout()
print({k: v for k, v in outcome.summary.items() if k.startswith("speed")})
