"""The whole-drive linearisation as ``acdrive.analysis`` offers it, asked of the drive registry
(``acdrive.drives``): each drive kind keeps its own linearisation in its folder and hands it out
through ``Drive.linearisation()``; nothing here names a kind.

A study that is the setup of a registered drive is linearised by that drive (one without a
linearisation refuses with an ``InputError``); any other study (a drive model, or the control
mode ``max_stable_bandwidth`` takes first) goes to the default drive's linearisation, the
drive of a scenario that names none, which checks it. ``OperatingPoint`` and ``DriveModel``
are the default drive's.
"""

from __future__ import annotations

from acdrive._arguments import Anything, Instance, forwarding
from acdrive.errors import InputError


def default_linearisation():
    """The linearisation of the default drive kind (``acdrive.drives.DEFAULT_KIND``)."""
    from acdrive.drives._registry import DEFAULT_KIND, get

    return get(DEFAULT_KIND).linearisation()


def linearisation_of(study):
    """The linearisation of the drive whose setup ``study`` is, else the default drive's."""
    from acdrive.drives._registry import for_setup

    try:
        drive = for_setup(study)
    except InputError:
        return default_linearisation()
    return drive.linearisation()


class Study(Instance):
    """The argument rule of a study: the setup of a registered drive or the default drive's
    ``DriveModel`` (the arguments after it are checked by the drive's own function)."""

    def __init__(self):
        super().__init__()

    @property
    def types(self) -> tuple[type, ...]:
        from acdrive.drives._registry import Setup

        return (*Setup().types, default_linearisation().DriveModel)

    def describe(self) -> str:
        return "the setup of a registered drive or a DriveModel"


@forwarding(setup=Study(), point=Anything())
def linearize(setup, point=None, *args, **kwargs):
    """Linearise the closed drive ``setup`` at ``point``: its drive's ``linearize`` (the DFIM's:
    ``acdrive.drives.dfim._linearisation.linearize``, Bodson's closed speed loop)."""
    return linearisation_of(setup).linearize(setup, point, *args, **kwargs)


@forwarding(model=Study())
def stability_map(model, *args, **kwargs):
    """The eigenvalue map over an operating-point grid, by the drive of ``model``."""
    return linearisation_of(model).stability_map(model, *args, **kwargs)


@forwarding()
def max_stable_bandwidth(*args, **kwargs):
    """The largest stable speed-loop bandwidth, by the drive of the first argument."""
    study = args[0] if args else kwargs.get("mode")
    return linearisation_of(study).max_stable_bandwidth(*args, **kwargs)


def __getattr__(name: str):
    if name in ("OperatingPoint", "DriveModel"):
        return getattr(default_linearisation(), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
