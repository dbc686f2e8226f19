"""Safe output folders: validated names, checked before any work, replaced atomically.

A command that writes results into ``<out>/<name>/`` goes through :class:`OutputFolder`:

1. ``OutputFolder(out, name)`` validates ``name`` as one safe path component (no separators,
   not ``.`` or ``..``, no leading dot) and checks ``out`` *before* any simulation: it must be a
   folder or creatable, writable (a staging folder is created in it right away), and an existing
   ``<out>/<name>`` must be a real folder (not a file or a symbolic link).
2. The caller writes everything into :attr:`OutputFolder.staging`, a hidden sibling of the target.
3. :meth:`OutputFolder.publish` swaps the staging folder into place with SIGINT/SIGTERM blocked,
   so an interruption at any moment leaves the complete old output or the complete new one.
   :meth:`OutputFolder.discard` (also called on any exception) removes the staging folder and the
   ``out`` folder itself (and any parent folders) if this run created it and left it empty.

Nothing outside ``out`` is ever deleted or overwritten.

:class:`OutputEntries` does the same for a command whose output is several named entries side by
side in ``out`` (``acdrive reproduce`` writes ``<paper>.md`` beside the folder ``<paper>/``): they
are staged together and swapped together, with SIGINT/SIGTERM blocked, so an interruption leaves
all old entries or all new ones.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import signal
import tempfile
from pathlib import Path

from acdrive.errors import InputError, require_safe_name


def finite_or_null(value):
    """``value`` with every non-finite float (NaN, +-infinity) replaced by None, recursively
    through dicts, lists and tuples; numpy scalars and arrays become plain Python values."""
    if isinstance(value, dict):
        return {k: finite_or_null(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite_or_null(v) for v in value]
    if hasattr(value, "tolist") and not isinstance(value, (str, bytes)):  # numpy scalar / array
        return finite_or_null(value.tolist())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def strict_json(value, **kwargs) -> str:
    """JSON text that every parser accepts: non-finite numbers are written as null (RFC 8259
    has no NaN or Infinity)."""
    return json.dumps(finite_or_null(value), allow_nan=False, **kwargs)


def _block_interrupts():
    if hasattr(signal, "pthread_sigmask"):
        return signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    return None


def _restore_interrupts(previous) -> None:
    if previous is not None:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def _remove(path: Path) -> None:
    """Remove a file, a symbolic link (not its target) or a folder tree."""
    if path.is_symlink() or not path.is_dir():
        path.unlink(missing_ok=True)
    else:
        shutil.rmtree(path)


def _make_staging(root: Path, name: str, field: str) -> tuple[Path, list[Path]]:
    """Create ``root`` if needed and a hidden staging folder in it; return the staging folder and
    the folders this created (``root`` first, then its new parents)."""
    created = []
    folder = root
    while not folder.exists() and not folder.is_symlink() and folder != folder.parent:
        created.append(folder)
        folder = folder.parent
    try:
        root.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(prefix=f".{name}.partial-", dir=root))
    except OSError as exc:
        for made in created:  # undo a partly created path
            try:
                made.rmdir()
            except OSError:
                break
        raise InputError(field, f"cannot write to '{root}' ({exc.strerror})") from None
    return staging, created


class _Staged:
    """Shared clean-up of a staging folder: ``staging``, ``root``, ``_created`` (folders this
    run created for ``root``, innermost first), ``_done``."""

    staging: Path
    root: Path
    _created: list[Path]
    _done: bool

    def discard(self) -> None:
        """Remove the staging folder, and the folders this run created for the root while they
        are empty."""
        if self._done:
            return
        previous = _block_interrupts()
        try:
            if self.staging.exists():
                _remove(self.staging)
            for folder in self._created:
                try:
                    folder.rmdir()
                except OSError:
                    break
            self._done = True
        finally:
            _restore_interrupts(previous)

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.discard()


class OutputFolder(_Staged):
    """The folder ``<root>/<name>`` of one command's output, written via a staging sibling."""

    def __init__(self, root: str | Path, name: str, field: str = "--out", name_field: str = "name"):
        self.name = require_safe_name(name_field, name)
        self.root = Path(root)
        self.target = self.root / self.name
        if self.root.exists() and not self.root.is_dir():
            raise InputError(field, f"'{self.root}' exists and is not a folder")
        if self.target.is_symlink() or (self.target.exists() and not self.target.is_dir()):
            raise InputError(
                field, f"'{self.target}' exists and is not a folder; refusing to replace it"
            )
        self.staging, self._created = _make_staging(self.root, self.name, field)
        self._done = False

    def publish(self) -> Path:
        """Move the staging folder into place, replacing an old output; return the target."""
        previous = _block_interrupts()
        try:
            backup = None
            if self.target.exists():
                backup = Path(tempfile.mkdtemp(prefix=f".{self.name}.old-", dir=self.root))
                os.rename(self.target, backup / self.name)
            os.rename(self.staging, self.target)
            self._done = True
            if backup is not None:
                shutil.rmtree(backup)
        finally:
            _restore_interrupts(previous)
        return self.target


