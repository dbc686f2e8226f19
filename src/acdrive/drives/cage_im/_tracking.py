"""Where a cage-IM drive's speed is expected to track its reference (``sim._metrics.TrackingRule``):
the window a single run's summary and a batch's reducers judge the speed error on."""

from __future__ import annotations

from acdrive.sim._metrics import TrackingRule, reference_tracking_rule


def im_tracking_rule(setup) -> TrackingRule | None:
    """The ``TrackingRule`` of a cage-IM speed loop (modes ``speed-p`` and ``speed-pi``; None
    otherwise): tau = its torque limit tau_max; a = k_p / J for the P loop (21) (its one pole),
    K_P / (2 J) for the PI (both roots at -a, Bodson (27))."""
    if setup.mode == "speed-p":
        a, tau = setup.speed_p.k_p / setup.mechanics.J, setup.speed_p.tau_max
    elif setup.mode == "speed-pi":
        a, tau = setup.speed_pi.K_P / (2.0 * setup.mechanics.J), setup.speed_pi.tau_max
    else:
        return None
    return reference_tracking_rule(setup.speed_reference, setup.mechanics.J, tau, a, False,
                                   "the speed loop's bandwidth")  # fmt: skip
