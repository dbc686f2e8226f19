"""Plant parts other than the machines: sources, converters and the SVPWM inverter, mechanics,
the supply network and relays, sensors."""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "ThreePhaseSource": ".sources",
        "UnbalancedSource": ".sources",
        "DCSource": ".sources",
        "AveragedConverter": ".converter",
        "DCFedConverter": ".converter",
        "Inverter": ".inverter",
        "CarrierLatch": ".inverter",
        "Shaft": ".mechanics",
        "PrescribedSpeed": ".mechanics",
        "SupplyBus": ".network",
        "StatorRelay": ".network",
        "RelayCommand": ".network",
        "ForcedRelay": ".network",
        "Encoder": ".sensors",
        "CurrentSensors": ".sensors",
        "VoltageSensor": ".sensors",
    },
)
