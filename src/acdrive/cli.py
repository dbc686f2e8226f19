"""The ``acdrive`` command.

Each subcommand lives in ``acdrive._commands.<name>`` and exposes ``register(subparsers)``,
which adds its parser and sets ``handler`` (a function of the parsed namespace returning an
exit code). Invalid input anywhere (``InputError`` / ``ValueError`` raised while validating)
becomes one line on stderr and exit code 2, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import re
import signal
import sys
import warnings

from acdrive import __version__
from acdrive._progress import ACTIVE_BARS
from acdrive.errors import (
    InputError,
    Notice,
    SimulationDiverged,
    Terminated,
    call_interruptible,
)

DESCRIPTION = "acdrive: AC-machine drives -- DFIM speed control, ICAD analysis and design, compiled simulation."

#: Subcommand -> its one-line help. Only the chosen command's module is imported (its
#: ``register`` builds the full parser); the others are listed from this table, so ``--help``
#: imports no numerical library. A listed module that does not exist (yet) is left out.
COMMANDS = {
    "run": "simulate a scenario (default: the Bodson Fig. 4 ramp)",
    "scenarios": "list the built-in scenarios",
    "limits": "torque limits of the built-in DFIM (Bodson (30), (32), (37))",
    "icad": "individual channel analysis",
    "stability": "drive stability (eigenvalues, map)",
    "reproduce": "regenerate a reproduction report",
    "sweep": "run a scenario over a grid of parameter values",
    "robustness": "robustness map of parameter errors (grid or Monte Carlo, batch engine)",
    "identify": "machine parameters from logged tests (cage IM, PM, DFIM, mechanics) with 95-percent intervals",
    "export": (
        "a scenario's controller chains as C99 (export c), run in acdrive's loop (export sil), "
        "their cost on a Cortex-M4F (export m4), controller and plant as FMI 2.0 FMUs "
        "(export fmu)"
    ),
    "parts": "list the built-in part kinds, or describe one (parameters, states, ports, units)",
    "bench": "benchmark suite: speed ratios against motulator and gym-electric-motor (both "
    "sides timed in interleaved process-CPU-time windows, with spread and load) with both "
    "sides' accuracy, and the ICAD timings (grid, point, `reproduce icad`)",
}
COMMAND_MODULES = tuple(COMMANDS)


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


def _exists(name: str) -> bool:
    """Whether ``acdrive._commands.<name>`` exists (found without importing it)."""
    return importlib.util.find_spec(f"acdrive._commands.{name}") is not None


def chosen_command(argv: list[str]) -> str | None:
    """The subcommand named in ``argv``: its first token that is not an option, if any."""
    return next((token for token in argv if not token.startswith("-")), None)


def build_parser(argv: list[str] | None = None) -> argparse.ArgumentParser:
    """The ``acdrive`` parser. With ``argv``, only the command it names is imported and gets its
    full parser; every other command is a one-line entry of :data:`COMMANDS`. Without ``argv``
    every command's full parser is built (documentation, tests)."""
    parser = _OneLineParser(prog="acdrive", description=DESCRIPTION)
    parser.add_argument(
        "--debug", action="store_true", help="show the full traceback of a failure (for developers)"
    )
    parser.add_argument("--version", action="version", version=f"acdrive {__version__}")
    sub = parser.add_subparsers(
        dest="command", parser_class=_OneLineParser, required=True, metavar="COMMAND"
    )
    chosen = chosen_command(argv) if argv is not None else None
    for name, help_line in COMMANDS.items():
        if not _exists(name):
            continue  # subcommand not built yet
        if argv is None or name == chosen:
            importlib.import_module(f"acdrive._commands.{name}").register(sub)
        else:
            sub.add_parser(name, help=help_line)
    return parser


def _one_line(text) -> str:
    """``text`` on one line (a message may quote a multi-line parser error or a file name)."""
    return " ".join(str(text).splitlines())


def _raise_terminated(signum, frame):
    raise Terminated()


def _show_notices(original):
    """A ``warnings.showwarning`` that prints a :class:`Notice` as one ``acdrive: note:`` line on
    stderr and hands every other warning to ``original``."""

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, Notice):
            line = f"acdrive: note: {_one_line(message)}"
            if ACTIVE_BARS:
                ACTIVE_BARS[-1].write(line, file=sys.stderr)
            else:
                sys.stderr.write(line + "\n")
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
    from acdrive import _figures

    _figures.COMMAND_PROCESS = True  # matplotlib's docstrings are not built (_figures)
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
        parser = build_parser(argv)
        args = parser.parse_args(argv)
        from acdrive._threads import one_blas_thread

        one_blas_thread()  # numpy's BLAS threads would spin beside the command (_threads)
        return int(call_interruptible(args.handler, args) or 0)
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
        # taken: a second interrupt, or one a library (pyarrow's stop handler) passed on again
        # while it was raised, must not end the process by the signal past its exit code
        signal.signal(signal.SIGINT, signal.SIG_IGN)
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


#: Collector thresholds of the ``acdrive`` process (CPython's default is (700, 10, 10)): a
#: warm ``acdrive run`` imports numba, scipy, pyarrow and matplotlib: 120,000 objects tracked
#: by the collector (180,000 with figures), and at the default it traverses them again and
#: again while they are made. A young
#: generation of 50,000 allocations still collects every cycle, with far fewer passes.
COMMAND_GC_THRESHOLDS = (50_000, 20, 20)


def command() -> int:
    """The ``acdrive`` console script: :func:`main` with the collector tuned for a short process.

    While it runs, the collector's thresholds are ``COMMAND_GC_THRESHOLDS``; when it returns,
    every object is frozen out of the collector (``gc.freeze``), so that the interpreter's
    shutdown, which collects once more, does not traverse them again (atexit handlers and the
    flushing of open files run as before). Measured on a warm ``acdrive run bodson-ramp``
    (2-core machine, loaded): the freeze saves about 0.25 CPU-s without figures and 0.35 with
    them (a module with one cached numba function alone exits in 0.67 CPU-s instead of 0.88),
    the thresholds about 0.05-0.15 more. ``main`` called from Python (a test, a notebook)
    leaves the collector alone."""
    import gc

    gc.set_threshold(*COMMAND_GC_THRESHOLDS)
    code = main()
    gc.freeze()
    return code


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(command())
