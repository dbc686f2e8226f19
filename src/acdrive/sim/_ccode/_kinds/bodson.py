"""C steps of Bodson's DFIM controller parts (``acdrive.control._bodson``): the speed and
supply-frequency estimators, the synchroniser (28) and the speed controller with its torque and
reactive-power law, generated from their kernels and the machine relations they evaluate on line
(``acdrive.machines._dfim``) by ``sim._ccode._translate``. The equation numbers are Bodson's."""

from __future__ import annotations

from acdrive.control._bodson import (
    SpeedController,
    SpeedEstimator,
    SupplyFrequencyEstimator,
    Synchroniser,
)
from acdrive.sim._ccode._kinds import register
from acdrive.sim._ccode._kind_c import c_step

register(
    SpeedEstimator,
    c_step(
        SpeedEstimator,
        source="Bodson IV-A: speed from the encoder, backward difference, first-order filter",
    ),
)

register(
    SupplyFrequencyEstimator,
    c_step(
        SupplyFrequencyEstimator,
        source="supply frequency from the grid voltage's phase advance per sample, filtered",
    ),
)

register(
    Synchroniser,
    c_step(
        Synchroniser,
        source="Bodson (28): grid synchronisation with the stator open",
    ),
)

register(
    SpeedController,
    c_step(
        SpeedController,
        source="Bodson section III: speed PI (25), torque limits (30)-(42), law (20)-(24), "
        "rotor current loop (45)-(49), sensor fallback",
    ),
)
