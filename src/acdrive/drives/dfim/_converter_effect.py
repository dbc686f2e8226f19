"""The bench converter's side effect on the stator reactive power and on the torque command.

Bodson's voltage-command law ((20) with the stator current command (22)) computes the rotor
voltage that makes the stator absorb the commanded reactive power Q_COM while the machine
produces tau_COM, assuming the converter applies that voltage. A rotor converter with dead time
and device drops (``acdrive.drives.dfim._setup.ConverterLosses.fundamental_loss``) applies less, against
the rotor current. In steady state the stator then absorbs a reactive power Q_S = Im(v_S i_S*)
(Bodson (5)) other than Q_COM, and the speed PI (25) settles on a torque command other than the
torque tau_e the machine produces. The current-command mode closes a loop on the rotor current
((43)-(47)) and is not expected to show either effect.

The functions below measure both effects from a run (logged ``q_s``, ``tau_com``, ``tau_e`` of
``DriveResult``) over its steady part, state them against named tolerances, and compare them with
the same scenario run with an ideal converter when that run is given.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from acdrive._frames import K_PEAK
from acdrive._spread import (
    SUBWINDOWS,
    mean_and_spread_over_stretches,
    round_to_spread,
    rounding_step,
)
from acdrive._verdicts import (
    Settling,
    Verdict,
    judge_settling,
    when_settled,
    window_drift,
    within_abs,
)
from acdrive.drives.dfim._setup import ConverterLosses, DriveSetup
from acdrive.sim._metrics import OSCILLATION_FINDING_RPM

#: A sample is steady once the speed reference has been constant for this long [s] with the
#: stator relay closed (the speed loop's transient after a step or a ramp end has settled).
STEADY_SETTLE_S = 0.5
#: Q_S counts as the commanded Q_COM within this fraction of the magnetising reactive power
#: v_S^2 / (w_e L_S): what the stator absorbs when it alone magnetises the machine (i_R = 0,
#: R_S neglected), the Q_COM that maximises the case-2 rotor-current torque limit (Bodson (42)).
Q_TOLERANCE_FRACTION = 0.1
#: The torque command counts as the produced torque within this [N m] (about 0.4 % of the
#: paper's tau_LIM = 0.274 N m; the two motors of Bodson Fig. 13 differ by a few mN m).
TORQUE_TOLERANCE_NM = 1e-3
#: A steady-state mean is judged only when the signal is settled: over every steady stretch of
#: the run its drift (``verdicts.window_drift``: least-squares slope times the stretch's length)
#: stays within this fraction of the tolerance of the verdict that uses the mean.
SETTLING_FRACTION = 0.5


def magnetising_reactive_power(L_s: float, v_s: float, w_e: float) -> float:
    """v_S^2 / (w_e L_S) [var]: the reactive power of a stator that magnetises the machine alone
    (v_S: space-vector magnitude, Bodson (8); the optimum Q_COM of (42))."""
    return v_s**2 / (w_e * L_s)


def converter_loss(setup: DriveSetup, motor: int = 0) -> float:
    """Fundamental voltage [V, space vector] the rotor converter of ``motor`` loses."""
    m = setup.motors[motor]
    return m.converter.fundamental_loss(m.dc_link_voltage)


def uses_bench_converter(setup: DriveSetup) -> bool:
    """Whether any motor's rotor converter has dead time or device drops."""
    return any(converter_loss(setup, k) > 0.0 for k in range(len(setup.motors)))


def ideal_converter(setup: DriveSetup) -> DriveSetup:
    """The same drive with an ideal rotor converter on every motor."""
    motors = tuple(dataclasses.replace(m, converter=ConverterLosses()) for m in setup.motors)
    return dataclasses.replace(setup, motors=motors)


def steady_mask(result, motor: int = 0, settle_s: float = STEADY_SETTLE_S) -> np.ndarray:
    """Samples at least ``settle_s`` after the start and after the last change of the speed
    reference, with the stator relay closed."""
    ref = result.signal("w_ref", motor)
    changing = np.r_[True, np.abs(np.diff(ref)) > 0.0]
    last_change = np.maximum.accumulate(np.where(changing, result.t, -np.inf))
    return (result.t - last_change >= settle_s) & (result.signal("relay_closed", motor) > 0)


