"""
Using acdrive from a notebook
=============================

Results are plain Python objects: a one-line ``repr`` with the headline numbers, ``plot()``, a
pandas frame of every logged signal (units and descriptions in ``frame.attrs``), the summary
dictionary that ``acdrive run`` writes as ``summary.json``, and ``save()`` to Parquet, CSV or
MATLAB ``.mat`` with a ``columns.md`` beside the data.
"""

import tempfile
from pathlib import Path

from acdrive.drives import simulate
from acdrive.scenarios import load_scenario

result = simulate(load_scenario("bodson-two-motors"))
result  # noqa: B018 - a notebook shows the repr of the last expression

# %%
# The result draws itself (speed, currents, torque of one motor).
fig = result.plot(motor=1)

# %%
# Pandas does the rest; the columns carry their units.
frame = result.to_dataframe()
print(frame.shape)
print({name: frame.attrs["units"][name] for name in ("t", "w_m1", "i_r_pk_m1", "tau_e_m2")})

# %%
# Saving: Parquet by default, or ``"csv"`` / ``"mat"``; every column is described in
# ``columns.md``.
folder = Path(tempfile.mkdtemp()) / "two-motors"
written = result.save(folder, "mat")
print([p.name for p in written])
print((folder / "columns.md").read_text().splitlines()[:6])
