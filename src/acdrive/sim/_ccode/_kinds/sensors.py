"""C steps of the sensors (``acdrive.plant._sensors``), the forced relay and the relay command
(``plant._network``), the speed reference profile (``acdrive.control._speed``) and the open-loop
voltage programs (``acdrive.control._open_loop``); each body mirrors its kernel line for line."""

from __future__ import annotations

from acdrive._frames import K_PEAK
from acdrive.control._current import CurrentProgram
from acdrive.control._delay import ComputationDelay
from acdrive.control._open_loop import ComplexProgram, VoltageProgram
from acdrive.control._speed import SpeedReference
from acdrive.plant._network import ForcedRelay, RelayCommand
from acdrive.plant._sensors import CurrentSensors, Encoder, VoltageSensor
from acdrive.sim._ccode._kinds import CStep, register
from acdrive.sim._ccode._kinds.common import TABLE_AT

register(
    Encoder,
    CStep(
        source="Bodson IV-A: incremental encoder (plant._sensors.encoder_angle)",
        body=r"""
    ACDRIVE_REAL reading = u->theta + p->offset;
    if (p->counts_per_rev <= ACD_R(0.0)) {
        y->theta = reading;
    } else {
        ACDRIVE_REAL count = ACD_R(2.0) * ACD_PI / p->counts_per_rev;
        y->theta = ACD_FLOOR(reading / count) * count;
    }
    return 0u;
""",
    ),
)

register(
    CurrentSensors,
    CStep(
        source="Bodson IV-A: current sensors, lost from fault_time (plant._sensors)",
        body=r"""
    if (p->fails != ACD_R(0.0) && t >= p->fault_time) {
        y->valid = ACD_R(0.0); /* the currents keep their last values */
        return ACD_CURRENT_SENSORS_LOST;
    }
    y->i_s = u->i_s;
    y->i_r = u->i_r;
    y->valid = ACD_R(1.0);
    return 0u;
""",
    ),
)

register(
    VoltageSensor,
    CStep(
        source="voltage sensor with a gain error, lost from fault_time (plant._sensors)",
        body=r"""
    if (p->fails != ACD_R(0.0) && t >= p->fault_time) {
        y->valid = ACD_R(0.0); /* the voltage keeps its last value */
        return ACD_VOLTAGE_SENSOR_LOST;
    }
    y->v = acd_c(p->gain * u->v.re, p->gain * u->v.im);
    y->valid = ACD_R(1.0);
    return 0u;
""",
    ),
)

register(
    SpeedReference,
    CStep(
        source="speed reference profile (control._speed, core._tables.table_at)",
        body=r"""
    y->w_ref = acd_table_at(p->w.n, p->w.t, p->w.v, t);
    return 0u;
""",
        support=(TABLE_AT,),
    ),
)

register(
    ForcedRelay,
    CStep(
        source="a relay closed from close_at whatever its command (plant._network)",
        body=r"""
    if (u->command != ACD_R(0.0)) {
        y->closed = ACD_R(1.0);
        return 0u;
    }
    if (t >= p->close_at) {
        y->closed = ACD_R(1.0);
        return ACD_FORCED_RELAY_FORCED;
    }
    y->closed = ACD_R(0.0);
    return 0u;
""",
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
    CStep(
        source="relay command at a set time (plant._network.relay_command_step)",
        body=r"""
    y->closed = (t >= p->close_at) ? ACD_R(1.0) : ACD_R(0.0);
    return 0u;
""",
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
