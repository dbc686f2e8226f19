"""acdrive: AC-machine drives -- models, controller design and analysis, compiled simulation."""

__version__ = "0.1.0"


def _configure_numba_cache() -> None:
    """Give numba's on-disk cache a folder keyed by the hash of acdrive's own sources.

    Numba keys a cached function by its own file only; a compiled caller keeps the machine code of
    a callee from another file even after that file changes. Keying the whole cache folder by the
    content of every acdrive source file makes a stale mix impossible (after an edit or an upgrade
    the first run compiles again). A NUMBA_CACHE_DIR set by the user is left alone.

    Importing acdrive does not import numba (``acdrive --help`` stays fast): before numba is
    imported the folder is handed over as NUMBA_CACHE_DIR, which numba reads when it is
    imported, with ACDRIVE_NUMBA_CACHE_DIR marking it as acdrive's own, so a child process
    (which inherits both) keys its cache by its own sources again instead of taking the folder
    for the user's. If numba is imported already, its configuration is set directly.
    """
    import hashlib
    import os
    import sys
    from pathlib import Path

    given = os.environ.get("NUMBA_CACHE_DIR")
    if given and given != os.environ.get("ACDRIVE_NUMBA_CACHE_DIR"):
        return  # the user's choice
    package = Path(__file__).resolve().parent
    digest = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        digest.update(path.relative_to(package).as_posix().encode())
        digest.update(path.read_bytes())
    if os.environ.get("ACDRIVE_STRICT_MATH") == "1":  # see acdrive._jit.STRICT_MATH
        digest.update(b"strict math")
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    folder = base / "acdrive" / f"numba-{digest.hexdigest()[:16]}"
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return  # read-only home: numba falls back to its default locations
    if "numba" in sys.modules:
        sys.modules["numba"].config.CACHE_DIR = str(folder)
    else:
        os.environ["NUMBA_CACHE_DIR"] = os.environ["ACDRIVE_NUMBA_CACHE_DIR"] = str(folder)


_configure_numba_cache()
