"""C steps of the sensors (``acdrive.plant._sensors``), the forced relay and the relay command
(``plant._network``), the speed reference profile (``acdrive.control._speed``), the computation
delay (``control._delay``, per instance: real or complex) and the open-loop programs
(``acdrive.control._open_loop``, ``control._current``), generated from their kernels by
``sim._ccode._translate``."""

from __future__ import annotations

from acdrive.control._current import CurrentProgram
from acdrive.control._delay import ComputationDelay
from acdrive.control._open_loop import ComplexProgram, VoltageProgram
from acdrive.control._speed import SpeedReference
from acdrive.plant._network import ForcedRelay, RelayCommand
from acdrive.plant._sensors import CurrentSensors, Encoder, VoltageSensor
from acdrive.sim._ccode._kind_c import c_step
from acdrive.sim._ccode._kinds import register

register(
    Encoder,
    c_step(
        Encoder,
        source="Bodson IV-A: incremental encoder (plant._sensors.encoder_angle)",
    ),
)

register(
    CurrentSensors,
    c_step(
        CurrentSensors,
        source="Bodson IV-A: current sensors, lost from fault_time (plant._sensors)",
    ),
)

register(
    VoltageSensor,
    c_step(
        VoltageSensor,
        source="voltage sensor with a gain error, lost from fault_time (plant._sensors)",
    ),
)

register(
    SpeedReference,
    c_step(
        SpeedReference,
        source="speed reference profile (control._speed, core._tables.table_at)",
    ),
)

register(
    ForcedRelay,
    c_step(
        ForcedRelay,
        source="a relay closed from close_at whatever its command (plant._network)",
    ),
)

register(
    ComputationDelay,
    c_step(
        ComputationDelay,
        source="one sample of computation delay (control._delay)",
    ),
)

register(
    CurrentProgram,
    c_step(
        CurrentProgram,
        source="a complex current from two piecewise-linear tables (control._current)",
    ),
)

register(
    RelayCommand,
    c_step(
        RelayCommand,
        source="relay command at a set time (plant._network.relay_command_step)",
    ),
)

register(
    VoltageProgram,
    c_step(
        VoltageProgram,
        source="open-loop three-phase voltage program, Bodson (8) scaling "
        "(control._open_loop.program_step)",
    ),
)

register(
    ComplexProgram,
    c_step(
        ComplexProgram,
        source="a complex command from two tables (control._open_loop.complex_program_step)",
    ),
)
