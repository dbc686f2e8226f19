"""The default on-line metrics of a cage-IM drive in a batch or sweep (``acdrive.batch.Reducer``)."""

from __future__ import annotations

from acdrive._reducer_parts import Reducer, as_steps


def im_reducers(setup) -> list[Reducer]:
    """The default metrics of a cage-IM drive: current tracking RMS error and peak current [A,
    space vector], peak torque, final speed, and with a speed loop its speed error over the
    whole run and where tracking is expected [rad/s] (``drives.cage_im._tracking.im_tracking_rule``; the
    single run's figures of the same names) and the step response of each speed-reference change
    and load step (the summary's ``step_response`` figures as columns,
    ``sim._step_response.flat``)."""
    from acdrive.drives.cage_im._recovery import im_step_events
    from acdrive.drives.cage_im._tracking import im_tracking_rule

    reference = "reference.i" if setup.mode == "current" else "ifoc.i_s_ref"  # IMDrive's
    out = [
        Reducer("current_error_rms_a", "rms", "machine.i_s", reference),
        Reducer("peak_stator_current_a", "peak", "machine.i_s"),
        Reducer("peak_torque_nm", "peak", "machine.tau_e"),
        Reducer("final_speed_rad_s", "final", "shaft.w"),
    ]
    if setup.mode in ("speed-p", "speed-pi"):
        out.append(Reducer("speed", "speed_error", "shaft.w", "speed_reference.w_ref",
                           rule=im_tracking_rule(setup), unit="rad_s"))  # fmt: skip
        steps = as_steps(im_step_events(setup))
        if steps:
            out.append(Reducer("speed_step", "step_response", "shaft.w", "speed_reference.w_ref",
                               unit="rad_s", steps=steps))  # fmt: skip
    return out
