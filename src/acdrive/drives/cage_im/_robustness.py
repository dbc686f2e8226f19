"""The cage-IM drive's answers to a robustness map (``acdrive.robustness``): the plant-only
perturbation table ``machine.perturbation`` (Amezquita-Brooks et al. sec. VIII), the criteria on a
variant's batch row and the linearised prediction of its current loop.

Criteria: tracking, with imposed currents (mode ``current``) the RMS of |i_s - i_s,ref| over
[``simulation.metrics_from``, end] at most a fraction of the reference's space-vector amplitude
sqrt(3/2) I_pk; with a speed loop the RMS speed error over the tracking window
(``im_tracking_rule``) at most a fraction of the largest |speed reference|; current limit, the
peak |i_s| over the run at most (1 + tolerance) times the FOC's current limit (``foc.i_max``, the
drive's default limit in mode ``current``, where no controller limits it); stability, a run that
finished with a finite state. A variant whose sampled current loop is unstable is refused by the
scenario's own pre-check (``_schema._check_controller``) before it runs; the map reports it as
refused, with that one-line reason.

Prediction: the spectral radius of the compiled sampled current loop over one carrier period
(``_current_loop.current_loop_radius``, the plant of the variant, the controller of the nominal
design) at the run's top speed; stable if < 1.
"""

from __future__ import annotations

import numpy as np

from acdrive._frames import K_PEAK as SQRT_3_2
from acdrive._reducer_parts import Reducer
from acdrive.drives._robustness_seam import (
    FINITE_RUN,
    Criterion,
    RobustnessSeam,
    finished_finite,
)
from acdrive.drives.cage_im._reducers import im_reducers
from acdrive.drives.cage_im._schema import PARAMS_FIELDS

FIELDS = {"R_s": "R_s", "R_r": "R_r", "L_s": "L_s", "L_r": "L_r", "L_m": "L_m", "J": "J"}
#: default tracking tolerance of imposed currents (fraction of the reference amplitude): the
#: current controllers of Amezquita-Brooks et al. are judged on waveforms, not on 1 % errors
CURRENT_TRACKING_DEFAULT = 0.1


def reducers(setup) -> list[Reducer]:
    out = im_reducers(setup)
    if setup.mode == "current":
        reference = "reference.i"
        out.append(Reducer("current_error_rms_settled_a", "rms", "machine.i_s", reference,
                           start=setup.metrics_from))  # fmt: skip
    return out


def criteria(setup, tolerances) -> list[Criterion]:
    i_max = setup.foc.i_max
    if setup.mode == "current":
        tol = tolerances.tracking if tolerances.tracking is not None else CURRENT_TRACKING_DEFAULT
        scale = SQRT_3_2 * abs(setup.current_reference.amplitude_pk)
        tracking = Criterion(
            "tracking", "current_error_rms_settled_a", tol * scale, "A",
            f"RMS |i_s - i_s,ref| over [{setup.metrics_from:g} s, end] <= {tol:g} x the "
            f"reference amplitude sqrt(3/2) I_pk = {scale:.4g} A",
        )  # fmt: skip
    else:
        tol = tolerances.tracking if tolerances.tracking is not None else 0.01
        top = setup.top_speed()
        tracking = Criterion("tracking", "speed_rms_error_tracking_rad_s", tol * top, "rad/s",
                             f"RMS speed error over the tracking window <= {tol:g} x the "
                             f"largest |speed reference| ({top:.4g} rad/s)")  # fmt: skip
    return [
        tracking,
        Criterion("current_limit", "peak_stator_current_a", (1 + tolerances.current) * i_max, "A",
                  f"peak |i_s| over the run <= {1 + tolerances.current:g} x the FOC current "
                  f"limit ({i_max:.4g} A, space vector)"),
        FINITE_RUN,
    ]  # fmt: skip


def derived(setup, row: dict) -> dict:
    """The stability flag of a finished row (the drive has no late-oscillation verdict)."""
    return finished_finite(row, ("current_error", "peak_stator"))


