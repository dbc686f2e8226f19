"""What the whole-drive linearisation (``drives.dfim._linearisation._stability``) reads of a DFIM drive: the
operating point (shaft speed, load), the setup held there (``operating_setup``) and the view of
its motor 0, controller and supply (``DriveView``: every property computed from the setup, no copy
of its fields). Both closed loops (``drives.dfim._linearisation._loops``) and the linearisation build on it.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from acdrive._arguments import REAL, checked
from acdrive._frames import K_PEAK as SQRT_3_2  # Bodson (8): space-vector magnitude per peak
from acdrive._toml import constant
from acdrive.drives.dfim._setup import DriveSetup
from acdrive.errors import InputError

RAD_S_PER_RPM = math.pi / 30.0
#: the speed loop of a linearisation: PI active, torque command held, or speed held too
SPEED_LOOPS = ("closed", "open", "frozen")


@checked(speed=REAL, load_torque=REAL)
@dataclass(frozen=True)
class OperatingPoint:
    """Shaft speed [rad/s] and load torque [N m] (the non-inertial load of (26), friction apart)."""

    speed: float
    load_torque: float = 0.0

    @property
    def speed_rpm(self) -> float:
        return self.speed / RAD_S_PER_RPM


class DriveView:
    """What the linearisation reads of a DFIM ``DriveSetup``, computed from it (never a copy of
    its fields): motor 0 of ``setup`` held at ``point`` (:func:`operating_setup`) and the speed
    loop's state (``"closed"``, ``"open"``, ``"frozen"``, as :class:`DriveModel`'s).

    ``setup`` is the drive the linearisation builds (``acdrive.drives.get("dfim").build``) and
    compiles; the properties below are read from its motor, controller and supply.
    """

    def __init__(self, setup: DriveSetup, point: OperatingPoint, speed_loop: str = "closed"):
        if speed_loop not in SPEED_LOOPS:
            raise InputError("speed_loop", f"must be one of {', '.join(SPEED_LOOPS)}")
        self.setup = operating_setup(setup, point)
        self.point, self.speed_loop = point, speed_loop
        self.motor = self.setup.motors[0]
        self.controller = self.motor.controller

    mode = property(lambda self: self.controller.mode)
    machine = property(lambda self: self.motor.machine)
    #: the controller's parameter estimates (None: the true machine's)
    controller_params = property(lambda self: self.controller.params)
    gains = property(lambda self: self.controller.gains)
    R_T = property(lambda self: self.controller.R_T)
    speed_filter_tau = property(lambda self: self.controller.speed_filter_tau)
    supply_resistance = property(lambda self: self.setup.supply.resistance)
    sample_time = property(lambda self: self.setup.sample_time)
    substeps = property(lambda self: self.setup.substeps)

    @property
    def current_gains(self) -> tuple[float, float]:
        """(K_P,C, K_I,C) of Bodson (49) from the controller's estimates."""
        return self.controller.current_gains(self.machine)

    @property
    def w_e(self) -> float:
        return 2.0 * math.pi * float(self.setup.supply.frequency_hz[1][0])

    @property
    def v_g(self) -> float:
        """Grid space-vector magnitude sqrt(3/2) V_pk (Bodson (8))."""
        return SQRT_3_2 * float(self.setup.supply.voltage_pk[1][0])

    @property
    def i_s_max(self) -> float:
        return SQRT_3_2 * self.controller.stator_current_limit_pk

    @property
    def i_r_max(self) -> float:
        return SQRT_3_2 * self.controller.rotor_current_limit_pk


def operating_setup(setup: DriveSetup, point: OperatingPoint) -> DriveSetup:
    """Motor 0 of ``setup`` alone on its supply, held at ``point``, as the linearisation sees it:
    speed reference and initial speed at the operating speed, the load constant, the supply
    constant at its values at t = 0 (balanced), the stator connected (no synchronisation), an
    ideal encoder resolution (a quantiser has no derivative), no sensor fault, a constant DC
    link, no forced relay. The encoder offset stays unless the setup synchronises: the
    synchroniser then has identified it (Bodson IV-A) and the connected drive runs as without. Everything else (machine, controller, estimates,
    converter, computation delay, sample time, substeps, integrator) is the setup's."""
    motor = setup.motors[0]
    supply = setup.supply
    controller = dataclasses.replace(
        motor.controller, sync=dataclasses.replace(motor.controller.sync, enabled=False)
    )
    motor = dataclasses.replace(
        motor, controller=controller, speed_reference=constant(point.speed),
        load_torque=constant(point.load_torque), initial_speed=point.speed,
        encoder_counts_per_rev=0.0, current_sensor_fault_time=math.inf, dc_link_profile=None,
        encoder_offset=0.0 if motor.controller.sync.enabled else motor.encoder_offset,
        relay_forced_close_time=math.inf,
    )  # fmt: skip
    supply = dataclasses.replace(
        supply, voltage_pk=constant(float(supply.voltage_pk[1][0])),
        frequency_hz=constant(float(supply.frequency_hz[1][0])), phase_scales=None,
    )  # fmt: skip
    return dataclasses.replace(setup, motors=(motor,), supply=supply, duration=1.0,
                               name="stability", compare_modes=(), log_every=1)  # fmt: skip
