"""Cross coupling between the two current channels, measured in simulation beside ICAD's (10).

Amezquita-Brooks et al. (10) (Ugalde-Loo et al. (6)) predict, for the 2 x 2 current plant G at a
fixed electrical speed w_r and the diagonal controller diag(k, k), the closed-loop response of
output i to the reference of the other channel j,

    y_i / r_j = S_i (g_ij / g_jj) h_j,   S_i = 1 / (1 + c_i)                         (10)

(``analysis._icad_frequency``; Fig. 8 draws |y_1 / r_2| over w_r). This module measures the same
quantity on the sampled, nonlinear drive simulator (``sim._system``): the machine part held at
w_r by a dynamometer (``plant.PrescribedSpeed``), the current controller as a sampled part
(``control.StationaryCurrentController``, Tustin at ``sample_time``), its command latched
once per carrier period (``plant.CarrierLatch``, N = ``hold_samples`` control samples)
and applied as an ideal voltage; a sinusoidal reference r_1 = A cos(W t) on channel 1, r_2 = 0;
after ``settle`` seconds the sinusoidal component at W of y_2 (and of y_1) is fitted by least
squares (cos, sin and a constant) over an integer number of periods and divided by that of r_1.

Within the linear range of the paper's 310 V link (|v| <= v_dc / sqrt(2), checked: ``peak_voltage``
against ``VOLTAGE_LIMIT``) the latched ideal voltage *is* the averaged inverter of ``drives.cage_im._drive``
(the carrier-period average of the SVPWM bridge), so no converter part is needed.

**Frames.** The cage IM (Amezquita-Brooks (1)) is controlled in the stationary frame (sec. VI):
channel 1 = alpha, channel 2 = beta, and the controller is ``k`` on both axes, e.g. (20). The PMSG
analysis of Ugalde-Loo et al. (sec. 3, (9)-(13)) is in the rotor (dq) frame: channel 1 = d,
channel 2 = q, and the diagonal controller acts on the dq errors. The simulator's controller is
stationary, so a dq controller k(s) is realised by its stationary equivalent at the constant
electrical speed w_e, k(s - j w_e) on the complex error (``stationary_equivalent``): with
theta_e = w_e t, e^{j theta_e} k(s) [e^{-j theta_e} e] = k(s - j w_e) e exactly. Its Tustin
discretisation is pre-warped at w_e so that the integrator of k (at s = 0 in dq) sits exactly at
z = e^{j w_e T_s}. The reference is r_dq e^{j w_e t}, the output the machine's own i_dq.

Seed 001 prints no PMSG current controller (it notes the usual design on a first-order SISO
model); ``pmsg_pi`` is that design: k = (L_d s + R_s) a / s, the PI that cancels the pole of the
first-order model 1 / (L_d s + R_s) and gives the loop a / s (bandwidth a). The PMSG starts in
the steady state of its magnet's back EMF (i_dq = 0, the controller's state giving
v_dq = j w_e psi_pm), so that only the injection is seen.

**Predictions.** ``icad_coupling``: (10) with the continuous controller; ``delay`` adds the
average delay of the sample-and-hold, N T_s / 2 (a command computed from the measurement at a
carrier period start is held for N T_s): k(j w) e^{-j w N T_s / 2} on both channels (the
delay is a diagonal input factor, so it moves into k_i unchanged in (10)); in the dq frame the
stationary hold also turns the voltage back by w_e N T_s / 2, a rotation put into the plant. ``closed_loop``: the
full closed loop (I + G K)^{-1} G K, whose (2, 1) entry equals (10) (a cross-check of the ICAD
form) and whose (1, 1) entry is the direct tracking measured beside it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from acdrive._arguments import (
    COUNT,
    NONNEGATIVE,
    POSITIVE,
    REAL,
    Array,
    Instance,
    Items,
    Table,
    Text,
    checked,
)
from acdrive._frames import K_PEAK as SQRT_3_2
from acdrive._toml import constant
from acdrive.analysis._freqresp import evaluate_ss
from acdrive.analysis._icad_frequency import icad_quantities
from acdrive.analysis._plants import plant_from_params
from acdrive.control._current import CurrentProgram, StationaryCurrentController
from acdrive.control._lti import LTI
from acdrive.control._lti_matrix import LTIMatrix
from acdrive.core._profile import Profile
from acdrive.errors import InputError, require_positive
from acdrive.machines._cage_part import CageInductionMachine
from acdrive.machines._induction import IMParams
from acdrive.machines._pmsm import PMSGParams
from acdrive.machines._pmsm_part import PermanentMagnetMachine
from acdrive.plant._converter import max_voltage_magnitude
from acdrive.plant._inverter import CarrierLatch
from acdrive.plant._mechanics import PrescribedSpeed
from acdrive.sim._system import System

#: The paper's DC link [V] (sec. VI): the linear SVPWM range v_dc / sqrt(2) (space vector) within
#: which the latched ideal voltage equals the averaged inverter.
PAPER_DC_LINK = 310.0
VOLTAGE_LIMIT = float(max_voltage_magnitude(PAPER_DC_LINK))


def stationary_equivalent(k: LTI, w_e: float) -> LTIMatrix:
    """The dq-frame controller diag(k, k) seen from the stationary frame at the constant electrical
    speed ``w_e``: k(s - j w_e) on e = e_alpha + j e_beta, as a real 2 x 2 state space
    (x' = A x + j w_e x + B e, v = C x + D e with complex x = x_re + j x_im)."""
    n = k.A.shape[0]
    rot = np.array([[0.0, -1.0], [1.0, 0.0]])
    A = np.kron(np.eye(2), k.A) + w_e * np.kron(rot, np.eye(n))
    B, C, D = (np.kron(np.eye(2), M) for M in (k.B, k.C, k.D))
    return LTIMatrix.ss(A, B, C, D, name=f"{k.name or 'k'} in dq at w_e = {w_e:g}")


@checked(p=Instance(PMSGParams), bandwidth=POSITIVE)
def pmsg_pi(p: PMSGParams, bandwidth: float) -> LTI:
    """k = a (L_d s + R_s) / s = a L_d + a R_s / s: the PI of the first-order SISO model
    1 / (L_d s + R_s) of Ugalde-Loo (12) without the speed terms, open loop a / s (module
    docstring)."""
    return LTI.pi(bandwidth * p.L_d, bandwidth * p.R_s, name=f"PMSG PI, a = {bandwidth:g} rad/s")


@checked(hold_samples=COUNT, sample_time=POSITIVE)
def hold_delay(hold_samples: int, sample_time: float) -> float:
    """Average delay [s] of a sample-and-hold that keeps a command for ``hold_samples`` samples
    of ``sample_time``: N T_s / 2 (module docstring)."""
    return hold_samples * sample_time / 2.0


def _plant(params, w_e: float):
    return plant_from_params(params, w_e)


def _plant_response(params, w_e: float, w: np.ndarray, delay: float) -> np.ndarray:
    """G(j w) of the plant at w_e; with a ``delay`` in the rotor (dq) frame, G R(-w_e delay): a
    hold in the stationary frame delays the dq voltage by ``delay`` and turns it back by
    w_e delay (e^{-(s + j w_e) delay} in dq), a rotation that is not diagonal and so belongs to
    the plant rather than to k."""
    plant = _plant(params, w_e)
    G = evaluate_ss(plant.A, plant.B, plant.C, plant.D, 1j * w)
    if delay and isinstance(params, PMSGParams):
        phi = w_e * delay
        R = np.array([[math.cos(phi), math.sin(phi)], [-math.sin(phi), math.cos(phi)]])
        G = G @ R
    return G


@checked(
    params=Instance(IMParams, PMSGParams), w_e=REAL, k=Instance(LTI), w=Array(1, low=0.0),
    delay=NONNEGATIVE,
)
def icad_coupling(params, w_e: float, k: LTI, w, delay: float = 0.0) -> np.ndarray:
    """y_2 / r_1 of (10) (``analysis._icad_frequency.icad_quantities``) at the frequencies ``w``
    [rad/s] for the plant of ``params`` at electrical speed ``w_e`` with k on both channels, k
    multiplied by e^{-j w delay} (module docstring; in the dq frame the plant also takes the
    rotation of ``_plant_response``)."""
    w = np.asarray(w, dtype=float)
    G = _plant_response(params, w_e, w, delay)
    kv = k.freqresp(w) * np.exp(-1j * w * delay)
    return icad_quantities(G, kv, kv)["coupling"][:, 1]


@checked(
    params=Instance(IMParams, PMSGParams), w_e=REAL, k=Instance(LTI), lo=POSITIVE, hi=POSITIVE,
    points=COUNT,
)
def icad_coupling_peak(
    params, w_e: float, k: LTI, lo: float = 100.0, hi: float = 3000.0, points: int = 29001
) -> tuple[float, float]:
    """(frequency [rad/s], magnitude [dB]) of the largest magnitude of y_2 / r_1 of (10)
    (``icad_coupling``) on ``points`` evenly spaced frequencies from ``lo`` to ``hi``."""
    lo = require_positive("lo", lo)
    hi = require_positive("hi", hi)
    if not hi > lo:
        raise InputError("hi", f"must be above lo = {lo:g}, got {hi:g}")
    if isinstance(points, bool) or not isinstance(points, int) or not 2 <= points <= 10**7:
        raise InputError("points", f"must be a whole number from 2 to 1e7, got {points!r}")
    w = np.linspace(lo, hi, points)
    magnitude = np.abs(icad_coupling(params, w_e, k, w))
    i = int(np.argmax(magnitude))
    return float(w[i]), float(20.0 * np.log10(magnitude[i]))


def closed_loop(params, w_e: float, k: LTI, w, delay: float = 0.0) -> np.ndarray:
    """The full closed loop r -> y, (I + G K)^{-1} G K with K = k e^{-j w delay} I, shape
    (len(w), 2, 2)."""
    w = np.asarray(w, dtype=float)
    G = _plant_response(params, w_e, w, delay)
    kv = (k.freqresp(w) * np.exp(-1j * w * delay))[:, None, None]
    L = G * kv
    return np.linalg.solve(np.eye(2)[None] + L, L)


def fit_sinusoid(t: np.ndarray, y: np.ndarray, w: float) -> complex:
    """Complex amplitude Y of y ~ Re(Y e^{j w t}) + c, least squares over the samples given."""
    M = np.column_stack([np.cos(w * t), -np.sin(w * t), np.ones_like(t)])
    coef, *_ = np.linalg.lstsq(M, y, rcond=None)
    return complex(coef[0], coef[1])


@checked(
    params=Instance(IMParams, PMSGParams), controller=Instance(LTI), w_e=REAL,
    frequencies=Items(POSITIVE), amplitude=POSITIVE, sample_time=POSITIVE, hold_samples=COUNT,
    settle=NONNEGATIVE, window=POSITIVE, min_periods=COUNT, substeps=COUNT, name=Text(empty=True),
)
@dataclass(frozen=True)
class CouplingSetup:
    """One coupling measurement: the machine (``IMParams``: stationary frame; ``PMSGParams``: dq
    frame), the controller k of both channels, the electrical speed w_e [rad/s], the injection
    frequencies [rad/s] and amplitude [A, phase peak: the paper's amplitude-invariant scaling],
    the control sample time [s], the hold N [samples; 10 = the paper's 5 kHz carrier at 50 kHz],
    the settling time before the fit [s] and the length of the fit window [s] (whole periods of
    each frequency within it, at least ``min_periods``)."""

    params: IMParams | PMSGParams
    controller: LTI
    w_e: float
    frequencies: tuple[float, ...]
    amplitude: float = 0.2
    sample_time: float = 2e-5
    hold_samples: int = 1
    settle: float = 0.5
    window: float = 0.2
    min_periods: int = 2
    substeps: int = 2
    name: str = ""

    def __post_init__(self):
        if not isinstance(self.params, (IMParams, PMSGParams)):
            raise InputError("params", "must be IMParams (cage IM) or PMSGParams (PMSG)")
        if not self.frequencies or min(self.frequencies) <= 0.0:
            raise InputError("frequencies", "must be positive injection frequencies [rad/s]")
        if int(self.hold_samples) != self.hold_samples or self.hold_samples < 1:
            raise InputError("hold_samples", "must be an integer >= 1")

    @property
    def frame(self) -> str:
        return "dq" if isinstance(self.params, PMSGParams) else "stationary"

    @property
    def delay(self) -> float:
        """Average delay of the sample-and-hold, N T_s / 2 [s] (``hold_delay``)."""
        return hold_delay(self.hold_samples, self.sample_time)

    def window_for(self, w: float) -> float:
        period = 2.0 * math.pi / w
        return max(self.min_periods, math.floor(self.window / period)) * period

    @property
    def duration(self) -> float:
        return self.settle + max(self.window_for(w) for w in self.frequencies)


@checked(
    setup=Instance(CouplingSetup), frequencies=Array(1, complex=True, finite=False, empty=True),
    measured=Array(1, complex=True, finite=False, empty=True),
    measured_direct=Array(1, complex=True, finite=False, empty=True),
    icad=Array(1, complex=True, finite=False, empty=True),
    icad_delayed=Array(1, complex=True, finite=False, empty=True),
    direct_predicted=Array(1, complex=True, finite=False, empty=True),
    uncertainty=Array(1, complex=True, finite=False, empty=True),
    peak_voltage=Array(1, complex=True, finite=False, empty=True), wall_time=NONNEGATIVE,
    extra=Table(empty=True),
)
@dataclass
class CouplingResult:
    """Per injection frequency: the measured y_2 / r_1 and y_1 / r_1 (complex), (10) without and
    with the hold's delay, the closed loop's (1, 1) entry, the measurement's own uncertainty
    (the change of the measured coupling between the two halves of the fit window, relative) and
    the peak voltage command [V, space vector]."""

    setup: CouplingSetup
    frequencies: np.ndarray
    measured: np.ndarray
    measured_direct: np.ndarray
    icad: np.ndarray
    icad_delayed: np.ndarray
    direct_predicted: np.ndarray
    uncertainty: np.ndarray
    peak_voltage: np.ndarray
    wall_time: float = 0.0
    extra: dict = field(default_factory=dict)

    def relative_error(self, delayed: bool = False) -> np.ndarray:
        """|measured - predicted| / |predicted| per frequency (complex difference)."""
        ref = self.icad_delayed if delayed else self.icad
        return np.abs(self.measured - ref) / np.abs(ref)

    def db(self, which: str = "measured") -> np.ndarray:
        return 20.0 * np.log10(np.abs(getattr(self, which)))

    def rows(self) -> list[dict]:
        """The numbers per frequency (dB, deg, relative errors) for tables and JSON."""
        out = []
        for i, w in enumerate(self.frequencies):
            out.append(
                {
                    "frequency_rad_s": float(w),
                    "measured_db": float(20 * np.log10(abs(self.measured[i]))),
                    "measured_phase_deg": float(np.degrees(np.angle(self.measured[i]))),
                    "icad_db": float(20 * np.log10(abs(self.icad[i]))),
                    "icad_phase_deg": float(np.degrees(np.angle(self.icad[i]))),
                    "icad_delayed_db": float(20 * np.log10(abs(self.icad_delayed[i]))),
                    "relative_error": float(self.relative_error()[i]),
                    "relative_error_delayed": float(self.relative_error(True)[i]),
                    "direct_measured_db": float(20 * np.log10(abs(self.measured_direct[i]))),
                    "direct_predicted_db": float(20 * np.log10(abs(self.direct_predicted[i]))),
                    "uncertainty": float(self.uncertainty[i]),
                    "peak_voltage_v": float(self.peak_voltage[i]),
                }
            )
        return out


def _reference(setup: CouplingSetup, w: float, t: np.ndarray) -> np.ndarray:
    """Stationary-frame reference (power-invariant): channel 1 = A cos(w t) in the control frame
    (alpha, or d rotated by e^{j w_e t})."""
    r = SQRT_3_2 * setup.amplitude * np.cos(w * t) + 0j
    if setup.frame == "dq":
        r = r * np.exp(1j * setup.w_e * t)
    return r


def build_loop(setup: CouplingSetup):
    """(system, parts, initial state) of the closed current loop of ``setup`` (module
    docstring); the reference tables are replaced per frequency by ``measure_coupling``."""
    p = setup.params
    T_s = setup.sample_time
    parts = {}
    if setup.frame == "dq":
        parts["machine"] = PermanentMagnetMachine.from_params("machine", p)
        k = stationary_equivalent(setup.controller, setup.w_e)
        prewarp = abs(setup.w_e) if setup.w_e != 0.0 else None
    else:
        parts["machine"] = CageInductionMachine.from_params("machine", p)
        k, prewarp = setup.controller, None
    parts["shaft"] = PrescribedSpeed("shaft", w=constant(setup.w_e / p.n_p))
    parts["reference"] = CurrentProgram("reference", re=0.0, im=0.0)
    parts["current"] = StationaryCurrentController("current", k, T_s, "tustin", prewarp)
    parts["latch"] = CarrierLatch("latch", f_pwm=1.0 / (setup.hold_samples * T_s))
    m, c, latch = parts["machine"], parts["current"], parts["latch"]
    wires = [
        (parts["shaft"].out.w, m.inp.w),
        (parts["reference"].out.i, c.inp.i_ref),
        (m.out.i_s, c.inp.i_meas),
        (c.out.v_ref, latch.inp.v_ref),
        (latch.out.v_ref, m.inp.v_s),
    ]
    initial = {}
    if setup.frame == "dq" and p.psi_m != 0.0:
        initial["current"] = c.state_for(_rotating_state(c, 1j * setup.w_e * SQRT_3_2 * p.psi_m))
        latch_v = 1j * setup.w_e * SQRT_3_2 * p.psi_m
        initial["latch"] = {"v": latch_v}
    return System(list(parts.values()), wires), parts, initial


def _rotating_state(part: StationaryCurrentController, v0: complex) -> np.ndarray:
    """Controller state whose free response (zero error) is the voltage v0 e^{j w_e k T_s}: a
    vector of the invariant subspace of A_d at the eigenvalue e^{j w_e T_s} (the integrator of the
    dq controller, exact with the pre-warped Tustin map) with C_d x = v0."""
    d = part.discrete
    lam, vec = np.linalg.eig(d.Ad)
    target = np.exp(1j * (d.prewarp or 0.0) * d.T_s)
    i = int(np.argmin(np.abs(lam - target)))
    z = vec[:, i]
    basis = np.column_stack([z.real, z.imag])
    coef, *_ = np.linalg.lstsq(d.Cd @ basis, np.array([v0.real, v0.imag]), rcond=None)
    x = basis @ coef
    if np.linalg.norm(d.Cd @ x - np.array([v0.real, v0.imag])) > 1e-6 * max(1.0, abs(v0)):
        raise InputError("controller", "has no rotating mode at w_e for a bumpless start")
    return x


@checked(setup=Instance(CouplingSetup))
def measure_coupling(setup: CouplingSetup) -> CouplingResult:
    """Run the loop once per injection frequency (one batch) and fit the responses (module
    docstring)."""
    system, parts, initial = build_loop(setup)
    compiled = system.compile()
    T_s = setup.sample_time
    n = round(setup.duration / T_s)
    t_tab = np.arange(n + 2) * T_s
    variants = []
    for w in setup.frequencies:
        r = _reference(setup, w, t_tab)
        variants.append({"reference": {"re": Profile(t_tab, r.real), "im": Profile(t_tab, r.imag)}})
    m, c = parts["machine"], parts["current"]
    out_port = m.out.i_dq if setup.frame == "dq" else m.out.i_s
    log = [out_port, parts["reference"].out.i, c.out.v_ref]
    results = compiled.run_batch(
        variants,
        n * T_s,
        T_s,
        substeps=setup.substeps,
        initial=initial,
        log=log,
        held={"latch": {"v_ref": initial.get("latch", {}).get("v", 0.0)}} if initial else None,
    )
    W = np.asarray(setup.frequencies, dtype=float)
    measured, direct, unc, vpk = (np.empty(W.size, dtype=complex) for _ in range(4))
    wall = 0.0
    for i, (w, res) in enumerate(zip(W, results, strict=True)):
        status = res.extra.get("status", "ok")
        if status != "ok":
            raise InputError("coupling", f"the run at {w:g} rad/s {status}")
        t = res.t
        y = res.signal(out_port)
        if setup.frame == "dq":
            r_ctl = SQRT_3_2 * setup.amplitude * np.cos(w * t)  # d reference
        else:
            r_ctl = res.signal(parts["reference"].out.i).real
        span = setup.window_for(w)
        win = t >= t[-1] - span
        half = t >= t[-1] - span / 2.0 if span / 2.0 >= 2.0 * math.pi / w else win
        R = fit_sinusoid(t[win], r_ctl[win], w)
        measured[i] = fit_sinusoid(t[win], y.imag[win], w) / R
        direct[i] = fit_sinusoid(t[win], y.real[win], w) / R
        first = win & ~half
        if first.any() and (2.0 * math.pi / w) <= span / 2.0:
            early = fit_sinusoid(t[first], y.imag[first], w) / fit_sinusoid(
                t[first], r_ctl[first], w
            )
            late = fit_sinusoid(t[half], y.imag[half], w) / fit_sinusoid(t[half], r_ctl[half], w)
            unc[i] = abs(late - early) / abs(measured[i])
        else:
            unc[i] = math.nan
        vpk[i] = float(np.max(np.abs(res.signal(c.out.v_ref)[win])))
        wall += res.wall_time
    p, k = setup.params, setup.controller
    cl = closed_loop(p, setup.w_e, k, W, setup.delay)
    return CouplingResult(
        setup=setup,
        frequencies=W,
        measured=measured,
        measured_direct=direct,
        icad=icad_coupling(p, setup.w_e, k, W),
        icad_delayed=icad_coupling(p, setup.w_e, k, W, setup.delay),
        direct_predicted=cl[:, 0, 0],
        uncertainty=unc.real,
        peak_voltage=vpk.real,
        wall_time=wall,
        extra={"closed_loop_coupling_delayed": cl[:, 1, 0]},
    )


def closed_loop_poles(params, w_e: float, k: LTI) -> np.ndarray:
    """Poles of the continuous closed loop (plant at w_e, diag(k, k)): the slowest sets
    ``settle``."""
    plant = _plant(params, w_e)
    A, B, C = plant.A, plant.B, plant.C
    Ak, Bk, Ck = (scipy.linalg.block_diag(M, M) for M in (k.A, k.B, k.C))
    Dk = float(k.D[0, 0]) * np.eye(2)
    Acl = np.block([[A - B @ Dk @ C, B @ Ck], [-Bk @ C, Ak]])
    return np.linalg.eigvals(Acl)
