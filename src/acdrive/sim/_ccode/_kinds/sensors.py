"""C steps of the sensors (``acdrive.plant._sensors``), the forced relay and the relay command
(``plant._network``), the speed reference profile (``acdrive.control._speed``) and the open-loop
voltage programs (``acdrive.control._open_loop``). The sensors, the speed reference and the relays
are generated from their kernels (``sim._ccode._translate``); each remaining body mirrors its
kernel line for line."""

from __future__ import annotations

from acdrive._frames import K_PEAK
from acdrive.control._current import CurrentProgram
from acdrive.control._delay import ComputationDelay
from acdrive.control._open_loop import ComplexProgram, VoltageProgram
from acdrive.control._speed import SpeedReference
from acdrive.plant._network import ForcedRelay, RelayCommand
from acdrive.plant._sensors import CurrentSensors, Encoder, VoltageSensor
from acdrive.sim._ccode._translate import c_step
from acdrive.sim._ccode._kinds import CStep, register
from acdrive.sim._ccode._kinds.common import TABLE_AT

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
    CStep(
        source="one sample of computation delay (control._delay)",
        body=r"""
    y->x = s->stored; /* the input of the previous sample */
    s->stored = u->x;
    return 0u;
""",
    ),
)

register(
    CurrentProgram,
    CStep(
        source="a complex current from two piecewise-linear tables (control._current)",
        body=r"""
    y->i = acd_c(acd_table_at(p->re.n, p->re.t, p->re.v, t), acd_table_at(p->im.n, p->im.t, p->im.v, t));
    return 0u;
""",
        support=(TABLE_AT,),
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
    CStep(
        source="open-loop three-phase voltage program, Bodson (8) scaling "
        "(control._open_loop.program_step)",
        body=rf"""
    if (s->started != ACD_R(0.0)) {{
        ACDRIVE_REAL f_mean = ACD_R(0.5) * (acd_table_at(p->f.n, p->f.t, p->f.v, s->t_prev)
                                            + acd_table_at(p->f.n, p->f.t, p->f.v, t));
        s->theta += ACD_R(2.0) * ACD_PI * f_mean * (t - s->t_prev);
    }}
    s->t_prev = t;
    s->started = ACD_R(1.0);
    y->v_ref = acd_cscale(ACD_R({K_PEAK!r}) * acd_table_at(p->V_pk.n, p->V_pk.t, p->V_pk.v, t),
                          acd_c(ACD_COS(s->theta), ACD_SIN(s->theta)));
    return 0u;
""",
        support=(TABLE_AT,),
    ),
)

register(
    ComplexProgram,
    CStep(
        source="a complex command from two tables (control._open_loop.complex_program_step)",
        body=r"""
    y->v_ref.re = acd_table_at(p->re.n, p->re.t, p->re.v, t);
    y->v_ref.im = acd_table_at(p->im.n, p->im.t, p->im.v, t);
    return 0u;
""",
        support=(TABLE_AT,),
    ),
)
