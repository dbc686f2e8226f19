"""A PM machine's R_s, L_d and L_q from d- and q-axis injection at standstill.

**The tests.** The bench of ``identify._experiment`` with a ``machines.PermanentMagnetMachine``:
the same DC source, SVPWM inverter (dead time, device drops), phase-a-only command and noisy,
quantised current reading. The rotor is locked, first with its d axis on phase a (electrical
angle n_p theta = 0), then with its q axis on phase a (n_p theta = pi / 2: turned a quarter of a
pole pitch, theta = pi / (2 n_p)). A phase-a voltage is then a pure d-axis, respectively q-axis,
voltage, and at zero speed Ugalde-Loo et al. (7) leave one RL winding per axis:

    L_x di_x/dt = v_x - R_s i_x        (x = d or q; no speed voltage, the magnet flux constant)

so each axis's standstill log is the existing multisine injection with a first-order model: its
zero-order-hold sampled admittance (voltage held over each carrier period, current sampled at the
period start; the exact discrete model of the RL branch) is

    Y_d(z) = (1 - a) / (R_s (z - a)),   a = exp(-R_s T / L_x),   z = e^{jwT},

fitted by the frequency-domain least squares of ``identify._impedance`` (same window, tones,
voltage-error compensation with the sign the inverter saw and the dead time's sample shift,
Jacobian and bootstrap intervals, the rule that every interval be within +-50 %): the RL branch
declares its state space (``rl_state_space``), the model ``identify._winding`` samples.

**Torque and the lock.** With the d axis on phase a the current is i_d only and the torque
n_p (psi_pm i_q + (L_d - L_q) i_d i_q) (Ugalde-Loo et al. (8)) is zero: the d test needs no lock
(a misalignment would make some). The q-axis current makes torque n_p psi_pm i_q, which would
turn the rotor towards d-axis alignment: the q test needs the shaft locked (a brake or a
clamp); on the simulated bench the shaft is ``plant.PrescribedSpeed`` at zero speed, which holds
any torque, and the test reports the peak torque the lock held (``AxisTest.holding_torque``) so a
bench's brake can be sized. The DC steps (R_s and the inverter's voltage error,
``identify._dc``) run with the d axis on phase a and positive current: no torque, and a field
that strengthens the magnet's instead of demagnetising it.

**What standstill data identify:** R_s (from each axis; the two are combined by their inverse
variances), L_d, L_q at the injected current level. Not: the magnet flux (no speed, no back-EMF:
``identify._spin``), the pole pairs, the inertia. acdrive's PM part has constant inductances, so
saturation and cross-saturation are outside what a simulated test can show.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from acdrive._arguments import (
    COUNT0,
    FLAG,
    NONNEGATIVE,
    POSITIVE,
    RESULT,
    SEED,
    Array,
    Instance,
    Items,
    Text,
    checked,
)
from acdrive.errors import InputError
from acdrive.identify._dc import Z_95, DCStepFit, fit_dc_steps
from acdrive.identify._experiment import StandstillLog, StandstillPlan, multisine, run_test
from acdrive.identify._fit import BOOTSTRAP_COUNT, Estimate, percentile_interval
from acdrive.identify._impedance import (
    AdmittanceModel,
    ImpedanceFit,
    fit_impedance,
    winding_model,
)
from acdrive.identify._winding import sampled_response

#: the rotor's electrical angle n_p theta that puts each axis on phase a
AXIS_ANGLE = {"d": 0.0, "q": 0.5 * math.pi}


def rl_state_space(values) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of the RL branch L di/dt = v - R i, ``values`` = (R, L): one state, the current."""
    R, L = (float(v) for v in values)
    return np.array([[-R / L]]), np.array([1.0 / L])


@checked(values=Array(1), w=Array(), hold=POSITIVE, dead_time=NONNEGATIVE)
def rl_admittance(values, w, hold: float, dead_time: float = 0.0) -> np.ndarray:
    """Y_d(e^{jwT}) = (1 - a) / (R (z - a)), a = exp(-R T / L) [S]: the RL branch driven by a
    voltage held over each period T = ``hold`` and its current sampled at the period starts
    (module docstring), t_d / 2 early by the inverter's dead time ``dead_time`` = t_d, which
    multiplies it by e^{R t_d / (2 L)} (``identify._winding``); ``values`` = (R, L)."""
    return sampled_response(*rl_state_space(values), w, hold, dead_time)


def _rl_start(spec) -> np.ndarray:
    """R from the lowest tone's impedance, L from the highest's reactance."""
    Z = spec.voltage / spec.current
    w = 2.0 * np.pi * spec.frequency
    return np.array([max(Z[0].real, 1e-6), max(Z[-1].imag / w[-1], 1e-9)])


def rl_model(resistance: tuple[str, str], inductance: tuple[str, str]) -> AdmittanceModel:
    """An RL winding whose resistance and inductance are named and explained by the pairs
    (name, meaning) given (module docstring)."""
    fields = ((resistance[0], "ohm", resistance[1]), (inductance[0], "H", inductance[1]))
    return winding_model(fields, rl_state_space, _rl_start, tuple)


def axis_model(axis: str) -> AdmittanceModel:
    """The winding of one axis at standstill (module docstring)."""
    if axis not in AXIS_ANGLE:
        raise InputError("axis", f"must be 'd' or 'q', got {axis!r}")
    return rl_model(("R_s", f"stator resistance ({axis}-axis test)"),
                    (f"L_{axis}", f"{axis}-axis inductance"))  # fmt: skip


@checked(log=Instance(StandstillLog), holding_torque=RESULT)
@dataclass(frozen=True)
class AxisTest:
    """One simulated axis test: its ``log`` and the peak torque the locked shaft held [N m]."""

    log: StandstillLog
    holding_torque: float


