"""The PM speed drive's answers to a robustness map (``acdrive.robustness``): the plant-only
perturbation table ``machine.perturbation`` (R_s, L_d, L_q, psi_m on the simulated machine, J on
the simulated shaft), the criteria on a variant's batch row, the linearised prediction of its
current loop and the design quantities a design comparison prints.

Criteria: tracking, the RMS speed error over the last quarter of the run ([0.75 duration, end]:
the settled drive under its final load: in the built-in BLY171D scenarios the speed step and
the load step at 0.1 s lie before it) at most a fraction (default 1 %) of the largest |speed
reference|; current limit, the peak phase current over the run at most (1 + tolerance) times the
controller's limit ``control.current_limit_pk_a``; stability, a run that finished with a finite
state. A variant whose sampled current loop is unstable is refused by the scenario's own
pre-check (``_period.check_current_period``) before it runs.

Prediction: the larger spectral radius of the two sampled current-loop axes
(``_period.axis_radii``: PI designed on the controller's machine, plant the variant's), stable if
< 1.
"""

from __future__ import annotations

from acdrive._reducer_parts import Reducer
from acdrive.core._signals import pack_table
from acdrive.drives._robustness_seam import (
    FINITE_RUN,
    Criterion,
    RobustnessSeam,
    finished_finite,
)
from acdrive.drives.pm._reducers import pm_reducers
from acdrive.drives.pm._schema import MACHINE_FIELDS

#: the map's parameter names -> the keys of ``[machine.perturbation]``
FIELDS = {"R_s": "R_s", "L_d": "L_d", "L_q": "L_q", "psi_m": "psi_m", "J": "J"}
#: default tracking tolerance: RMS speed error over the window / largest |speed reference|
TRACKING_DEFAULT = 0.01
#: the tracking window starts at this fraction of the run
TRACKING_FROM = 0.75


def top_speed(setup) -> float:
    """The largest |speed reference| of the run [rad/s]."""
    packed = pack_table("speed_reference", setup.speed_reference)
    n = int(packed[0])
    return float(max(abs(float(v)) for v in packed[1 + n : 1 + 2 * n]))


def reducers(setup) -> list[Reducer]:
    return [*pm_reducers(setup),
            Reducer("speed_error_rms_tracking_rad_s", "rms", "shaft.w", "speed_reference.w_ref",
                    start=TRACKING_FROM * setup.duration)]  # fmt: skip


def criteria(setup, tolerances) -> list[Criterion]:
    tol = tolerances.tracking if tolerances.tracking is not None else TRACKING_DEFAULT
    top = top_speed(setup)
    limit = (1.0 + tolerances.current) * setup.i_max_peak
    return [
        Criterion("tracking", "speed_error_rms_tracking_rad_s", tol * top, "rad/s",
                  f"RMS speed error over [{TRACKING_FROM * setup.duration:g} s, end] <= {tol:g} "
                  f"x the largest |speed reference| ({top:.4g} rad/s)"),
        Criterion("current_limit", "current_peak_a", limit, "A",
                  f"peak phase current over the run <= {1 + tolerances.current:g} x the "
                  f"controller's limit ({setup.i_max_peak:.4g} A peak)"),
        FINITE_RUN,
    ]  # fmt: skip


def derived(setup, row: dict) -> dict:
    """The stability flag of a finished row (the drive has no late-oscillation verdict)."""
    return finished_finite(row, ("speed_error", "current_peak"))


def linear(setup) -> dict:
    from acdrive.drives.pm._period import axis_radii

    radius = max(axis_radii(setup).values())
    return {"predicted_stable": bool(radius < 1.0), "spectral_radius": radius}


def design_figures(setup) -> dict:
    """The designs as the drive builds them (``_build.controller_parts``): the current PI's
    K_P,d, K_P,q, K_I (internal-model design on the controller's R_s, L_d, L_q), the speed PI's
    K_P, K_I (on its design J), the controller's estimates and the sampled current loop's
    spectral radius on the simulated plant (``linear``)."""
    from acdrive.control._speed import SpeedPIGains
    from acdrive.drives.pm._design import CurrentPIGains

    m = setup.controller_machine
    cur = CurrentPIGains.design(m.R_s, m.L_d, m.L_q, setup.current_bandwidth)
    spd = SpeedPIGains.design(setup.speed_design_J, setup.speed_bandwidth, K_F=setup.K_F)
    out = {f"estimate_{k}": float(getattr(m, k)) for k in ("R_s", "L_d", "L_q", "psi_m")}
    out.update({"design_J": setup.speed_design_J, "K_P_d": cur.K_P_d, "K_P_q": cur.K_P_q,
                "K_I_current": cur.K_I_d, "speed_K_P": spd.K_P, "speed_K_I": spd.K_I,
                "torque_limit_n_m": setup.torque_limit})  # fmt: skip
    out["current_loop_spectral_radius"] = linear(setup)["spectral_radius"]
    out["controllers_design"] = (
        "re-derived from the design machine: current PI, MTPA and field-weakening references, "
        "torque limit, speed PI (design J); none fixed"
    )
    return out


SEAM = RobustnessSeam(
    table="machine.perturbation",
    fields=FIELDS,
    reducers=reducers,
    criteria=criteria,
    derived=derived,
    linear=linear,
    design_table="design",
    design_fields=MACHINE_FIELDS,
    design_figures=design_figures,
    linear_rule=(
        "spectral radius of the sampled d- and q-axis current loops at standstill (PI designed "
        "on the controller's machine, plant the variant's): stable if < 1"
    ),
)
