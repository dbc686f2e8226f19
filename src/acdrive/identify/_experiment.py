"""Standstill tests of a cage IM as a system of acdrive's own parts, and their logs.

The bench: a DC source (``plant.DCSource``) feeding the two-level SVPWM inverter
(``plant.Inverter``, with its dead time ``t_d`` and device drop ``v_drop``), which drives the
cage IM (``machines.CageInductionMachine``) whose shaft is held at zero speed
(``plant.PrescribedSpeed``: a locked rotor). The command is an open-loop table
(``control.ComplexProgram``) on the a-axis only (real space vectors, so phases b and c carry
-1/2 of phase a each, and a locked rotor sees no torque that matters). The controller samples
once per carrier period (T_s = 1 / f_pwm); the log holds one row per carrier period:

- ``time`` [s], the carrier-period start t_k;
- ``v_a`` [V], the phase-a voltage the PWM unit latched at t_k (the inverter's ``v_lim``, what
  a drive's controller knows it commanded; the inverter's own error is *not* in it);
- ``i_a`` [A], the phase-a current at t_k as the current sensor reports it.

A phase value is the a-axis space-vector component over sqrt(3/2) (power-invariant scaling,
Bodson (8); ``_frames.K_PEAK``); v_a / i_a equals the space-vector ratio, so the impedance of
``identify._circuit`` applies to the phase values as they are.

**The current sensor.** acdrive's ``plant.CurrentSensors`` part passes the current through
(it models a lost measurement, no noise or converter). The test therefore adds, after the run,
a seeded Gaussian noise of ``noise_std`` [A], an offset ``offset`` [A] and rounds to the ADC's
step ``lsb`` [A] (``measured_current``); the run itself is deterministic.

Two tests, each one run of the same compiled system:

1. **DC steps**: ``dc_levels`` [V] on phase a, each held ``dc_step`` [s];
2. **Injection**: a multisine of ``tones`` (integer multiples of ``base_frequency`` [Hz]) with
   ``tone_amplitude`` [V] each and Schroeder phases (a low crest factor), for ``settle`` [s]
   plus ``periods`` whole periods of the base frequency.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from acdrive._arguments import (
    COUNT,
    NONNEGATIVE,
    POSITIVE,
    REAL,
    SEED,
    Array,
    Instance,
    Items,
    Text,
    checked,
)
from acdrive._frames import K_PEAK
from acdrive.core._profile import Profile
from acdrive.errors import InputError, require_finite, require_nonnegative, require_positive
from acdrive.machines._pmsm import PMSGParams
from acdrive.machines._registry import MACHINE_RECORD

#: the log's columns: name -> (unit, meaning); the one declaration readers and writers use
LOG_COLUMNS = {
    "time": ("s", "start of the carrier period (the sample instant)"),
    "v_a": ("V", "phase-a voltage command latched by the PWM unit for this period"),
    "i_a": ("A", "phase-a current measured at the sample instant"),
}


#: the machines a standstill bench takes
MACHINE = MACHINE_RECORD


@checked(time=Array(1), v_a=Array(1), i_a=Array(1), source=Text())
@dataclass(frozen=True)
class StandstillLog:
    """One logged test: equal-length arrays ``time`` [s], ``v_a`` [V], ``i_a`` [A]; ``source``
    names where it came from (a file or a simulated test) for messages."""

    time: np.ndarray
    v_a: np.ndarray
    i_a: np.ndarray
    source: str = "log"


@checked(noise_std=NONNEGATIVE, offset=REAL, lsb=NONNEGATIVE)
@dataclass(frozen=True)
class CurrentSensor:
    """The current measurement added after the run (module docstring): Gaussian noise of standard
    deviation ``noise_std`` [A], an ``offset`` [A], an ADC step ``lsb`` [A] (0: no rounding)."""

    noise_std: float = 5e-3
    offset: float = 0.0
    lsb: float = 20.0 / 4096  # a 12-bit converter over +-10 A


@checked(
    dc_levels=Items(REAL), dc_step=POSITIVE, base_frequency=POSITIVE, tones=Items(COUNT),
    tone_amplitude=NONNEGATIVE, settle=NONNEGATIVE, periods=COUNT, f_pwm=POSITIVE, v_dc=POSITIVE,
    t_d=NONNEGATIVE, v_drop=NONNEGATIVE, sensor=Instance(CurrentSensor),
)
@dataclass(frozen=True)
class StandstillPlan:
    """The two standstill tests and the bench they run on (module docstring)."""

    dc_levels: tuple[float, ...] = (12.0, 24.0, 36.0)
    dc_step: float = 2.0
    base_frequency: float = 1.0
    tones: tuple[int, ...] = (1, 2, 3, 5, 8, 13, 20, 40, 80, 160)
    tone_amplitude: float = 15.0
    settle: float = 2.0
    periods: int = 2
    f_pwm: float = 5000.0
    v_dc: float = 310.0
    t_d: float = 0.0
    v_drop: float = 0.0
    sensor: CurrentSensor = field(default_factory=CurrentSensor)

    def __post_init__(self):
        for name in ("dc_step", "base_frequency", "f_pwm", "v_dc"):
            require_positive(name, getattr(self, name))
        for name in ("settle", "t_d", "v_drop", "tone_amplitude"):
            require_nonnegative(name, getattr(self, name))
        for level in self.dc_levels:
            require_finite("dc_levels", level)
        if not self.tones or any(
            isinstance(k, bool) or not isinstance(k, int) or k < 1 for k in self.tones
        ):
            raise InputError("tones", "must be integer multiples >= 1 of the base frequency")
        if isinstance(self.periods, bool) or not isinstance(self.periods, int) or self.periods < 1:
            raise InputError("periods", f"must be an integer >= 1, got {self.periods!r}")

    @property
    def sample_time(self) -> float:
        return 1.0 / self.f_pwm

    def injection_duration(self) -> float:
        return self.settle + self.periods / self.base_frequency

    def dc_duration(self) -> float:
        return self.dc_step * len(self.dc_levels)


def multisine(plan: StandstillPlan, t: np.ndarray) -> np.ndarray:
    """Phase-a voltage of the injection: sum_k A cos(2 pi k f_0 t + phi_k) with Schroeder phases
    phi_k = -pi k (k - 1) / K over the K tones (k their index from 1)."""
    count = len(plan.tones)
    v = np.zeros_like(t)
    for k, multiple in enumerate(plan.tones, start=1):
        phase = -math.pi * k * (k - 1) / count
        v += plan.tone_amplitude * np.cos(
            2.0 * math.pi * multiple * plan.base_frequency * t + phase
        )
    return v


def dc_steps(plan: StandstillPlan, t: np.ndarray) -> np.ndarray:
    """Phase-a voltage of the DC test: level j over [j dc_step, (j + 1) dc_step)."""
    index = np.minimum((t / plan.dc_step).astype(int), len(plan.dc_levels) - 1)
    return np.asarray(plan.dc_levels, dtype=float)[index]


def measured_current(i_a: np.ndarray, sensor: CurrentSensor, rng) -> np.ndarray:
    """What the sensor reports of the true current ``i_a`` (module docstring)."""
    reading = i_a + sensor.offset + sensor.noise_std * rng.standard_normal(i_a.shape)
    if sensor.lsb > 0.0:
        reading = np.round(reading / sensor.lsb) * sensor.lsb
    return reading


def machine_part(machine):
    """The plant part of ``machine``: a cage IM (``IMParams``), a PM machine (``PMSGParams``,
    ``identify._pm``) or a DFIM (``DFIMParams``, ``identify._dfim``), named ``machine``."""
    from acdrive.machines._cage_part import CageInductionMachine
    from acdrive.machines._dfim import DFIMParams
    from acdrive.machines._dfim_part import DoublyFedMachine
    from acdrive.machines._induction import IMParams
    from acdrive.machines._pmsm_part import PermanentMagnetMachine

    if isinstance(machine, IMParams):
        return CageInductionMachine.from_params("machine", machine)
    if isinstance(machine, PMSGParams):
        return PermanentMagnetMachine.from_params("machine", machine)
    if isinstance(machine, DFIMParams):
        return DoublyFedMachine.from_params("machine", machine)
    raise InputError("machine", f"a standstill bench takes a cage IM, a PM machine or a DFIM, "
                     f"got {type(machine).__name__}")  # fmt: skip


#: the DFIM bench's stator connection -> when its relay closes [s] (open: after any test)
STATOR_RELAY = {"open": 1e12, "shorted": 0.0}


@functools.cache
def _bench(kind: type):
    """The standstill bench (module docstring) for a machine record of type ``kind``, compiled
    once per process: (compiled system, parts by role). Runs swap in re-parametrised parts of the
    same shape."""
    from acdrive.control._open_loop import ComplexProgram
    from acdrive.machines._dfim import BODSON_DFIM, DFIMParams
    from acdrive.machines._induction import DELORENZO_IM, IMParams
    from acdrive.machines._pmsm import PMSG_2MW
    from acdrive.plant._inverter import Inverter
    from acdrive.plant._mechanics import PrescribedSpeed
    from acdrive.plant._network import RelayCommand
    from acdrive.plant._sources import DCSource
    from acdrive.sim._system import System

    template = {IMParams: DELORENZO_IM, PMSGParams: PMSG_2MW, DFIMParams: BODSON_DFIM}[kind]
    parts = {
        "program": ComplexProgram("program"),
        "dc": DCSource("dc", V=310.0),
        "inverter": Inverter("inverter"),
        "machine": machine_part(template),
        "shaft": PrescribedSpeed("shaft", w=0.0),
    }
    p = parts
    wires = [
        (p["program"].out.v_ref, p["inverter"].inp.v_ref),
        (p["dc"].out.v_dc, p["inverter"].inp.v_dc),
        (p["shaft"].out.w, p["machine"].inp.w),
    ]
    if kind is DFIMParams:  # the converter feeds the rotor; the stator is open or shorted
        p["stator"] = ComplexProgram("stator")
        p["relay"] = RelayCommand("relay", close_at=0.0)
        wires += [
            (p["machine"].out.i_r_rotor, p["inverter"].inp.i_s),
            (p["inverter"].out.v, p["machine"].inp.v_r),
            (p["stator"].out.v_ref, p["machine"].inp.v_s),
            (p["relay"].out.closed, p["machine"].inp.connected),
        ]
    else:
        wires += [
            (p["machine"].out.i_s, p["inverter"].inp.i_s),
            (p["inverter"].out.v, p["machine"].inp.v_s),
        ]
    return System(list(parts.values()), wires).compile(), parts


def run_test(machine, plan: StandstillPlan, voltage, duration: float, seed: int,
             source: str, initial=None, torque: list | None = None,
             speed: float = 0.0, stator: str = "open") -> StandstillLog:  # fmt: skip
    """Run the bench with phase-a command ``voltage(t)`` for ``duration`` seconds on ``machine``
    (a cage IM's ``IMParams`` or a PM machine's ``PMSGParams``, its part's states from
    ``initial``, e.g. a locked rotor's angle) and return the log with the sensor's reading
    (seeded). A list ``torque`` receives the torque the shaft holds [N m], per sample. A complex
    ``voltage(t)`` is a space vector over sqrt(3/2) (its real part phase a's voltage: a balanced
    set for e^{jwt}); ``speed`` [rad/s] is the speed the shaft is driven at (a dynamometer;
    0: locked). On a DFIM the inverter feeds the rotor, the log's v_a, i_a are the rotor's
    phase-a voltage and current (referred to the stator, Bodson (3)) and its stator is
    ``stator``: "open" (relay open) or "shorted" (relay closed onto zero voltage)."""
    require_positive("duration", duration)
    compiled, parts = _bench(type(machine))
    T = plan.sample_time
    n = round(duration / T)
    t = np.arange(n + 1) * T
    command = K_PEAK * np.asarray(voltage(t))
    imaginary = Profile(t, command.imag) if np.iscomplexobj(command) else 0.0
    variants = [
        parts["program"].with_params(re=Profile(t, command.real), im=imaginary),
        parts["shaft"].with_params(w=float(speed)),
        parts["dc"].with_params(V=plan.v_dc),
        parts["inverter"].with_params(f_pwm=plan.f_pwm, t_d=plan.t_d, v_drop=plan.v_drop),
        machine_part(machine),
    ]
    inverter, motor = parts["inverter"], parts["machine"]
    current = motor.out.i_s
    if "relay" in parts:
        if stator not in STATOR_RELAY:
            raise InputError("stator", f"must be one of {', '.join(STATOR_RELAY)}")
        variants.append(parts["relay"].with_params(close_at=STATOR_RELAY[stator]))
        current = motor.out.i_r_rotor
    result = compiled.run(n * T, T, substeps=2, parts=variants, initial=initial,
                          log=[inverter.out.v_lim, current, motor.out.tau_e])  # fmt: skip
    if torque is not None:
        torque.append(result.signal(motor.out.tau_e).copy())
    v_a = result.signal(inverter.out.v_lim).real / K_PEAK
    i_a = result.signal(current).real / K_PEAK
    rng = np.random.default_rng(seed)
    return StandstillLog(result.t.copy(), v_a, measured_current(i_a, plan.sensor, rng), source)


@checked(machine=MACHINE, plan=Instance(StandstillPlan), seed=SEED)
def dc_test(machine, plan: StandstillPlan, seed: int = 0) -> StandstillLog:
    """The DC-step test of ``plan`` on ``machine`` (module docstring)."""
    return run_test(machine, plan, lambda t: dc_steps(plan, t), plan.dc_duration(), seed,
                    "simulated DC-step test")  # fmt: skip


@checked(machine=MACHINE, plan=Instance(StandstillPlan), seed=SEED)
def injection_test(machine, plan: StandstillPlan, seed: int = 1) -> StandstillLog:
    """The multisine injection test of ``plan`` on ``machine`` (module docstring)."""
    return run_test(machine, plan, lambda t: multisine(plan, t), plan.injection_duration(), seed,
                    "simulated injection test")  # fmt: skip
