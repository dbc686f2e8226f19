"""Scenario files (TOML) -> a drive's validated setup, through the registry of drives.

A scenario names its drive with ``drive = "<kind>"`` (``acdrive.drives.kinds()``; a file without
it is a DFIM scenario); that drive's loader (``Drive.load``) checks every field and raises
``InputError("<path.to.field>", "<rule>")`` for a bad one, before any simulation. The schemas
are in the drives' folders (``drives.dfim._schema``, ``drives.cage_im._schema``).
"""

from __future__ import annotations

from pathlib import Path

from acdrive.scenarios._files import builtin_names, builtin_text, read_scenario

__all__ = ["build_setup", "builtin_names", "builtin_text", "load_scenario", "read_scenario"]


def build_setup(data: dict):
    """Validate a parsed scenario and build its drive's setup (``Drive.load``)."""
    from acdrive.drives import for_data

    return for_data(data).load(data)


def load_scenario(source: str | Path):
    """Read (a built-in name or a TOML path), validate and build a scenario into its drive's
    setup (a ``DriveSetup`` for the DFIM, an ``IMDriveSetup`` for ``drive = "cage-im"``)."""
    return build_setup(read_scenario(source))
