"""The ``acdrive`` command.

Each subcommand lives in ``acdrive.commands.<name>`` and exposes ``register(subparsers)``,
which adds its parser and sets ``handler`` (a function of the parsed namespace returning an
exit code). Invalid input anywhere (``InputError`` / ``ValueError`` raised while validating)
becomes one line on stderr and exit code 2, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import re
import signal
import sys
import warnings

from acdrive.errors import InputError, Notice, SimulationDiverged

DESCRIPTION = "acdrive: AC-machine drives -- DFIM speed control, ICAD analysis and design, compiled simulation."
COMMAND_MODULES = ("run", "scenarios", "limits", "icad", "stability", "reproduce", "sweep", "bench")


#: A negative number as an option value (``--load-nm -0.1``, ``--speed -1e5``, ``-inf``):
#: argparse's own pattern knows only plain decimals, so ``-1e5`` would be taken for an option.
#: No acdrive option looks like a negative number, so such a token is always a value.
NEGATIVE_NUMBER = re.compile(
    r"^-(?:(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?|inf(?:inity)?|nan)$", re.IGNORECASE
)


class _OneLineParser(argparse.ArgumentParser):
    """ArgumentParser whose errors are a single line on stderr with exit code 2, and which reads
    negative numbers in any float notation as option values."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_NUMBER

    def error(self, message: str):
        sys.stderr.write(f"acdrive: error: {message}\n")
        raise SystemExit(2)


def build_parser() -> argparse.ArgumentParser:
    parser = _OneLineParser(prog="acdrive", description=DESCRIPTION)
    parser.add_argument(
        "--debug", action="store_true", help="show the full traceback of a failure (for developers)"
    )
    sub = parser.add_subparsers(dest="command", parser_class=_OneLineParser, required=True)
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(f"acdrive.commands.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"acdrive.commands.{name}":
                continue  # subcommand not built yet
            raise
        module.register(sub)
    return parser


def _one_line(text) -> str:
    """``text`` on one line (a message may quote a multi-line parser error or a file name)."""
    return " ".join(str(text).splitlines())


class Terminated(BaseException):
    """SIGTERM turned into an exception, so cleanup (``finally``, output staging) runs."""


def _raise_terminated(signum, frame):
    raise Terminated()


def _show_notices(original):
    """A ``warnings.showwarning`` that prints a :class:`Notice` as one ``acdrive: note:`` line on
    stderr and hands every other warning to ``original``."""

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, Notice):
            sys.stderr.write(f"acdrive: note: {_one_line(message)}\n")
        else:
            original(message, category, filename, lineno, file, line)

    return show


def main(argv: list[str] | None = None) -> int:
    """Run the command; every failure is one line on stderr with a conventional exit code.

    2 invalid input (field and rule), 3 a simulation that diverged (time and what to change),
    70 an internal error (a bug; ``--debug`` shows where), 74 an input/output failure,
    130 interrupted (SIGINT), 143 terminated (SIGTERM). ``--debug`` (anywhere in the arguments)
    re-raises with the traceback and shows numerical warnings. A decision taken for the user
    (``acdrive.errors.Notice``, e.g. more substeps) is one ``acdrive: note:`` line on stderr.
    """
    if hasattr(signal, "SIGPIPE"):  # `acdrive ... | head` ends quietly, as shell tools do
        signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    argv = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in argv
    if debug:
        argv.remove("--debug")
    previous_term = signal.signal(signal.SIGTERM, _raise_terminated)
    caught = warnings.catch_warnings()
    caught.__enter__()
    if not debug:  # numerical warnings are for developers; results and inputs are checked
        warnings.simplefilter("ignore", RuntimeWarning)
    warnings.simplefilter("always", Notice)  # every decision taken for the user is reported
    warnings.showwarning = _show_notices(warnings.showwarning)  # restored by catch_warnings
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        return int(args.handler(args) or 0)
    except InputError as exc:
        if debug:
            raise
        sys.stderr.write(f"acdrive: error: {_one_line(exc)}\n")
        return 2
    except SimulationDiverged as exc:
        if debug:
            raise
        sys.stderr.write(f"acdrive: error: {_one_line(exc)}\n")
        return 3
    except KeyboardInterrupt:
        if debug:
            raise
        sys.stderr.write("acdrive: interrupted (SIGINT)\n")
        return 130
    except Terminated:
        if debug:
            raise
        sys.stderr.write("acdrive: terminated (SIGTERM)\n")
        return 143
    except OSError as exc:
        if debug:
            raise
        where = f" ({exc.filename})" if getattr(exc, "filename", None) else ""
        sys.stderr.write(f"acdrive: error: input/output failure{where}: {exc.strerror or exc}\n")
        return 74
    except Exception as exc:  # a bug: still one line, the traceback only with --debug
        if debug:
            raise
        sys.stderr.write(
            f"acdrive: error: internal error ({type(exc).__name__}: {_one_line(exc)}); please "
            "report it with the output of the same command run with --debug\n"
        )
        return 70
    finally:
        caught.__exit__(None, None, None)
        signal.signal(signal.SIGTERM, previous_term)


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
