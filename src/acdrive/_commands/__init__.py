"""Subcommands of the acdrive CLI, one module each."""
