"""Individual channel analysis (ICAD) of 2x2 plants with diagonal controllers: ``analyse``,
``sweep`` and the built-in controllers of ``acdrive icad``.

Ugalde-Loo et al. (1)-(6) and Amezquita-Brooks et al. (5)-(10): for y = G u and u_i = k_i e_i,
the individual channels c_i = k_i g_ii (1 - gamma h_j), their margins and Nyquist counts, the
diagonal loops h_i and the coupling y_i / r_j, for one plant (``analyse``) or over a set of
plants (``sweep``, ``summarize``). The pieces: the quantities on frequency grids
(``_icad_frequency``), roots and exact Nyquist counts (``_icad_roots``), the structure conditions
i-iv (``_icad_conditions``) and the papers' closed forms (``_icad_closed_forms``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from acdrive._arguments import FLAG, Array, Instance, Items, checked
from acdrive.analysis._freqresp import LTI, check_frequency_grid
from acdrive.analysis._icad_conditions import StructureConditions, siso_zeros, structure_conditions
from acdrive.analysis._icad_frequency import ICADResponse, PointEvaluator, icad_response
from acdrive.analysis._icad_roots import (
    NyquistCount,
    close_loop,
    eigenvalues,
    invariant_zeros,
    markov_zero,
    nyquist_count,
    on_axis,
    scalar_d,
)
from acdrive.analysis._margins import (
    LoopMargins,
    StructuralMargin,
    bandwidth,
    loop_margins,
    structural_margin,
)
from acdrive.analysis._plants import PLANT, Plant2x2, as_plant
from acdrive.control._lti import CONTROLLER, PAPER_20, PAPER_PI, as_lti
from acdrive.errors import InputError, require_finite
from acdrive.machines._induction import IMParams
from acdrive.machines._pmsm import PMSGParams

# ---------------------------------------------------------------------------------------------
# channel analysis


@dataclass(frozen=True)
class ChannelAnalysis:
    """Channel i of the ICAD decomposition (1-based ``index``).

    ``margins``: of c_i (critical point -1); ``kg_margins``: of k_i g_ii (the loop of h_i);
    ``bandwidth_rad_s``: -3 dB bandwidth of c_i/(1 + c_i); ``channel_count``: c_i around -1;
    ``kg_count``: k_i g_ii around -1; ``gamma_h_count``: gamma h_j around +1;
    ``structural``: structural gain margin of gamma h_j; ``coupling_peak_db``: peak |y_i / r_j|.
    ``h_stable`` / ``channel_stable``: h_i and the closed loop of c_i are stable (eigenvalues).
    """

    index: int
    margins: LoopMargins
    kg_margins: LoopMargins
    bandwidth_rad_s: float
    channel_count: NyquistCount
    kg_count: NyquistCount
    gamma_h_count: NyquistCount
    structural: StructuralMargin
    coupling_peak_db: float
    h_stable: bool
    channel_stable: bool


@checked(
    plant=Instance(Plant2x2), conditions=Instance(StructureConditions),
    structural=Instance(StructuralMargin), channels=Items(Instance(ChannelAnalysis)),
    closed_loop_poles=Array(1, complex=True, finite=False, empty=True), closed_loop_stable=FLAG,
    b1=FLAG, b2=FLAG, response=Instance(ICADResponse),
)
@dataclass(frozen=True)
class ICADAnalysis:
    """Full ICAD of one plant with a diagonal controller on a frequency grid.

    ``b1``: both channels and both h_i closed loops are stable (Amezquita-Brooks et al. (b.1)
    without a margin threshold); ``b2``: neither gamma nor gamma h_j encircles or passes through
    (1, 0) ((b.2) without a proximity threshold; see ``structural`` and channel margins).
    """

    plant: Plant2x2
    conditions: StructureConditions
    structural: StructuralMargin  # of gamma
    channels: tuple[ChannelAnalysis, ChannelAnalysis]
    closed_loop_poles: np.ndarray
    closed_loop_stable: bool
    b1: bool
    b2: bool
    response: ICADResponse

    @property
    def coupling_peak_db(self) -> float:
        return worst((ch.coupling_peak_db for ch in self.channels), max)


def check_controller(k, name: str) -> LTI:
    """Require a controller without open right-half-plane poles (integrators are allowed); a
    python-control SISO ``TransferFunction`` or ``StateSpace`` is taken as its ``LTI``."""
    k = as_lti(k, name)
    bad = k.rhp_poles()
    if bad.size:
        raise InputError(
            name,
            f"has right-half-plane pole(s) {', '.join(f'{p:.4g}' for p in bad)}; the channel"
            " analysis needs a stable controller (imaginary-axis poles are allowed)",
        )
    return k


def default_grid(plant: Plant2x2, k1: LTI, k2: LTI, n: int = 4000) -> np.ndarray:
    """Log-spaced grid from 1/100 of the slowest to 100 x the fastest plant/controller root."""
    roots = [plant.poles(), k1.poles(), k2.poles(), invariant_zeros(k1.A, k1.B, k1.C, k1.D)]
    if plant.speed:
        roots.append(np.array([plant.speed]))
    r = np.abs(np.concatenate(roots))
    r = r[r > 0]
    lo, hi = (r.min() / 100.0, r.max() * 300.0) if r.size else (1e-2, 1e3)
    ev = PointEvaluator(plant, k1, k2)
    for _ in range(8):  # extend until both loops k_i g_ii are well below 0 dB at the top
        with np.errstate(all="ignore"):
            kg = ev.all(np.array([1j * hi]))["kg"]
        if np.all(np.abs(kg) < 0.05):
            break
        hi *= 10.0
    return np.logspace(np.log10(lo), np.log10(hi), n)


@checked(plant=PLANT, k1=CONTROLLER, k2=CONTROLLER, w=Array(1, low=0.0, optional=True), verify=FLAG)
def analyse(plant, k1: LTI, k2: LTI, w=None, *, verify: bool = True) -> ICADAnalysis:
    """ICAD of a 2x2 plant with diagonal controller diag(k1, k2).

    Conditions i-iv (exact counts), structural margins of gamma and gamma h_j, channel and
    k_i g_ii margins, bandwidths and coupling peaks on grid ``w`` (default ``default_grid``).
    ``verify`` cross-checks every encirclement count with a contour winding number.
    """
    plant = as_plant(plant)
    k1, k2 = check_controller(k1, "k1"), check_controller(k2, "k2")
    w = default_grid(plant, k1, k2) if w is None else check_frequency_grid(w)
    cond = structure_conditions(plant, verify=verify)
    ev = PointEvaluator(plant, k1, k2)
    A, B, C, D = plant.A, plant.B, plant.C, plant.D
    ks = (k1, k2)
    loops = [close_loop(A, B, C, D, i, i, ks[i]) for i in range(2)]  # loop i closed
    phi = [eigenvalues(lp[0]) for lp in loops]
    full = close_loop(*loops[1], 0, 0, k1)  # loop 2 then loop 1 (remaining input is u_1)
    phi_cl = eigenvalues(full[0])
    poles = cond.plant_poles
    dk = [k.poles() for k in ks]
    sing = np.concatenate([poles, dk[0], dk[1]])
    gdc = _dc(ev)
    channels = []
    for i in range(2):
        j = 1 - i
        Aj, Bj, Cj, Dj = loops[j]  # plant with loop j closed, remaining input u_i
        zeta = invariant_zeros(Aj, Bj, Cj[i : i + 1, :], Dj[i : i + 1, :])
        nii = siso_zeros(plant, i, i)

        def f_c(s, i=i):
            return 1.0 + ev.all(s)["c"][..., i]

        def f_kg(s, i=i):
            return 1.0 + ev.all(s)["kg"][..., i]

        def f_gh(s, i=i):
            return 1.0 - ev.all(s)["gamma_h"][..., i]

        c_count = nyquist_count([phi_cl], [phi[j], dk[i]], -1.0, f_c if verify else None, sing)
        kg_count = nyquist_count([phi[i]], [poles, dk[i]], -1.0, f_kg if verify else None, sing)
        if cond.gamma_identically_zero:
            gh_count = NyquistCount(1.0, 0, 0, (), (), 0, None)
        else:
            gh_count = nyquist_count(
                [zeta, poles], [nii, phi[j]], 1.0, f_gh if verify else None, sing
            )
        T = ev.of_w("T", i)
        channels.append(
            ChannelAnalysis(
                index=i + 1,
                margins=loop_margins(ev.of_w("c", i), w),
                kg_margins=loop_margins(ev.of_w("kg", i), w),
                bandwidth_rad_s=bandwidth(T, w, dc_gain=_dc_T(ev, i)),
                channel_count=c_count,
                kg_count=kg_count,
                gamma_h_count=gh_count,
                structural=structural_margin(ev.of_w("gamma_h", i), w, _dc_gh(ev, i)),
                coupling_peak_db=-math.inf
                if markov_zero(*scalar_d(plant.siso(i, j)))
                else _db(np.nanmax(np.abs(ev.of_w("coupling", i)(w)))),
                h_stable=_stable(phi[i]),
                channel_stable=_stable(phi_cl) and _stable(phi[j]),
            )
        )
    response = icad_response(plant, k1, k2, w)
    cl_stable = _stable(phi_cl)
    b1 = all(ch.h_stable and ch.channel_stable for ch in channels)
    b2 = cond.iv and all(ch.gamma_h_count.encirclements == 0 for ch in channels)
    return ICADAnalysis(
        plant=plant,
        conditions=cond,
        structural=structural_margin(lambda x: ev.gamma(1j * np.asarray(x)), w, gdc),
        channels=(channels[0], channels[1]),
        closed_loop_poles=phi_cl,
        closed_loop_stable=cl_stable,
        b1=b1,
        b2=b2,
        response=response,
    )


def _db(x: float) -> float:
    return 20.0 * math.log10(x) if x > 0 else -math.inf


def _stable(roots: np.ndarray) -> bool:
    return bool(np.all(roots.real < 0) and not np.any(on_axis(roots)))


def _finite_at_zero(values) -> complex | None:
    v = complex(values[0])
    return v if np.isfinite(v) else None


def _dc(ev: PointEvaluator) -> complex | None:
    """gamma(0) if the plant has no pole at s = 0."""
    if np.any(np.abs(ev.plant.poles()) < 1e-12):
        return None
    with np.errstate(all="ignore"):
        return _finite_at_zero(ev.gamma(np.zeros(1)))


def _dc_T(ev: PointEvaluator, i: int) -> float | None:
    """|T_i(0)| of c_i/(1+c_i) as a limit (evaluated just off s = 0 to pass integrators)."""
    s = np.array([1e-9 * max(1.0, float(np.max(np.abs(ev.plant.poles()), initial=1.0)))]) * 1j
    v = ev.all(s)["T"][0, i]
    return float(abs(v)) if np.isfinite(v) else None


def _dc_gh(ev: PointEvaluator, i: int) -> complex | None:
    s = np.array([1e-9 * max(1.0, float(np.max(np.abs(ev.plant.poles()), initial=1.0)))]) * 1j
    v = ev.all(s)["gamma_h"][0, i]
    return complex(v.real, 0.0) if np.isfinite(v) else None


# ---------------------------------------------------------------------------------------------
# sweeps


@dataclass(frozen=True)
class SweepSummary:
    """Worst case of each ICAD figure over a set of analyses (speeds or perturbed plants)."""

    speeds: np.ndarray
    all_conditions: bool  # i-iv hold for every member
    closed_loop_stable: bool
    structural_gm_db: float  # min over members of the gamma structural margin
    structural_gm_h_db: float  # min over members and channels of the gamma h_j margin
    pm_deg: float  # min channel phase margin
    gm_db: float  # min channel upward gain margin
    kg_pm_deg: float
    kg_gm_db: float
    bandwidth_rad_s: float  # min channel bandwidth
    crossover_rad_s: float  # min channel crossover
    coupling_peak_db: float  # max coupling


def worst(values, fn=min) -> float:
    """min (or ``fn``) of figures; nan if any is nan (an undefined figure is never skipped)."""
    arr = np.asarray(list(values), dtype=float)
    return math.nan if np.isnan(arr).any() else float(fn(arr))


def summarize(analyses: Sequence[ICADAnalysis]) -> SweepSummary:
    """Worst-case figures over a sequence of analyses."""
    if not analyses:
        raise InputError("analyses", "must not be empty")
    chans = [ch for a in analyses for ch in a.channels]
    return SweepSummary(
        speeds=np.array([np.nan if a.plant.speed is None else a.plant.speed for a in analyses]),
        all_conditions=all(
            a.conditions.i and a.conditions.ii and a.conditions.iii and a.conditions.iv
            for a in analyses
        ),
        closed_loop_stable=all(a.closed_loop_stable for a in analyses),
        structural_gm_db=worst(a.structural.gm_db for a in analyses),
        structural_gm_h_db=worst(ch.structural.gm_db for ch in chans),
        pm_deg=worst(ch.margins.pm_deg for ch in chans),
        gm_db=worst(ch.margins.gm_db for ch in chans),
        kg_pm_deg=worst(ch.kg_margins.pm_deg for ch in chans),
        kg_gm_db=worst(ch.kg_margins.gm_db for ch in chans),
        bandwidth_rad_s=worst(ch.bandwidth_rad_s for ch in chans),
        crossover_rad_s=worst(ch.margins.crossover_rad_s for ch in chans),
        coupling_peak_db=worst((ch.coupling_peak_db for ch in chans), max),
    )


@checked(
    plants=Items(PLANT), k1=CONTROLLER, k2=CONTROLLER, w=Array(1, low=0.0, optional=True),
    verify=FLAG,
)
def sweep(plants: Sequence, k1: LTI, k2: LTI, w=None, *, verify: bool = False):
    """``analyse`` over plants (e.g. ``plants_for(machine, speeds)``); returns (list, summary)."""
    analyses = [analyse(p, k1, k2, w, verify=verify) for p in plants]
    return analyses, summarize(analyses)


# ---------------------------------------------------------------------------------------------
# built-in controllers

#: Bodson's current-loop bandwidth a_D,CUR = 2 pi 500 Hz (section IV-A), reused as the default
#: bandwidth of the internal-model PI below.
A_CUR_DEFAULT = 3142.0

CONTROLLER_NAMES = ("paper-20", "paper-pi", "imc-pi")


def imc_pi(params, a: float = A_CUR_DEFAULT) -> LTI:
    """Internal-model PI K_P = L' a, K_I = R' a for the first-order model 1/(L' s + R').

    Bodson (49) with R_T = R_R: (L', R') = (sigma L_r, R_r) for the DFIM rotor current; by the
    same rule (sigma L_s, R_s) for the IM stator current and (L_d, R_s) for the PMSG.
    """
    from acdrive.machines._dfim import DFIMParams

    a = require_finite("bandwidth", a)
    if a <= 0:
        raise InputError("bandwidth", "must be > 0 rad/s")
    if isinstance(params, IMParams):
        L, R = params.sigma * params.L_s, params.R_s
    elif isinstance(params, PMSGParams):
        L, R = params.L_d, params.R_s
    elif isinstance(params, DFIMParams):
        L, R = params.sigma * params.L_r, params.R_r
    else:
        raise InputError("params", f"unsupported machine parameters {type(params).__name__}")
    return LTI.pi(L * a, R * a, name="imc-pi")


def controller_for(name: str, params=None, a: float = A_CUR_DEFAULT) -> LTI:
    """Built-in controller by name: ``paper-20`` (Amezquita-Brooks et al. (20)), ``paper-pi``
    (their PI, K_P = 360, K_I = 9000) or ``imc-pi`` (``imc_pi`` for the machine ``params``).
    The paper's controllers are the shared built-in objects of ``acdrive.control._lti``."""
    if name == "paper-20":
        return PAPER_20
    if name == "paper-pi":
        return PAPER_PI
    if name == "imc-pi":
        if params is None:
            raise InputError("controller", "imc-pi needs machine parameters")
        return imc_pi(params, a)
    raise InputError("controller", f"unknown '{name}', known: {', '.join(CONTROLLER_NAMES)}")


def default_controller_name(params) -> str:
    """paper-20 for induction motors (it was designed for one), imc-pi otherwise."""
    return "paper-20" if isinstance(params, IMParams) else "imc-pi"
