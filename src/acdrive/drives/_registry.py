"""The registry of drive kinds and the ``Drive`` interface the command line, batches, sweeps
and reports use (docs/design.md, "Drives as plug-ins").

A drive kind is one folder (``acdrive/drives/<kind>/``) and one ``Drive`` object. Everything
above the engine asks the registry instead of naming a kind: ``acdrive run`` loads a scenario
with ``for_data(data).load(data)``, runs it with ``run``, writes it with ``write`` and prints
``headline``; a batch builds each variant's system with ``build`` and reduces it with
``reducers``; a sweep does both. A built-in drive is registered below by one line, the path of
the module that defines its ``DRIVE`` object, imported on first use (``acdrive --help`` and
``import acdrive.drives`` stay light); any other drive, e.g. one defined in a user's script or
a test, is registered with ``register(drive)`` and is then used exactly as the built-ins are.
From Python, ``run_scenario(setup)`` runs the setup of any drive the same way (``for_setup``,
then ``run``); ``require_setup`` is the check a drive's own functions make before any work.
"""

from __future__ import annotations

import importlib

from acdrive._arguments import TEXT, Anything, Function, Instance, Table, checked
from acdrive.errors import InputError

#: the scenario's ``drive`` value -> the module defining that built-in drive's ``DRIVE``
BUILTIN = {
    "dfim": "acdrive.drives.dfim._plugin",
    "cage-im": "acdrive.drives.cage_im._plugin",
    "pm": "acdrive.drives.pm._plugin",
}
#: the drive of a scenario that names none (the scenarios written before ``drive`` existed)
DEFAULT_KIND = "dfim"

_REGISTERED: dict[str, Drive] = {}


