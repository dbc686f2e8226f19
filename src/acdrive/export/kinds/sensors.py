"""C steps of the sensors (``acdrive.plant._sensors``) and of the speed reference profile
(``acdrive.control._speed``); each body mirrors its kernel line for line."""

from __future__ import annotations

from acdrive.control._speed import SpeedReference
from acdrive.export.kinds import CStep, CSupport, register
from acdrive.plant._sensors import CurrentSensors, Encoder, VoltageSensor

#: core._tables.table_at: linear between points, held outside, a vertical step where two times
#: are equal. The bisection halves [lo, hi] each pass: 32 passes cover any table an int counts.
TABLE_AT = CSupport(
    "table_at",
    r"""
static ACDRIVE_REAL acd_table_at(int n, const ACDRIVE_REAL *times, const ACDRIVE_REAL *values,
                                 ACDRIVE_REAL t)
{
    int lo = 0, hi = n - 1, pass;
    ACDRIVE_REAL dt;
    if (n == 1 || t <= times[0]) {
        return values[0];
    }
    if (t >= times[n - 1]) {
        return values[n - 1];
    }
    for (pass = 0; pass < 32 && hi - lo > 1; ++pass) { /* times[lo] <= t < times[hi] */
        int mid = (lo + hi) / 2;
        if (times[mid] <= t) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    dt = times[hi] - times[lo];
    if (dt <= ACD_R(0.0)) {
        return values[hi];
    }
    return values[lo] + (values[hi] - values[lo]) * (t - times[lo]) / dt;
}
""",
)

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
