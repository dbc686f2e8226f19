"""Seed 001's PMSG current subsystem in the time domain, with the ICAD-designed current
controller: a step on the d current reference and the cross-coupling it causes in i_q, measured
in simulation beside ICAD's coupling (10).

**The loop.** Ugalde-Loo et al. (7)-(11): the PMSG's dq currents driven by the dq voltages at a
constant electrical speed w_e (the machine part ``machines.PermanentMagnetMachine`` held at
w_e / n_p by ``plant.PrescribedSpeed``), closed by the diagonal controller diag(k, k) that ICAD
analyses, k = a (L_d s + R_s) / s (``analysis._coupling.pmsg_pi``, the controller acdrive's
coupling report uses for this machine, Ugalde-Loo sec. 3: a PI on the first-order SISO model;
seed 001 prints no controller). It runs as the PM drive's ``RotorFrameCurrentController`` with
K_P = a L_d, K_I = a R_s on both axes (read off k by ``pi_gains``), no decoupling and no
back-EMF feed-forward (``decouple = 0``: the plant ICAD analyses, cross terms included) and no
angle advance (``advance = 0``: the command is held in the stationary frame, the hold that
``analysis._coupling`` models). (9)-(11) have no voltage limit and the paper gives no DC link:
the controller's limit is set to the largest finite number (``UNLIMITED_V_DC``; a part's
parameter must be finite) and the summary counts that it never acted and reports the peak
voltage. The voltage goes straight to the machine, held over the sample (an ideal converter).

**The measurement.** The loop is linear at constant speed (the back EMF j w_e psi_pm is a
constant input in dq, and the controller's integrator starts at it, ``initial``), so two runs
that differ only by the step r_d = A 1(t - t_0) differ by exactly the step response:
dy(t) = i_dq,step(t) - i_dq,base(t) (one batch of the two runs). The controller sees the step at
its first sample t_s >= the step time, and would see the same samples for a step anywhere in
(t_s - T_s, t_s]: the step's time in (S) is the middle of that interval, t_0 = t_s - T_s / 2
(consistent with the hold's mean delay T_s / 2 of the prediction below, which delays the
reference path too; the built-in scenario puts its step there). For a stable loop the Laplace
transform of a step response is H(s) A / s, so with the increments of dy between samples
(piecewise linear dy)

    H(j w) = (1 / A) sum_k (dy_{k+1} - dy_k) e^{-j w (t_{k+1/2} - t_0)}                   (S)

the transfer function r_d -> i_q (coupling) and r_d -> i_d (direct) at any w; the sum stops at
the end of the run, so the change still to come, |dy(end) - dy(inf)| / A (dy(inf) = (0, A): PI
integrators), bounds the error of (S) (``tail``). (S) is exact for piecewise-linear dy; the
error of that interpolation is of order (w T_s)^2 / 24.

**The prediction.** ``analysis._coupling.icad_coupling``: (10), y_2 / r_1 = S_2 (g_21 / g_11)
h_1 (Ugalde-Loo (6), the form of ``analysis._icad_frequency``) with the continuous k, and the
same with the hold's mean delay T_s / 2 (k e^{-j w T_s / 2} and the plant turned by w_e T_s / 2,
``analysis._coupling._plant_response``); ``analysis._coupling.closed_loop`` gives the direct
channel (1, 1). The verdict: every frequency's relative complex difference from (10) within
``ICAD_REL_TOL`` up to ``ICAD_W_MAX`` (the delay-free (10) differs from the sampled loop by about
w T_s / 2: 1 % at 1000 rad/s with T_s = 20 us), and from (10) with the delay within
``DELAYED_REL_TOL`` at every frequency (what remains is of second order in w T_s: (w T_s)^2 =
0.16 % at 2000 rad/s).
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass

import numpy as np

from acdrive._frames import K_PEAK
from acdrive._toml import constant
from acdrive.analysis._coupling import closed_loop, hold_delay, icad_coupling, pmsg_pi
from acdrive.control._current import CurrentProgram
from acdrive.control._lti import LTI
from acdrive.drives.pm._build import Built
from acdrive.drives.pm._control import RotorFrameCurrentController
from acdrive.drives.pm._design import magnet_flux
from acdrive.drives.pm._size import check_run_size
from acdrive.errors import InputError, require_nonnegative, require_positive
from acdrive.machines._pmsm import PMSGParams
from acdrive.machines._pmsm_part import PermanentMagnetMachine
from acdrive.plant._mechanics import PrescribedSpeed
from acdrive.sim._compiled import LOG_BUDGET_BYTES
from acdrive.sim._system import System

#: the most frequencies a run compares (S) with (10) at: a table, not a spectrum
MAX_FREQUENCIES = 1000
#: the relative complex difference allowed between the measured coupling and (10), at the
#: frequencies up to ICAD_W_MAX [rad/s] (module docstring; the coupling report's 2 % and 1000 rad/s)
ICAD_REL_TOL = 0.02
ICAD_W_MAX = 1000.0
#: ... and between the measured coupling and (10) with the hold's delay, at every frequency
DELAYED_REL_TOL = 0.002
#: the controller's DC link when no limit applies (module docstring)
UNLIMITED_V_DC = sys.float_info.max
#: the step response must have come this close to its final value (relative to A) by the end
TAIL_TOL = 1e-4


@dataclass(frozen=True)
class CurrentStepSetup:
    """One time-domain run of a PMSG current subsystem under ICAD's controller (module
    docstring): machine (``machines.PMSGParams``), electrical speed w_e [rad/s], the bandwidth a
    [rad/s] of k = a (L_d s + R_s) / s, the step A of the d reference [A, phase peak] at
    ``step_time`` [s], the frequencies [rad/s] where (S) is compared with (10), the run's
    duration and control sample time [s], substeps per sample."""

    machine: PMSGParams
    electrical_speed: float
    bandwidth: float
    step: float
    step_time: float
    frequencies: tuple[float, ...]
    duration: float
    sample_time: float
    substeps: int = 2
    name: str = "pm-current-step"

    def __post_init__(self):
        if not isinstance(self.machine, PMSGParams):
            raise InputError("machine", "must be a machines.PMSGParams")
        for field in ("electrical_speed", "bandwidth", "step", "duration", "sample_time"):
            object.__setattr__(self, field, require_positive(field, getattr(self, field)))
        require_nonnegative("step_time", self.step_time)
        if self.step_time >= self.duration:
            raise InputError(
                "step_time", f"must be before the end of the run ({self.duration:g} s)"
            )
        w = tuple(float(f) for f in self.frequencies)
        nyquist = math.pi / self.sample_time
        if not w or min(w) <= 0.0 or max(w) >= nyquist:
            raise InputError(
                "frequencies", f"must be positive and below pi / sample_time = {nyquist:g} rad/s"
            )
        object.__setattr__(self, "frequencies", w)
        if (
            isinstance(self.substeps, bool)
            or not isinstance(self.substeps, int)
            or self.substeps < 1
        ):
            raise InputError("substeps", "must be an integer >= 1")
        samples = check_run_size(self.duration, self.sample_time, self.substeps, runs=2)
        if len(w) > MAX_FREQUENCIES:
            raise InputError("frequencies", f"at most {MAX_FREQUENCIES} frequencies, got {len(w)}")
        table_bytes = 16.0 * len(w) * samples  # step_transfer's complex frequencies x samples
        if table_bytes > LOG_BUDGET_BYTES:
            raise InputError(
                "frequencies", f"{len(w)} frequencies x {samples:.3g} samples of the run need "
                f"{table_bytes / 1024**3:.3g} GB for the comparison (limit "
                f"{LOG_BUDGET_BYTES / 1024**3:g} GB): compare at fewer frequencies or shorten "
                "the run"
            )  # fmt: skip

    @property
    def controller(self) -> LTI:
        """ICAD's k = a (L_d s + R_s) / s (``analysis._coupling.pmsg_pi``)."""
        return pmsg_pi(self.machine, self.bandwidth)

    @property
    def delay(self) -> float:
        """The hold's mean delay T_s / 2 [s] (``analysis._coupling.hold_delay``, one sample)."""
        return hold_delay(1, self.sample_time)


