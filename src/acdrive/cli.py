"""The ``acdrive`` command.

Each subcommand lives in ``acdrive.commands.<name>`` and exposes ``register(subparsers)``,
which adds its parser and sets ``handler`` (a function of the parsed namespace returning an
exit code). Invalid input anywhere (``InputError`` / ``ValueError`` raised while validating)
becomes one line on stderr and exit code 2, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import signal
import sys

from acdrive.errors import InputError

DESCRIPTION = "acdrive: AC-machine drives -- DFIM speed control, ICAD analysis and design, compiled simulation."
COMMAND_MODULES = ("run", "scenarios", "limits", "icad", "stability", "reproduce")


class _OneLineParser(argparse.ArgumentParser):
    """ArgumentParser whose errors are a single line on stderr with exit code 2."""

    def error(self, message: str):
        sys.stderr.write(f"acdrive: error: {message}\n")
        raise SystemExit(2)


def build_parser() -> argparse.ArgumentParser:
    parser = _OneLineParser(prog="acdrive", description=DESCRIPTION)
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


def main(argv: list[str] | None = None) -> int:
    if hasattr(signal, "SIGPIPE"):  # `acdrive ... | head` ends quietly, as shell tools do
        signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.handler(args) or 0)
    except InputError as exc:
        sys.stderr.write(f"acdrive: error: {exc}\n")
        return 2


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
