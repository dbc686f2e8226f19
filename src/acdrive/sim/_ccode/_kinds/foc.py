"""C steps of the cage-IM controllers: indirect field orientation, the speed and position loops
(``acdrive.control._foc``, Amezquita-Brooks et al. section VI, Fig. 12, (21)) and the
stationary-frame current controller of any order with its limit and anti-windup
(``acdrive.control._current``: controller (20) or the PI, discretised), generated from their
kernels by ``sim._ccode._translate``; the current controller's per instance, for its order and
its voltage-limit source (``STRUCTURAL``)."""

from __future__ import annotations

from acdrive.control._current import StationaryCurrentController
from acdrive.control._foc import IndirectFOC, PositionP, SaturatedSpeedP, SpeedPI
from acdrive.sim._ccode._kind_c import c_step
from acdrive.sim._ccode._kinds import register

register(
    IndirectFOC,
    c_step(
        IndirectFOC,
        source="indirect field orientation: (slip), (flux), (torque) of control._foc's docstring",
    ),
)

register(
    SpeedPI,
    c_step(
        SpeedPI,
        source="speed PI with clamping anti-windup and torque limit (control._speed.speed_pi)",
    ),
)

register(
    SaturatedSpeedP,
    c_step(
        SaturatedSpeedP,
        source="Amezquita-Brooks (21): saturated proportional speed controller",
    ),
)

register(PositionP, c_step(PositionP, source="P position loop of the P-PI cascade (Fig. 12)"))

register(
    StationaryCurrentController,
    c_step(
        StationaryCurrentController,
        source="stationary-frame current controller K(z) with magnitude limit and anti-windup by "
        "conditioning (control._current; Amezquita-Brooks (20) or the PI)",
    ),
)