def pi_gains(k: LTI) -> tuple[float, float]:
    """(K_P, K_I) of a PI k(s) = K_P + K_I / s given as a state space (one integrator state):
    K_P = D, K_I = C B."""
    if k.A.shape != (1, 1) or k.A[0, 0] != 0.0:
        raise InputError("controller", "must be a PI (one integrator state)")
    return float(k.D[0, 0]), float(k.C[0, 0] * k.B[0, 0])


def _step_table(setup: CurrentStepSetup, amplitude: float) -> list:
    """d reference points [t, i] (power-invariant): 0, then ``amplitude`` from step_time."""
    t0, end = setup.step_time, setup.duration + setup.sample_time
    return [[0.0, 0.0], [t0, 0.0], [t0, amplitude], [end, amplitude]]


def build(setup: CurrentStepSetup) -> Built:
    """Parts, wires, initial state (integrator at the back EMF) and logged ports (module
    docstring); the reference carries the step (``run`` replaces it per run of the batch)."""
    m = setup.machine
    w_e = setup.electrical_speed
    K_P, K_I = pi_gains(setup.controller)
    machine = PermanentMagnetMachine.from_params("machine", m)
    shaft = PrescribedSpeed("shaft", w=constant(w_e / m.n_p))
    reference = CurrentProgram("reference", re=_step_table(setup, K_PEAK * setup.step), im=0.0)
    current = RotorFrameCurrentController(
        "current", K_P_d=K_P, K_P_q=K_P, K_I_d=K_I, K_I_q=K_I, R_s=m.R_s, L_d=m.L_d, L_q=m.L_q,
        psi_m=m.psi_m, n_p=m.n_p, V_dc=UNLIMITED_V_DC, advance=0.0, decouple=0.0,
    )  # fmt: skip
    wires = [
        (shaft.out.w, machine.inp.w),
        (shaft.out.theta, current.inp.theta),
        (shaft.out.w, current.inp.w),
        (reference.out.i, current.inp.i_dq_ref),
        (machine.out.i_s, current.inp.i_s),
        (current.out.v_ref, machine.inp.v_s),
    ]
    system = System([machine, shaft, reference, current], wires)
    emf = 1j * w_e * magnet_flux(m.psi_m)  # the steady voltage of zero current, rotor frame
    log = {
        "i_dq_ref": reference.out.i,
        "i_dq": machine.out.i_dq,
        "v_dq": current.out.v_dq_ref,
    }
    return Built(system, {"current": {"x": emf}}, {"current": {"v_ref": emf}}, log)


