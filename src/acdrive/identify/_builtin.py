"""The simulated benches of the built-in machines for the tests other than the cage IM's, by name:
what ``acdrive identify NAME --kind pm | dfim | mechanics`` runs (docs/guide/identification.md).

Each bench is the plan the estimator's own tests validate on that machine, so a name simulates
the same parts and sensors as the Python API (``identify._pm``, ``_spin``, ``_dfim``,
``_mechanics``): the SVPWM inverter on its DC source, the machine part, the seeded noisy and
quantised current reading (``identify._experiment.CurrentSensor``) and, for the mechanics, the
PM speed drive with its 4096-count encoder.

- **pm**: the PM machines of the PM drive's catalog (``drives.pm._schema.MACHINES``) that have a
  validated bench. ``bly171d`` (the 24 V BLY171D servo motor): tones 2 to 320 Hz around its
  119 Hz corner R_s / (2 pi L), 0.15 V each, about its rated 1.8 A peak at the lowest tones; spin
  test at 20, 40, 60 rad/s. ``ipmsm-2.2kw`` (motulator's 2.2 kW interior PMSM from 540 V): tones
  1 to 160 Hz around its 16 Hz (d) and 11 Hz (q) corners, 2 V each; spin test at 5, 10, 15 rad/s,
  3 s each (five electrical periods at the lowest speed), whose short-circuit current stays
  below the nominal 6.1 A peak. The catalog's ``pmsg-2mw`` has none: its kiloampere currents
  need another current sensor and a megawatt dynamometer, a bench no test of acdrive validates.
- **dfim**: ``bodson-dfim``, from its rotor converter on Bodson's 30 V link, tones of 0.3 V
  (about 3 A at the lowest tones), DC steps of 1, 2, 3 V.
- **mechanics**: ``bly171d``, the BLY171D speed drive of the scenario ``pm-bly171d-speed``
  (its table's viscous friction, rated current limit, 400 Hz current and 200 rad/s speed
  bandwidths) on the switching converter at 20 kHz, with a Coulomb friction of 2 mN m on the
  shaft (3.5 % of the rated torque; the table gives none, so it is assumed, and the scenario
  has no field for it).

``measured_window(kind)`` is what a measured log of that kind is assumed to share with these
benches unless the command says otherwise: its injection's base frequency and settling time, and
the spin test's settling time, computed from the benches' plans.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from acdrive._arguments import TEXT, Text, checked
from acdrive.errors import InputError
from acdrive.identify._experiment import StandstillPlan
from acdrive.identify._mechanics import MechanicsPlan
from acdrive.identify._spin import SpinPlan


@dataclass(frozen=True)
class PMBench:
    """A PM machine's standstill plan (DC steps, d- and q-axis injection) and spin test."""

    machine: object
    standstill: StandstillPlan
    spin: SpinPlan


@dataclass(frozen=True)
class DFIMBench:
    """A DFIM's rotor-converter plan (DC steps and injection, stator open and shorted)."""

    machine: object
    standstill: StandstillPlan


@dataclass(frozen=True)
class MechanicsBench:
    """A PM speed-drive scenario table and the staircase run on it; ``viscous_friction`` the
    scenario's [N m s/rad]."""

    machine: object
    viscous_friction: float
    plan: MechanicsPlan
    converter: dict = field(default_factory=dict)
    control: dict = field(default_factory=dict)
    sample_time: float = 5e-5

    def scenario(self, name: str) -> dict:
        """The scenario table ``speed_step_test`` runs (a fresh copy)."""
        return {
            "drive": "pm",
            "name": f"{name}-speed-steps",
            "machine": {"machine": name, "viscous_friction": self.viscous_friction},
            "converter": dict(self.converter),
            "control": dict(self.control),
            "simulation": {"sample_time": self.sample_time},
        }


