"""The cage-IM current controller acdrive designs from machine parameters (``controller =
"imc-pi"``), as opposed to the built-in published transfer functions (``control._lti.BUILTIN``:
Amezquita-Brooks et al.'s (20), the PI of their sec. VI-D, the PI family of Fig. 17), which are
fixed numbers and are never re-derived.

Internal-model design on the stator's transient model: seen from the stator terminals, over
times short against the rotor time constant, the machine's stator current obeys
sigma L_s di_s/dt = v_s - (R_s + R_R) i_s - (rotor-flux back-EMF), with R_R = R_r (L_m / L_r)^2
the inverse-Gamma rotor resistance (the rotor-flux term is left to the loop as a disturbance).
The stationary-frame PI K_P = alpha sigma L_s, K_I = alpha (R_s + R_R) cancels that pole and
makes the closed loop alpha / (s + alpha) for the transient model. It is designed on the
scenario's design machine (the nominal machine, or a ``[design]`` table's estimates).
"""

from __future__ import annotations

from acdrive.errors import require_positive
from acdrive.machines._induction import IMParams

#: the name of the designed controller in ``[current_control] controller``
DESIGNED = "imc-pi"


def imc_current_pi(machine: IMParams, bandwidth: float) -> tuple[float, float]:
    """(K_P [V/A = ohm], K_I [ohm/s]) of the internal-model PI of the module docstring for
    ``machine`` at closed-loop bandwidth ``bandwidth`` [rad/s]."""
    a = require_positive("current_control.bandwidth_rad_s", bandwidth)
    r_rotor = machine.R_r * (machine.L_m / machine.L_r) ** 2
    return a * machine.sigma * machine.L_s, a * (machine.R_s + r_rotor)
