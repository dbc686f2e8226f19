"""C of the plant kinds the plant C is built from (``sim._ccode._plant_source``), every one
generated from its kernels (``sim._ccode._kind_c.c_plant``): the continuous parts (the DC and
three-phase sources, the cage induction motor, the PM machine, the DFIM, its supply bus (per
instance: one input set per machine) and stator relay (Bodson (9)), the free shaft, the
prescribed speed), the modulators (the averaged converters and the switching SVPWM inverter,
its segments inside one control period), and the step of the PWM unit's latch (a sampled part
in front of an averaged converter)."""

from __future__ import annotations

from acdrive.machines._cage_part import CageInductionMachine
from acdrive.machines._dfim_part import DoublyFedMachine
from acdrive.machines._pmsm_part import PermanentMagnetMachine
from acdrive.plant._converter import AveragedConverter, DCFedConverter
from acdrive.plant._inverter import CarrierLatch, Inverter
from acdrive.plant._mechanics import PrescribedSpeed, Shaft
from acdrive.plant._network import StatorRelay, SupplyBus
from acdrive.plant._sources import DCSource, ThreePhaseSource
from acdrive.sim._ccode._kind_c import c_plant, c_step
from acdrive.sim._ccode._kinds import register, register_plant

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

register_plant(
    Inverter,
    c_plant(
        Inverter,
        source="two-level inverter, centred SVPWM, dead time and device drops; Amezquita-Brooks "
        "et al. VI (plant._inverter.inverter_segments)",
    ),
)
