"""Scenario files: the built-in scenarios (this package's ``builtin/`` and each built-in drive's
``scenarios/`` folder) and reading a built-in or a TOML file into its parsed tables
(``acdrive._toml`` validates them).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from acdrive._toml import parse_toml
from acdrive.drives._registry import builtin_packages
from acdrive.errors import InputError


def _builtin_folders() -> list:
    """Where built-in scenarios live: this package's ``builtin/`` (the papers' scenarios) and
    the ``scenarios/`` folder of each built-in drive's package (``drives/<kind>/scenarios``), so
    a drive added as one folder brings its scenarios with it."""
    folders = [resources.files("acdrive.scenarios") / "builtin"]
    for package in builtin_packages():
        folder = resources.files(package) / "scenarios"
        if folder.is_dir():
            folders.append(folder)
    return folders


def _builtin_files() -> dict:
    """Built-in scenario name -> its file; a name found twice is a packaging error."""
    files = {}
    for folder in _builtin_folders():
        for path in folder.iterdir():
            if not path.name.endswith(".toml"):
                continue
            name = path.name[:-5]
            if name in files:
                raise RuntimeError(f"built-in scenario {name!r} is in two folders")
            files[name] = path
    return files


def builtin_names() -> list[str]:
    return sorted(_builtin_files())


def builtin_text(name: str) -> str:
    return _builtin_files()[name].read_text()


def read_scenario(source: str | Path) -> dict:
    """Parse a scenario: a built-in name or a path to a TOML file."""
    source = str(source)
    if source in builtin_names():
        text, origin = builtin_text(source), source
    else:
        path = Path(source)
        if not path.is_file():
            raise InputError(
                "scenario",
                f"'{source}' is neither a built-in scenario ({', '.join(builtin_names())}) nor a file",
            )
        try:
            text, origin = path.read_text(encoding="utf-8"), str(path)
        except UnicodeDecodeError:
            raise InputError("scenario", f"{path} is not a UTF-8 text file") from None
        except OSError as exc:
            raise InputError("scenario", f"cannot read {path} ({exc.strerror})") from None
    return parse_toml(text, origin, "scenario")
