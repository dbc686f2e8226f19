"""Standstill test logs of motulator 0.18's 2.2 kW cage IM, written in acdrive's log format.

Runs in motulator's own virtualenv (motulator 0.18 needs Python >= 3.12; made by
``acdrive._bench.venvs.ensure_venv``), never with acdrive on the path:

    python motulator_standstill.py --test dc --out-dir DIR [--offsets 0 0.05 0.2] [...]
    python motulator_standstill.py --test injection --tone-amplitude 15 --out-dir DIR [...]

prints one JSON line (what was simulated, the files written, the peak current) and writes one
CSV log per current-sensor offset, ``DIR/<test>_offset<c>.csv``, with acdrive's standstill
columns ``time [s]``, ``v_a [V]``, ``i_a [A]``: one row per carrier period, the phase-a voltage
command latched for that period and the phase-a current sampled at its start.

**The machine** is the unsaturated cage IM of motulator's 2.2 kW examples, inverse-Gamma
parameters R_s = 3.7 ohm, R_R = 2.1 ohm, L_sgm = 21 mH, L_M = 224 mH, n_p = 2
(``motulator.drive.model.InductionMachine``), its rotor held at zero speed
(``ExternalRotorSpeed`` at w_M = 0: a locked rotor). Its rotor corner is
R_R / (2 pi L_M) = 1.49 Hz.

**The inverter** is motulator's own: ``VoltageSourceConverter(u_dc=540, t_d, u_th)`` with the
carrier comparison of ``Drive(..., pwm=True)``. motulator models the dead time itself: each leg
is blanked for ``t_d`` after each switching instant, and during the blanking the direction of
the leg's current (at the blanking's start) decides which diode conducts; ``u_th`` is the
threshold voltage of the conducting device, subtracted as ``u_th sign(i)`` from each phase. The
duty ratios are updated once per carrier period (``single_update=True``) at the sampling
instant and loaded at once (``delay=0``): the command computed at t_k is applied over
[t_k, t_k + T], T = 1 / f_pwm, which is what acdrive's log row k means. The carrier starts each
period at its bottom (all legs low), so the sample at t_k sits at the ripple's symmetric point.
The duty ratios come from motulator's space-vector PWM (``motulator.common.control.PWM``: the
min-max zero sequence) and are quantised by motulator's carrier counter (2^12 levels); the
logged ``v_a`` is the phase-a voltage of the quantised duty ratios, u_dc (d_a - mean(d_abc)),
which is what the PWM unit latched. Defaults: 540 V link, 5 kHz, t_d = 2 us, u_th = 1 V; with
i_b = i_c = -i_a / 2 this costs phase a 4/3 (t_d f_pwm u_dc + u_th) = 8.53 V.

**The current sensor** is motulator's ``Sensor`` with an offset on phase a only
(``offset=[c, 0, 0]``, no gain error, no noise): the run is open loop and motulator's inverter
takes the current's direction from the machine, not from the sensor, so one run gives the
reading of every offset in ``--offsets``. The caller adds the converter's noise and rounding to
these readings (``benchmarks/coverage_motulator.py``), one run serving many noise draws.

**The tests** (acdrive's ``identify._experiment``): ``dc`` holds zero command for ``--rest-s``
(the zero-current stretch acdrive reads the sensor's offset from) and then each of ``--levels``
[V] for ``--step-s``; ``injection`` is the multisine sum_k A cos(2 pi m_k f_0 t + phi_k) of the
tones m_k = ``--tones`` times f_0 = ``--base-frequency-hz``, A = ``--tone-amplitude`` [V], with
Schroeder phases phi_k = -pi k (k - 1) / K (k = 1 .. K), for ``--seconds``.

The solver is motulator's default (RK45) with tighter tolerances (rtol 1e-8, atol 1e-10) than
its default, so that the logs carry the inverter's error and not the integrator's.
"""

from __future__ import annotations

import argparse
import json
import math
import platform
from importlib.metadata import version
from pathlib import Path
from types import SimpleNamespace

import numpy as np
from motulator.common.control import PWM, ControlSystem
from motulator.common.model import Sensor, SolverCfg
from motulator.common.utils import complex2abc
from motulator.drive import model

PAR = {"n_p": 2, "R_s": 3.7, "R_R": 2.1, "L_sgm": 0.021, "L_M": 0.224}  # inverse-Gamma [ohm, H]
COUNTER_LEVELS = 2**12  # motulator's carrier-comparison default


class OpenLoopCommand(ControlSystem):
    """Applies ``command(k)`` [V], the phase-a voltage of carrier period k, as an a-axis space
    vector (real: phases b and c get -1/2 of it) through motulator's space-vector PWM, and keeps
    at each sampling instant the latched phase-a voltage and every sensor's phase-a reading."""

    def __init__(self, command, T: float, u_dc: float, sensors: list) -> None:
        super().__init__()
        self.command, self.T, self.u_dc, self.sensors = command, T, u_dc, sensors
        self.pwm = PWM(single_update=True)
        self.k = 0
        self.v_a: list[float] = []
        self.readings: list[list[float]] = [[] for _ in sensors]
        self.true_i_a: list[float] = []

    def run_control_loop(self, mdl) -> tuple[float, list[float]]:
        i_abc = complex2abc(mdl.machine.out.i_s_ab)
        self.true_i_a.append(float(i_abc[0]))
        for reading, sensor in zip(self.readings, self.sensors, strict=True):
            reading.append(float(np.asarray(sensor(i_abc))[0]))
        d = np.asarray(self.pwm.duty_ratios(complex(self.command(self.k)), self.u_dc))
        latched = np.round(COUNTER_LEVELS * d) / COUNTER_LEVELS  # what the counter compares
        self.v_a.append(float(self.u_dc * (latched[0] - latched.mean())))
        self.k += 1
        self.t = self.k * self.T
        return self.T, list(d)


