"""C of the plant kinds the plant C is built from (``sim._ccode._plant_source``). The
continuous parts (the DC and three-phase sources, the cage induction motor, the PM machine, the
DFIM, its supply bus (per instance: one input set per machine) and stator relay (Bodson (9)),
the free shaft, the prescribed speed) and the averaged converters have it generated from their
kernels (``sim._ccode._translate.c_plant``), as the PWM unit's latch (a sampled part in front of
an averaged converter) has its step. Written here beside its kernel: the switching SVPWM
inverter (its segments inside one control period), whose kernel sorts the switching instants
with a loop of run-time length, outside the kernel language; it repeats its numba kernel
operation for operation, and the native-tier and FMU tests keep the two equal."""

from __future__ import annotations

import math

from acdrive._frames import K_3C
from acdrive.machines._cage_part import CageInductionMachine
from acdrive.machines._dfim_part import DoublyFedMachine
from acdrive.machines._pmsm_part import PermanentMagnetMachine
from acdrive.plant._converter import AveragedConverter, DCFedConverter
from acdrive.plant._inverter import CarrierLatch, Inverter
from acdrive.plant._mechanics import PrescribedSpeed, Shaft
from acdrive.plant._network import StatorRelay, SupplyBus
from acdrive.plant._sources import DCSource, ThreePhaseSource
from acdrive.sim._ccode._translate import c_plant, c_step
from acdrive.sim._ccode._kinds import CSupport, PlantC, register, register_plant
from acdrive.sim._ccode._kinds.common import CLIP_MAGNITUDE


register_plant(
    DCSource,
    c_plant(
        DCSource,
        source="DC source: the voltage profile (plant._sources.dc_state_outputs)",
    ),
)

register_plant(
    CageInductionMachine,
    c_plant(
        CageInductionMachine,
        source="Amezquita-Brooks et al. (1)-(2), complex form (machines._cage_part)",
    ),
)

register_plant(
    ThreePhaseSource,
    c_plant(
        ThreePhaseSource,
        source="balanced three-phase source: v = sqrt(3/2) V_pk(t) u_g, du_g/dt = j 2 pi f(t) "
        "u_g (plant._sources)",
    ),
)


register_plant(
    SupplyBus,
    c_plant(
        SupplyBus,
        source="supply bus behind a shared series R-L, solved exactly (plant._network)",
    ),
)


register_plant(
    StatorRelay,
    c_plant(
        StatorRelay,
        source="stator relay: the bus voltage while closed, the open stator's voltage while open "
        "(plant._network)",
    ),
)

register_plant(
    DoublyFedMachine,
    c_plant(
        DoublyFedMachine,
        source="Bodson (9) in the stationary frame, flux linkages as states, the stator relay "
        "and the rotor converter's loss (machines._dfim_part)",
    ),
)


register_plant(
    PermanentMagnetMachine,
    c_plant(
        PermanentMagnetMachine,
        source="Ugalde-Loo et al. (7)-(8) in rotor coordinates, fed from the stationary frame "
        "(machines._pmsm_part)",
    ),
)

register_plant(
    Shaft,
    c_plant(
        Shaft,
        source="Bodson (26): J dw/dt = tau_e - tau_L(t) - (B + k_b(t)) w - tau_c tanh(w / "
        "W_COULOMB) (plant._mechanics)",
    ),
)

register_plant(
    PrescribedSpeed,
    c_plant(
        PrescribedSpeed,
        source="a shaft held at a speed profile (plant._mechanics.speed_state_outputs, speed_rhs)",
    ),
)

register_plant(
    AveragedConverter,
    c_plant(
        AveragedConverter,
        source="averaged converter: the command held over the sample, |v| <= V_dc / sqrt(2) "
        "(plant._converter)",
    ),
)

register_plant(
    DCFedConverter,
    c_plant(
        DCFedConverter,
        source="averaged converter fed from a DC link: |v| <= max(v_dc, 0) / sqrt(2) "
        "(plant._converter)",
    ),
)

register(
    CarrierLatch,
    c_step(
        CarrierLatch,
        source="the PWM unit's shadow register, N = max(1, round(1 / (f_pwm T_s))) samples "
        "(plant._inverter.latch_step)",
    ),
)

