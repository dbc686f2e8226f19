"""Generate, cache and load the compiled loop of one system topology.

The loop is written as Python source whose globals are the parts' kernels and whose slot offsets
are literal constants taken from the parts' declarations; numba compiles it once and caches the
machine code on disk. The file name is the hash of the source (which names every kernel and every
offset), kept in the numba cache folder that ``acdrive/__init__.py`` keys by acdrive's own sources,
so a second process loads the compiled loop instead of compiling it, and an edit of any acdrive
source or of the topology gives a new file.
"""

from __future__ import annotations

import hashlib
import importlib.util
import inspect
import json
import os
import sys
import tempfile
import warnings
from pathlib import Path

import numba

from acdrive.errors import Notice

_LOADED: dict[str, object] = {}
#: generated modules whose loop is compiled in this process (not loaded from numba's cache)
_COMPILING: list[object] = []
#: where the last compile time is kept, in the folder of the generated modules
_COMPILE_RECORD = "last-compile.json"


def _folder() -> Path:
    base = Path(numba.config.CACHE_DIR) if numba.config.CACHE_DIR else None
    for candidate in (base, Path(tempfile.gettempdir()) / "acdrive-systems"):
        if candidate is None:
            continue
        folder = candidate / "systems"
        try:
            folder.mkdir(parents=True, exist_ok=True)
            return folder
        except OSError:
            continue
    raise OSError("no writable folder for the compiled system")


def load_module(source: str):
    """Import the generated ``source`` as a module, writing it once to the cache folder."""
    digest = hashlib.sha256(source.encode()).hexdigest()[:20]
    if digest in _LOADED:
        return _LOADED[digest]
    name = f"acdrive_system_{digest}"
    path = _folder() / f"{name}.py"
    if not path.exists():  # written once: a rewrite would change mtime and void numba's cache
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
        with os.fdopen(fd, "w") as handle:
            handle.write(source)
        os.replace(tmp, path)
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    _LOADED[digest] = module
    if _needs_compile(module):
        _COMPILING.append(module)
        if os.environ.get("ACDRIVE_COMPILE_NOTICE", "1") != "0":  # "0": scripts, the test suite
            warnings.warn(Notice(_compile_notice(path.parent)), stacklevel=2)
    return module


def _needs_compile(module) -> bool:
    """Whether numba has no cached machine code for the loop ``module.run`` (its cache index file
    is missing): the first call compiles. False if that cannot be told (numba internals)."""
    try:
        return not os.path.exists(module.run._cache._cache_file._index_path)
    except AttributeError:
        return False


def _compile_notice(folder: Path) -> str:
    """The one-line notice that the loop is compiled now, with the last compile time measured in
    ``folder`` (``record_compile_times``) if there is one."""
    try:
        seconds = float(json.loads((folder / _COMPILE_RECORD).read_text())["seconds"])
        about = f"about {seconds:.2g} s as the last time; "
    except (OSError, ValueError, KeyError, TypeError):
        about = ""
    return f"compiling the simulation loop for this drive once ({about}later runs load it)"


def record_compile_times() -> float:
    """Compile time [s] of the loops compiled in this process since the last call (numba's own
    timers of every compiled signature), kept in the generated modules' folder for the next
    compile notice; 0 if none was compiled."""
    total = 0.0
    while _COMPILING:
        module = _COMPILING.pop()
        for function in (getattr(module, "run", None), getattr(module, "run_batch", None)):
            for signature in getattr(function, "signatures", ()):
                try:
                    timers = function.get_metadata(signature)["timers"]
                except (KeyError, AttributeError):
                    continue
                total += float(timers.get("compiler_lock", 0.0))
    if total > 0.0:
        try:
            (_folder() / _COMPILE_RECORD).write_text(json.dumps({"seconds": total}))
        except OSError:
            pass  # a read-only cache: the next notice has no estimate
    return total


def kernel_import(function, alias: str) -> str:
    """``from <module> import <name> as <alias>`` for a module-level numba function."""
    py = getattr(function, "py_func", None)
    if py is None:
        raise TypeError(f"{function!r} is not a numba-compiled function")
    if py.__qualname__ != py.__name__:
        raise TypeError(f"kernel {py.__qualname__} must be defined at module level")
    return f"from {py.__module__} import {py.__name__} as {alias}"


def kernel_fingerprint(function) -> str | None:
    """A hash of the source a kernel from outside acdrive is compiled from, or None for acdrive's
    own kernels (the cache folder is keyed by acdrive's sources already).

    The generated loop inlines its kernels, so numba's cache of the loop does not see an edit of a
    kernel defined elsewhere (a user's module, a test file); the fingerprint in the generated
    source makes such an edit a new source, hence a new cache entry. It hashes the kernel's whole
    module file (the kernel may call helpers defined beside it), or the function's code object
    when there is no file (a notebook cell).
    """
    py = function.py_func
    if py.__module__ == "acdrive" or py.__module__.startswith("acdrive."):
        return None
    digest = hashlib.sha256()
    try:
        path = inspect.getsourcefile(py)
        digest.update(Path(path).read_bytes() if path else b"")
    except (OSError, TypeError):
        path = None
    if not path:
        code = py.__code__
        digest.update(code.co_code + repr(code.co_consts).encode() + repr(code.co_names).encode())
    return digest.hexdigest()[:16]
