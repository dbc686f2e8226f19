"""
Using acdrive from a notebook
=============================

Results are plain Python objects: a pandas frame of every logged signal (with units in
``frame.attrs``), a summary dictionary, and arrays by name. This is how a notebook session
typically looks.
"""

from acdrive.scenarios.loader import load_scenario
from acdrive.sim.setup import simulate

setup = load_scenario("bodson-two-motors")
result = simulate(setup)
frame = result.to_dataframe()
print(frame.shape)
print(frame.columns[:8].tolist())

# %%
# Pandas does the rest: resample, describe, plot.
ax = frame.iloc[::50].plot(
    x="t", y=[c for c in frame.columns if c.startswith("w")][:2], figsize=(7, 3)
)
ax.set_ylabel("speed [rad/s]")

# %%
# The summary is the same dictionary that ``acdrive run`` writes as ``summary.json``.
summary = result.summary()
print({k: summary[k] for k in list(summary)[:6]})