@checked(
    machine=Instance("acdrive.machines._pmsm:PMSGParams"), plan=Instance(StandstillPlan),
    axis=Text(("d", "q")), seed=SEED,
)
def axis_test(machine, plan: StandstillPlan, axis: str, seed: int = 1) -> AxisTest:
    """The multisine of ``plan`` on phase a of the PM machine ``machine`` (a ``PMSGParams``)
    with the rotor locked with its ``axis`` ('d' or 'q') on phase a (module docstring)."""
    axis_model(axis)  # the axis, checked
    theta = AXIS_ANGLE[axis] / machine.n_p
    initial = {"machine": {"theta": theta, "e_r": complex(np.exp(1j * AXIS_ANGLE[axis]))}}
    torque: list = []
    log = run_test(machine, plan, lambda t: multisine(plan, t), plan.injection_duration(), seed,
                   f"simulated {axis}-axis injection test", initial, torque)  # fmt: skip
    return AxisTest(log, float(np.max(np.abs(torque[0]))))


@checked(
    d=Instance(ImpedanceFit), q=Instance(ImpedanceFit), dc=Instance(DCStepFit, optional=True),
    estimates=Items(Instance(Estimate)),
)
@dataclass(frozen=True)
class PMStandstillIdentification:
    """The d- and q-axis fits, the DC-step fit (or None) and the combined estimates
    (``estimates``: R_s, L_d, L_q)."""

    d: ImpedanceFit
    q: ImpedanceFit
    dc: DCStepFit | None
    estimates: tuple[Estimate, ...]

    def value(self, name: str) -> float:
        return next(e.value for e in self.estimates if e.name == name)


def combined_resistance(d: ImpedanceFit, q: ImpedanceFit, meaning: str) -> Estimate:
    """The resistance (first parameter) of two independent fits ``d`` and ``q``, weighted by
    their inverse Jacobian variances; its bootstrap draws are the same weighting of the two
    fits' draws (independent tests, so paired draws are draws of the combination)."""
    inverse = np.array([1.0 / fit.cov[0, 0] for fit in (d, q)])
    weights = inverse / inverse.sum()
    value = float(weights @ [d.estimates[0].value, q.estimates[0].value])
    std = 1.0 / math.sqrt(inverse.sum())
    draws = weights[0] * d.draws[:, 0] + weights[1] * q.draws[:, 0]
    return Estimate(d.estimates[0].name, "ohm", meaning, value,
                    (value - Z_95 * std, value + Z_95 * std),
                    percentile_interval(draws))  # fmt: skip


@checked(
    d_log=Instance(StandstillLog), q_log=Instance(StandstillLog), base_frequency=POSITIVE,
    settle=NONNEGATIVE, dc=Instance(StandstillLog, optional=True), seed=SEED, bootstrap=COUNT0,
    dead_time=NONNEGATIVE, check=FLAG,
)
def identify_pm_standstill(d_log: StandstillLog, q_log: StandstillLog, base_frequency: float,
                           settle: float, dc: StandstillLog | None = None, seed: int = 0,
                           bootstrap: int = BOOTSTRAP_COUNT,
                           dead_time: float = 0.0,
                           check: bool = True) -> PMStandstillIdentification:  # fmt: skip
    """R_s, L_d, L_q from the two axis logs (and a DC-step log, whose voltage error then
    compensates both with the sign the inverter saw; module docstring); ``dead_time`` [s], the
    inverter's programmed dead time, moves each model's sample t_d / 2 early
    (``identify._impedance``, as for the cage IM). ``check=False`` skips the identifiability rules
    (to show what a bad test gives, e.g. the bias of an uncompensated dead time)."""
    dc_fit = fit_dc_steps(dc, seed=seed, bootstrap=bootstrap) if dc is not None else None
    error = dc_fit.voltage_error.value if dc_fit is not None else None
    error_std = dc_fit.voltage_error_std if dc_fit is not None else 0.0
    fits = {
        axis: fit_impedance(
            log,
            base_frequency,
            settle,
            voltage_error=error,
            seed=seed + k + 1,
            bootstrap=bootstrap,
            voltage_error_std=error_std,
            model=axis_model(axis),
            dead_time=dead_time,
            check=check,
        )
        for k, (axis, log) in enumerate((("d", d_log), ("q", q_log)))
    }
    R_s = combined_resistance(
        fits["d"], fits["q"], "stator resistance (both axis tests, inverse-variance weighted)"
    )
    estimates = (R_s, fits["d"].estimates[1], fits["q"].estimates[1])
    return PMStandstillIdentification(fits["d"], fits["q"], dc_fit, estimates)


@checked(result=Instance(PMStandstillIdentification))
def pm_identifiability(result: PMStandstillIdentification) -> list[str]:
    """What the PM standstill data determine and what they do not, as sentences."""
    tones = result.d.spectrum.frequency
    lines = [
        (
            f"identified: R_s, L_d, L_q from the rotor locked with its d axis, then its q axis, "
            f"on phase a ({tones.size} tones, {tones[0]:g} to {tones[-1]:g} Hz)"
        ),
        (
            "not identifiable at standstill: the magnet flux psi_m (no speed, no back-EMF; a "
            "spin test gives it), the pole pairs (given), the inertia and friction (no motion)"
        ),
        "the inductances hold at the injected current level (no saturation in the model)",
    ]
    if result.dc is not None:
        lines.append(f"inverter voltage error U_err = {result.dc.voltage_error.value:.4g} V "
                     "(DC-step intercept), compensated in both axis tests")  # fmt: skip
    for axis, fit in (("d", result.d), ("q", result.q)):  # identify._judge
        lines += [f"warning ({axis}-axis test): {line}" for line in fit.warnings]
    return lines
