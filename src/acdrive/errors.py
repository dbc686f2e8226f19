"""Input errors: one line naming the field and the rule it breaks."""

import contextlib
import re
import signal
import threading

__all__ = ["InputError", "Notice", "SimulationDiverged", "UnknownField"]


class InputError(ValueError):
    """Invalid user input (parameter, scenario field or CLI argument).

    The message always has the form ``<field>: <rule>`` so the CLI can print it as one line.
    """

    def __init__(self, field: str, rule: str):
        self.field = field
        self.rule = rule
        super().__init__(f"{field}: {rule}")


class UnknownField(InputError):
    """An ``InputError`` for a name that does not exist (a misspelt key, a part or a list entry
    the scenario does not have), as opposed to a value that breaks its rule: a batch refuses an
    override naming one instead of running its variant as invalid."""


class Notice(UserWarning):
    """A decision the program took for the user (for example a raised number of substeps).

    Raised with ``warnings.warn``; the CLI prints it as one line ``acdrive: note: <message>`` on
    stderr and carries on. Library callers see an ordinary warning they can filter or record.
    """


class Terminated(BaseException):
    """SIGTERM turned into an exception by the ``acdrive`` command (``acdrive.cli.main``), so
    cleanup (``finally``, output staging) runs and a command can say how to carry on. Defined
    here, not in ``acdrive.cli``, so that ``python -m acdrive.cli`` raises the class the commands
    catch."""


class SimulationDiverged(RuntimeError):
    """A simulation whose state stopped being finite at ``time`` [s].

    ``hint`` says what to change in the scenario (sample time, substeps, inertia, gains). The CLI
    prints ``simulation: diverged ... at t = <time> s; <hint>`` as one line with exit code 3.
    """

    def __init__(self, time: float, hint: str, name: str | None = None):
        self.time = float(time)
        self.hint = hint
        self.name = name
        which = f" '{name}'" if name else ""
        super().__init__(
            f"simulation: scenario{which} diverged (state no longer finite) at "
            f"t = {self.time:.6g} s; {hint}"
        )


@contextlib.contextmanager
def named_as(names: dict[str, str]):
    """Re-raise an ``InputError`` raised inside the block whose field is a key of ``names`` (a
    Python argument, also as ``key[i]`` or ``key['k']`` for one of its items) as naming
    ``names[key]`` instead (the CLI flag the user typed), with the same rule."""
    try:
        yield
    except InputError as exc:
        base = exc.field if exc.field in names else exc.field.split("[", 1)[0]
        if base not in names:
            raise
        raise InputError(names[base], exc.rule) from None


def require_finite(field: str, value) -> float:
    """Return ``value`` as float, or raise InputError if it is not a finite real number."""
    import math

    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(field, f"must be a number, got {type(value).__name__}")
    value = float(value)
    if not math.isfinite(value):
        raise InputError(field, "must be finite (not NaN or infinite)")
    return value


def require_positive(field: str, value) -> float:
    """Return ``value`` as float, or raise InputError unless it is finite and > 0."""
    value = require_finite(field, value)
    if value <= 0.0:
        raise InputError(field, f"must be > 0, got {value:g}")
    return value


def require_nonnegative(field: str, value) -> float:
    """Return ``value`` as float, or raise InputError unless it is finite and >= 0."""
    value = require_finite(field, value)
    if value < 0.0:
        raise InputError(field, f"must be >= 0, got {value:g}")
    return value


def require_between(field: str, value, low: float, high: float) -> float:
    """Return ``value`` as float, or raise InputError unless it is finite and in [low, high]."""
    value = require_finite(field, value)
    if not low <= value <= high:
        raise InputError(field, f"must be between {low:g} and {high:g}, got {value:g}")
    return value


#: one path component: starts with a letter or digit; letters, digits, '.', '_', '-'; at most 100
_SAFE_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,99}")


def require_safe_name(field: str, value) -> str:
    """Return ``value`` if it is usable as one file or folder name, else raise InputError."""
    if not isinstance(value, str):
        raise InputError(field, "must be a string")
    if not _SAFE_NAME.fullmatch(value):
        raise InputError(
            field,
            f"must be one file name of 1-100 letters, digits, '.', '_' or '-' starting with a "
            f"letter or digit (no '/', '.', '..' or leading dot), got {value!r}",
        )
    return value


def interrupt_behind(exc: BaseException) -> BaseException | None:
    """The interrupt (KeyboardInterrupt, a SIGTERM exception, SystemExit: a BaseException that is
    not an Exception) hidden behind ``exc``, or None.

    A signal that arrives while a parallel compiled (numba) function runs has its handler run
    inside that call; CPython then reports a ``SystemError`` ("returned a result with an exception
    set") whose ``__cause__`` is the handler's exception. Callers re-raise that cause, so an
    interrupt stays an interrupt."""
    cause = exc.__cause__ if isinstance(exc, SystemError) else None
    if isinstance(cause, BaseException) and not isinstance(cause, Exception):
        return cause
    return None


def call_interruptible(function, *args):
    """``function(*args)`` (a parallel compiled function), re-raising an interrupt that arrived
    during the call as itself (``interrupt_behind``)."""
    try:
        return function(*args)
    except SystemError as exc:
        cause = interrupt_behind(exc)
        if cause is not None:
            raise cause from None
        raise


@contextlib.contextmanager
def interrupt_held():
    """Hold SIGINT and SIGTERM for the block and take them when it ends.

    numba compiles and loads its cached code through llvmlite, which calls Python back from
    inside LLVM (the object cache's notifications): an interrupt raised in such a callback is
    printed as "Exception ignored" and lost, and the command runs on to its end (seen: a SIGINT
    2.05 s into ``acdrive run`` while numba loaded the loop). Held, a signal that came is passed
    to its Python handler once the compile or load is over (``KeyboardInterrupt``, the command's
    ``Terminated``). Only in the main thread, and only for a signal whose handler is a Python
    function (a default or ignored disposition is left alone)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    held = {}
    for signum in (signal.SIGINT, signal.SIGTERM):
        handler = signal.getsignal(signum)
        if callable(handler):
            held[signum] = handler
    came = []
    for signum in held:
        signal.signal(signum, lambda number, frame: came.append((number, frame)))
    try:
        yield
    finally:
        for signum, handler in held.items():
            signal.signal(signum, handler)
    for number, frame in came[:1]:  # the first signal decides, as it would have unheld
        held[number](number, frame)
