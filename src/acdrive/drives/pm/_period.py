"""Pre-run check of the PM drive's current loop against its control period.

The rotor-frame current controller (``drives.pm._control``) is designed as a continuous loop:
with the cross terms and the back-EMF fed forward, each axis is L di/dt = v - R_s i, and the
internal-model PI K_P = alpha L, K_I = alpha R_s makes it alpha / (s + alpha)
(``_design.CurrentPIGains``). The converter applies each command for a command period T_c: the
sample time T_s with the averaged converter, the carrier period (``carrier_samples`` samples)
with the switching one. Sampled that way, the loop's pole is about 1 - alpha T_c (R_s T_c / L
small): it is the designed first-order loop only while alpha T_c is well below 1, at
alpha T_c = 1 the pole reaches 0 (the current steps to its reference in one period, no longer the
design), above 1 it turns negative (the current rings at half the command rate), and at 2 the loop
is unstable. So the setup is refused, before any part is built:

* if alpha T_c > ``CURRENT_BANDWIDTH_T_C_MAX`` (= 1, the limit the other drives warn at,
  ``drives._period.CURRENT_BANDWIDTH_T_S_WARN``): the current bandwidth is not well below the
  command rate;
* if the sampled loop of either axis is unstable (``drives._period.current_loop_radius`` >= 1,
  the PI designed on the controller's estimates, the plant the simulated machine, the command
  held over T_c): with estimates far from the machine an alpha T_c below 1 can still be too much.

The axes are checked at standstill, where the feed-forward decouples them exactly.
"""

from __future__ import annotations

from acdrive.drives._period import CURRENT_BANDWIDTH_T_S_WARN, current_loop_radius
from acdrive.drives.pm._design import CurrentPIGains
from acdrive.errors import InputError

#: the largest alpha T_c the PM drive accepts (module docstring)
CURRENT_BANDWIDTH_T_C_MAX = CURRENT_BANDWIDTH_T_S_WARN


def command_period(setup) -> float:
    """T_c [s]: how long the converter applies one command (module docstring)."""
    return setup.carrier_samples * setup.sample_time


def axis_radii(setup) -> dict[str, float]:
    """Spectral radius of the sampled current loop of each axis ("d", "q"; module docstring)."""
    est, plant = setup.controller_machine, setup.machine
    gains = CurrentPIGains.design(est.R_s, est.L_d, est.L_q, setup.current_bandwidth)
    n = setup.carrier_samples
    return {
        "d": current_loop_radius(plant.L_d, plant.R_s, gains.K_P_d, gains.K_I_d,
                                 setup.sample_time, n),
        "q": current_loop_radius(plant.L_q, plant.R_s, gains.K_P_q, gains.K_I_q,
                                 setup.sample_time, n),
    }  # fmt: skip


def check_current_period(setup) -> None:
    """Refuse a current loop the control period cannot carry (module docstring): an
    ``InputError`` on ``current_bandwidth`` stating the rule and its numbers."""
    alpha, T_c = setup.current_bandwidth, command_period(setup)
    held = "the sample time" if setup.carrier_samples == 1 else "the carrier period"
    if alpha * T_c > CURRENT_BANDWIDTH_T_C_MAX:
        raise InputError(
            "current_bandwidth",
            f"must be well below the command rate: bandwidth x command period ({held}) = "
            f"{alpha:.6g} rad/s x {T_c:g} s = {alpha * T_c:.3g}, above "
            f"{CURRENT_BANDWIDTH_T_C_MAX:g} (the sampled pole 1 - alpha T_c turns negative): "
            f"lower it to at most {CURRENT_BANDWIDTH_T_C_MAX / T_c:.6g} rad/s or shorten {held}",
        )
    for axis, rho in axis_radii(setup).items():
        if rho >= 1.0:
            raise InputError(
                "current_bandwidth",
                f"the sampled {axis}-axis current loop (PI designed on the estimates at "
                f"{alpha:.4g} rad/s, the machine's L_{axis} and R_s, command held {T_c:g} s) is "
                f"unstable (spectral radius {rho:.4g} >= 1): lower it or correct the estimates",
            )
