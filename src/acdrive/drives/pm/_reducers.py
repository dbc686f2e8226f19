"""The default on-line metrics of a PM speed drive in a batch or sweep (``acdrive.batch.Reducer``).

Each is a figure of the single run's summary (``drives.pm._metrics``) of the same name, computed
on the same samples (every logged one, the whole run), or a figure a batch adds:
``final_speed_rad_s`` (the speed at the last logged sample), ``current_over_limit`` (samples with
|i_s| above the current limit by more than ``_reducer_parts.OVER_LIMIT_TOLERANCE``, 1 %),
``voltage_command_peak_v`` (the largest |v_dq| the current
controller asked for before its limit; the summary's ``voltage_margin_min`` is 1 minus it over
V_dc / sqrt(2)). A current-step setup compares two runs and is no batch variant (``_plugin``).
"""

from __future__ import annotations

from acdrive._frames import K_PEAK
from acdrive._reducer_parts import Reducer, as_steps, over_limit


def pm_reducers(setup) -> list[Reducer]:
    """The metrics of the module docstring for ``setup`` (a ``PMDriveSetup``), on the ports of
    ``drives.pm._build.build``, and the summary's ``step_response`` figures as columns
    (``sim._step_response.flat``)."""
    from acdrive.drives.pm._metrics import step_events

    out = [
        Reducer("speed_error_rms_rad_s", "rms", "shaft.w", "speed_reference.w_ref"),
        Reducer("speed_error_max_rad_s", "peak", "shaft.w", "speed_reference.w_ref"),
        Reducer("final_speed_rad_s", "final", "shaft.w"),
        Reducer("current_peak_a", "peak", "machine.i_s", scale=1.0 / K_PEAK),
        over_limit("current_over_limit", "machine.i_s", setup.i_max),
        Reducer("torque_peak_n_m", "peak", "machine.tau_e"),
        Reducer("voltage_command_peak_v", "peak", "current.v_dq_wanted"),
    ]
    steps = as_steps(step_events(setup))
    if steps:
        out.append(Reducer("speed_step", "step_response", "shaft.w", "speed_reference.w_ref",
                           unit="rad_s", steps=steps))  # fmt: skip
    return out
