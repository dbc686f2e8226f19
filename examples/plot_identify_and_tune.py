"""
From a standstill test log to a drive tuned on the estimates
============================================================

A drive engineer's first day with a new cage induction motor: log two standstill tests on the
inverter-fed motor, identify the equivalent circuit from the logs, design the drive's controllers
on the estimates and see how the drive designed on them compares with the one designed on the
truth, then map how robust that design is to the parameters the tests measured poorly.

Here the "motor on the bench" is acdrive's own simulated DeLorenzo IM behind a two-level inverter
with 2 us dead time and 1.5 V device drops, the current measured with noise and a 12-bit ADC. The
logs are written as CSV files and read back exactly as a measured log would be.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from acdrive.cli import main
from acdrive.drives import run_im_scenario
from acdrive.identify import StandstillPlan, dc_test, injection_test, read_log, write_log
from acdrive.machines import machine_params
from acdrive.robustness import MapSpec, design_comparison, robustness_map
from acdrive.scenarios import build_setup, read_scenario

work = Path(tempfile.mkdtemp(prefix="acdrive-identify-"))  # a fresh folder of this example's own

# %%
# The raw test logs
# -----------------
# DC steps (R_s and the inverter's voltage error) and a multisine injection on phase a with the
# rotor at rest (the inverse-Gamma circuit). Each log has the columns ``time [s]``, ``v_a [V]``
# (the command latched for the PWM period) and ``i_a [A]`` (the measured current).
truth = machine_params("delorenzo-im")
bench = StandstillPlan(t_d=2e-6, v_drop=1.5)
write_log(dc_test(truth, bench), work / "dc.csv")
write_log(injection_test(truth, bench), work / "injection.csv")
print((work / "injection.csv").read_text().splitlines()[:3])
injection = read_log(work / "injection.csv")

fig, ax = plt.subplots(figsize=(7, 2.6))
ax.plot(injection.time, injection.i_a, lw=0.4)
ax.set(xlabel="time [s]", ylabel="i_a [A]", title="multisine injection at standstill (the log)")
fig.tight_layout()

# %%
# Identification
# --------------
# ``acdrive identify`` fits the logs (with the DC log's voltage error compensated), prints every
# estimate with its 95 % intervals and writes a machine parameter file. The leakage split is an
# assumption (equal stator and rotor leakage), as the table says.
estimates = work / "motor.toml"
main(["identify", str(work / "injection.csv"), "--dc-log", str(work / "dc.csv"),
      "--pole-pairs", "1", "--out", str(estimates)])  # fmt: skip

# %%
# Design on the estimates, run on the truth
# -----------------------------------------
# The speed drive of Amezquita-Brooks et al.'s Fig. 13 with a current PI that acdrive designs
# from the machine (``controller = "imc-pi"``, an internal-model PI at 1500 rad/s): with
# ``[design] machine_file`` the IFOC's slip law and this current PI are designed on the estimates,
# while the simulated motor stays the truth. (The paper's controller (20) is a fixed published
# transfer function: it would not change.)
scenario = read_scenario("im-foc-speed")
scenario["simulation"]["duration"] = 0.7  # the speed step, and the brake from 0.6 s
scenario["current_control"] = {"controller": "imc-pi", "bandwidth_rad_s": 1500.0}
comparison = design_comparison(scenario, estimates)
print("\n".join(comparison.lines()))

runs = {
    "design on the truth": scenario,
    "design on the estimates": {**scenario, "design": {"machine_file": str(estimates)}},
}
fig, (ax_w, ax_i) = plt.subplots(2, 1, sharex=True, figsize=(7, 4.5))
for label, data in runs.items():
    result = run_im_scenario(build_setup(data)).main
    ax_w.plot(result.t, result.signal("w"), lw=0.8, label=label)
    ax_i.plot(result.t, np.abs(result.phase_peak("i_s")), lw=0.5, label=label)
ax_w.plot(result.t, result.signal("w_ref"), "k--", lw=0.7, label="reference")
ax_w.set_ylabel("speed [rad/s]")
ax_w.legend(fontsize=8)
ax_i.set(xlabel="time [s]", ylabel="|i_s| [A, phase peak]")
fig.tight_layout()

# %%
# How robust is the design?
# -------------------------
# A small Monte Carlo map (30 variants: the nominal and 29 draws) of plant errors on the drive
# designed on the estimates: the stator and rotor resistances (they drift with temperature) and
# the inertia (a standstill test cannot see it) of the simulated motor are drawn log-uniformly in
# [0.5, 2] times their values, the controllers keep their design. Each run is judged by the
# stated criteria (tracking, current limit, stability); the figure shows the speed error and the
# peak current against the rotor-resistance factor, which the IFOC's slip law is most sensitive
# to. (Drawing the inductances independently would mostly give plants with sigma <= 0, which the
# map refuses.)
designed = {**scenario, "design": {"machine_file": str(estimates)}}
designed["simulation"] = {**scenario["simulation"], "duration": 0.3}
spec = MapSpec(kind="monte-carlo", params=("R_s", "R_r", "J"), variants=30, low=0.5, high=2.0)
rmap = robustness_map(designed, spec)
valid = [r for r in rmap.rows if r["valid"]]
r_r = np.array([r["factors"].get("R_r", 1.0) for r in valid])
ok = np.array([all(r["verdicts"].values()) for r in valid])
fig, axes = plt.subplots(2, 1, sharex=True, figsize=(7, 4.5))
labels = {"tracking": "RMS speed error", "current_limit": "peak |i_s|"}
for ax, name in zip(axes, labels, strict=True):
    criterion = next(c for c in rmap.criteria if c.name == name)
    figure = np.array([r[criterion.column] for r in valid])
    ax.scatter(r_r[ok], figure[ok], s=12, label="passes every criterion")
    ax.scatter(r_r[~ok], figure[~ok], s=12, marker="x", label="breaks a criterion")
    ax.axhline(criterion.limit, color="k", lw=0.7, ls="--", label=f"{name} limit")
    ax.set(xscale="log", ylabel=f"{labels[name]} [{criterion.unit}]")
    ax.legend(fontsize=7)
axes[-1].set_xlabel("R_r factor on the simulated motor")
fig.tight_layout()
print(f"{len(valid)} of {len(rmap.rows)} variants simulated; "
      f"{int(ok.sum())} pass every criterion")  # fmt: skip
