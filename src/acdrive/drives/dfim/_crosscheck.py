"""The linearised tolerated speed-loop bandwidth of a DFIM setup, for a sweep's ``[crosscheck]``
(``acdrive.sweep._report``): the largest a_D,VEL at which the linearised sampled closed loop of
motor 0 (``_linearisation._studies.max_stable_bandwidth`` on the setup itself) is stable at
the setup's final speed reference and load, with every other field of the setup as it is."""

from __future__ import annotations

import math


def linearised_tolerated_bandwidth(setup, lower: float, upper: float) -> dict:
    """``speed_rpm``, ``load_nm``, ``converter_loss_v`` (the operating point) and
    ``linearised_tolerated`` [rad/s] searched in [``lower``, ``upper``] to 1 rad/s."""
    from acdrive.drives.dfim._linearisation._studies import max_stable_bandwidth

    m = setup.motors[0]
    speed_rpm = float(m.speed_reference[1][-1]) * 30 / math.pi
    load = float(m.load_torque[1][-1])
    loss = float(m.converter.fundamental_loss(m.dc_link_voltage))
    linear = max_stable_bandwidth(setup, [speed_rpm], [load], kind="sampled", lower=lower,
                                  upper=upper, tol=1.0)  # fmt: skip
    return {"speed_rpm": speed_rpm, "load_nm": load, "converter_loss_v": loss,
            "linearised_tolerated": linear}  # fmt: skip
