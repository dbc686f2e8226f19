"""Scenario files: reading, validation, the built-in scenarios."""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "load_scenario": ".loader",
        "build_setup": ".loader",
        "builtin_names": ".files",
        "read_scenario": ".files",
    },
)