@dataclass(frozen=True)
class SideEffect:
    """Steady-state means of one motor in one run (``mode``): Q_S and its command [var], the
    torque command and the electromagnetic torque [N m]; ``samples``: steady samples used (the
    means are NaN without any); ``q_tolerance`` [var]: Q_TOLERANCE_FRACTION of the magnetising
    reactive power at the nominal supply; ``oscillation_rpm``: the run's speed-error RMS in the
    limit-cycle band (``DriveResult.speed_oscillation``). ``q_spread``, ``offset_spread``: the
    spread of the Q_S and tau_COM - tau_e means over sub-windows (``spread.mean_and_spread_over_stretches``),
    taken when the run limit-cycles (0 otherwise: the means are printed in full);
    ``q_settling``, ``offset_settling``: whether Q_S and tau_COM - tau_e are settled over the
    steady stretches (``steady_settling``)."""

    mode: str
    motor: int
    samples: int
    q_s: float
    q_com: float
    tau_com: float
    tau_e: float
    q_tolerance: float
    oscillation_rpm: float
    q_spread: float = 0.0
    offset_spread: float = 0.0
    tau_com_spread: float = 0.0
    tau_e_spread: float = 0.0
    q_settling: Settling | None = None
    offset_settling: Settling | None = None

    def q_text(self) -> str:
        """Q_S [var] as printed: rounded to its spread when the run limit-cycles."""
        return round_to_spread(self.q_s, self.q_spread, ".2f", sign=True, show_step=True)

    def torques_text(self) -> str:
        """'torque command X mN m against tau_e = Y mN m', rounded to the spreads when the run
        limit-cycles."""
        com = round_to_spread(
            1e3 * self.tau_com, 1e3 * self.tau_com_spread, ".2f", sign=True, show_step=True
        )
        e = round_to_spread(
            1e3 * self.tau_e, 1e3 * self.tau_e_spread, ".2f", sign=True, show_step=True
        )
        return f"torque command {com} mN m against tau_e = {e} mN m"

    def offset_text(self) -> str:
        """tau_COM - tau_e [mN m] as printed: rounded to its spread when the run limit-cycles."""
        return round_to_spread(
            1e3 * self.torque_offset, 1e3 * self.offset_spread, ".2f", sign=True, show_step=True
        )

    @property
    def torque_offset(self) -> float:
        return self.tau_com - self.tau_e

    def reactive_power(self) -> Verdict:
        """Q_S against Q_COM within ``q_tolerance``, judged only if Q_S is settled."""
        verdict = within_abs(
            self.q_s,
            self.q_com,
            self.q_tolerance,
            " var",
            yes="holds Q_COM",
            no="departs from Q_COM",
        )
        if self.q_spread > 0.0:
            verdict = _rounded(
                verdict, self.q_s - self.q_com, self.q_spread, self.q_tolerance, "var"
            )
        return when_settled(verdict, self._settlings("Q_S"), " var")

    def torque(self) -> Verdict:
        """The torque command against the torque produced within TORQUE_TOLERANCE_NM, judged
        only if tau_COM - tau_e is settled."""
        verdict = torque_verdict(self.tau_com, self.tau_e)
        if self.offset_spread > 0.0:
            verdict = _rounded(
                verdict,
                1e3 * self.torque_offset,
                1e3 * self.offset_spread,
                1e3 * TORQUE_TOLERANCE_NM,
                "mN m",
            )
        return when_settled(verdict, self._settlings("tau_COM - tau_e"), " mN m")

    @property
    def q_settled(self) -> bool:
        """Q_S is settled over the steady part (no steady stretch: not settled)."""
        return self.q_settling is not None and self.q_settling.settled

    @property
    def offset_settled(self) -> bool:
        """tau_COM - tau_e is settled over the steady part (no steady stretch: not settled)."""
        return self.offset_settling is not None and self.offset_settling.settled

    def _settlings(self, which: str) -> dict[str, Settling]:
        state = {"Q_S": self.q_settling, "tau_COM - tau_e": self.offset_settling}[which]
        return {which: state} if state is not None else {}

    @property
    def limit_cycles(self) -> bool:
        """The run's speed oscillates above the summary's finding threshold: its means are taken
        over a limit cycle."""
        return self.oscillation_rpm > OSCILLATION_FINDING_RPM

    def q_against(self, ideal: SideEffect) -> Verdict:
        """Q_S of this (bench) run against the same run with an ideal converter, judged only if
        both are settled."""
        verdict = within_abs(
            self.q_s,
            ideal.q_s,
            self.q_tolerance,
            " var",
            yes="same as with an ideal converter",
            no="differs from the ideal converter's",
        )
        spread = max(self.q_spread, ideal.q_spread)
        if spread > 0.0:
            verdict = _rounded(verdict, self.q_s - ideal.q_s, spread, self.q_tolerance, "var")
        states = {**self._settlings("Q_S"), **_renamed(ideal._settlings("Q_S"), "ideal ")}
        return when_settled(verdict, states, " var")

    def torque_against(self, ideal: SideEffect) -> Verdict:
        """tau_COM - tau_e of this (bench) run against the same run with an ideal converter,
        judged only if both are settled."""
        verdict = within_abs(
            1e3 * self.torque_offset,
            1e3 * ideal.torque_offset,
            1e3 * TORQUE_TOLERANCE_NM,
            " mN m",
            yes="same as with an ideal converter",
            no="differs from the ideal converter's",
        )
        spread = max(self.offset_spread, ideal.offset_spread)
        if spread > 0.0:
            verdict = _rounded(
                verdict,
                1e3 * (self.torque_offset - ideal.torque_offset),
                1e3 * spread,
                1e3 * TORQUE_TOLERANCE_NM,
                "mN m",
            )
        states = {
            **self._settlings("tau_COM - tau_e"),
            **_renamed(ideal._settlings("tau_COM - tau_e"), "ideal "),
        }
        return when_settled(verdict, states, " mN m")


