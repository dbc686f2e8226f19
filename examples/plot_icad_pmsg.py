"""
ICAD of the PMSG current subsystem across speed
===============================================

Ugalde-Loo et al.'s 2 MW permanent-magnet generator: the peak magnitude of the structure function
gamma, the measure of cross-coupling between the d and q current channels, computed at eight rotor
speeds.
"""

import matplotlib.pyplot as plt
import numpy as np

from acdrive.analysis import icad_response, plants_for
from acdrive.control import LTI

speeds = np.linspace(50.0, 400.0, 8)
w = np.logspace(0, 4, 600)
k = LTI.pi(1.0, 100.0)  # an illustrative PI on both channels
response = icad_response(plants_for("pmsg-2mw", speeds), k, k, w)
peak_db = 20 * np.log10(np.max(np.abs(response.gamma), axis=1))

fig, ax = plt.subplots(figsize=(7, 3.5))
ax.plot(speeds, peak_db, "o-")
ax.set_xlabel("electrical rotor speed [rad/s]")
ax.set_ylabel("peak |gamma| [dB]")
fig.tight_layout()