#: kinds of entry an :class:`OutputEntries` holds
FILE, FOLDER = "file", "folder"


def _is_kind(path: Path, kind: str) -> bool:
    if path.is_symlink():
        return False
    return path.is_dir() if kind == FOLDER else path.is_file()


class OutputEntries(_Staged):
    """Several named entries ``<root>/<name>`` (files or folders) written and replaced together.

    ``entries`` maps each name to :data:`FILE` or :data:`FOLDER`. The checks are those of
    :class:`OutputFolder`, made before any work: every name is one safe path component, ``root``
    is a folder or creatable and writable, and an existing entry must be of its declared kind
    (never a symbolic link), else it is refused rather than replaced. The caller writes the
    entries into :attr:`staging`; :meth:`publish` requires exactly the declared entries there (a
    writer that left one out or added another is a bug: the old output is kept) and swaps them in
    with SIGINT/SIGTERM blocked, putting the old ones back if a rename fails. Only a hard kill
    (SIGKILL, power loss) between two renames could leave a mix; the old entries then remain in a
    hidden ``.<name>.old-*`` folder in ``root``.
    """

    def __init__(
        self, root: str | Path, entries: dict[str, str], field: str = "--out",
        name_field: str = "name",
    ):  # fmt: skip
        if not entries:
            raise ValueError("OutputEntries needs at least one entry")
        self.entries = {require_safe_name(name_field, n): kind for n, kind in entries.items()}
        self.root = Path(root)
        if self.root.exists() and not self.root.is_dir():
            raise InputError(field, f"'{self.root}' exists and is not a folder")
        for name, kind in self.entries.items():
            target = self.root / name
            if (target.exists() or target.is_symlink()) and not _is_kind(target, kind):
                raise InputError(
                    field, f"'{target}' exists and is not a {kind}; refusing to replace it"
                )
        self._first = next(iter(self.entries))
        self.staging, self._created = _make_staging(self.root, self._first, field)
        self._done = False

    def target(self, staged: str | Path) -> Path:
        """Where a path inside the staging folder ends up once published (other paths as given)."""
        staged = Path(staged)
        try:
            return self.root / staged.relative_to(self.staging)
        except ValueError:
            return staged

    def _check_staged(self) -> None:
        present = {p.name for p in self.staging.iterdir()}
        missing = [n for n, kind in self.entries.items() if not _is_kind(self.staging / n, kind)]
        extra = sorted(present - set(self.entries))
        if missing or extra:
            raise RuntimeError(
                "the output writer did not produce exactly "
                + ", ".join(f"{n} ({k})" for n, k in self.entries.items())
                + (f"; missing {', '.join(missing)}" if missing else "")
                + (f"; unexpected {', '.join(extra)}" if extra else "")
                + "; the old output is unchanged"
            )

    def publish(self) -> list[Path]:
        """Swap every staged entry into place, replacing the old ones; return the targets."""
        self._check_staged()
        previous = _block_interrupts()
        try:
            backup = Path(tempfile.mkdtemp(prefix=f".{self._first}.old-", dir=self.root))
            moved_old, moved_new = [], []
            try:
                for name in self.entries:
                    target = self.root / name
                    if target.exists() or target.is_symlink():
                        os.rename(target, backup / name)
                        moved_old.append(name)
                for name in self.entries:
                    os.rename(self.staging / name, self.root / name)
                    moved_new.append(name)
            except OSError:
                for name in reversed(moved_new):  # undo: new entries back, old ones restored
                    os.rename(self.root / name, self.staging / name)
                for name in reversed(moved_old):
                    os.rename(backup / name, self.root / name)
                shutil.rmtree(backup)
                raise
            self._done = True
            shutil.rmtree(backup)
            shutil.rmtree(self.staging)
        finally:
            _restore_interrupts(previous)
        return [self.root / name for name in self.entries]
