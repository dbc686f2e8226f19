"""
Synchronising the DFIM to the supply (Bodson, section IV-A)
===========================================================

With the stator relay open, the rotor converter builds a stator voltage; the synchroniser adjusts
its magnitude (m_adj) and angle (theta_adj, which also finds the encoder's unknown offset) until
the stator voltage matches the grid's, then closes the relay, and speed control takes over from
zero torque.
"""

import matplotlib.pyplot as plt

from acdrive.drives import simulate
from acdrive.scenarios import load_scenario

result = simulate(load_scenario("bodson-sync"))

fig, axes = plt.subplots(3, 1, sharex=True, figsize=(7, 6))
axes[0].plot(result.t, result.signal("v_mismatch"), lw=0.8)
axes[0].set_ylabel("|v_s - v_grid| / |v_grid|")
axes[1].plot(result.t, result.signal("theta_adj"), lw=0.8, label="theta_adj [rad]")
axes[1].plot(result.t, result.signal("m_adj"), lw=0.8, label="m_adj")
axes[1].legend()
axes[2].plot(result.t, result.signal("relay_closed"), lw=0.8)
axes[2].set_ylabel("relay closed")
axes[2].set_xlabel("time [s]")
fig.tight_layout()

# %%
# The relay closes once the mismatch is small; the time is read from the logged relay state.
closed_at = result.t[result.signal("relay_closed") > 0.5]
print(f"relay closed at t = {closed_at[0]:.3f} s" if closed_at.size else "relay never closed")
