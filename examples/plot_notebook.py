"""
Using acdrive from a notebook
=============================

Results are plain Python objects: a one-line ``repr`` with the headline numbers, each part's
signals as attributes (``result.dfim1.w``: motor 2 of this two-motor run; ``result.dfim.w`` in a
single-motor run), ``plot()``, a pandas frame of every logged signal (units and descriptions in ``frame.attrs``), the summary
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
# Every signal of a part, with the unit of its declaration.
print(result.parts, result.dfim1.units["w"], float(result.dfim1.w.max()))

# %%
# The result draws itself: speed, current magnitudes and torque of motor 2 (parts are named as
# the machines, dfim0 and dfim1), one axis per unit on one time axis, each signal as the
# min/max envelope of its time bins.
fig = result.plot(["dfim1.w", "dfim1.w_ref", "dfim1.i_r_mag", "dfim1.i_s_mag", "dfim1.tau_e"])

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
