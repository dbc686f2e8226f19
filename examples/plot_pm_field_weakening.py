"""
Interior PMSM speed drive with MTPA and field weakening
=======================================================

The 2.2-kW interior PMSM documented by motulator (n_p = 3, R_s = 3.6 ohm, L_d = 36 mH,
L_q = 51 mH, 540 V DC link) on the averaged converter: rotor-frame current control with
decoupling and anti-windup, a speed PI whose torque limit is the torque available at the measured
speed, and the current references from MTPA below base speed and on the voltage limit above it.
The speed is ramped to 2.2 times the base speed computed for this current limit and DC link, then
loaded with 7 N m.

The d current goes negative as the speed passes the base speed (the magnet flux is weakened) and
the voltage command stays under the limit m V_dc / sqrt(2) the references aim at.
"""

import matplotlib.pyplot as plt
import numpy as np

from acdrive.drives.pm import run, signals
from acdrive.scenarios import load_scenario

setup = load_scenario("pm-ipmsm-field-weakening")
result, summary = run(setup)
s = signals(setup, result)
t = result.t
phase_peak = 1.0 / np.sqrt(1.5)  # power-invariant space vector -> phase peak (Bodson (8))

fig, (ax_w, ax_i, ax_v) = plt.subplots(3, 1, sharex=True, figsize=(7, 7))
ax_w.plot(t, s["w_ref"], "k--", lw=0.8, label="reference")
ax_w.plot(t, s["w"], lw=0.8, label="speed")
ax_w.axhline(summary["base_speed_rad_s"], color="C3", lw=0.6, label="base speed (steady state)")
ax_w.set_ylabel("speed [rad/s]")
ax_w.legend(fontsize=8)
ax_i.plot(t, phase_peak * s["i_dq"].real, lw=0.8, label="i_d")
ax_i.plot(t, phase_peak * s["i_dq"].imag, lw=0.8, label="i_q")
ax_i.set_ylabel("current [A, phase peak]")
ax_i.legend(fontsize=8)
ax_v.plot(t, np.abs(s["v_dq_ref"]), lw=0.8, label="|v_dq| commanded")
limit = setup.voltage_margin * setup.V_dc / np.sqrt(2.0)
ax_v.axhline(limit, color="C3", lw=0.6, label="m V_dc / sqrt(2)")
ax_v.set_ylabel("voltage [V, space vector]")
ax_v.set_xlabel("time [s]")
ax_v.legend(fontsize=8)
fig.tight_layout()
print({k: summary[k] for k in ("base_speed_rad_s", "voltage_bound_speed_rad_s",
                               "speed_final_to_base_ratio", "i_d_final_a", "i_d_min_a")})
