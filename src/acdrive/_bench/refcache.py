"""The accuracy references on disk, keyed by a hash of everything they are computed from.

A reference (``_bench.reference.accuracy``: Radau segment by segment, the extended-precision
sixth-order run and its half-substep twin) costs minutes per case and side, and depends only on
its inputs: the initial state and the held-segment sequence the simulator integrated (for a
peer, a function of its version, the case definition, the model time and its solver settings,
all of which it is recorded from), the reference's settings (tolerances, substeps), the
equations (the source of the module defining the model and its parameters) and the reference
code itself (``reference.py``). ``key`` hashes all of them, so any change of any input gives a
new key and a fresh computation; an unchanged input reuses the arrays, and a re-run of
``acdrive bench`` takes minutes instead of a quarter of an hour.

Entries are ``<key>.npz`` files in ``cache_dir()`` (``$XDG_CACHE_HOME/acdrive/bench-references``),
written to a temporary name and renamed, so an interrupted write leaves no entry. An entry
that cannot be read, or whose stored key differs from its name, is reported in one line and
recomputed (and rewritten); only ``*.npz`` entries of this folder are ever replaced.
"""

from __future__ import annotations

import hashlib
import inspect
import json
import os
import sys
import zipfile
from pathlib import Path

import numpy as np

#: bump when the stored layout changes
LAYOUT = 1


def cache_dir() -> Path:
    """``$XDG_CACHE_HOME/acdrive/bench-references``, else ``~/.cache/acdrive/bench-references``."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "acdrive" / "bench-references"


def _feed(digest, value) -> None:
    """Hash ``value`` with its type and shape: arrays by dtype, shape and bytes; dicts by sorted
    keys; lists and tuples item by item; everything else by its repr."""
    if isinstance(value, np.ndarray):
        a = np.ascontiguousarray(value)
        digest.update(f"array {a.dtype.str} {a.shape}".encode())
        digest.update(a.tobytes())
    elif isinstance(value, dict):
        digest.update(f"dict {len(value)}".encode())
        for k in sorted(value, key=str):
            _feed(digest, str(k))
            _feed(digest, value[k])
    elif isinstance(value, (list, tuple)):
        digest.update(f"seq {len(value)}".encode())
        for v in value:
            _feed(digest, v)
    else:
        digest.update(f"{type(value).__name__} {value!r}".encode())


def key(**inputs) -> str:
    """The hex SHA-256 of ``inputs`` (``_feed``) and the layout version."""
    digest = hashlib.sha256(f"acdrive bench reference, layout {LAYOUT}".encode())
    _feed(digest, inputs)
    return digest.hexdigest()


def model_identity(model) -> dict:
    """What a reference model's equations are: its class, the source of the module that defines
    it (the right-hand side, the load profile, the constants it reads) and its parameters."""
    module = sys.modules[type(model).__module__]
    params = {k: v for k, v in vars(model).items() if not callable(v)}
    return {
        "class": type(model).__qualname__,
        "module_source": inspect.getsource(module),
        "parameters": json.loads(json.dumps(params, default=repr)),
    }


def load(folder: Path, name: str, say) -> dict | None:
    """The arrays stored under ``name``, or None if there is no entry; an unreadable entry, or
    one whose stored key is not ``name``, is reported by ``say`` in one line and ignored."""
    path = Path(folder) / f"{name}.npz"
    if not path.exists():
        return None
    try:
        with np.load(path, allow_pickle=False) as f:
            arrays = {k: f[k] for k in f.files}
        if str(arrays.pop("_key", "")) != name:
            raise ValueError("stored key differs from the file name")
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
        say(f"reference cache: {path} is unreadable ({type(exc).__name__}: {exc}); recomputing")
        return None
    return arrays


def store(folder: Path, name: str, arrays: dict) -> Path | None:
    """Write ``arrays`` as ``<name>.npz`` (through a temporary file and a rename); None, and
    nothing left behind, if the folder cannot be written."""
    folder = Path(folder)
    path = folder / f"{name}.npz"
    tmp = folder / f".{name}.{os.getpid()}.tmp.npz"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        np.savez(tmp, _key=np.array(name), **arrays)
        os.replace(tmp, path)
    except OSError:
        tmp.unlink(missing_ok=True)
        return None
    return path


def cached(folder: Path | None, name: str, compute, say) -> tuple[dict, bool]:
    """``(arrays, True)`` from the entry ``name`` if it is readable, else ``(compute(), False)``
    with the result stored; ``folder`` None: always computed, nothing stored."""
    if folder is not None:
        got = load(folder, name, say)
        if got is not None:
            return got, True
    arrays = compute()
    if folder is not None:
        store(folder, name, arrays)
    return arrays, False