@checked()
class Drive:
    """One drive kind: the answers the command line, batches, sweeps and reports need.

    A subclass sets ``kind`` (the scenario file's ``drive = "<kind>"``) and ``setup_types`` (the
    classes ``load`` returns) and implements the methods that raise ``NotImplementedError``;
    the others have defaults that fit a drive without the feature.

    * ``load(data)``: the validated setup of a parsed scenario (a ``dict`` from TOML); every
      error an ``InputError`` naming the field by its dotted path, before any simulation.
    * ``run(setup, on_run=None)``: simulate; returns the outcome, an object with ``results``
      (label -> result with ``wall_time`` [s]) and ``summary`` (a dict: what summary.json
      holds); a built-in drive's is an ``acdrive.drives.Outcome``. ``on_run(label)`` is
      called before each simulation (``runs(setup)`` of them).
    * ``write(outcome, folder, figures, fmt)``: the data files (``acdrive.columns.FORMATS``),
      figures and summary.json into ``folder``; returns the summary written.
    * ``figures(outcome, folder)``: the figures ``write`` draws, alone (``Outcome.figures``);
      returns their paths.
    * ``headline(outcome, summary)``: (first line, rows of (label, text)) that ``acdrive run``
      prints, each computed from the summary.
    * ``build(setup)``: the drive's system of parts for one run, an object with ``system``
      (``acdrive.sim.System``) and ``initial()`` -> (initial states, held outputs): what a batch
      variant runs (a setup that compares several runs is refused with an ``InputError``).
    * ``log_width(setup)``: (output values, event words) the loop logs per logged sample of one
      run of ``setup`` (``acdrive.sim._log_plan.LogPlan``); None: not known before the run.
    * ``reducers(setup)``: the default on-line metrics of a batch or sweep
      (``acdrive.batch.Reducer``); ``verdict(setup, row)`` the batch row's ``stable`` column
      (None: the drive has no such verdict).
    * ``default_machine`` and ``params_fields(machine)``: the built-in machine a scenario's
      machine table defaults to and the fields of its ``[params]`` form, so a batch can vary
      one parameter of a built-in machine (None: no such form).
    * ``robustness()``: what a robustness map needs of the drive (``acdrive.robustness``).
    * ``crosscheck(setup, lower, upper)``: the linearised tolerated speed-loop bandwidth of a
      setup for a sweep's ``[crosscheck]`` (drives without a linearisation refuse it).
    * ``linearisation()``: the drive's small-signal linearisation, a namespace with at least
      ``linearize(study, point=None, ...)``, ``OperatingPoint``, ``stability_map`` and
      ``max_stable_bandwidth`` (``acdrive.analysis`` and ``acdrive stability`` reach it here);
      ``linearize(study, point, ...)`` linearises a setup of this drive with it. A drive without
      one refuses both with an ``InputError``.
    """

    kind: str = ""
    setup_types: tuple[type, ...] = ()
    default_machine: str | None = None

    def load(self, data: dict):
        raise NotImplementedError

    def owns(self, setup) -> bool:
        """True if ``setup`` is a setup of this drive."""
        return isinstance(setup, self.setup_types)

    def runs(self, setup) -> int:
        """The number of simulations ``run(setup)`` makes."""
        return 1

    def run(self, setup, on_run=None):
        raise NotImplementedError

    def write(self, outcome, folder, figures: bool = True, fmt: str = "parquet") -> dict:
        raise NotImplementedError

    def headline(self, outcome, summary: dict) -> tuple[str, list[tuple[str, str]]]:
        raise NotImplementedError

    def figures(self, outcome, folder) -> list:
        raise NotImplementedError

    def build(self, setup):
        raise NotImplementedError

    def log_width(self, setup) -> tuple[int, int] | None:
        return None

    def reducers(self, setup) -> list:
        return []

    def verdict(self, setup, row: dict) -> bool | None:
        return None

    def params_fields(self, machine) -> tuple[str, ...] | None:
        return None

    def crosscheck(self, setup, lower: float, upper: float) -> dict:
        raise InputError("crosscheck", f"the {self.kind} drive has no linearised speed loop")

    def linearisation(self):
        raise InputError("drive", f"drive {self.kind!r} has no linearisation")

    def linearize(self, study, point=None, *args, **kwargs):
        return self.linearisation().linearize(study, point, *args, **kwargs)

    def robustness(self):
        """The drive's ``acdrive.robustness.RobustnessSeam`` (its plant-only perturbation table,
        criteria and linearised prediction); a drive without one refuses a map."""
        raise InputError(
            "drive", f"drive {self.kind!r} has no plant perturbation for a robustness map"
        )

    def __repr__(self) -> str:
        return f"<{type(self).__name__} kind={self.kind!r}>"


class Setup(Instance):
    """The argument rule of a drive setup: an instance of a registered drive's ``setup_types``
    (the registry asked at each check, so a drive registered later counts)."""

    def __init__(self, *, optional: bool = False):
        super().__init__(optional=optional)

    @property
    def types(self) -> tuple[type, ...]:
        return tuple(t for kind in kinds() for t in get(kind).setup_types)

    def describe(self) -> str:
        return f"the setup of a registered drive ({', '.join(t.__name__ for t in self.types)})"

    def check_value(self, name, value):
        if _owner(value) is None:
            self.refuse(name, value)


@checked(drive=Instance(Drive))
def register(drive: Drive) -> Drive:
    """Register ``drive`` under ``drive.kind`` (a scenario's ``drive = "<kind>"`` then selects
    it); returns it. A kind already taken by another drive is refused (``InputError``)."""
    kind = getattr(drive, "kind", None)
    if not isinstance(kind, str) or not kind:
        raise InputError("drive", "needs a non-empty string kind")
    taken = _REGISTERED.get(kind)
    if (taken is not None and taken is not drive) or (taken is None and kind in BUILTIN):
        raise InputError("drive", f"kind {kind!r} is registered already")
    _REGISTERED[kind] = drive
    return drive


@checked(kind=TEXT)
def unregister(kind: str) -> None:
    """Remove a drive registered with ``register`` (built-in drives stay)."""
    if kind in BUILTIN:
        raise InputError("kind", f"{kind!r} is a built-in drive, which stays registered")
    _REGISTERED.pop(kind, None)


