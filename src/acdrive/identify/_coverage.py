"""How often the 95 % intervals of the standstill identification cover the truth (issue 23,
item 3): the simulated tests repeated with independent sensor noise (seeds ``seed`` to
``seed + repetitions - 1``), each identified, each interval of each inverse-Gamma parameter
checked against the machine's own (``identify._circuit.inverse_gamma``).

With ``compensate`` (the default) the estimator gets what an engineer has of the inverter: the
DC-step log (its intercept U_err compensates the injection's voltage) and the programmed dead
time ``plan.t_d`` (the sample instant's shift, ``identify._impedance``). Without it, the injection
alone is fitted as if the inverter were ideal: the bias of an uncompensated dead time.

The bench is deterministic and the sensor's noise is added after the run
(``identify._experiment``), so each test is simulated once without noise and every repetition
draws its own reading from it: the same logs as simulating each repetition, in a fraction of the
time.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from acdrive._arguments import COUNT, COUNT0, FLAG, RESULT, SEED, Instance, Table, checked
from acdrive.errors import InputError
from acdrive.identify._circuit import NAMES, inverse_gamma
from acdrive.identify._experiment import (
    CurrentSensor,
    StandstillLog,
    StandstillPlan,
    dc_test,
    injection_test,
    measured_current,
)
from acdrive.identify._fit import BOOTSTRAP_COUNT
from acdrive.identify._standstill import identify_standstill


@checked(
    repetitions=COUNT, jacobian=Table(RESULT), bootstrap=Table(RESULT), bias=Table(RESULT),
    half_width=Table(RESULT),
)
@dataclass(frozen=True)
class Coverage:
    """Per parameter (``_circuit.NAMES`` order): the fraction of repetitions whose Jacobian and
    bootstrap intervals hold the truth, the mean relative error of the estimates (its bias) and
    the mean relative half-width of the Jacobian interval."""

    repetitions: int
    jacobian: dict[str, float]
    bootstrap: dict[str, float]
    bias: dict[str, float]
    half_width: dict[str, float]


def reading(log: StandstillLog, sensor: CurrentSensor, seed: int) -> StandstillLog:
    """``log`` of a noise-free run as ``sensor`` reports it with the noise of ``seed``: the log
    ``identify._experiment.run_test`` returns for that seed."""
    current = measured_current(log.i_a, sensor, np.random.default_rng(seed))
    return StandstillLog(log.time, log.v_a, current, log.source)


@checked(
    machine=Instance("acdrive.machines._induction:IMParams"), plan=Instance(StandstillPlan),
    repetitions=COUNT, seed=SEED, bootstrap=COUNT0, compensate=FLAG,
)
def coverage(machine, plan: StandstillPlan, repetitions: int, seed: int = 0,
             bootstrap: int = BOOTSTRAP_COUNT, compensate: bool = True) -> Coverage:  # fmt: skip
    """Repeat the simulated standstill tests of ``plan`` on ``machine`` (module docstring)."""
    if isinstance(repetitions, bool) or not isinstance(repetitions, int) or repetitions < 1:
        raise InputError("repetitions", f"must be an integer >= 1, got {repetitions!r}")
    truth = inverse_gamma(machine).as_array()
    hits = {"jacobian": np.zeros(len(NAMES)), "bootstrap": np.zeros(len(NAMES))}
    errors, widths = np.zeros(len(NAMES)), np.zeros(len(NAMES))
    quiet = replace(plan, sensor=CurrentSensor(noise_std=0.0, offset=0.0, lsb=0.0))
    injection, dc = injection_test(machine, quiet), dc_test(machine, quiet)
    for r in range(repetitions):
        run = seed + r
        result = identify_standstill(
            reading(injection, plan.sensor, 2 * run + 1), plan.base_frequency, plan.settle,
            dc=reading(dc, plan.sensor, 2 * run) if compensate else None, n_p=machine.n_p,
            seed=run, bootstrap=bootstrap, dead_time=plan.t_d if compensate else 0.0,
        )  # fmt: skip
        for j, (estimate, true) in enumerate(zip(result.impedance.estimates, truth, strict=True)):
            for which, count in hits.items():
                count[j] += estimate.covers(true, which)
            errors[j] += (estimate.value - true) / true
            widths[j] += estimate.half_width()
    return Coverage(
        repetitions,
        {n: float(h) / repetitions for n, h in zip(NAMES, hits["jacobian"], strict=True)},
        {n: float(h) / repetitions for n, h in zip(NAMES, hits["bootstrap"], strict=True)},
        {n: float(e) / repetitions for n, e in zip(NAMES, errors, strict=True)},
        {n: float(w) / repetitions for n, w in zip(NAMES, widths, strict=True)},
    )
