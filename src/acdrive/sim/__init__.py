"""Simulation engine: systems from parts, their compiled loop, integrators, results. The drives
built on it are in ``acdrive.drives``."""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "System": "._system",
        "CompiledSystem": "._compiled",
        "SystemResult": "._result",
        "Result": "._result",
        "INTEGRATORS": "._integrators",
    },
)
