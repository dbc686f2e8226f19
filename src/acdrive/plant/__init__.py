"""Plant parts other than the machines: sources, converters and the SVPWM inverter, mechanics,
the supply network and relays, sensors."""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "ThreePhaseSource": "._sources",
        "UnbalancedSource": "._sources",
        "DCSource": "._sources",
        "AveragedConverter": "._converter",
        "DCFedConverter": "._converter",
        "Inverter": "._inverter",
        "CarrierLatch": "._inverter",
        "Shaft": "._mechanics",
        "PrescribedSpeed": "._mechanics",
        "SupplyBus": "._network",
        "StatorRelay": "._network",
        "RelayCommand": "._network",
        "ForcedRelay": "._network",
        "Encoder": "._sensors",
        "CurrentSensors": "._sensors",
        "VoltageSensor": "._sensors",
        "QuadratureEncoder": "._encoder",
        "Resolver": "._resolver",
        "HallSensors": "._hall",
        "CurrentSensing": "._current_sensing",
    },
)
