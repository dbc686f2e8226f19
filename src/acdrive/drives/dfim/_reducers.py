"""The default on-line metrics of a DFIM drive in a batch or sweep (``acdrive.batch.Reducer``)
and the batch's stability verdict on them."""

from __future__ import annotations

import math

from acdrive._frames import K_PEAK as SQRT_3_2
from acdrive._reducer_parts import Reducer, as_steps, over_limit
from acdrive.sim._metrics import OSCILLATION_FINDING_RPM, RPM_PER_RAD_S


def dfim_reducers(setup) -> list[Reducer]:
    """The default metrics of a DFIM drive, per motor k (suffix ``_m<k>`` beyond the first):
    the speed error over the whole run and where tracking is expected (the columns of
    ``sim._metrics.speed_error_figures``, the window of ``drives.dfim._tracking.tracking_rule``: the
    single run's figures of the same names), the band-limited speed oscillation over the last
    ``LATE_WINDOW_S`` and its growth (``speed_oscillation_late_rpm``), peak phase currents [A]
    and samples above the controller's current limits by more than OVER_LIMIT_TOLERANCE
    (``acdrive._reducer_parts``), peak torque, final speed, and the step response of each
    speed-reference change and load step (the columns of ``sim._step_response.flat``: the
    summary's ``step_response`` figures, in rpm)."""
    from acdrive.drives.dfim._recovery import step_events
    from acdrive.drives.dfim._tracking import tracking_rule

    out = []
    for k, motor in enumerate(setup.motors):
        sfx = "" if k == 0 else f"_m{k}"
        c = motor.controller
        w, ref = f"shaft{k}.w", f"reference{k}.w_ref"
        out += [
            Reducer(
                "speed",
                "speed_error",
                w,
                ref,
                gate=f"relay{k}.closed",
                rule=tracking_rule(setup, k),
                scale=RPM_PER_RAD_S,
                unit="rpm",
                suffix=sfx,
            ),
            Reducer(f"speed_oscillation_late_rpm{sfx}", "oscillation", w, ref, scale=RPM_PER_RAD_S),
            Reducer(f"peak_stator_current_a{sfx}", "peak", f"dfim{k}.i_s", scale=1 / SQRT_3_2),
            Reducer(f"peak_rotor_current_a{sfx}", "peak", f"dfim{k}.i_r_rotor", scale=1 / SQRT_3_2),
            over_limit(f"stator_current_over_limit{sfx}", f"dfim{k}.i_s",
                       SQRT_3_2 * c.stator_current_limit_pk),
            over_limit(f"rotor_current_over_limit{sfx}", f"dfim{k}.i_r_rotor",
                       SQRT_3_2 * c.rotor_current_limit_pk),
            Reducer(f"peak_torque_nm{sfx}", "peak", f"dfim{k}.tau_e"),
            Reducer(f"final_speed_rpm{sfx}", "final", w, scale=RPM_PER_RAD_S),
        ]
        steps = as_steps(step_events(setup, k))
        if steps:
            out.append(Reducer("speed_step", "step_response", w, ref, scale=RPM_PER_RAD_S,
                               unit="rpm", suffix=sfx, steps=steps))  # fmt: skip
    return out


def verdict(row: dict) -> bool | None:
    """A batch row's ``stable``: False if the late speed oscillation of any motor (its RMS in
    ``OSCILLATION_BAND_HZ`` over the last ``LATE_WINDOW_S``, ``sim._metrics``) exceeds
    ``OSCILLATION_FINDING_RPM`` (the threshold of the single run's limit-cycle finding); True
    otherwise; None without that metric."""
    keys = [
        k for k in row if k.startswith("speed_oscillation_late_rpm") and not k.endswith("_growth")
    ]
    if not keys:
        return None
    values = [row[k] for k in keys]
    if any(math.isnan(v) for v in values):
        return None
    return bool(max(values) <= OSCILLATION_FINDING_RPM)
