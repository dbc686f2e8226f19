"""
From an ICAD design to C on a Cortex-M4: export, software in the loop, instruction count
========================================================================================

Design a stationary-frame current controller for the DeLorenzo cage IM with the ICAD design
search (Amezquita-Brooks et al., sec. V-B specifications), export the sampled controller of a
locked-rotor current test as C99 (``acdrive.export.to_c``), run that C, compiled with gcc, in
acdrive's loop in place of the compiled controller (``run_in_loop``), and count the
instructions of one control step of its float build on QEMU's Cortex-M4 board model
(``board_cost``; needs the cross tools of ``scripts/install-cross-tools.sh``).
"""

import matplotlib.pyplot as plt
import numpy as np

from acdrive.analysis import propose_controller
from acdrive.control import CurrentProgram, StationaryCurrentController
from acdrive.errors import InputError
from acdrive.export import board_cost, run_in_loop, to_c
from acdrive.machines import CageInductionMachine, machine_params
from acdrive.plant import DCSource, Inverter, PrescribedSpeed
from acdrive.sim import System

# %%
# The design: a PI (or PI x lag) k_1 = k_2 meeting the paper's specifications over 0-375 rad/s,
# checked with the full individual-channel analysis.
proposal = propose_controller("delorenzo-im")
print("proposed:", proposal.candidate.structure, "| specs met:", ", ".join(proposal.met))
print("specs not met:", ", ".join(proposal.unmet) or "none")

# %%
# The drive around it: 310 V DC link, two-level SVPWM at 5 kHz, the controller sampled at
# 20 kHz, rotor locked, a 300 rad/s sinusoidal current reference (a table the C holds in its
# parameters, interpolated linearly: 161 points, 0.075 rad of the sinusoid apart).
T_s, duration, amplitude, w_ref = 5e-5, 0.04, 2.0, 300.0
times = np.linspace(0.0, duration, 161)
reference = CurrentProgram.from_function(
    "reference", lambda t: amplitude * np.sqrt(1.5) * np.exp(1j * w_ref * t), times
)
dc = DCSource("dc", V=310.0)
machine = CageInductionMachine.from_params("machine", machine_params("delorenzo-im"))
rotor = PrescribedSpeed("rotor", w=0.0)
current = StationaryCurrentController("current", proposal.controller, T_s, "tustin",
                                      v_dc_input=True)  # fmt: skip
inverter = Inverter("inverter", f_pwm=5000.0)
system = System(
    [dc, machine, rotor, reference, current, inverter],
    [
        (rotor.out.w, machine.inp.w),
        (machine.out.i_s, current.inp.i_meas),
        (reference.out.i, current.inp.i_ref),
        (dc.out.v_dc, current.inp.v_dc),
        (dc.out.v_dc, inverter.inp.v_dc),
        (current.out.v_ref, inverter.inp.v_ref),
        (machine.out.i_s, inverter.inp.i_s),
        (inverter.out.v, machine.inp.v_s),
    ],
)

# %%
# The C export, and the run with it in the loop against acdrive's own run. The double build
# repeats the kernel's operations in their order; the difference is printed against the peak.
export = to_c(system, T_s, name="icad_current")
print(f"{export.header_name}: {len(export.header.splitlines())} lines, "
      f"{export.source_name}: {len(export.source.splitlines())} lines")  # fmt: skip
compiled = system.compile()
logged = [machine.out.i_s, current.out.v_ref]
acdrive_run = compiled.run(duration, T_s, substeps=4, log=logged)
sil_run = run_in_loop(compiled, export, duration, T_s, substeps=4, log=logged)
i_acdrive = acdrive_run.signal(machine.out.i_s) / np.sqrt(1.5)  # phase peak
i_sil = sil_run.signal(machine.out.i_s) / np.sqrt(1.5)
difference = np.max(np.abs(i_sil - i_acdrive)) / np.max(np.abs(i_acdrive))
print(f"SIL against acdrive: largest stator-current difference {difference:.2e} of its peak")

# %%
# Instructions per control step of the float build on the Cortex-M4 model (an instruction
# count, read as cycles of a 168 MHz core at one instruction per cycle).
try:
    chain = board_cost(compiled, export, duration, T_s, substeps=4)[0]
except InputError as missing:
    print(f"no instruction count on the Cortex-M4 model: {missing}")
else:
    print(f"{chain['chain']}: {chain['instructions_per_step']:.1f} instructions per step "
          f"over {chain['samples']} replayed samples")  # fmt: skip
    for rate, fraction in chain["fraction_of_period"].items():
        print(f"  {100 * fraction:.2f} % of a {float(rate) / 1e3:g} kHz period at 168 MHz")
    print(f"  {100 * chain['fraction_of_own_period']:.2f} % of its own {1e-3 / T_s:g} kHz period")

fig, ax = plt.subplots(figsize=(7, 3.5))
ax.plot(acdrive_run.t, i_acdrive.real, lw=1.6, label="acdrive: i_alpha")
ax.plot(sil_run.t, i_sil.real, "--", lw=0.9, label="C in the loop: i_alpha")
ax.plot(acdrive_run.t, i_acdrive.imag, lw=1.6, label="acdrive: i_beta")
ax.plot(sil_run.t, i_sil.imag, "--", lw=0.9, label="C in the loop: i_beta")
ax.set_xlabel("time [s]")
ax.set_ylabel("phase current [A, peak]")
ax.legend(ncol=2, fontsize=8)
fig.tight_layout()