#: plant._inverter's helpers, each mirrored: the leg polarity, duty cycle, pulse and its edges
SVPWM = CSupport(
    "svpwm",
    r"""
/* plant._inverter._polarity */
static ACDRIVE_REAL acd_polarity(ACDRIVE_REAL x)
{
    if (x > ACD_R(0.0)) {
        return ACD_R(1.0);
    }
    if (x < ACD_R(0.0)) {
        return ACD_R(-1.0);
    }
    return ACD_R(0.0);
}

/* plant._inverter._duty: pole duty cycle of phase value x with zero-sequence offset */
static ACDRIVE_REAL acd_duty(ACDRIVE_REAL x, ACDRIVE_REAL offset, ACDRIVE_REAL v_dc)
{
    if (v_dc <= ACD_R(0.0)) {
        return ACD_R(0.5);
    }
    return acd_min(acd_max(ACD_R(0.5) + (x + offset) / v_dc, ACD_R(0.0)), ACD_R(1.0));
}

/* plant._inverter._pulse: a leg's high interval [*start, *end] in control samples */
static void acd_pulse(ACDRIVE_REAL d, ACDRIVE_REAL polarity, ACDRIVE_REAL n_carrier,
                      ACDRIVE_REAL delta, ACDRIVE_REAL *start, ACDRIVE_REAL *end)
{
    if (d <= ACD_R(0.0)) {
        *start = ACD_R(0.0);
        *end = ACD_R(0.0);
        return;
    }
    if (d >= ACD_R(1.0)) {
        *start = ACD_R(0.0);
        *end = n_carrier;
        return;
    }
    *start = ACD_R(0.5) * (ACD_R(1.0) - d) * n_carrier;
    *end = ACD_R(0.5) * (ACD_R(1.0) + d) * n_carrier;
    if (polarity > ACD_R(0.0)) {
        *start += delta; /* rising edge delayed: the lower diode holds the pole low */
        if (*start >= *end) {
            *start = ACD_R(0.0);
            *end = ACD_R(0.0);
        }
    } else if (polarity < ACD_R(0.0)) {
        *end = acd_min(*end + delta, n_carrier); /* falling edge delayed */
    }
}

/* plant._inverter._add_edges: the pulse edges strictly inside sample j, appended to dt[m..] */
static int acd_add_edges(ACDRIVE_REAL start, ACDRIVE_REAL end, ACDRIVE_REAL j, ACDRIVE_REAL *dt,
                         int m)
{
    if (start < end) {
        ACDRIVE_REAL e = start - j;
        if (ACD_R(0.0) < e && e < ACD_R(1.0)) {
            dt[m++] = e;
        }
        e = end - j;
        if (ACD_R(0.0) < e && e < ACD_R(1.0)) {
            dt[m++] = e;
        }
    }
    return m;
}
""",
)

