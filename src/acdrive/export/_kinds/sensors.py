"""C steps of the sensors (``acdrive.plant._sensors``), the forced relay (``plant._network``) and of the speed reference profile
(``acdrive.control._speed``); each body mirrors its kernel line for line."""

from __future__ import annotations

from acdrive.control._current import CurrentProgram
from acdrive.control._delay import ComputationDelay
from acdrive.control._speed import SpeedReference
from acdrive.export._kinds import CStep, register
from acdrive.export._kinds.common import TABLE_AT
from acdrive.plant._network import ForcedRelay
from acdrive.plant._sensors import CurrentSensors, Encoder, VoltageSensor

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
