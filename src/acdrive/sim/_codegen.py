"""Generate, cache and load compiled modules: the specialised loop of one topology
(``sim._loop_source``) and the kernels of one part kind (``sim._kernels``).

A generated module is Python source whose globals are the parts' kernels; numba compiles its
functions once and caches the machine code on disk. The file name is the hash of the source
(which names every kernel and every offset), kept in the numba cache folder that
``acdrive/__init__.py`` keys by acdrive's own sources, so a second process loads the compiled code
instead of compiling it, and an edit of any acdrive source or of the topology gives a new file.

Damage is repaired, never a crash: a generated file whose text is not its source (truncated,
edited) is written again, and a numba cache file that cannot be read is removed and its function
compiled again, each with a one-line notice (``Notice``). Compile times are measured here
(``compile_for``) and kept per loop kind and size for the next compile notice
(``expected_compile``).
"""

from __future__ import annotations

import hashlib
import importlib.util
import inspect
import json
import os
import pickle
import sys
import tempfile
import time
import warnings
from pathlib import Path

from acdrive._cache import _cache_dir, cache_folder
from acdrive.errors import Notice, interrupt_held

_LOADED: dict[str, object] = {}
#: compile seconds measured in this process since the last ``record_compile_times``
_COMPILED_SECONDS: list[float] = []
#: where the measured compile times are kept, in the folder of the generated modules
_COMPILE_RECORD = "compile-times.json"
#: records kept per loop kind (the newest)
_RECORDS_KEPT = 20


def _folder() -> Path:
    return cache_folder("systems", "acdrive-systems")


def notice(message: str) -> None:
    """One line for the user (``Notice``), unless ACDRIVE_COMPILE_NOTICE=0 (scripts, tests)."""
    if os.environ.get("ACDRIVE_COMPILE_NOTICE", "1") != "0":
        warnings.warn(Notice(message), stacklevel=3)


def _write_atomically(path: Path, text: str) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
    try:
        with os.fdopen(fd, "w") as handle:
            handle.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def module_path(source: str) -> Path:
    """Where the generated ``source`` is kept."""
    digest = hashlib.sha256(source.encode()).hexdigest()[:20]
    return _folder() / f"acdrive_system_{digest}.py"


def load_module(source: str):
    """Import the generated ``source`` as a module, writing it once to the cache folder (again,
    with a notice, if the file there is not this source)."""
    path = module_path(source)
    name = path.stem
    if name in _LOADED:
        return _LOADED[name]
    try:
        found = path.read_text()
    except (OSError, UnicodeDecodeError):
        found = None
    if found != source:  # missing, or damaged: a rewrite voids numba's cache of it (mtime)
        if found is not None:
            notice(f"the cached module {path.name} was damaged; written again and recompiled")
        _write_atomically(path, source)
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    _LOADED[name] = module
    return module


def is_cached(dispatcher) -> bool:
    """Whether numba has an on-disk cache index for ``dispatcher`` (a load, not a compile, on its
    first call). False if that cannot be told (numba internals)."""
    try:
        return os.path.exists(dispatcher._cache._cache_file._index_path)
    except AttributeError:
        return False


def _cache_files(index: Path) -> list[Path]:
    """An index file and the data files it lists (numba names them ``<stem>.<n>.nbc``)."""
    stem = index.name.removesuffix(".nbi")
    return [index, *index.parent.glob(f"{stem}.*.nbc")]


def _unreadable_indexes(root: Path) -> list[Path]:
    """The numba index files under ``root`` that do not unpickle."""
    bad = []
    for index in root.rglob("*.nbi"):
        try:
            with open(index, "rb") as handle:
                pickle.load(handle)
                pickle.loads(handle.read())
        except Exception:  # noqa: BLE001 - any failure to read is damage
            bad.append(index)
    return bad


def _drop_damaged(dispatcher) -> int:
    """Remove the cache files that can make ``dispatcher``'s compile fail: every unreadable index
    in acdrive's cache folder and all files of ``dispatcher``'s own module (a damaged data file
    reads like any other until it is loaded). All are acdrive's: the folder is its own. Returns
    how many files were removed."""
    index = Path(dispatcher._cache._cache_file._index_path)
    module = index.name.split(".")[0]
    root = Path(_cache_dir()) if _cache_dir() else index.parent
    doomed = set(index.parent.glob(f"{module}.*.nbi")) | set(_unreadable_indexes(root))
    removed = 0
    for path in sorted({f for i in doomed for f in _cache_files(i)}):
        try:
            path.unlink()
            removed += 1
        except OSError:
            pass
    return removed


