"""What every DFIM controller shares (Bodson section III): modes, the drive's event names and the
rotor current-loop gains (49).

The controller itself is a set of sampled parts (``acdrive.control._bodson``): speed and supply
frequency estimates, the synchroniser (28) and the speed controller (speed PI (25), on-line torque
limits (30)-(42), the torque and reactive-power law (20)-(24), the rotor current loop (45)-(47)).
"""

from __future__ import annotations

MODE_VOLTAGE, MODE_CURRENT = 0.0, 1.0

#: the event flags of a DFIM drive result, one bit each in this order (``DriveResult.events``)
EVENT_NAMES = (
    "torque_limit",  # speed PI output clipped to the on-line torque limits
    "sqrt_limit",  # radicand of (22)/(24) negative: command limited
    "supply_lost",  # measured voltage below V_min: last safe output held
    "no_rotor_margin",  # rotor current limit below magnetising need: torque window empty
    "converter_saturation",  # converter could not apply the commanded rotor voltage
    "rotor_current_limit",  # rotor current command (43) limited to the rotor current limit
    "sensor_fallback",  # current measurement failed: running in voltage command
    "relay_closed",  # the synchroniser closed the relay on this sample
)
#: below this estimated supply frequency [rad/s] the law (20) is not evaluated (Z_MS -> 0)
MIN_SUPPLY_FREQUENCY = 1.0


def current_loop_gains(
    sigma: float, L_r: float, R_T: float, bandwidth: float
) -> tuple[float, float]:
    """K_P,C = sigma L_r a_D,CUR and K_I,C = R_T a_D,CUR (Bodson (49)), which make the rotor
    current loop a_D,CUR / (s + a_D,CUR) (50)."""
    return sigma * L_r * bandwidth, R_T * bandwidth
