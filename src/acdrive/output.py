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
   ``out`` folder itself if this run created it and left it empty.

Nothing outside ``out`` is ever deleted or overwritten.
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


class OutputFolder:
    """The folder ``<root>/<name>`` of one command's output, written via a staging sibling."""

    def __init__(self, root: str | Path, name: str, field: str = "--out"):
        self.name = require_safe_name("name", name)
        self.root = Path(root)
        self.target = self.root / self.name
        if self.root.exists() and not self.root.is_dir():
            raise InputError(field, f"'{self.root}' exists and is not a folder")
        if self.target.is_symlink() or (self.target.exists() and not self.target.is_dir()):
            raise InputError(
                field, f"'{self.target}' exists and is not a folder; refusing to replace it"
            )
        created = not self.root.exists()
        try:
            self.root.mkdir(parents=True, exist_ok=True)
            self.staging = Path(tempfile.mkdtemp(prefix=f".{self.name}.partial-", dir=self.root))
        except OSError as exc:
            raise InputError(field, f"cannot write to '{self.root}' ({exc.strerror})") from None
        self._created_root = created
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

    def discard(self) -> None:
        """Remove the staging folder (and the root if this run created it and it is empty)."""
        if self._done:
            return
        previous = _block_interrupts()
        try:
            if self.staging.exists():
                _remove(self.staging)
            if self._created_root:
                try:
                    self.root.rmdir()
                except OSError:
                    pass
            self._done = True
        finally:
            _restore_interrupts(previous)

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.discard()
