"""The standstill identification of a cage IM: DC steps, then the injection, then a T-circuit.

1. The DC-step log (optional) gives R_s and the inverter's voltage error U (``identify._dc``);
2. the injection log, compensated by U when the DC steps gave it, gives the four inverse-Gamma
   parameters with their intervals, widened by U's own uncertainty (``identify._impedance``);
3. a T-circuit (``machines.IMParams``) under a stated leakage split (``identify._circuit``), its
   parameters' intervals from the bootstrap draws converted one by one and from the Jacobian
   covariance carried through the conversion to first order.

What the data identify is said in :func:`identifiability`: the inverse-Gamma parameters; not the
leakage split, not the pole pairs (given), not the inertia (no motion at standstill).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acdrive._arguments import COUNT, COUNT0, NONNEGATIVE, POSITIVE, SEED, Instance, Text, checked
from acdrive.identify._circuit import LEAKAGE_SPLITS, InverseGamma, t_circuit
from acdrive.identify._dc import DCStepFit, fit_dc_steps
from acdrive.identify._experiment import StandstillLog
from acdrive.identify._fit import (
    BOOTSTRAP_COUNT,
    Estimate,
    jacobian_interval,
    percentile_interval,
    propagate,
    t_quantile,
)
from acdrive.identify._impedance import ImpedanceFit, fit_impedance
from acdrive.identify._judge import RESIDUAL_FACTOR
from acdrive.identify._offset import (
    OFFSET_ROUNDS,
    OFFSET_TOLERANCE,
    joint_offset,
    offset_estimate,
)

#: the T-circuit fields written, with unit and meaning (those of ``machines.IMParams``)
T_FIELDS = (
    ("R_s", "ohm", "stator resistance"),
    ("R_r", "ohm", "rotor resistance referred to the stator (depends on the split)"),
    ("L_s", "H", "stator self inductance, L_sigma + L_M"),
    ("L_r", "H", "rotor self inductance (depends on the split)"),
    ("L_m", "H", "magnetising inductance (depends on the split)"),
)


@dataclass(frozen=True)
class StandstillIdentification:
    """Everything one standstill identification found (module docstring)."""

    dc: DCStepFit | None
    impedance: ImpedanceFit
    split: str
    n_p: int
    t_estimates: tuple[Estimate, ...]
    current_offset: Estimate | None = None
    voltage_error: float | None = None

    @property
    def warnings(self) -> tuple[str, ...]:
        """What the fit found in its own residual and timing (``identify._judge``)."""
        return self.impedance.warnings

    @property
    def params(self) -> InverseGamma:
        return self.impedance.params

    def machine(self, L_M: float | None = None):
        """The ``IMParams`` of the estimates under the leakage split (with the magnetising
        inductance ``L_M`` [H] of a no-load run instead of the injection's, if given)."""
        params = self.params
        if L_M is not None:
            params = InverseGamma(params.R_s, params.L_sigma, params.R_R, float(L_M))
        return t_circuit(params, self.n_p, self.split)


def _less(log: StandstillLog, offset: float) -> StandstillLog:
    """``log`` with ``offset`` [A] subtracted from its current."""
    return StandstillLog(log.time, log.v_a, log.i_a - offset, log.source)


def _t_values(values, n_p: int, split: str) -> np.ndarray:
    machine = t_circuit(InverseGamma.from_array(values), n_p, split)
    return np.array([getattr(machine, name) for name, _, _ in T_FIELDS])


@checked(
    injection=Instance(StandstillLog), base_frequency=POSITIVE, settle=NONNEGATIVE,
    dc=Instance(StandstillLog, optional=True), n_p=COUNT, split=Text(LEAKAGE_SPLITS), seed=SEED,
    bootstrap=COUNT0, dead_time=NONNEGATIVE,
)
def identify_standstill(injection: StandstillLog, base_frequency: float, settle: float,
                        dc: StandstillLog | None = None, n_p: int = 1, split: str = "equal",
                        seed: int = 0, bootstrap: int = BOOTSTRAP_COUNT,
                        dead_time: float = 0.0) -> StandstillIdentification:  # fmt: skip
    """Identify a cage IM from its standstill logs (module docstring); ``dead_time`` [s] is the
    inverter's programmed dead time, whose shift of the sample instant the injection's model
    includes (``identify._impedance``)."""
    t_circuit(InverseGamma(1.0, 1.0, 1.0, 1.0), n_p, split)  # the split and n_p, checked first
    dc_fit = fit_dc_steps(dc, seed=seed, bootstrap=bootstrap) if dc is not None else None
    error = dc_fit.voltage_error.value if dc_fit is not None else None
    error_std = dc_fit.voltage_error_std if dc_fit is not None else 0.0
    offset = dc_fit.offset if dc_fit is not None else None
    reading = injection
    if dc_fit is not None and offset is None:  # the offset from the injection's mean
        intercept, intercept_std, slope = error, error_std, dc_fit.R_s.value
        value = 0.0
        for _ in range(OFFSET_ROUNDS):  # until the offset moves less than OFFSET_TOLERANCE
            trial = fit_impedance(_less(injection, value), base_frequency, settle,
                                  voltage_error=error, bootstrap=0, check=False,
                                  dead_time=dead_time)  # fmt: skip
            joint = joint_offset(injection, trial, base_frequency, intercept, intercept_std,
                                 slope)  # fmt: skip
            moved = abs(joint.value - value)
            error, error_std, value = joint.voltage_error, joint.voltage_error_std, joint.value
            if moved <= OFFSET_TOLERANCE * joint.std:
                break
        offset = offset_estimate(joint.value, joint.std, "current-sensor offset, from the "
                                 "injection's mean current jointly with the parameters and the "
                                 "DC steps (subtracted; U_err corrected by R_s times it)")  # fmt: skip
    if offset is not None:  # the reading's sign starts the polarity's rounds: without the offset
        reading = _less(injection, offset.value)
    fit = fit_impedance(reading, base_frequency, settle, voltage_error=error, seed=seed + 1,
                        bootstrap=bootstrap, voltage_error_std=error_std,
                        dead_time=dead_time)  # fmt: skip
    values = fit.params.as_array()
    t_values = _t_values(values, n_p, split)
    cov = propagate(lambda v: _t_values(v, n_p, split), values, fit.cov)
    draws = np.array([_t_values(d, n_p, split) if np.all(np.isfinite(d)) else np.full(5, np.nan)
                      for d in fit.draws]).reshape(-1, len(T_FIELDS))  # none with bootstrap=0
    q = t_quantile(fit.dof)
    t_estimates = tuple(
        Estimate(name, unit, meaning, float(t_values[j]),
                 jacobian_interval(t_values[j], cov[j, j], q), percentile_interval(draws[:, j]))
        for j, (name, unit, meaning) in enumerate(T_FIELDS)
    )  # fmt: skip
    return StandstillIdentification(dc_fit, fit, split, n_p, t_estimates, offset,
                                    error if dc_fit is not None else None)  # fmt: skip


@checked(result=Instance(StandstillIdentification))
def identifiability(result: StandstillIdentification) -> list[str]:
    """What the standstill data determine and what they do not, as sentences."""
    spec = result.impedance.spectrum
    corner = result.params.rotor_corner / (2.0 * np.pi)
    lines = [
        (
            f"identified: R_s, L_sigma, R_R, L_M (the inverse-Gamma circuit) from "
            f"{spec.frequency.size} tones, {spec.frequency[0]:g} to {spec.frequency[-1]:g} Hz, "
            f"bracketing the rotor corner R_R / (2 pi L_M) = {corner:.3g} Hz"
        ),
        (
            "not identifiable at standstill: the split of the leakage between stator and rotor "
            "(hence L_m, L_r, R_r separately); the T-circuit assumes "
            f"{LEAKAGE_SPLITS[result.split]}"
        ),
        (
            f"not identified: the pole pairs n_p = {result.n_p} (given), the inertia and "
            "friction (no motion)"
        ),
    ]
    if result.dc is None:
        lines.append("no DC-step log: the inverter's voltage error was neither measured nor "
                     "compensated; a current-sensor offset was not estimated (it does not "
                     "enter the injection's tones)")  # fmt: skip
    else:
        error = result.voltage_error
        if error is None:
            error = result.dc.voltage_error.value
        offset = result.current_offset
        low, high = offset.jacobian
        lines.append(f"inverter voltage error U_err = {error:.4g} V (DC-step intercept "
                     f"{result.dc.voltage_error.value:.4g} V plus R_s times the current "
                     f"offset), compensated in the injection; current-sensor offset "
                     f"{offset.value:.3g} A (95 %: {low:.3g} to {high:.3g} A), subtracted")  # fmt: skip
    fit = result.impedance
    if fit.residual_ratio == fit.residual_ratio:  # judged (identify._judge)
        lines.append(f"residual {fit.residual_ratio:.3g} times the noise floor of the off-tone "
                     f"bins ({fit.noise_rms:.3g} A; above {RESIDUAL_FACTOR:g} the model misses "
                     "part of the log)")  # fmt: skip
    else:
        lines.append("residual not judged against the noise: the window has no off-tone bins "
                     "(one period of the base frequency: log two or more) or no noise in them")  # fmt: skip
    lines += [f"warning: {line}" for line in fit.warnings]
    return lines
