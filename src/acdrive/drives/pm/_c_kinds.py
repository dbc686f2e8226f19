"""The C steps of the PM drive's controller parts (``drives.pm._control``: the speed PI, the
torque reference, the rotor-frame current controller), generated from their kernels and the
MTPA / field-weakening functions they call (``drives.pm._design``) by ``sim._ccode._translate``.

Importing the module registers the three kinds in the engine's C registry
(``sim._ccode._kinds``), which imports it when it first looks one of them up: each class names
it as its ``C_MODULE`` (``_control.C_KINDS``), so the registry, below the drives, names no drive.
"""

from __future__ import annotations

from acdrive.drives.pm._control import PMSpeedPI, PMTorqueReference, RotorFrameCurrentController
from acdrive.sim._ccode._kinds import register
from acdrive.sim._ccode._kind_c import c_step

register(
    PMTorqueReference,
    c_step(
        PMTorqueReference,
        source="torque -> rotor-frame current reference: MTPA, field weakening on (V)",
    ),
)

register(
    PMSpeedPI,
    c_step(
        PMSpeedPI,
        source="Bodson (25) limited to min(tau_max, the torque available at the measured speed)",
    ),
)

register(
    RotorFrameCurrentController,
    c_step(
        RotorFrameCurrentController,
        source="rotor-frame PI per axis with decoupling, back-EMF feed-forward and "
        "back-calculation anti-windup at V_dc / sqrt(2)",
    ),
)