register_plant(
    Inverter,
    PlantC(
        source="two-level inverter, centred SVPWM, dead time and device drops; Amezquita-Brooks "
        "et al. VI (plant._inverter.inverter_segments)",
        segments=rf"""
    const ACDRIVE_REAL k_3c = ACD_R({K_3C!r}), half_sqrt3 = ACD_R({math.sqrt(3.0) / 2.0!r});
    const ACDRIVE_REAL inv_sqrt2 = ACD_R({1.0 / math.sqrt(2.0)!r});
    ACDRIVE_REAL n_carrier = acd_max(ACD_R(1.0), ACD_FLOOR(ACD_R(1.0) / (p->f_pwm * T_s) + ACD_R(0.5)));
    ACDRIVE_REAL j = s->k, v_dc = acd_max(u->v_dc, ACD_R(0.0));
    ACDRIVE_REAL sig_a, sig_b, sig_c, delta, a0, a1, b0, b1, c0, c1, m_a, m_b, m_c;
    ACDRIVE_REAL previous = ACD_R(0.0), used = ACD_R(0.0);
    int m, i, count = 0;
    if (j < ACD_R(0.0) || j >= n_carrier) {{
        j = ACD_R(0.0);
    }}
    if (j == ACD_R(0.0)) {{ /* carrier period start: latch the limited command as duties */
        int limited;
        acd_complex applied = acd_clip_magnitude(u->v_ref, v_dc / ACD_SQRT(ACD_R(2.0)), &limited);
        ACDRIVE_REAL re = applied.re, im = applied.im;
        ACDRIVE_REAL x_a = k_3c * re;
        ACDRIVE_REAL x_b = k_3c * (ACD_R(-0.5) * re + half_sqrt3 * im);
        ACDRIVE_REAL x_c = k_3c * (ACD_R(-0.5) * re - half_sqrt3 * im);
        ACDRIVE_REAL offset = ACD_R(-0.5) * (acd_max(acd_max(x_a, x_b), x_c) +
                                             acd_min(acd_min(x_a, x_b), x_c));
        s->d_a = acd_duty(x_a, offset, v_dc);
        s->d_b = acd_duty(x_b, offset, v_dc);
        s->d_c = acd_duty(x_c, offset, v_dc);
        s->v_lim = applied;
        s->limited = limited ? ACD_R(1.0) : ACD_R(0.0);
    }}
    s->k = (j + ACD_R(1.0) < n_carrier) ? j + ACD_R(1.0) : ACD_R(0.0);

    /* current polarity of each phase (Bodson (2) without its positive factor) */
    sig_a = acd_polarity(u->i_s.re);
    sig_b = acd_polarity(ACD_R(-0.5) * u->i_s.re + half_sqrt3 * u->i_s.im);
    sig_c = acd_polarity(ACD_R(-0.5) * u->i_s.re - half_sqrt3 * u->i_s.im);
    delta = p->t_d / T_s;
    acd_pulse(s->d_a, sig_a, n_carrier, delta, &a0, &a1);
    acd_pulse(s->d_b, sig_b, n_carrier, delta, &b0, &b1);
    acd_pulse(s->d_c, sig_c, n_carrier, delta, &c0, &c1);

    /* switching instants inside this sample, sorted (insertion sort, at most six) */
    m = acd_add_edges(a0, a1, j, dt, 0);
    m = acd_add_edges(b0, b1, j, dt, m);
    m = acd_add_edges(c0, c1, j, dt, m);
    for (i = 1; i < m; ++i) {{
        ACDRIVE_REAL e = dt[i];
        int q = i - 1;
        while (q >= 0 && dt[q] > e) {{
            dt[q + 1] = dt[q];
            q -= 1;
        }}
        dt[q + 1] = e;
    }}

    m_a = ACD_R(2.0) * s->d_a - ACD_R(1.0);
    m_b = ACD_R(2.0) * s->d_b - ACD_R(1.0);
    m_c = ACD_R(2.0) * s->d_c - ACD_R(1.0);
    for (i = 0; i < m + 1; ++i) {{
        ACDRIVE_REAL e = i < m ? dt[i] : ACD_R(1.0); /* read before dt[count] is overwritten */
        ACDRIVE_REAL middle, e_a, e_b, e_c, length;
        if (e <= previous) {{
            continue; /* two legs switching at the same instant */
        }}
        middle = j + ACD_R(0.5) * (previous + e);
        e_a = ((a0 < middle && middle < a1) ? v_dc : ACD_R(0.0)) - p->v_drop * sig_a;
        e_b = ((b0 < middle && middle < b1) ? v_dc : ACD_R(0.0)) - p->v_drop * sig_b;
        e_c = ((c0 < middle && middle < c1) ? v_dc : ACD_R(0.0)) - p->v_drop * sig_c;
        length = i < m ? (e - previous) * T_s : T_s - used;
        dt[count] = length;
        used += length;
        v[count].v = acd_c(k_3c * (e_a - ACD_R(0.5) * (e_b + e_c)), inv_sqrt2 * (e_b - e_c));
        v[count].v_lim = s->v_lim;
        v[count].m_a = m_a;
        v[count].m_b = m_b;
        v[count].m_c = m_c;
        count += 1;
        previous = e;
    }}
    *n = count;
    return s->limited != ACD_R(0.0) ? ACD_INVERTER_OVERMODULATION : 0u;
""",
        support=(CLIP_MAGNITUDE, SVPWM),
    ),
)