def schroeder_multisine(tones, amplitude: float, base: float):
    """The phase-a voltage [V] at time t of the multisine (module docstring)."""
    count = len(tones)
    phases = [-math.pi * k * (k - 1) / count for k in range(1, count + 1)]

    def voltage(t: float) -> float:
        return sum(amplitude * math.cos(2.0 * math.pi * m * base * t + phi)
                   for m, phi in zip(tones, phases, strict=True))  # fmt: skip

    return voltage


def run(args) -> dict:
    T = 1.0 / args.f_pwm
    if args.test == "dc":
        rows_rest = round(args.rest_s / T)
        rows_step = round(args.step_s / T)
        levels = [0.0] * rows_rest + [v for v in args.levels for _ in range(rows_step)]

        def command(k: int) -> float:
            return levels[min(k, len(levels) - 1)]

        rows = len(levels)
    else:
        voltage = schroeder_multisine(args.tones, args.tone_amplitude, args.base_frequency_hz)

        def command(k: int) -> float:
            return voltage(k * T)

        rows = round(args.seconds / T)
    sensors = [Sensor(offset=[c, 0.0, 0.0]) for c in args.offsets]
    converter = model.VoltageSourceConverter(u_dc=args.u_dc, t_d=args.dead_time_s,
                                             u_th=args.threshold_v)  # fmt: skip
    mechanics = model.ExternalRotorSpeed()
    mechanics.set_external_rotor_speed(0.0)
    drive = model.Drive(model.InductionMachine(model.InductionMachineInvGammaPars(**PAR)),
                        mechanics, converter, pwm=True, delay=0, single_update=True)  # fmt: skip
    ctrl = OpenLoopCommand(command, T, args.u_dc, sensors)
    sim = model.Simulation(drive, ctrl, show_progress=False,
                           cfg=SolverCfg(rtol=1e-8, atol=1e-10))  # fmt: skip
    # the loop samples every instant up to t_stop: rows 0 .. rows - 1
    result = sim.simulate(t_stop=(rows - 0.5) * T)
    if not result.success:
        raise RuntimeError("motulator's solver reported failure")
    n = min(rows, len(ctrl.v_a))
    time = np.arange(n) * T
    out_dir = Path(args.out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    for c, reading in zip(args.offsets, ctrl.readings, strict=True):
        path = out_dir / f"{args.test}_offset{c:g}.csv"
        with open(path, "w", encoding="utf-8") as handle:
            handle.write("time [s],v_a [V],i_a [A]\n")
            rows_out = zip(time, ctrl.v_a[:n], reading[:n], strict=True)
            handle.writelines(f"{float(t)!r},{v!r},{i!r}\n" for t, v, i in rows_out)
        written.append({"offset_a": c, "path": str(path)})
    u_err = 4.0 / 3.0 * (args.dead_time_s * args.f_pwm * args.u_dc + args.threshold_v)
    return {
        "peer": "motulator",
        "version": version("motulator"),
        "python": platform.python_version(),
        "test": args.test,
        "rows": n,
        "machine_inverse_gamma": PAR,
        "u_dc_v": args.u_dc,
        "f_pwm_hz": args.f_pwm,
        "dead_time_s": args.dead_time_s,
        "threshold_v": args.threshold_v,
        "phase_a_voltage_error_v": u_err,
        "peak_current_a": float(np.max(np.abs(ctrl.true_i_a[:n]))),
        "logs": written,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--test", choices=("dc", "injection"), required=True)
    parser.add_argument("--out-dir", required=True)
    parser.add_argument("--offsets", type=float, nargs="+", default=[0.0],
                        help="phase-a current-sensor offsets [A], one log each")  # fmt: skip
    parser.add_argument("--u-dc", type=float, default=540.0, help="DC link [V]")
    parser.add_argument("--f-pwm", type=float, default=5000.0, help="carrier frequency [Hz]")
    parser.add_argument("--dead-time-s", type=float, default=2e-6)
    parser.add_argument("--threshold-v", type=float, default=1.0, help="device drop [V]")
    parser.add_argument("--rest-s", type=float, default=0.2, help="dc: zero command first [s]")
    parser.add_argument("--levels", type=float, nargs="+", default=[12.0, 24.0, 36.0])
    parser.add_argument("--step-s", type=float, default=2.0, help="dc: each level's hold [s]")
    parser.add_argument("--tones", type=int, nargs="+",
                        default=[1, 2, 3, 5, 8, 13, 20, 40, 80, 160])  # fmt: skip
    parser.add_argument("--tone-amplitude", type=float, default=15.0, help="each tone [V]")
    parser.add_argument("--base-frequency-hz", type=float, default=1.0)
    parser.add_argument("--seconds", type=float, default=4.0, help="injection: duration [s]")
    print(json.dumps(run(parser.parse_args())))


if __name__ == "__main__":
    main()