def builtin_packages() -> list[str]:
    """The package of each built-in drive (``acdrive.drives.<kind>``), without importing its
    plug-in module: where its own built-in scenarios are found (``<package>/scenarios``)."""
    return [module.rsplit(".", 1)[0] for module in BUILTIN.values()]


@checked()
def kinds() -> list[str]:
    """Every drive kind a scenario can name, built-in first."""
    return list(BUILTIN) + sorted(k for k in _REGISTERED if k not in BUILTIN)


@checked(kind=TEXT)
def get(kind: str) -> Drive:
    """The drive of ``kind`` (a built-in is imported now); an ``InputError`` naming ``kind`` and
    the kinds if there is none."""
    return _drive(kind, "kind")


def _drive(kind: str, field: str) -> Drive:
    """The drive of ``kind``, or an ``InputError`` naming ``field`` and the kinds."""
    drive = _REGISTERED.get(kind) if isinstance(kind, str) else None
    if drive is not None:
        return drive
    if isinstance(kind, str) and kind in BUILTIN:
        drive = importlib.import_module(BUILTIN[kind]).DRIVE
        _REGISTERED[kind] = drive
        return drive
    names = ", ".join(f'"{k}"' for k in kinds())
    raise InputError(field, f'must be one of {names} (omitted: "{DEFAULT_KIND}")')


@checked(data=Table(empty=True))
def for_data(data) -> Drive:
    """The drive of a parsed scenario: its ``drive`` value (an error names that field),
    ``DEFAULT_KIND`` if absent."""
    return _drive(data.get("drive", DEFAULT_KIND), "drive")


@checked(setup=Setup())
def for_setup(setup) -> Drive:
    """The drive whose ``load`` made ``setup`` (``InputError`` if no registered drive owns it)."""
    return _owner(setup)


def _owner(setup) -> Drive | None:
    """The registered drive that owns ``setup``, else None."""
    for kind in kinds():
        drive = get(kind)
        if drive.owns(setup):
            return drive
    return None


@checked(value=Anything())
def is_setup(value) -> bool:
    """True if ``value`` is the setup of a registered drive."""
    return _owner(value) is not None


@checked(setup=Setup(), on_run=Function(optional=True))
def run_scenario(setup, on_run=None):
    """Simulate the setup of any registered drive (what ``acdrive.scenarios.load_scenario``
    returns) with that drive's ``run`` and return its outcome: the object ``acdrive run`` writes,
    for a built-in drive an ``acdrive.drives.Outcome`` (``name``, ``kind``, ``results`` by run
    label, ``summary`` as summary.json holds it, ``headline()``, ``figures(folder)``,
    ``write(folder)``). ``on_run(label)``,
    if given, is called before each simulation (a progress display). A value that is not a
    registered drive's setup is an ``InputError`` on ``setup``, before any work."""
    return _owner(setup).run(setup, on_run)


def require_setup(setup, setup_types: tuple[type, ...], function: str, argument: str = "setup"):
    """``setup`` if it is one of ``setup_types``, else an ``InputError`` naming ``argument``: the
    drive whose setup it is, that ``function`` (a drive's own name, e.g.
    ``acdrive.drives.simulate``) takes its own drive's setups only, and that
    ``acdrive.drives.run_scenario`` runs any drive's."""
    if isinstance(setup, setup_types):
        return setup
    wanted = " or ".join(t.__name__ for t in setup_types)
    owner = _owner(setup)
    if owner is not None:
        kind = owner.kind
        raise InputError(argument, f'is the setup of drive "{kind}" ({type(setup).__name__}); '
                         f"{function} takes {wanted} only: acdrive.drives.run_scenario({argument}) "
                         "runs the setup of any drive")  # fmt: skip
    raise InputError(argument, f"must be of type {wanted} (what acdrive.scenarios.load_scenario "
                     f"returns), got {type(setup).__name__}")  # fmt: skip
