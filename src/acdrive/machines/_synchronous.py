"""Synchronous machines with a magnetic model: the parameter record and the built-in machines."""

from __future__ import annotations

from acdrive.machines._record import machine_record
from acdrive.machines._synchronous_part import ALGEBRAIC, SynchronousMachine


@machine_record(SynchronousMachine, inertia_required=False)
class SynchronousMachineParams:
    """Synchronous machine parameters (surface or interior PM, SyRM, PM-SyRM), those of
    ``SynchronousMachine``: the magnetic model ``saturation`` (0 linear, 1 algebraic) with its
    parameters, and the mechanics of its ``plant.Shaft`` (J may be None: the electrical part does
    not use it)."""


#: The 6.7-kW, 2-pole-pair SyRM with the algebraic saturation model of Hinkkanen et al.,
#: "Sensorless self-commissioning of synchronous reluctance motors at standstill without rotor
#: locking", IEEE Trans. Ind. Appl., 2017 (doi 10.1109/TIA.2016.2644624). The coefficients
#: (peak-valued space vectors, fluxes in Wb, currents in A), R_s = 0.54 ohm, n_p = 2 and
#: J = 0.015 kg m^2 are those of motulator 0.18's examples of this machine
#: (examples/drive/flux_vector/plot_7kw_syrm_sat_fvc.py and
#: examples/drive/vhz/plot_7kw_syrm_sat_ovhz.py; the latter cites that paper for the saturation
#: model), as are its nominal values 370 V, 15.5 A, 105.8 Hz, 6.7 kW, 20.1 N m; J is motulator's
#: value for the drive's mechanics.
SYRM_6_7KW = SynchronousMachineParams(
    R_s=0.54, n_p=2, saturation=ALGEBRAIC,
    a_d0=17.4, a_dd=373.0, S=5, a_q0=52.1, a_qq=658.0, T=1, a_dq=1120.0, U=1, V=0,
    J=0.015,
)  # fmt: skip