#: what a damaged cache file raises while numba loads it
_DAMAGE = (pickle.UnpicklingError, EOFError, ValueError, TypeError, AttributeError, ImportError,
           IndexError, KeyError, OSError)  # fmt: skip


def compile_for(dispatcher, signature) -> tuple[float, bool]:
    """Compile ``dispatcher`` for ``signature`` (a numba signature or a tuple of argument types)
    or load it from numba's cache: (seconds taken, True if it compiled). A cache file that cannot
    be read is removed and the function compiled again, with a one-line notice."""
    args = tuple(getattr(signature, "args", signature))
    if args in dispatcher.overloads:
        return 0.0, False
    hits = dispatcher.stats.cache_hits.total()
    start = time.perf_counter()
    with interrupt_held():  # llvmlite calls Python back from inside LLVM (errors.interrupt_held)
        try:
            dispatcher.compile(signature)
        except _DAMAGE as error:
            if not _drop_damaged(dispatcher):
                raise  # no cache file to blame: the code itself does not compile
            notice(
                f"a compiled-code cache file of {dispatcher.py_func.__module__}."
                f"{dispatcher.py_func.__name__} could not be read ({type(error).__name__}); "
                "removed, compiling again"
            )
            dispatcher.compile(signature)
    seconds = time.perf_counter() - start
    compiled = dispatcher.stats.cache_hits.total() == hits
    if compiled:
        _COMPILED_SECONDS.append(seconds)
    return seconds, compiled


def _records() -> dict:
    try:
        records = json.loads((_folder() / _COMPILE_RECORD).read_text())
        return records if isinstance(records, dict) else {}
    except (OSError, ValueError):
        return {}


def record_time(loop: str, size: int, seconds: float) -> None:
    """Keep the compile time of a ``loop`` (its kind: "specialised", "batch", ...) of
    ``size`` parts, measured on this machine, for later notices."""
    records = _records()
    kept = [r for r in records.get(loop, []) if isinstance(r, list) and len(r) == 2]
    records[loop] = [*kept, [int(size), float(seconds)]][-_RECORDS_KEPT:]
    try:
        _write_atomically(_folder() / _COMPILE_RECORD, json.dumps(records))
    except OSError:
        pass  # a read-only cache: the next notice has no estimate


def expected_time(loop: str, size: int) -> float | None:
    """The compile time [s] a ``loop`` of ``size`` parts is expected to take on this machine:
    the measured time of the recorded compile closest in size, scaled by size; None if none was
    measured."""
    kept = [r for r in _records().get(loop, []) if isinstance(r, list) and len(r) == 2]
    if not kept or size < 1:
        return None
    near_size, seconds = min(kept, key=lambda r: (abs(r[0] - size), -kept.index(r)))
    return float(seconds) * size / max(int(near_size), 1)


def record_compile_times() -> float:
    """Compile time [s] measured in this process since the last call (0 if nothing compiled)."""
    total = sum(_COMPILED_SECONDS)
    _COMPILED_SECONDS.clear()
    return total


def kernel_import(function, alias: str) -> str:
    """``from <module> import <name> as <alias>`` for a module-level numba function."""
    py = getattr(function, "py_func", None)
    if py is None:
        raise TypeError(f"{function!r} is not a numba-compiled function")
    if py.__qualname__ != py.__name__:
        raise TypeError(f"kernel {py.__qualname__} must be defined at module level")
    return f"from {py.__module__} import {py.__name__} as {alias}"


#: the imports ``inlined_kernel`` lines need in a generated module
INLINED_KERNEL_IMPORTS = (
    "from acdrive.sim._rebind import rebound_kernel",
    "from acdrive.sim._lane_math import LANE_MATH",
)


def inlined_kernel(alias: str, original: str, *tables: str) -> str:
    """The generated line that binds ``alias`` to the kernel ``original`` re-jitted for numba-IR
    inlining, with acdrive's sin, cos, |z| and sqrt (``sim._lane_math``: the same in every tier)
    and the further replacement ``tables`` named (``sim._rebind``)."""
    replaced = ", ".join((*tables, "LANE_MATH"))  # disjoint tables: the order does not matter
    return f'{alias} = njit(inline="always", error_model="numpy")(rebound_kernel({original}.py_func, {replaced}))'


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