def linear(setup) -> dict:
    from acdrive.control._current import StationaryCurrentController
    from acdrive.drives.cage_im._current_loop import current_loop_radius

    cc = setup.current_control
    part = StationaryCurrentController("current", cc.lti, setup.sample_time, cc.method,
                                       cc.prewarp, v_dc_input=True, aw_gain=cc.aw_gain)  # fmt: skip
    top = setup.top_speed()
    radius = max(current_loop_radius(setup.plant, float(w), part, setup.carrier_samples,
                                     setup.substeps) for w in np.linspace(0.0, top, 3))  # fmt: skip
    return {"predicted_stable": bool(radius < 1.0), "spectral_radius": radius}


def design_figures(setup) -> dict:
    """The designs of the drive as it builds them: the IFOC's estimates R_r, L_r, L_m (its slip
    law, ``control._foc`` (slip)), the speed PI's K_P, K_I (mode speed-pi), the current
    controller by name and whether it is re-derived from the design machine ("imc-pi",
    ``_current_design``, with its K_P, K_I; "icad-proposed", with the specifications its ICAD
    check meets, its gain and PI zero) or fixed (a built-in published transfer function such
    as Amezquita-Brooks et al.'s (20)), and the spectral radius of the sampled current loop on the
    simulated plant (``linear``)."""
    est = setup.estimates
    out = {f"ifoc_{k}": float(getattr(est, k)) for k in ("R_r", "L_r", "L_m")}
    if setup.mode == "speed-pi":
        out.update({"K_P": setup.speed_pi.K_P, "K_I": setup.speed_pi.K_I})
    cc = setup.current_control
    out["current_controller"] = cc.controller
    if cc.proposal is not None:
        check = cc.proposal.check
        out["current_controller_design"] = (
            f"re-derived from the design machine (ICAD propose_controller, "
            f"{cc.proposal.candidate.structure})"
        )
        out["current_icad_specs_met"] = (
            "all" if check.met_all else "unmet: " + ", ".join(check.unmet)
        )
        out["current_icad_gain"] = cc.proposal.candidate.gain
        out["current_icad_pi_zero_rad_s"] = cc.proposal.candidate.pi_zero
    elif cc.designed:
        out["current_controller_design"] = (
            f"re-derived from the design machine (internal-model "
            f"PI, bandwidth {cc.bandwidth:g} rad/s)"
        )
        out["current_K_P"], out["current_K_I"] = cc.pi_gains
    else:
        out["current_controller_design"] = (
            "fixed: a published transfer function, not re-derived from any machine"
        )
    out["current_loop_spectral_radius"] = linear(setup)["spectral_radius"]
    return out


#: electrical rotor speeds of the ICAD check, as fractions of the run's top speed
_ICAD_SPEEDS = (0.0, 1 / 3, 2 / 3, 1.0)


def icad_point(setup, factors: dict) -> dict:
    """ICAD of the continuous current loop (Amezquita-Brooks et al. Figs. 21-22; ``analysis.
    perturbation_sweep``) with the scenario's current controller on the nominal machine perturbed
    by ``factors``, at electrical rotor speeds ``_ICAD_SPEEDS`` x n_p x the run's top speed
    (at least 375 rad/s, Fig. 21's range): conditions i-iv at every speed (gamma does not
    encircle (1, 0)) and the worst structural gain margin and channel phase margin."""
    from acdrive.analysis._robustness import Perturbation, perturbation_sweep

    top = max(setup.machine.n_p * setup.top_speed(), 375.0)
    speeds = [f * top for f in _ICAD_SPEEDS]
    lti = setup.current_control.lti
    r = perturbation_sweep(setup.machine, lti, lti, speeds, [Perturbation(**factors)])
    return {"conditions_hold": bool(r.all_conditions),
            "worst_structural_gm_db": r.worst["structural_gm_db"].value,
            "worst_channel_pm_deg": r.worst["pm_deg"].value,
            "speeds_rad_s": speeds}  # fmt: skip


SEAM = RobustnessSeam(
    table="machine.perturbation",
    fields=FIELDS,
    reducers=reducers,
    criteria=criteria,
    derived=derived,
    linear=linear,
    design_table="design",
    design_fields=PARAMS_FIELDS,
    design_figures=design_figures,
    point_analysis=icad_point,
    linear_rule=(
        "spectral radius of the sampled current loop over one carrier period (plant of the "
        "variant, controller of the nominal design) at 0, 1/2 and 1 x the run's top speed: "
        "stable if < 1"
    ),
)
