"""What happened to a cage-IM drive's speed or position at each disturbance of a run (a change of
the active load torque or of the eddy-current brake coefficient, a DC link that departs from its
starting value) and at its end, judged by ``sim._recovery``'s rules."""

from __future__ import annotations

import numpy as np

from acdrive.sim._metrics import RPM_PER_RAD_S
from acdrive.sim._step_response import events
from acdrive.sim._recovery import (
    POSITION_RULE,
    POSITION_SPEED_NOT_JUDGED,
    RULE,
    _departures,
    _steps,
    judge_position,
    judge_speed,
    position_tracking_windows,
)


def im_disturbances(setup) -> list[dict]:
    """The disturbances of a cage-IM ``setup`` (``drives.cage_im._setup.IMDriveSetup``), by start time:
    ``what``, ``start_s``, ``cleared_s`` (None: it stays). A held shaft (prescribed speed) has
    no load disturbances."""
    m = setup.mechanics
    found = []
    if m.free:
        found += _steps(m.load, "load torque", "N m")
        found += _steps(m.brake, "brake coefficient", "N m s/rad")
    found += _departures(setup.inverter.dc_link, "DC link", "V")
    found = [d for d in found if 0.0 < d["start_s"] < setup.duration]
    return sorted(found, key=lambda d: d["start_s"])


def im_speed_outcome(result, mask: np.ndarray) -> dict:
    """What happened to the speed of a cage-IM ``result`` (``drives.cage_im._result.IMDriveResult``) at
    each disturbance (``im_disturbances``) and at the end (``judge_speed`` on the ``mask``
    (tracked) samples, the DFIM's rule): the logged speed [rad/s] converted once to rpm, the
    rule's unit; ``warnings`` name the run by its label."""
    found = im_disturbances(result.setup)
    judged = judge_speed(
        result.t, result.signal("w") * RPM_PER_RAD_S, result.signal("w_ref") * RPM_PER_RAD_S,
        mask, [(d["what"], d["start_s"]) for d in found], result.label,
    )  # fmt: skip
    for d, a in zip(found, judged["disturbances"], strict=True):
        d.update(a)
    return {"rule": RULE, "unit": "rpm (the logged rad/s x 30/pi)", "disturbances": found,
            "end_of_run": judged["end_of_run"], "warnings": judged["warnings"]}  # fmt: skip


def im_position_outcome(result) -> dict:
    """The position error of a cage-IM position ``result`` after each disturbance
    (``judge_position`` outside ``position_tracking_windows``), the claim a position drive
    makes; its speed is not judged (POSITION_SPEED_NOT_JUDGED). ``warnings``: a position that
    did not recover, naming the run by its label."""
    s, t = result.setup, result.t
    found = im_disturbances(s)
    windows = position_tracking_windows(s.position_reference, s.position.w_max, s.position.K_theta)
    mask = np.ones(t.size, dtype=bool)
    for a, b in windows:
        mask &= ~((t >= a) & (t < b))
    theta = result.signal("theta") + s.sensors.offset
    judged = judge_position(t, theta, result.signal("theta_ref"), mask,
                            [(d["what"], d["start_s"]) for d in found])  # fmt: skip
    warnings = []
    for d, a in zip(found, judged, strict=True):
        d.update(a)
        if a["recovered"] is False:
            warnings.append(
                f"{result.label}: the position did not recover after the {d['what']} at "
                f"{d['start_s']:g} s: the error stayed beyond {a['band_rad']:.3g} rad (largest "
                f"{a['largest_position_error_rad']:.3g} rad at {a['largest_at_s']:.3f} s) until "
                f"{a['judged_until_s']:.3f} s"
            )
    return {"rule": POSITION_RULE, "windows_s": [[a, min(b, float(t[-1]))] for a, b in windows],
            "speed_not_judged": POSITION_SPEED_NOT_JUDGED, "disturbances": found,
            "warnings": warnings}  # fmt: skip


def im_step_events(setup) -> list[dict]:
    """The speed-reference changes and load steps (the active load torque and the brake
    coefficient; none on a held shaft) of a cage-IM speed ``setup``
    (``sim._step_response.events``)."""
    m = setup.mechanics
    loads = ({"load torque": (m.load, "N m"), "brake coefficient": (m.brake, "N m s/rad")}
             if m.free else {})  # fmt: skip
    return events(setup.speed_reference, loads, setup.duration)
