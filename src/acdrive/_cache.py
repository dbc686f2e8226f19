"""Where acdrive keeps what it computed once for this machine: the generated modules of the
compiled loops, the native libraries, the discretised controllers. All in numba's cache folder,
which ``acdrive/__init__.py`` keys by the hash of acdrive's own sources (an edit or an upgrade
starts afresh), else in the temporary folder.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


def _cache_dir() -> str:
    """numba's cache folder (acdrive/__init__.py hands it over as NUMBA_CACHE_DIR before numba
    is imported; read from there while numba is not imported, so that this costs no import)."""
    import sys

    numba = sys.modules.get("numba")
    if numba is not None:
        return numba.config.CACHE_DIR
    return os.environ.get("NUMBA_CACHE_DIR", "")


def cache_folder(name: str, fallback: str) -> Path:
    """The folder ``name`` of acdrive's compiled code in numba's cache folder (keyed by acdrive's
    own sources), else ``fallback/name`` in the temporary folder; made if missing."""
    base = Path(_cache_dir()) if _cache_dir() else None
    for candidate in (base, Path(tempfile.gettempdir()) / fallback):
        if candidate is None:
            continue
        folder = candidate / name
        try:
            folder.mkdir(parents=True, exist_ok=True)
            return folder
        except OSError:
            continue
    raise OSError(f"no writable folder for acdrive's compiled code ({name})")
