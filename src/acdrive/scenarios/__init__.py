"""Scenario files: reading, validation, the built-in scenarios."""

from acdrive._lazy import namespace

__all__, __getattr__, __dir__ = namespace(
    __name__,
    {
        "load_scenario": "._loader",
        "build_setup": "._loader",
        "builtin_names": "._files",
        "read_scenario": "._files",
    },
)