#: How the verdicts of this module begin when they could not compare the numbers.
UNJUDGED = ("not settled", "not decidable")


def judged(verdict: Verdict) -> bool:
    """Whether ``verdict`` compared its numbers (not "not settled" or "not decidable")."""
    return not verdict.text.startswith(UNJUDGED)


def _renamed(states: dict[str, Settling], prefix: str) -> dict[str, Settling]:
    return {prefix + name: s for name, s in states.items()}


def _rounded(verdict: Verdict, difference: float, spread: float, tol: float, unit: str) -> Verdict:
    """``verdict`` (a ``within_abs`` of a limit-cycle mean) restated with its difference rounded
    to the spread of the limit cycle (``spread.round_to_spread``); when the rounding step
    exceeds the tolerance, the comparison cannot be decided and does not hold."""
    head = verdict.text.split(" (difference", 1)[0]
    step = rounding_step(spread)
    if step > tol:
        return Verdict(
            False,
            f"not decidable: the limit cycle moves the mean by up to {step:g} {unit} (the "
            f"rounding step of its spread over sub-windows), more than the tolerance "
            f"{tol:.3g} {unit}",
            verdict.kind,
        )
    return Verdict(
        verdict.holds,
        f"{head} (difference {round_to_spread(difference, spread, sign=True, show_step=True)} "
        f"{unit}, rounded "
        f"to the limit cycle's spread; tolerance {tol:.3g} {unit})",
        verdict.kind,
    )


def torque_verdict(tau_com: float, tau_e: float) -> Verdict:
    """tau_COM against the produced tau_e within TORQUE_TOLERANCE_NM."""
    return within_abs(
        1e3 * tau_com,
        1e3 * tau_e,
        1e3 * TORQUE_TOLERANCE_NM,
        " mN m",
        yes="matches the torque produced",
        no="is offset from the torque produced",
    )


def q_tolerance(setup: DriveSetup, motor: int = 0) -> float:
    """Q_TOLERANCE_FRACTION of v_S^2/(w_e L_S) at the supply's first voltage and frequency."""
    v_s = K_PEAK * float(setup.supply.voltage_pk[1][0])
    w_e = 2.0 * np.pi * float(setup.supply.frequency_hz[1][0])
    return Q_TOLERANCE_FRACTION * magnetising_reactive_power(
        setup.motors[motor].machine.L_s, v_s, w_e
    )


def steady_stretches(mask: np.ndarray) -> list[slice]:
    """The contiguous runs of True in ``mask``, as slices."""
    edges = np.flatnonzero(np.diff(np.r_[0, mask.astype(np.int8), 0]))
    return [slice(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2])]


def steady_settling(t, x, mask, tolerance: float, spread: float = 0.0) -> Settling | None:
    """Whether ``x`` is settled over the steady part ``mask``: the drift of each contiguous
    stretch (``verdicts.window_drift``), the stretch with the largest |drift| judged against
    ``tolerance``. None without a stretch of two samples. With a ``spread`` (a limit-cycling
    run), the drift is rounded to it (``spread.round_to_spread``) before it is judged and
    printed: the digits below it differ between platforms."""
    worst = None
    for part in steady_stretches(mask):
        if part.stop - part.start < 2:
            continue
        mean, drift, span = window_drift(t[part], x[part])
        if worst is None or abs(drift) > abs(worst.drift):
            worst = judge_settling(drift, span, tolerance, mean)
    if worst is not None and spread > 0.0:
        drift = float(round_to_spread(worst.drift, spread))
        worst = judge_settling(drift, round(worst.window_s, 1), tolerance, worst.mean)
    return worst