@dataclass
class CurrentStepResult:
    """The two runs (with and without the step), the step response dy per unit step (complex:
    d + j q), the step's time t_0 in (S) (module docstring), and the summary (``measure``)."""

    setup: CurrentStepSetup
    t: np.ndarray
    step_response: np.ndarray
    t_0: float
    runs: tuple
    summary: dict


def step_transfer(t: np.ndarray, dy: np.ndarray, t_0: float, w: np.ndarray) -> np.ndarray:
    """(S) per unit step: sum_k (dy_{k+1} - dy_k) e^{-j w (t_{k+1/2} - t_0)} at each w."""
    mid = 0.5 * (t[1:] + t[:-1]) - t_0
    return np.exp(-1j * np.outer(w, mid)) @ np.diff(dy)


def run(setup: CurrentStepSetup, compiled=None) -> CurrentStepResult:
    """The batch of the two runs and the comparison with (10) (module docstring)."""
    built = build(setup)
    compiled = compiled or built.system.compile()
    zero = {"reference": {"re": _step_table(setup, 0.0)}}
    step = {"reference": {"re": _step_table(setup, K_PEAK * setup.step)}}
    results = compiled.run_batch(
        [step, zero], setup.duration, setup.sample_time, substeps=setup.substeps,
        initial=built.initial, held=built.held, log=list(built.log.values()),
    )  # fmt: skip
    for res in results:
        status = res.extra.get("status", "ok")
        if status != "ok":
            raise InputError("simulation", f"the run {status}")
    with_step, without = results
    t = with_step.t
    A = K_PEAK * setup.step
    dy = (with_step.signal(built.log["i_dq"]) - without.signal(built.log["i_dq"])) / A
    seen = np.flatnonzero(with_step.signal(built.log["i_dq_ref"]).real != 0.0)
    if seen.size == 0:
        raise InputError("step_time", "the controller never saw the step")
    t_0 = float(t[seen[0]]) - 0.5 * setup.sample_time
    v_dq = with_step.signal(built.log["v_dq"])
    summary = measure(setup, t, dy, t_0, v_dq, with_step.events["current"]["saturated"])
    return CurrentStepResult(setup, t, dy, t_0, (with_step, without), summary)


