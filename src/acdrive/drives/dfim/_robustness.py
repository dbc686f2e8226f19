"""The DFIM drive's answers to a robustness map (``acdrive.robustness``): the plant-only
perturbation table ``motor[0].perturbation``, the criteria on a variant's batch row and the
linearised prediction of its stability.

Criteria (motor 0): tracking, the RMS speed error over the tracking window
(``drives.dfim._tracking.tracking_rule``: where the reference is reachable and the relay
closed) at most a fraction of the largest |speed reference|; current limit, the peak stator and
rotor phase currents over the whole run at most (1 + tolerance) times the controller's limits
(Bodson (43)); stability, the batch's verdict (no speed oscillation above
``OSCILLATION_FINDING_RPM`` in 20-200 Hz over the last 0.25 s, finite state).

Prediction: the sampled-data linearisation (``drives.dfim._linearisation.linearize``, kind
"sampled") at the run's final operating point (final speed reference and load), where the
stability verdict's window lies; stable if every eigenvalue of the one-sample map is inside the
unit circle.
"""

from __future__ import annotations

import math

import numpy as np

from acdrive.drives._robustness_seam import Criterion, RobustnessSeam
from acdrive.drives.dfim._reducers import dfim_reducers
from acdrive.drives.dfim._schema import DESIGN_ALIASES, PARAMS_FIELDS
from acdrive.sim._metrics import OSCILLATION_FINDING_RPM, RPM_PER_RAD_S

#: default tracking tolerance: RMS speed error over the tracking window / largest |reference|
TRACKING_DEFAULT = 0.01
FIELDS = {"R_s": "R_s", "R_r": "R_r", "L_s": "L_s", "L_r": "L_r", "L_m": "M", "J": "J"}


def criteria(setup, tolerances) -> list[Criterion]:
    motor = setup.motors[0]
    c = motor.controller
    tol = tolerances.tracking if tolerances.tracking is not None else TRACKING_DEFAULT
    top_rpm = float(np.max(np.abs(motor.speed_reference[1]))) * RPM_PER_RAD_S
    limit = max(c.stator_current_limit_pk, c.rotor_current_limit_pk)
    peak = "peak_phase_current_over_limit"
    return [
        Criterion("tracking", "speed_rms_error_tracking_rpm", tol * top_rpm, "rpm",
                  f"RMS speed error over the tracking window <= {tol:g} x the "
                  f"largest |speed reference| ({top_rpm:g} rpm)"),
        Criterion(
            "current_limit", peak, 1.0 + tolerances.current, "",
            f"peak stator and rotor phase currents over the run <= {1 + tolerances.current:g} "
            f"x the controller's limits ({c.stator_current_limit_pk:g} A, "
            f"{c.rotor_current_limit_pk:g} A peak; largest {limit:g} A)",
        ),
        Criterion("stability", "stable", 0.0, "",
                  f"speed oscillation (20-200 Hz) over the last 0.25 s <= "
                  f"{OSCILLATION_FINDING_RPM:g} rpm RMS and a finite state"),
    ]  # fmt: skip


def derived(setup, row: dict) -> dict:
    """The figures a criterion reads that the reducers do not give directly."""
    c = setup.motors[0].controller
    ratios = [row.get("peak_stator_current_a", math.nan) / c.stator_current_limit_pk,
              row.get("peak_rotor_current_a", math.nan) / c.rotor_current_limit_pk]  # fmt: skip
    return {"peak_phase_current_over_limit": float(max(ratios))}


def linear(setup) -> dict:
    from acdrive.drives.dfim._linearisation._stability import linearize
    from acdrive.errors import InputError

    try:
        r = linearize(setup, None, "sampled")
    except InputError as exc:
        return {"predicted_stable": None, "linear_note": exc.rule}
    radius = float(np.max(np.abs(r.z_eigenvalues)))
    return {"predicted_stable": bool(r.stable), "spectral_radius": radius,
            "within_limits": bool(r.within_limits)}  # fmt: skip


def design_figures(setup) -> dict:
    """Bodson's a-priori design of motor 0 as the drive uses it: K_P, K_I, K_F of (25)-(27), K_P,C
    and K_I,C of (49) (``DFIMController.current_gains``), the controller's estimates (its laws'
    R_s, R_r, L_s, L_r, M) and the design inertia J = K_P^2 / (4 K_I) (27)."""
    motor = setup.motors[0]
    c = motor.controller
    est = c.params or motor.machine
    k_pc, k_ic = c.current_gains(motor.machine)
    out = {"K_P": c.gains.K_P, "K_I": c.gains.K_I, "K_F": c.gains.K_F, "K_PC": k_pc, "K_IC": k_ic,
           "design_J": c.gains.K_P**2 / (4.0 * c.gains.K_I)}  # fmt: skip
    out.update({f"estimate_{k}": float(getattr(est, k)) for k in ("R_s", "R_r", "L_s", "L_r", "M")})
    return out


SEAM = RobustnessSeam(
    table="motor[0].perturbation",
    fields=FIELDS,
    reducers=dfim_reducers,
    criteria=criteria,
    derived=derived,
    linear=linear,
    design_table="motor[0].design",
    design_fields=PARAMS_FIELDS,
    design_aliases=DESIGN_ALIASES,
    design_figures=design_figures,
    linear_rule=(
        "sampled-data linearisation at the final speed reference and load (where the stability "
        "window lies): stable if the one-sample map's spectral radius < 1"
    ),
)
