"""Options a command's chosen task does not use: refused by name, never silently ignored.

A command whose options serve different tasks (``acdrive stability --map`` or ``--scenario``,
``acdrive robustness --estimates``) declares the options each task leaves unused, with ``None``
as their parser default so that a given option can be told from a default one (the default is
filled in once the task is known); ``refuse_unused`` then turns a given unused option into one
line naming it and the option that chose the task (exit code 2 from the CLI).
"""

from __future__ import annotations

import contextlib


def flag(dest: str) -> str:
    """The command-line flag of the parsed attribute ``dest`` (``speed_rpm`` -> ``--speed-rpm``)."""
    return "--" + dest.replace("_", "-")


def given(args, dest: str) -> bool:
    """Whether the option ``dest`` (parser default ``None``) was given."""
    return getattr(args, dest, None) is not None


def refuse_unused(args, dests, chosen: str, why: str) -> None:
    """An ``InputError`` on the first of ``dests`` that was given: it does not apply with the
    option ``chosen`` (e.g. ``--map``), because ``why``."""
    from acdrive.errors import InputError

    for dest in dests:
        if given(args, dest):
            raise InputError(flag(dest), f"does not apply with {chosen}: {why}")


@contextlib.contextmanager
def typed_names(names: dict[str, str]):
    """Re-raise an ``InputError`` on a Python argument of ``names`` (e.g. ``base_frequency``)
    under the option the user typed for it (``--base-frequency-hz``), with the same rule."""
    from acdrive.errors import InputError

    try:
        yield
    except InputError as exc:
        if exc.field not in names:
            raise
        raise InputError(names[exc.field], exc.rule) from None