def measure(setup: CurrentStepSetup, t, dy, t_0: float, v_dq, saturated: int) -> dict:
    """Every figure of the comparison, computed once (module docstring): dy per unit step,
    v_dq the voltage command of the run with the step, ``saturated`` the controller's limit
    count."""
    W = np.asarray(setup.frequencies)
    coupling = step_transfer(t, dy.imag, t_0, W)
    direct = step_transfer(t, dy.real, t_0, W)
    k, w_e, p = setup.controller, setup.electrical_speed, setup.machine
    icad = icad_coupling(p, w_e, k, W)
    icad_delayed = icad_coupling(p, w_e, k, W, setup.delay)
    direct_predicted = closed_loop(p, w_e, k, W, setup.delay)[:, 0, 0]
    err = np.abs(coupling - icad) / np.abs(icad)
    err_delayed = np.abs(coupling - icad_delayed) / np.abs(icad_delayed)
    err_direct = np.abs(direct - direct_predicted) / np.abs(direct_predicted)
    tail = float(max(abs(dy[-1].imag), abs(dy[-1].real - 1.0)))
    compared = W <= ICAD_W_MAX
    after = t >= t_0
    peak = int(np.argmax(np.abs(dy.imag)))
    rows = [
        {
            "frequency_rad_s": float(W[i]),
            "measured_db": float(20.0 * np.log10(abs(coupling[i]))),
            "measured_phase_deg": float(np.degrees(np.angle(coupling[i]))),
            "icad_db": float(20.0 * np.log10(abs(icad[i]))),
            "icad_phase_deg": float(np.degrees(np.angle(icad[i]))),
            "icad_delayed_db": float(20.0 * np.log10(abs(icad_delayed[i]))),
            "relative_error": float(err[i]),
            "relative_error_delayed": float(err_delayed[i]),
            "direct_relative_error": float(err_direct[i]),
        }
        for i in range(W.size)
    ]
    return {
        "electrical_speed_rad_s": float(w_e),
        "controller": k.name,
        "step_at_s": t_0,
        "cross_peak_per_step": float(abs(dy.imag[peak])),
        "cross_peak_after_step_s": float(t[peak] - t_0),
        "cross_before_step": float(np.max(np.abs(dy[~after]))) if (~after).any() else 0.0,
        "tail": tail,
        "relative_error_max": float(np.max(err[compared])),
        "relative_error_delayed_max": float(np.max(err_delayed)),
        "direct_relative_error_max": float(np.max(err_direct)),
        "voltage_peak_v": float(np.max(np.abs(v_dq))),
        "controller_limited_samples": int(saturated),
        "coupling_matches_icad": bool(
            np.all(err[compared] <= ICAD_REL_TOL)
            and np.all(err_delayed <= DELAYED_REL_TOL)
            and tail <= TAIL_TOL
            and saturated == 0
        ),
        "rows": rows,
    }
