"""Where a DFIM motor's speed is expected to track its reference (``sim._metrics.TrackingRule``):
the window a single run's summary and a batch's reducers judge the speed error on."""

from __future__ import annotations

import math

from acdrive.sim._metrics import TrackingRule, reference_tracking_rule


def slew_torque(setup, motor: int) -> float:
    """The smaller of the motoring and generating torque limits [N m] of DFIM ``motor`` at the
    nominal supply (Bodson (30)-(37), as ``acdrive limits``): the torque a reference step is
    slewed with at most."""
    from acdrive._frames import K_PEAK
    from acdrive.machines._dfim import machine_vector, torque_limits_case1

    m = setup.motors[motor]
    c = m.controller
    v_pk = float(setup.supply.voltage_pk[1][0])
    w_e = 2.0 * math.pi * float(setup.supply.frequency_hz[1][0])
    t1, t2, t3, m2, m3, _ = torque_limits_case1(
        machine_vector(m.machine), w_e, K_PEAK * v_pk, K_PEAK * c.stator_current_limit_pk,
        K_PEAK * c.rotor_current_limit_pk,
    )  # fmt: skip
    return min(abs(min(t1, t2, t3)), abs(max(m2, m3)))


def tracking_rule(setup, motor: int = 0) -> TrackingRule:
    """The ``TrackingRule`` of DFIM motor ``motor`` of ``setup`` (module docstring): tau from
    ``slew_torque`` at the nominal supply, a = a_D,VEL = K_P / (2 J) (Bodson (27))."""
    m = setup.motors[motor]
    J = m.machine.J
    a = m.controller.gains.K_P / (2.0 * J)
    return reference_tracking_rule(m.speed_reference, J, slew_torque(setup, motor), a, True,
                                   "a_D,VEL")  # fmt: skip
