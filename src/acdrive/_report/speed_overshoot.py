"""Overshoot of the speed loop after a small reference step (Bodson (25)-(27), K_F after (27)).

Bodson states after (27) that K_F = 2/3 "yields a fast response without overshoot". Two numbers
test that claim: the closed form of the continuous loop (``SpeedPIGains.step_overshoot``: ideal
torque, (26)), and the overshoot of the simulated drive after a reference step small enough that
the torque command stays inside tau_LIM (the integrator is never clamped). The run is the
built-in scenario ``bodson-step`` in current-command mode with an ideal rotor converter (the
drive whose torque follows its command most closely: a 500 Hz current loop), started at a
constant speed and stepped once.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from acdrive._verdicts import Verdict
from acdrive.core._profile import Profile
from acdrive.drives.dfim._converter_effect import ideal_converter
from acdrive.drives.dfim._outcome import run_scenario
from acdrive.scenarios._loader import load_scenario
from acdrive.sim._step_response import events, step_response

#: "Without overshoot" holds when the speed exceeds its new reference by at most this fraction of
#: the step (0.1 %: well above the speed ripple of the simulated run, far below a visible bump).
NO_OVERSHOOT_TOL = 1e-3
#: The simulated step: the scenario, its controller mode, the speed it holds [rpm], the step
#: [rad/s] (K_F K_P x step = 0.15 N m, inside tau_LIM = 0.274 N m), when the step comes and
#: how long the run lasts [s] (the loop's poles are at -314 rad/s: the peak comes ~13 ms after).
STEP_SCENARIO, STEP_MODE = "bodson-step", "current"
STEP_FROM_RPM, STEP_RAD_S = 900.0, 1.0
STEP_TIME_S, STEP_DURATION_S = 0.3, 0.4


def no_overshoot_verdict(overshoot: float) -> Verdict:
    """Bodson after (27): 'without overshoot', within NO_OVERSHOOT_TOL of the step."""
    ok = overshoot <= NO_OVERSHOOT_TOL
    return Verdict(
        ok,
        f"{'no overshoot' if ok else 'overshoots'} ({100 * overshoot:.2f} % of the step; "
        f"tolerance {100 * NO_OVERSHOOT_TOL:g} %)",
    )


def step_setup():
    """The scenario of the simulated step: STEP_SCENARIO in STEP_MODE with an ideal converter,
    started at STEP_FROM_RPM and stepped by STEP_RAD_S at STEP_TIME_S."""
    setup = ideal_converter(load_scenario(STEP_SCENARIO)).with_mode(STEP_MODE)
    w0 = STEP_FROM_RPM * np.pi / 30.0
    reference = Profile(
        [0.0, STEP_TIME_S, STEP_TIME_S, STEP_DURATION_S],
        [w0, w0, w0 + STEP_RAD_S, w0 + STEP_RAD_S],
    )
    motors = tuple(
        dataclasses.replace(m, speed_reference=reference, initial_speed=w0) for m in setup.motors
    )
    return dataclasses.replace(setup, motors=motors, duration=STEP_DURATION_S)


def measured_overshoot(t, w, t_step: float, w_before: float, w_after: float) -> float:
    """Overshoot of ``w(t)`` after a step from ``w_before`` to ``w_after`` at ``t_step``, as a
    fraction of the step (0 if it never exceeds the new reference): the step-response metric
    of every drive's summary (``sim._step_response``), over the samples from the step on."""
    t = np.asarray(t, dtype=float)
    end = float(t[-1]) + 1.0  # the step is the only event: judged to the last sample
    reference = Profile([0.0, t_step, t_step], [w_before, w_before, w_after])
    w_ref = np.where(t >= t_step, w_after, w_before)
    (event,) = step_response(t, w, w_ref, events(reference, {}, end))["events"]
    return event["overshoot_pct"] / 100.0


def simulated_overshoot() -> tuple[float, object]:
    """(overshoot fraction, setup) of the simulated small step (``step_setup``)."""
    setup = step_setup()
    result = run_scenario(setup).main
    w0 = setup.motors[0].speed_reference[1][0]
    return measured_overshoot(result.t, result.signal("w"), STEP_TIME_S, w0, w0 + STEP_RAD_S), setup


def overshoot_rows(machine, design_gains, k_f_used: dict[str, float], row) -> list[str]:
    """Report rows (``row(item, paper, ours, note)``): the closed-form overshoot with the gains
    of (27) at K_F = ``design_gains.K_F`` and at each K_F the scenarios use (``k_f_used``:
    scenario name -> K_F), and the overshoot of the simulated small step."""
    paper = "none ('without overshoot', after (27))"
    rows = [
        row(
            f"speed-step overshoot, K_F = {design_gains.K_F:.4g}, gains (27), continuous loop "
            "(`SpeedPIGains.step_overshoot`)",
            paper,
            f"{100 * design_gains.step_overshoot(machine.J):.2f} %",
            str(no_overshoot_verdict(design_gains.step_overshoot(machine.J))),
        )
    ]
    for k_f in sorted(set(k_f_used.values())):
        gains = dataclasses.replace(design_gains, K_F=k_f)
        rows.append(
            row(
                f"speed-step overshoot, K_F = {k_f:g} (scenarios), continuous loop",
                paper,
                f"{100 * gains.step_overshoot(machine.J):.2f} %",
                str(no_overshoot_verdict(gains.step_overshoot(machine.J))),
            )
        )
    measured, setup = simulated_overshoot()
    used = setup.motors[0].controller.gains
    continuous = used.step_overshoot(setup.motors[0].machine.J)
    rows.append(
        row(
            f"speed-step overshoot, simulated: `{STEP_SCENARIO}` in {STEP_MODE} command, ideal "
            f"converter, {STEP_RAD_S:g} rad/s step at {STEP_FROM_RPM:g} rpm (K_F = {used.K_F:g})",
            paper,
            f"{100 * measured:.1f} %",
            f"{no_overshoot_verdict(measured)}; the continuous loop with the same gains gives "
            f"{100 * continuous:.2f} %"
            + (
                f"; the simulated drive (speed PI sampled every {1e6 * setup.sample_time:g} us, "
                "torque through the current loop) overshoots more: which of the two adds the "
                "overshoot is not separated here (cause open)"
                if measured - continuous > NO_OVERSHOOT_TOL
                else f"; they agree within {100 * NO_OVERSHOOT_TOL:g} % of the step"
            ),
        )
    )
    return rows