def _benches() -> dict[str, dict[str, object]]:
    from acdrive.machines._dfim import BODSON_DFIM
    from acdrive.machines._pm_catalog import (
        BLY171D,
        BLY171D_B,
        BLY171D_I_RATED_PEAK,
        BLY171D_V_DC,
        IPMSM_2KW2,
        IPMSM_2KW2_V_DC,
    )

    bly = StandstillPlan(dc_levels=(0.3, 0.6, 0.9), dc_step=0.5, base_frequency=2.0,
                         tone_amplitude=0.15, settle=0.5, v_dc=BLY171D_V_DC)  # fmt: skip
    ipm = StandstillPlan(dc_levels=(6.0, 12.0, 18.0), dc_step=0.5, base_frequency=1.0,
                         tone_amplitude=2.0, settle=0.5, v_dc=IPMSM_2KW2_V_DC)  # fmt: skip
    return {
        "pm": {
            "bly171d": PMBench(
                BLY171D, bly, SpinPlan(speeds=(20.0, 40.0, 60.0), v_dc=BLY171D_V_DC)
            ),
            "ipmsm-2.2kw": PMBench(
                IPMSM_2KW2, ipm, SpinPlan(speeds=(5.0, 10.0, 15.0), hold=3.0, v_dc=IPMSM_2KW2_V_DC)
            ),
        },
        "dfim": {
            "bodson-dfim": DFIMBench(
                BODSON_DFIM,
                StandstillPlan(dc_levels=(1.0, 2.0, 3.0), tone_amplitude=0.3, v_dc=30.0),
            ),
        },
        "mechanics": {
            "bly171d": MechanicsBench(
                BLY171D,
                BLY171D_B,
                MechanicsPlan(tau_c=2e-3),
                converter={
                    "model": "switching",
                    "pwm_frequency_hz": 20000.0,
                    "dc_link_voltage": BLY171D_V_DC,
                },
                control={
                    "current_limit_pk_a": BLY171D_I_RATED_PEAK,
                    "current_bandwidth_rad_s": 2 * math.pi * 400,
                    "speed_bandwidth_rad_s": 200.0,
                },
            ),
        },
    }


#: what each kind calls its built-in names in messages
KIND_NOUN = {"pm": "PM machine", "dfim": "DFIM", "mechanics": "speed drive (mechanics)"}


@checked(kind=TEXT)
def builtin_names(kind: str) -> tuple[str, ...]:
    """The names ``acdrive identify NAME --kind KIND`` simulates."""
    return tuple(_benches().get(kind, {}))


@checked(kind=Text(KIND_NOUN), name=TEXT, field=TEXT)
def builtin_bench(kind: str, name: str, field: str = "name"):
    """The bench of the built-in ``name`` of ``kind``, or an InputError naming ``field`` and
    listing the names of that kind."""
    benches = _benches().get(kind)
    if benches is None:
        raise InputError("kind", f"must be one of {', '.join(KIND_NOUN)}, got {kind!r}")
    if name not in benches:
        raise InputError(field, f"unknown built-in {KIND_NOUN[kind]} '{name}' (known for --kind "
                         f"{kind}: {', '.join(benches)})")  # fmt: skip
    return benches[name]


@dataclass(frozen=True)
class MeasuredWindow:
    """What ``acdrive identify LOG --kind KIND`` assumes of a measured log unless told: the base
    frequency [Hz] of its injection (every tone a multiple of it), the time [s] dropped at its
    start, and (pm) the time [s] dropped at the start of each spin plateau."""

    base_frequency: float
    settle: float
    spin_settle: float | None = None


def _common_base(frequencies) -> float:
    """The largest frequency of which every one of ``frequencies`` is a whole multiple (their
    greatest common divisor, as exact fractions of at most 1e6 in the denominator)."""
    from fractions import Fraction

    parts = [Fraction(f).limit_denominator(10**6) for f in frequencies]
    common = math.lcm(*(p.denominator for p in parts))
    return math.gcd(*(int(p * common) for p in parts)) / common


def measured_window(kind: str) -> MeasuredWindow:
    """The defaults of a measured log of ``kind`` (pm, dfim), from that kind's benches, so that
    every built-in bench's own logs are analysed as printed, at all their tones: the base
    frequency of which each bench's is a whole multiple, the longest of their settling times
    (pm: 1 Hz, the BLY171D's 2 Hz and the 2.2 kW IPMSM's 1 Hz; 0.5 s) and of their spin
    plateaus' settling times."""
    benches = list(_benches().get(kind, {}).values())
    plans = [b.standstill for b in benches if hasattr(b, "standstill")]
    if not plans:
        raise InputError("kind", f"{kind!r} has no standstill test")
    spins = [b.spin.settle for b in benches if hasattr(b, "spin")]
    return MeasuredWindow(
        base_frequency=_common_base(p.base_frequency for p in plans),
        settle=max(p.settle for p in plans),
        spin_settle=max(spins) if spins else None,
    )
