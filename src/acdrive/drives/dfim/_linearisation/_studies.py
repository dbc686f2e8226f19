"""Studies over many linearisations of the DFIM drive (``drives.dfim._linearisation._stability``): stability
maps over speed x load, the tolerated speed-loop bandwidth a_D,VEL, and the candidate effects of
Bodson's test bench with the size each must have to remove the instability (docs/stability.md).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from acdrive._arguments import POSITIVE, Array, Either, Instance, Number, Text, checked
from acdrive.control._speed import SpeedPIGains
from acdrive.drives.dfim._linearisation._stability import (
    KINDS,
    MODES,
    DriveModel,
    _torque_window,
    linearize,
    view_of,
)
from acdrive.drives.dfim._linearisation._view import RAD_S_PER_RPM, OperatingPoint
from acdrive.drives.dfim._setup import ConverterLosses, DriveSetup
from acdrive.errors import InputError
from acdrive.machines._dfim import BODSON_DFIM

# ---------------------------------------------------------------------------------------------
# maps over operating points and the tolerated velocity bandwidth
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class StabilityMap:
    """max_real_part[i, j] and stable[i, j] at speeds_rpm[i], loads_nm[j] for one model.

    feasible[i, j] is False where the drive has no equilibrium inside its limits (max_real_part
    is then NaN and stable False); ``all_stable`` looks at the feasible points only.
    """

    model: object  # the DriveSetup or DriveModel
    kind: str
    speeds_rpm: np.ndarray
    loads_nm: np.ndarray
    max_real_part: np.ndarray
    stable: np.ndarray
    feasible: np.ndarray

    @property
    def all_stable(self) -> bool:
        return bool(np.all(self.stable[self.feasible]))


def default_grid(model, n_speed: int = 13, n_load: int = 7, fraction: float = 0.9):
    """Speeds 0..2,700 rpm (the paper's experiments) and loads across ``fraction`` of the torque
    window (30)-(37) of the controller at the nominal supply."""
    view = view_of(model, OperatingPoint(0.0))
    lo, hi = _torque_window(view, view.v_g)
    speeds = np.linspace(0.0, 2700.0, n_speed)
    loads = np.linspace(fraction * lo, fraction * hi, n_load)
    return speeds, loads


@checked(
    model=Either(Instance(DriveSetup), Instance(DriveModel)), speeds_rpm=Array(1),
    loads_nm=Array(1), kind=Text(KINDS),
)
def stability_map(model, speeds_rpm, loads_nm, kind: str = "continuous") -> StabilityMap:
    """Linearise ``model`` (a DFIM ``DriveSetup`` or a :class:`DriveModel`) at every
    (speed, load) of the grid."""
    speeds_rpm = np.asarray(speeds_rpm, dtype=float)
    loads_nm = np.asarray(loads_nm, dtype=float)
    mrp = np.empty((speeds_rpm.size, loads_nm.size))
    stable = np.zeros(mrp.shape, dtype=bool)
    feasible = np.ones(mrp.shape, dtype=bool)
    for i, n in enumerate(speeds_rpm):
        for j, tl in enumerate(loads_nm):
            try:
                r = linearize(model, OperatingPoint(n * RAD_S_PER_RPM, tl), kind)
            except InputError as exc:
                if exc.field != "load_torque":
                    raise
                mrp[i, j], feasible[i, j] = np.nan, False
                continue
            feasible[i, j] = r.within_limits
            mrp[i, j], stable[i, j] = r.max_real_part, r.stable
    return StabilityMap(model, kind, speeds_rpm, loads_nm, mrp, stable, feasible)


def with_speed_bandwidth(study, bandwidth: float):
    """``study`` (a :class:`DriveModel` or a DFIM ``DriveSetup``) with the speed PI of motor 0
    designed for a_D,VEL = ``bandwidth`` by (27) with the same design inertia and K_F (of a
    setup: J = K_P^2 / (4 K_I), the inertia its gains were designed with)."""
    if isinstance(study, DriveModel):
        return dataclasses.replace(study, speed_bandwidth=bandwidth)
    motor = study.motors[0]
    g = motor.controller.gains
    gains = dataclasses.replace(SpeedPIGains.design(g.K_P**2 / (4.0 * g.K_I), bandwidth), K_F=g.K_F)
    controller = dataclasses.replace(motor.controller, gains=gains)
    motor = dataclasses.replace(motor, controller=controller)
    return dataclasses.replace(study, motors=(motor, *study.motors[1:]))


@checked(
    mode=Either(Text(MODES), Instance(DriveSetup)), speeds_rpm=Array(1, optional=True),
    loads_nm=Array(1, optional=True),
    kind=Text(KINDS), lower=POSITIVE, upper=POSITIVE, tol=POSITIVE, ratio=Number(1.0, above=True),
)
def max_stable_bandwidth(
    mode="voltage",
    speeds_rpm=None,
    loads_nm=None,
    *,
    kind: str = "continuous",
    lower: float = 5.0,
    upper: float = 3000.0,
    tol: float = 1.0,
    ratio: float = 1.25,
    **model_fields,
) -> float:
    """Largest a_D,VEL [rad/s] such that every grid point is stable for every bandwidth from
    ``lower`` up to it: the bandwidth is raised geometrically (factor ``ratio``) until a grid
    point becomes unstable, then the boundary is bisected to ``tol``. (Stability need not be
    monotonic in a_D,VEL: the voltage-command drive regains stability at no load in a window of
    higher bandwidths; this function reports the first loss.) Returns ``upper`` if no loss is
    found, 0.0 if the grid is unstable at ``lower``.

    ``mode``: "voltage" or "current" (a :class:`DriveModel` of that mode and ``model_fields``),
    or a DFIM ``DriveSetup`` whose speed PI is redesigned (:func:`with_speed_bandwidth`).
    """
    base = mode if isinstance(mode, DriveSetup) else DriveModel(mode=mode, **model_fields)
    if speeds_rpm is None or loads_nm is None:
        speeds_rpm, loads_nm = default_grid(base)

    def ok(a):
        return stability_map(with_speed_bandwidth(base, a), speeds_rpm, loads_nm, kind).all_stable

    if not ok(lower):
        return 0.0
    a = lower
    while a < upper:
        nxt = min(a * ratio, upper)
        if not ok(nxt):
            return _boundary(ok, a, nxt, tol, stable_below=True)
        a = nxt
    return upper


def _boundary(ok, lower: float, upper: float, tol: float, stable_below: bool) -> float:
    """Bisection for the value where ``ok`` (stable) changes, assuming it changes once.

    stable_below: stable at ``lower`` and unstable beyond the boundary (returns the largest
    stable value; 0.0 if unstable at ``lower``, ``upper`` if stable there); otherwise unstable
    at ``lower`` and stable beyond (returns the smallest stable value; ``lower`` if stable there,
    inf if unstable even at ``upper``).
    """
    if stable_below:
        if not ok(lower):
            return 0.0
        if ok(upper):
            return upper
    else:
        if ok(lower):
            return lower
        if not ok(upper):
            return math.inf
    lo, hi = lower, upper  # invariant: ok(lo) == stable_below != ok(hi)
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if ok(mid) == stable_below else (lo, mid)
    return lo if stable_below else hi


def _first_stable(ok, lower: float, upper: float, step: float, tol: float) -> float:
    """Smallest value in [lower, upper] where ``ok`` holds: scan by ``step``, then bisect the
    last step to ``tol`` (inf if ``ok`` never holds on the scan)."""
    if ok(lower):
        return lower
    v = lower
    while v < upper:
        nxt = min(v + step, upper)
        if ok(nxt):
            return _boundary(ok, v, nxt, tol, stable_below=False)
        v = nxt
    return math.inf


# ---------------------------------------------------------------------------------------------
# why the test bench did not oscillate: candidate effects, each in the linear model
# ---------------------------------------------------------------------------------------------


#: fundamental converter loss [V] of the paper scenarios' bench converter (1 us dead time at
#: 10 kHz on 30 V, 0.7 V device drop: sqrt(3/2) (4/pi) (0.3 + 0.7) V)
BENCH_LOSS = ConverterLosses(
    dead_time=1e-6, switching_frequency=10e3, device_drop=0.7
).fundamental_loss(30.0)


@dataclass(frozen=True)
class Candidate:
    """One effect the paper's bench may have had, as a DriveModel (and linearisation kind)."""

    name: str
    model: DriveModel
    kind: str = "continuous"


@dataclass(frozen=True)
class CandidateResult:
    """max_real_part at 900 rpm / 0 N m, worst over speeds 0..2700 rpm at zero load, and worst
    over the speed x load grid (feasible points); stable_*: the corresponding verdicts."""

    candidate: Candidate
    max_real_part_900: float
    worst_zero_load: float
    worst_grid: float
    stable_zero_load: bool
    stable_grid: bool


def bench_candidates(bandwidth: float = 314.0) -> list[Candidate]:
    """The effects named in issue 3 and a few more, at velocity bandwidth ``bandwidth``, voltage
    command. Parameter errors are in the controller's estimates unless the name says "true"."""
    m0 = BODSON_DFIM
    base = DriveModel(speed_bandwidth=bandwidth, design_inertia=m0.J)
    replace = dataclasses.replace

    def est(**changes):
        return dataclasses.replace(base, controller_params=dataclasses.replace(m0, **changes))

    def true(**changes):
        return dataclasses.replace(
            base, machine=dataclasses.replace(m0, **changes), controller_params=m0
        )

    c = [
        Candidate("paper model (continuous-time law)", base),
        Candidate("sampled 5 kHz, ZOH, encoder difference", base, "sampled"),
        Candidate("sampled + one-sample computation delay", replace(base, delay_samples=1), "sampled"),
        Candidate("speed filter 1 ms", replace(base, speed_filter_tau=1e-3)),
        Candidate("speed filter 5 ms", replace(base, speed_filter_tau=5e-3)),
        Candidate("transformer R 0.3 ohm", replace(base, supply_resistance=0.3)),
        Candidate("transformer L 0.5 mH", replace(base, supply_inductance=0.5e-3)),
        Candidate(
            "transformer R 0.3 ohm + L 0.5 mH",
            replace(base, supply_resistance=0.3, supply_inductance=0.5e-3),
        ),
        Candidate("controller R_s x 0.7", est(R_s=0.7 * m0.R_s)),
        Candidate("controller R_s x 1.3", est(R_s=1.3 * m0.R_s)),
        Candidate("controller R_r x 0.7", est(R_r=0.7 * m0.R_r)),
        Candidate("controller R_r x 1.3", est(R_r=1.3 * m0.R_r)),
        Candidate("controller L_s, L_r, M x 0.9", est(L_s=0.9 * m0.L_s, L_r=0.9 * m0.L_r, M=0.9 * m0.M)),
        Candidate("controller M x 0.95", est(M=0.95 * m0.M)),
        Candidate("DC machine viscous B = 1e-4 (0.028 N m at 283 rad/s)", true(B=1e-4)),
        Candidate("true J = 2 x design", true(J=2 * m0.J)),
        Candidate("true J = 3 x design", true(J=3 * m0.J)),
        Candidate("true R_s x 2 (hot winding, cables)", true(R_s=2 * m0.R_s)),
        Candidate("true R_r + 0.25 ohm (converter, brushes, cables)", true(R_r=m0.R_r + 0.25)),
        Candidate("true R_r + 0.5 ohm (converter, brushes, cables)", true(R_r=m0.R_r + 0.5)),
        Candidate("converter voltage loss 1 V (dead time, device drops)", replace(base, converter_loss=1.0)),
        Candidate("converter voltage loss 2 V (dead time, device drops)", replace(base, converter_loss=2.0)),
        Candidate("scenario bench converter 1.56 V, sampled", replace(base, converter_loss=BENCH_LOSS), "sampled"),
        Candidate("scenario bench converter 1.56 V, sampled + delay", replace(base, converter_loss=BENCH_LOSS, delay_samples=1), "sampled"),
    ]  # fmt: skip
    return c


def evaluate_candidate(candidate: Candidate, n_speed: int = 7, n_load: int = 5) -> CandidateResult:
    """Linearise ``candidate`` at 900 rpm / 0 N m, along the zero-load line and over the grid."""
    m, kind = candidate.model, candidate.kind
    speeds, loads = default_grid(m, n_speed, n_load)
    zero = stability_map(m, speeds, [0.0], kind)
    grid = stability_map(m, speeds, loads, kind)
    at_900 = linearize(m, OperatingPoint(900 * RAD_S_PER_RPM, 0.0), kind)
    return CandidateResult(
        candidate=candidate,
        max_real_part_900=at_900.max_real_part,
        worst_zero_load=_worst(zero),
        worst_grid=_worst(grid),
        stable_zero_load=zero.all_stable,
        stable_grid=grid.all_stable,
    )


def _worst(m: StabilityMap) -> float:
    return float(np.max(np.where(m.feasible, m.max_real_part, -np.inf)))


@dataclass(frozen=True)
class Threshold:
    """Smallest value of a bench quantity that makes the voltage-command drive stable at the
    given bandwidth: along the zero-load line and over the whole speed x load grid (inf: not
    reached within the searched range, or the drive loses its equilibrium first, e.g. a viscous
    load that needs more torque than the limits allow)."""

    name: str
    unit: str
    zero_load: float
    grid: float


def stabilising_thresholds(
    bandwidth: float = 314.0,
    n_speed: int = 7,
    n_load: int = 5,
    kind: str = "continuous",
    **model_fields,
) -> list[Threshold]:
    """How large the true inertia, an extra rotor-circuit resistance unknown to the controller,
    a viscous load or a converter voltage loss must be for the drive to be stable at
    ``bandwidth``: the smallest such value (scan, then bisection).

    "zero load": speeds 0..2,700 rpm without load; "grid": the same speeds with loads across 90 %
    of the torque window, judged at the points where the drive keeps an equilibrium inside its
    limits (for the viscous load and the converter loss, which themselves cost torque or rotor
    voltage, a point they push outside the limits counts as a failure). ``model_fields`` go to the DriveModel (e.g. delay_samples=1);
    """
    m0 = BODSON_DFIM
    base = DriveModel(
        speed_bandwidth=bandwidth, design_inertia=m0.J, controller_params=m0, **model_fields
    )
    speeds, _ = default_grid(base, n_speed, n_load)

    def true(**changes):
        return dataclasses.replace(base, machine=dataclasses.replace(m0, **changes))

    makers = (  # name, unit, model for value v, scan range and step, tolerance, strict
        ("true J / design J", "-", lambda v: true(J=v * m0.J), 1.0, 10.0, 0.25, 0.01, False),
        ("extra rotor resistance", "ohm", lambda v: true(R_r=m0.R_r + v), 0.0, 3.0, 0.1, 0.005, False),
        ("viscous friction B", "N m s/rad", lambda v: true(B=v), 0.0, 0.02, 5e-4, 1e-5, True),
        ("converter voltage loss", "V", lambda v: dataclasses.replace(base, converter_loss=v), 0.0, 6.0, 0.25, 0.01, True),
    )  # fmt: skip
    out = []
    for name, unit, make, lo, hi, step, tol, strict in makers:
        verdicts = []
        for grid in ("zero", "full"):

            def ok(v, grid=grid, make=make, strict=strict):
                model = make(v)
                _, loads = default_grid(model, n_speed, n_load)
                m = stability_map(model, speeds, [0.0] if grid == "zero" else loads, kind)
                # the friction is itself a load: a point it pushes outside the limits fails
                return bool(np.all(m.stable)) if strict else m.all_stable

            verdicts.append(_first_stable(ok, lo, hi, step, tol))
        out.append(Threshold(name, unit, *verdicts))
    return out
