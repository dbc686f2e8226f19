"""Permanent-magnet machines with published parameters, for the PM drive's scenarios and the
identification benches (``identify._builtin``).

Each record is a ``machines.PMSMParams`` (R_s, L_d, L_q per phase; psi_m the magnet's peak flux
linkage per phase; n_p; J of the rotor alone) with the source of every number. Printed values
are taken as printed; where a source rounds, the rounding is said here.

**Surface PMSM: Anaheim Automation BLY171D-24V-4000** (a 24 V, 4000 rpm, 8-pole brushless
servo motor), as tabulated by MathWorks, Motor Control Blockset documentation,
``mcb.getPMSMParameters("BLY171D")`` (https://www.mathworks.com/help/mcb/ref/mcb.getpmsmparameters.html):
p = 4, Rs = 0.7500 ohm, Ld = Lq = 0.0010 H, J = 2.4019e-06 kg m^2, B = 1.1604e-05 N m s/rad,
Ke = 3.8000 V (peak line-to-line per 1000 rpm), Kt = 0.0340 N m/A, I_rated = 1.8000 A,
N_max = 10000 rpm, FluxPM = 0.0052 Wb, T_rated = 0.0566 N m. The page prints four digits, so
Ld, Lq and FluxPM are known to +-5e-5 H and +-5e-5 Wb. Two checks that the printed numbers
belong together (computed in ``tests/test_pm_drive_machines.py``): the back-EMF constant gives
psi_m = Ke / sqrt(3) / (1000 rpm n_p) = 5.24e-3 Wb, FluxPM within its rounding; and the
amplitude-invariant torque (3/2) p FluxPM I_rated = 0.0562 N m is the rated torque 0.0566 within
1 %, so I_rated is a phase PEAK current and FluxPM a peak flux per phase, the scaling of psi_m.

**Interior PMSM: the 2.2-kW IPMSM of motulator** (motulator documentation and examples, Aalto
University, 2.2-kW IPMSM default parameters: the default of its synchronous-machine model, "The
default values correspond to a 2.2-kW permanent-magnet synchronous motor"): n_p = 3,
R_s = 3.6 ohm, L_d = 0.036 H, L_q = 0.051 H, psi_f = 0.545 V s, J = 0.015 kg m^2, DC link
540 V; nominal U = 370 V (line-to-line, rms), I = 4.3 A (rms), f = 75 Hz, P = 2.2 kW,
tau = 14 N m. motulator uses peak-valued space vectors (the amplitude-invariant scaling: a
balanced set of phase peak X has |x| = X), so its psi_f is the magnet's peak flux linkage per
phase, acdrive's ``psi_m``; in acdrive's power-invariant scaling the magnet flux is
sqrt(3/2) 0.545 = 0.6675 V s (``_design.magnet_flux``). R_s, L_d and L_q are the same in both
scalings. Checks that the nominal values belong together (``tests/test_pm_drive_machines.py``):
the MTPA torque at the nominal current (phase peak sqrt(2) 4.3 A) is 15.1 N m, 8 % above the
nominal 14 N m (= 2.2 kW at 1500 rpm: the nominal current carries more than the nominal torque;
the table does not say why, e.g. losses or rounding); the no-load back-EMF at 75 Hz is 315 V
(line rms) and the steady-state voltage of that MTPA point at 75 Hz is 368 V, the nominal 370 V
within 1 %.
"""

from __future__ import annotations

import math

from acdrive.machines._pmsm import PMSMParams

#: Anaheim Automation BLY171D-24V-4000 (module docstring): 8-pole surface PMSM.
BLY171D = PMSMParams(R_s=0.75, L_d=0.0010, L_q=0.0010, psi_m=0.0052, n_p=4, J=2.4019e-06)
#: its viscous friction [N m s/rad], rated phase-peak current [A], rated torque [N m], DC link
#: [V], back-EMF constant [V peak line-to-line per 1000 rpm] and speed limit [rad/s] from the
#: same table
BLY171D_B = 1.1604e-05
BLY171D_I_RATED_PEAK = 1.8
BLY171D_T_RATED = 0.0566
BLY171D_V_DC = 24.0
BLY171D_KE = 3.8
BLY171D_N_MAX = 10000.0 * 2.0 * math.pi / 60.0

#: motulator's 2.2-kW interior PMSM (module docstring); psi_m = motulator's psi_f (peak scaling)
IPMSM_2KW2 = PMSMParams(R_s=3.6, L_d=0.036, L_q=0.051, psi_m=0.545, n_p=3, J=0.015)
#: its DC link [V] and nominal values from the same source: line voltage [V rms], current
#: [A rms], electrical frequency [Hz], power [W], torque [N m]
IPMSM_2KW2_V_DC = 540.0
IPMSM_2KW2_U_NOM = 370.0
IPMSM_2KW2_I_NOM = 4.3
IPMSM_2KW2_F_NOM = 75.0
IPMSM_2KW2_P_NOM = 2200.0
IPMSM_2KW2_T_NOM = 14.0