def measure(outcome) -> list[SideEffect]:
    """The side effect of every motor in every run of a ``ScenarioOutcome``."""
    setup = outcome.setup
    out = []
    for mode, result in outcome.results.items():
        for k in range(result.n_motors):
            steady = steady_mask(result, k)
            n = int(np.count_nonzero(steady))
            q_s = result.signal("q_s", k)
            offset = result.signal("tau_com", k) - result.signal("tau_e", k)
            oscillation = result.speed_oscillation(k)[0]
            cycling = oscillation > OSCILLATION_FINDING_RPM and n > 1

            def mean(name, result=result, steady=steady, k=k, n=n):
                return float(np.mean(result.signal(name, k)[steady])) if n else float("nan")

            def spread_of(name, result=result, steady=steady, k=k, cycling=cycling):
                if not cycling:
                    return 0.0
                x = result.signal(name, k)
                return mean_and_spread_over_stretches(x, steady_stretches(steady))[1]

            tol_q = q_tolerance(setup, k)
            stretches = steady_stretches(steady)
            q_spread = mean_and_spread_over_stretches(q_s, stretches)[1] if cycling else 0.0
            offset_spread = mean_and_spread_over_stretches(offset, stretches)[1] if cycling else 0.0
            out.append(
                SideEffect(
                    mode=mode,
                    motor=k,
                    samples=n,
                    q_s=mean("q_s"),
                    q_com=setup.motors[k].controller.reactive_power,
                    tau_com=mean("tau_com"),
                    tau_e=mean("tau_e"),
                    q_tolerance=tol_q,
                    oscillation_rpm=oscillation,
                    q_spread=q_spread,
                    offset_spread=offset_spread,
                    tau_com_spread=spread_of("tau_com"),
                    tau_e_spread=spread_of("tau_e"),
                    q_settling=steady_settling(
                        result.t, q_s, steady, SETTLING_FRACTION * tol_q, q_spread
                    ),
                    offset_settling=steady_settling(
                        result.t,
                        1e3 * offset,
                        steady,
                        SETTLING_FRACTION * 1e3 * TORQUE_TOLERANCE_NM,
                        1e3 * offset_spread,
                    ),
                )
            )
    return out


def _who(e: SideEffect, n_motors: int) -> str:
    return f"{e.mode} command" + (f", motor {e.motor + 1}" if n_motors > 1 else "")


def describe(
    bench: list[SideEffect], ideal: list[SideEffect] | None, setup: DriveSetup
) -> list[str]:
    """Markdown lines: for each run and motor, Q_S and the torque command over the steady part
    with their verdicts, and where ``ideal`` is given the same figures with an ideal converter
    and whether the converter accounts for the difference."""
    n_motors = len(setup.motors)
    losses = sorted({round(converter_loss(setup, k), 3) for k in range(n_motors)})
    lines = [
        "- bench converter side effect (rotor converter loss "
        + ", ".join(f"{v:.2f} V" for v in losses)
        + f" of fundamental; means over the steady part: reference constant for {STEADY_SETTLE_S:g} s"
        " or more, relay closed; a mean is judged only if settled: its drift over every steady "
        f"stretch within {SETTLING_FRACTION:g} x the verdict's tolerance):"
    ]
    twins = {(e.mode, e.motor): e for e in ideal or []}
    for e in bench:
        who = _who(e, n_motors)
        if e.samples == 0:
            lines.append(f"  - {who}: no steady samples")
            continue
        line = (
            f"  - {who} ({e.samples} samples): stator reactive power Q_S = {e.q_text()} var against "
            f"Q_COM = {e.q_com:g} var, {e.reactive_power()}; {e.torques_text()}, {e.torque()}"
        )
        twin = twins.get((e.mode, e.motor))
        if twin is not None and twin.samples:
            line += (
                f". Ideal converter: Q_S = {twin.q_text()} var, {twin.torques_text()} "
                f"(speed oscillation {twin.oscillation_rpm:.1f} rpm RMS"
                + (
                    f" above the {OSCILLATION_FINDING_RPM:g} rpm threshold: means over a limit "
                    f"cycle, rounded to their spread over {SUBWINDOWS} sub-windows"
                    if twin.limit_cycles
                    else ""
                )
                + f"); Q_S {e.q_against(twin)}; tau_COM - tau_e {e.torque_against(twin)}"
            )
        lines.append(line)
    return lines


def summary(outcome) -> dict | None:
    """The bench side effect of ``outcome`` as JSON-ready numbers and verdict sentences (None
    when every converter is ideal)."""
    setup = outcome.setup
    if not uses_bench_converter(setup):
        return None
    return {
        "converter_loss_v": [converter_loss(setup, k) for k in range(len(setup.motors))],
        "steady_settle_s": STEADY_SETTLE_S,
        "torque_tolerance_nm": TORQUE_TOLERANCE_NM,
        "runs": [
            {
                "mode": e.mode,
                "motor": e.motor + 1,
                "steady_samples": e.samples,
                "q_s_mean_var": e.q_s,
                "q_com_var": e.q_com,
                "q_tolerance_var": e.q_tolerance,
                "tau_com_mean_nm": e.tau_com,
                "tau_e_mean_nm": e.tau_e,
                "reactive_power": e.reactive_power().text if e.samples else None,
                "torque_command": e.torque().text if e.samples else None,
            }
            for e in measure(outcome)
        ],
    }
