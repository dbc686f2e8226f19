"""A DFIM's parameters from its rotor converter at standstill (Bodson's machine and setting).

**The setting.** In Bodson's drive the rotor is fed by the converter and the stator is switched
onto the supply by a relay. At standstill (rotor at rest, rotor coordinates = stator coordinates)
the converter injects on rotor phase a, as the cage IM's bench does on its stator
(``identify._experiment``: DC steps and a multisine; the log's ``v_a``, ``i_a`` are the rotor's
phase-a voltage command and measured current, referred to the stator as Bodson (3) refers every
rotor quantity), twice:

1. **stator open** (relay open, i_s = 0): the rotor is one RL winding,
   psi_r = L_r i_r, dpsi_r/dt = v_r - R_r i_r (Bodson (9)), so the injection gives R_r and L_r
   (the RL model of ``identify._pm``) and the DC steps R_r and the converter's voltage error;
2. **stator shorted** (relay closed onto zero voltage): the rotor sees the stator circuit through
   M, Z(s) = R_r + s L_r - s^2 M^2 / (R_s + s L_s), which is the inverse-Gamma form of
   ``identify._circuit`` seen from the rotor,

       Z(s) = R_r + s L_sigma_r + s L_M' R_S' / (R_S' + s L_M'),
       L_sigma_r = L_r - M^2 / L_s,  L_M' = M^2 / L_s,  R_S' = R_s (M / L_s)^2,

   fitted by the same estimator (``identify._impedance``) with these four names.

Both models declare their state space (``identify._winding``), so a DC-step log and the
converter's programmed dead time compensate the injections as for the cage IM: the simulated
sign and the sample t_d / 2 early (``identify_dfim``'s ``dead_time``).

**What is identifiable.** R_r (both tests; combined by inverse variance), L_r, L_M' = M^2 / L_s
and R_S' = R_s (M/L_s)^2; the open test's L_r and the shorted test's L_sigma_r + L_M' must agree
(``consistency``, a check of the data). M, L_s and R_s separately are not: the stator is reached
only through M, so one ratio (M / L_s, the stator's turns ratio) is free, as the leakage split is
for the cage IM. A stator resistance measured apart (an ohmmeter or a DC test on the stator
terminals, which the rotor converter cannot make; ``R_s`` and its standard error given) fixes
it: M / L_s = sqrt(R_S' / R_s), L_s = L_M' R_s / R_S', M = L_M' sqrt(R_s / R_S'), with their
intervals carried through to first order and in the bootstrap. The pole pairs and the mechanics
are not seen at standstill.
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
    Instance,
    Items,
    Text,
    checked,
    optional,
)
from acdrive.errors import InputError, require_positive
from acdrive.identify._circuit import standstill_state_space
from acdrive.identify._dc import Z_95, DCStepFit, fit_dc_steps
from acdrive.identify._experiment import (
    StandstillLog,
    StandstillPlan,
    dc_steps,
    multisine,
    run_test,
)
from acdrive.identify._fit import (
    BOOTSTRAP_COUNT,
    Estimate,
    jacobian_interval,
    percentile_interval,
    propagate,
)
from acdrive.identify._impedance import (
    INVERSE_GAMMA_MODEL,
    ImpedanceFit,
    fit_impedance,
    winding_model,
)
from acdrive.identify._pm import combined_resistance, rl_model

#: the open-stator test: the rotor winding alone
OPEN_MODEL = rl_model(("R_r", "rotor resistance (stator open)"),
                      ("L_r", "rotor self inductance (stator open)"))  # fmt: skip
#: the shorted-stator test: the rotor-side inverse-Gamma circuit (module docstring)
SHORTED_MODEL = winding_model(
    (
        ("R_r", "ohm", "rotor resistance (stator shorted)"),
        ("L_sigma_r", "H", "rotor transient inductance L_r - M^2/L_s"),
        ("R_S", "ohm", "stator resistance seen from the rotor, R_s (M/L_s)^2"),
        ("L_M", "H", "magnetising inductance seen from the rotor, M^2/L_s"),
    ),
    standstill_state_space,
    INVERSE_GAMMA_MODEL.start,
    tuple,
)


@checked(
    machine=Instance("acdrive.machines._dfim:DFIMParams"), plan=Instance(StandstillPlan),
    stator=Text(("open", "shorted")), kind=Text(("dc", "injection")), seed=SEED,
)
def dfim_test(machine, plan: StandstillPlan, stator: str, kind: str, seed: int = 1):
    """The ``kind`` ('dc' or 'injection') test of ``plan`` from the rotor converter of the DFIM
    ``machine`` (a ``DFIMParams``) at standstill with its stator ``stator`` ('open' or
    'shorted'; module docstring)."""
    if kind == "dc":
        voltage, duration = (lambda t: dc_steps(plan, t)), plan.dc_duration()
    elif kind == "injection":
        voltage, duration = (lambda t: multisine(plan, t)), plan.injection_duration()
    else:
        raise InputError("kind", f"must be 'dc' or 'injection', got {kind!r}")
    return run_test(machine, plan, voltage, duration, seed,
                    f"simulated {kind} test, stator {stator}", stator=stator)  # fmt: skip


@checked(
    open=Instance(ImpedanceFit), shorted=Instance(ImpedanceFit),
    dc=Instance(DCStepFit, optional=True), estimates=Items(Instance(Estimate)), consistency=RESULT,
)
@dataclass(frozen=True)
class DFIMIdentification:
    """The open- and shorted-stator fits, the open-stator DC fit (or None), the estimates
    (R_r, L_r, L_sigma_r, R_S, L_M; then M, L_s, R_s if a stator resistance was given) and the
    consistency check (L_r against L_sigma_r + L_M: difference over its standard error)."""

    open: ImpedanceFit
    shorted: ImpedanceFit
    dc: DCStepFit | None
    estimates: tuple[Estimate, ...]
    consistency: float

    def value(self, name: str) -> float:
        return next(e.value for e in self.estimates if e.name == name)


def _stator_side(values) -> np.ndarray:
    """(M, L_s) from (L_M', R_S', R_s) (module docstring)."""
    L_M, R_S, R_s = (float(v) for v in values)
    return np.array([L_M * math.sqrt(R_s / R_S), L_M * R_s / R_S])


@checked(
    open_log=Instance(StandstillLog), shorted_log=Instance(StandstillLog), base_frequency=POSITIVE,
    settle=NONNEGATIVE, dc=Instance(StandstillLog, optional=True), R_s=optional(POSITIVE),
    R_s_std=NONNEGATIVE, seed=SEED, bootstrap=COUNT0, dead_time=NONNEGATIVE, check=FLAG,
)
def identify_dfim(open_log: StandstillLog, shorted_log: StandstillLog, base_frequency: float,
                  settle: float, dc: StandstillLog | None = None, R_s: float | None = None,
                  R_s_std: float = 0.0, seed: int = 0, bootstrap: int = BOOTSTRAP_COUNT,
                  dead_time: float = 0.0, check: bool = True) -> DFIMIdentification:  # fmt: skip
    """The DFIM's parameters from its rotor-converter logs (module docstring); ``dc`` the
    open-stator DC-step log, whose voltage error compensates both injections with the sign the
    converter saw; ``dead_time`` [s] the converter's programmed dead time (the models' sample
    t_d / 2 early, ``identify._impedance``, as for the cage IM); ``R_s`` [ohm] a stator
    resistance measured apart (with its standard error ``R_s_std``); ``check=False`` skips the
    identifiability rules (to show what a bad test gives)."""
    if R_s is not None:
        require_positive("R_s", R_s)
        if not (math.isfinite(R_s_std) and R_s_std >= 0.0):
            raise InputError("R_s_std", "must be a finite number >= 0")
    dc_fit = fit_dc_steps(dc, seed=seed, bootstrap=bootstrap) if dc is not None else None
    error = dc_fit.voltage_error.value if dc_fit is not None else None
    error_std = dc_fit.voltage_error_std if dc_fit is not None else 0.0
    fits = {
        name: fit_impedance(log, base_frequency, settle, voltage_error=error, seed=seed + k + 1,
                            bootstrap=bootstrap, voltage_error_std=error_std, model=model,
                            dead_time=dead_time, check=check)
        for k, (name, log, model) in enumerate((("open", open_log, OPEN_MODEL),
                                                ("shorted", shorted_log, SHORTED_MODEL)))
    }  # fmt: skip
    opened, shorted = fits["open"], fits["shorted"]
    R_r = combined_resistance(
        opened, shorted, "rotor resistance (both tests, inverse-variance weighted)"
    )
    estimates = [R_r, opened.estimates[1], *shorted.estimates[1:]]
    sum_var = shorted.cov[1, 1] + shorted.cov[3, 3] + 2.0 * shorted.cov[1, 3]
    difference = opened.estimates[1].value - (shorted.estimates[1].value
                                              + shorted.estimates[3].value)  # fmt: skip
    consistency = difference / math.sqrt(opened.cov[1, 1] + sum_var)
    if R_s is not None:
        estimates += _stator_estimates(shorted, R_s, R_s_std, seed, bootstrap)
    return DFIMIdentification(opened, shorted, dc_fit, tuple(estimates), float(consistency))


def _stator_estimates(shorted: ImpedanceFit, R_s: float, R_s_std: float, seed: int,
                      bootstrap: int) -> list[Estimate]:  # fmt: skip
    """M, L_s and R_s with their intervals from the shorted fit and the given R_s."""
    values = np.array([shorted.estimates[3].value, shorted.estimates[2].value, R_s])
    cov = np.zeros((3, 3))
    cov[:2, :2] = shorted.cov[np.ix_([3, 2], [3, 2])]
    cov[2, 2] = R_s_std**2
    result = _stator_side(values)
    spread = propagate(_stator_side, values, cov)
    rng = np.random.default_rng(seed + 7)
    draws = np.array([_stator_side((d[3], d[2], R_s + R_s_std * rng.standard_normal()))
                      if np.all(np.isfinite(d)) else np.full(2, np.nan)
                      for d in shorted.draws])  # fmt: skip
    names = (("M", "H", "stator-rotor mutual inductance (with the R_s given)"),
             ("L_s", "H", "stator self inductance (with the R_s given)"))  # fmt: skip
    found = [Estimate(name, unit, meaning, float(result[j]),
                      jacobian_interval(float(result[j]), spread[j, j], Z_95),
                      percentile_interval(draws[:, j]))
             for j, (name, unit, meaning) in enumerate(names)]  # fmt: skip
    half = Z_95 * R_s_std
    found.append(Estimate("R_s", "ohm", "stator resistance (given, measured apart)", R_s,
                          (R_s - half, R_s + half), (R_s - half, R_s + half)))  # fmt: skip
    return found


@checked(result=Instance(DFIMIdentification))
def dfim_identifiability(result: DFIMIdentification) -> list[str]:
    """What the rotor-converter tests determine, as sentences."""
    lines = [
        (
            "identified from the rotor converter: R_r and L_r (stator open), L_r - M^2/L_s, "
            "M^2/L_s and R_s (M/L_s)^2 (stator shorted)"
        ),
        (
            f"check: L_r (open) - (L_sigma_r + L_M) (shorted) = {result.consistency:+.2f} standard "
            "errors"
        ),
    ]
    if any(e.name == "M" for e in result.estimates):
        lines.append("M and L_s follow from the stator resistance given (measured apart)")
    else:
        lines.append("not identifiable from the rotor side: M, L_s, R_s separately (the ratio "
                     "M/L_s is free); a stator resistance measured apart fixes them")  # fmt: skip
    lines.append("not identified at standstill: the pole pairs, the inertia and friction")
    for stator, fit in (("open", result.open), ("shorted", result.shorted)):  # identify._judge
        lines += [f"warning (stator {stator}): {line}" for line in fit.warnings]
    return lines
