"""Running a sweep: chunks, the Parquet dataset, resuming, size checks and backends.

Output folder ``<out>/<name>/``:

* ``sweep.json`` -- the manifest: the sweep's digest (``SweepSpec.digest``), the number of
  variants and the chunk size, written (atomically) before the first chunk, and the command that
  runs (and resumes) it when the command line started it (``command``);
* ``table/chunk-NNNNNN.parquet`` -- one file per chunk of ``chunk`` consecutive variants,
  written to a temporary file in the same folder, flushed to disk and renamed into place
  (``os.replace``), so a chunk file exists complete or not at all;
* ``traces/chunk-NNNNNN.parquet`` -- decimated traces, if asked for (written before the chunk's
  table file, which is the chunk's "done" mark);
* ``report.md`` and ``figures/*.png`` (``sweep._report``).

**Resume.** Running the same sweep into the same folder again reads the manifest (a different
digest is refused: it would mix two sweeps), deletes left-over temporary files, checks each
finished chunk file (readable, holding exactly the variant ids expected for its index) and runs
only the missing chunks. A kill at any moment loses at most the chunks in progress and never
leaves a partial or duplicated one. Wherever a folder with unfinished chunks is met (a resume, a
refused second sweep, ``read_table``) the message says how many variants are done and the command
that resumes it (:func:`resume_hint`); ``acdrive sweep`` prints that command when interrupted.

**Bounded memory.** A chunk holds one row of scalars per variant (plus its decimated traces if
asked for); the batch loop logs nothing per sample otherwise (``acdrive.batch``). Before anything
runs, ``estimate`` sizes the table, the traces and the memory of a chunk, and the sweep is
refused (one-line ``InputError``) beyond ``[limits]`` or the free disk space.

**Backends.** ``local`` runs the chunks one after another in this process, each in the compiled
batch loop on all cores (numba ``prange`` over the chunk's variants). ``dask`` sends chunks to an
existing ``distributed`` scheduler (``--scheduler tcp://host:port``; at most two chunks in flight
per worker thread), connecting within ``timeout`` seconds or failing with one line; results come
back to this process, which alone writes the folder. A chunk's table does not depend on where it
ran (the same compiled loop, the same variant -> result function).
"""

from __future__ import annotations

import json
import math
import os
import shutil
import sys
from pathlib import Path

from acdrive._arguments import COUNT0, FLAG, PATH, POSITIVE, Instance, Text, checked, optional
from acdrive.errors import InputError
from acdrive.sweep import _variants as V
from acdrive.sweep._spec import SweepSpec, spec_from_payload

MANIFEST = "sweep.json"
CONNECT_TIMEOUT_S = 10.0
#: estimated bytes of one table row besides its metrics: ids, status, reason, event counts
ROW_OVERHEAD_BYTES = 8 * 40 + 200


def _chunk_name(c: int) -> str:
    return f"chunk-{c:06d}.parquet"


# --- one chunk -------------------------------------------------------------------------------


def _reducer_factory(spec: SweepSpec):
    from acdrive.batch import default_reducers

    def make(setup):
        return (default_reducers(setup) if spec.default_metrics else []) + list(spec.reducers)

    return make


def _pluck(summary: dict, path: str):
    from acdrive.batch import _segments

    node = summary
    for key, index in _segments(path):
        if not isinstance(node, dict) or key not in node:
            return math.nan
        node = node[key]
        if index is not None:
            if not isinstance(node, list) or index >= len(node):
                return math.nan
            node = node[index]
    if isinstance(node, bool):
        return float(node)
    if isinstance(node, (int, float)):
        return float(node)
    return json.dumps(node) if node is not None else math.nan


def _summary_metrics(spec: SweepSpec, overrides: dict) -> dict:
    """The ``summary.json`` keys of one variant: a full single run of its drive (``Drive.run``)."""
    import dataclasses

    from acdrive.batch import apply_overrides, build_variant_setup
    from acdrive.drives import for_setup

    setup = build_variant_setup(apply_overrides(spec.base_data, overrides))
    changes = {}
    if spec.integrator:
        changes["integrator"] = spec.integrator
    if spec.substeps:
        changes["substeps"] = spec.substeps
    setup = dataclasses.replace(setup, **changes) if changes else setup
    summary = for_setup(setup).run(setup).summary
    return {f"summary.{key}": _pluck(summary, key) for key in spec.summary}


def run_chunk(payload: dict, c: int):
    """(table, traces or None) of chunk ``c`` as pandas DataFrames: a pure function of the
    sweep's payload and the chunk index (it runs on any backend)."""
    import numpy as np
    import pandas as pd

    from acdrive.batch import simulate_batch

    spec = spec_from_payload(payload)
    n = V.count(spec)
    grids = [V.grid_values(v) for v in spec.vary] if spec.method == "grid" else None
    indices = list(V.chunk_range(spec, c, n))
    varied = [V.variant(spec, i, grids) for i in indices]
    overrides = [{**spec.fixed, **v} for v in varied]
    result = simulate_batch(
        spec.base_data,
        overrides,
        reducers=_reducer_factory(spec),
        log=list(spec.traces) or None,
        log_every=spec.trace_every or None,
        integrator=spec.integrator,
        substeps=spec.substeps,
    )
    rows = []
    for i, v, row, o in zip(indices, varied, result.rows, overrides, strict=True):
        out = {"variant_id": V.variant_id(i, v), "variant": i}
        out.update({f"vary.{k}": value for k, value in v.items()})
        out.update({k: value for k, value in row.items() if k != "variant"})
        if spec.summary:
            if row["status"] == "ok":
                out.update(_summary_metrics(spec, o))
            else:
                out.update({f"summary.{k}": math.nan for k in spec.summary})
        rows.append(out)
    table = pd.DataFrame(rows)
    table.attrs["units"] = table_units(table.columns, result.units)
    for name in table.columns:
        if name == "stable":
            table[name] = table[name].astype("boolean")
        elif name.startswith("events.") or (
            name not in ("variant", "valid")
            and pd.api.types.is_numeric_dtype(table[name])
            and not pd.api.types.is_bool_dtype(table[name])
        ):
            table[name] = table[name].astype(np.float64)
    traces = None
    if spec.traces:
        parts = []
        for i, v in zip(indices, varied, strict=True):
            tr = result.traces.get(i - indices[0])
            if tr is None:
                continue
            frame = pd.DataFrame(tr.data, columns=tr.columns)
            frame.insert(0, "t", tr.t)
            frame.insert(0, "variant_id", V.variant_id(i, v))
            parts.append(frame)
        traces = pd.concat(parts, ignore_index=True) if parts else None
        if traces is not None:
            trace_units = {"t": "s", **result.traces[next(iter(result.traces))].units}
            traces.attrs["units"] = {c: trace_units.get(c, "") for c in traces.columns}
    return table, traces


def table_units(columns, metric_units: dict) -> dict[str, str]:
    """Column -> unit of a sweep table: the batch's metric units (``BatchResult.units``), and
    for ``vary.<field>`` and ``summary.<key>`` the unit their name declares
    (``acdrive.columns.unit_from_name``: scenario fields and summary keys end with their unit);
    "" for identifiers, flags, counts and text."""
    from acdrive.columns import unit_from_name

    out = {}
    for name in columns:
        if name.startswith(("vary.", "summary.")):
            out[name] = unit_from_name(name.rsplit(".", 1)[-1])
        else:
            out[name] = metric_units.get(name, "")
    return out


# --- sizes -----------------------------------------------------------------------------------


def _base_timing(spec: SweepSpec) -> tuple[float, float]:
    """(longest duration, sample time) of the sweep's runs, from the base, the fixed overrides
    and the varied fields (the largest value a varied duration may take)."""
    from acdrive.batch import apply_overrides, get_field

    fixed = {k: v for k, v in spec.fixed.items() if not k.startswith(("part:", "initial:"))}
    data = apply_overrides(spec.base_data, fixed)
    duration = get_field(data, "simulation.duration")
    duration = 1.0 if duration is None else duration  # the loaders' default
    sample_time = get_field(data, "simulation.sample_time") or 200e-6
    for v in spec.vary:
        if v.field == "simulation.duration":
            top = max(V.grid_values(v)) if v.values is not None else v.high
            duration = max(duration, top)
    return float(duration), float(sample_time)


@checked(spec=Instance(SweepSpec), n=optional(COUNT0))
def estimate(spec: SweepSpec, n: int | None = None) -> dict:
    """Bytes of the table, of the traces and of memory, estimated before anything runs."""
    n = V.count(spec) if n is None else n
    metrics = 3 * len(spec.reducers) + len(spec.summary) + (30 if spec.default_metrics else 0)
    row = ROW_OVERHEAD_BYTES + 8 * (metrics + len(spec.vary))
    table = n * row
    traces = 0
    per_chunk_traces = 0
    if spec.traces:
        duration, sample_time = _base_timing(spec)
        rows = math.ceil(duration / sample_time / spec.trace_every)
        per_variant = rows * (2 * len(spec.traces) + 2) * 8 + rows * 40
        traces = n * per_variant
        per_chunk_traces = min(spec.chunk, n) * per_variant * 3  # log, frame, Parquet buffer
    memory = table + per_chunk_traces  # the report reads the whole table back
    return {"variants": n, "table_bytes": table, "trace_bytes": traces, "memory_bytes": memory}


def check_size(spec: SweepSpec, folder: Path, n: int) -> dict:
    """Refuse a sweep beyond ``[limits]`` or the free disk space (``InputError``)."""
    field = "sampling.samples" if spec.method == "random" else "vary"
    limits = spec.limits
    if n > limits["max_variants"]:
        raise InputError(
            field, f"{n:.4g} variants exceed limits.max_variants = {limits['max_variants']}"
        )
    e = estimate(spec, n)
    disk = e["table_bytes"] + e["trace_bytes"]
    mb = 1024**2
    if disk > limits["max_table_mb"] * mb:
        raise InputError(
            field,
            f"{n:.4g} variants would write about {disk / mb:.4g} MB "
            f"(limits.max_table_mb = {limits['max_table_mb']:g}): fewer variants or traces",
        )
    probe = folder
    while not probe.exists():
        probe = probe.parent
    free = shutil.disk_usage(probe).free
    if disk > 0.9 * free:
        raise InputError(
            field, f"{n:.4g} variants would write about {disk / mb:.4g} MB, more than 90 % of "
            f"the {free / mb:.4g} MB free on {probe}"
        )  # fmt: skip
    if e["memory_bytes"] > limits["max_memory_mb"] * mb:
        raise InputError(
            field,
            f"the sweep would need about {e['memory_bytes'] / mb:.4g} MB of memory "
            f"(limits.max_memory_mb = {limits['max_memory_mb']:g}): fewer variants, a smaller "
            "chunk or fewer traces",
        )
    return e


# --- files -----------------------------------------------------------------------------------


#: Parquet schema metadata key of a sweep table's units (JSON: column -> unit)
UNITS_KEY = b"acdrive.units"


def write_atomic(frame, path: Path) -> None:
    """Write ``frame`` as Parquet at ``path``: a temporary file in the same folder, flushed to
    disk, then renamed over ``path`` (complete or absent, whenever the process dies). The units
    of ``frame.attrs["units"]`` go into the schema metadata (``UNITS_KEY``) and each field's
    metadata (``unit``), as ``acdrive.columns`` writes a run's table."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    units = {str(c): frame.attrs.get("units", {}).get(c, "") for c in frame.columns}
    table = pa.Table.from_pandas(frame, preserve_index=False)
    fields = [f.with_metadata({"unit": units[f.name]}) for f in table.schema]
    meta = {**(table.schema.metadata or {}), UNITS_KEY: json.dumps(units)}
    pq.write_table(table.cast(pa.schema(fields, metadata=meta)), tmp)
    with open(tmp, "rb") as handle:
        os.fsync(handle.fileno())
    os.replace(tmp, path)


def _write_json_atomic(value: dict, path: Path) -> None:
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps(value, indent=2) + "\n")
    os.replace(tmp, path)


LOCK = ".acdrive-lock"


def _open_folder(folder: Path) -> None:
    """Check the sweep folder ``folder`` (``<out>/<name>``) and create it: it must not be a
    symbolic link (``--out`` itself may be one) and, if it exists, be a folder acdrive wrote (its
    marker, or the manifest of a sweep written before markers existed) or empty."""
    from acdrive._output import MARKER, is_acdrive_folder, not_ours

    if folder.is_symlink():
        raise InputError("out", f"{folder} is a symbolic link; refusing to write through it")
    if folder.exists() and not folder.is_dir():
        raise InputError("out", f"{folder} exists and is not a folder")
    if folder.exists() and not is_acdrive_folder(folder):
        legacy = (folder / MANIFEST).is_file()
        if not legacy and any(folder.iterdir()):
            raise not_ours("out", folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError("out", f"cannot create {folder} ({exc.strerror})") from None
    if not (folder / MARKER).exists():
        from acdrive._output import write_marker

        write_marker(folder)


class _Lock:
    """An exclusive lock on a sweep folder for the whole run (``flock`` on its file
    :data:`LOCK`, released by the system when the process ends, however it ends): a second sweep
    into the same folder is refused with one line and touches nothing."""

    def __init__(self, folder: Path):
        import fcntl

        self.path = folder / LOCK
        self._fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o666)
        try:
            fcntl.flock(self._fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            holder = os.read(self._fd, 32).decode(errors="replace").strip() or "unknown"
            os.close(self._fd)
            raise InputError(
                "out", f"{folder} is in use by another sweep (process {holder}): wait for it to "
                "finish or choose another folder"
            ) from None  # fmt: skip
        os.ftruncate(self._fd, 0)
        os.write(self._fd, str(os.getpid()).encode())

    def release(self) -> None:
        if self._fd is not None:
            os.close(self._fd)  # closing the descriptor releases the flock
            self._fd = None

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.release()


def sweep_progress(folder: Path) -> tuple[int, int] | None:
    """(variants in finished chunk files, variants of the sweep) of the sweep folder ``folder``
    from its manifest and chunk file names, or None without a readable manifest. Names only:
    the contents are checked when the sweep resumes (:func:`finished_chunks`)."""
    try:
        manifest = json.loads((Path(folder) / MANIFEST).read_text())
        n, chunk = int(manifest["variants"]), int(manifest["chunk"])
    except (OSError, ValueError, KeyError, TypeError):
        return None
    done = 0
    for path in (Path(folder) / "table").glob("chunk-*.parquet"):
        try:
            c = int(path.stem.split("-")[1])
        except (ValueError, IndexError):
            continue
        if 0 <= c * chunk < n:
            done += min(chunk, n - c * chunk)
    return done, n


def resume_hint(folder: Path) -> str:
    """``"K of N variants done; resume with: COMMAND"`` for a sweep folder with unfinished chunks
    (the command its manifest recorded; "run the same sweep into the same --out" if none was),
    or "" for a finished folder or one that holds no sweep."""
    state = sweep_progress(folder)
    if state is None or state[0] >= state[1]:
        return ""
    try:
        command = json.loads((Path(folder) / MANIFEST).read_text()).get("command")
    except (OSError, ValueError):
        command = None
    how = f"resume with: {command}" if command else "resume by running the same sweep into the "
    how = how if command else how + f"same --out ({Path(folder).parent})"
    return f"{state[0]} of {state[1]} variants done; {how}"


def _prepare_folder(spec: SweepSpec, folder: Path, n: int, command: str | None = None) -> int:
    """Open the (locked) sweep folder: write or check its manifest and remove the temporary
    files of an interrupted run; returns the chunk size in force (the manifest's on a resume,
    so chunk files stay aligned). A manifest of a different sweep is refused unless the folder
    holds no finished chunk yet (then nothing of value is lost: the sweep starts over)."""
    manifest = folder / MANIFEST
    chunk = None
    if manifest.exists():
        try:
            old = json.loads(manifest.read_text())
        except (OSError, ValueError):
            raise InputError("out", f"{manifest} is unreadable: choose another folder") from None
        started = any((folder / "table").glob("chunk-*.parquet"))
        if old.get("digest") == spec.digest() and old.get("variants") == n:
            chunk = int(old["chunk"])
        elif started:
            hint = resume_hint(folder)
            raise InputError(
                "out", f"{folder} holds a different sweep (its file or base scenario changed): "
                "choose another folder or delete that one"
                + (f" (that sweep is unfinished: {hint})" if hint else "")
            )  # fmt: skip
        if chunk is not None and command and old.get("command") != command:
            _write_json_atomic({**old, "command": command}, manifest)
    if chunk is None:
        chunk = spec.chunk
        _write_json_atomic(
            {"name": spec.name, "digest": spec.digest(), "variants": n, "chunk": chunk,
             "base": spec.base, **({"command": command} if command else {})},
            manifest,
        )  # fmt: skip
    for sub in ("table", "traces"):
        (folder / sub).mkdir(exist_ok=True)
        for stale in (folder / sub).glob(".*.tmp"):
            stale.unlink()
    for stale in folder.glob(".*.tmp"):
        stale.unlink()
    return chunk


def finished_chunks(spec: SweepSpec, folder: Path, n: int) -> set[int]:
    """Chunks whose table file holds exactly the expected variant ids (others are removed and
    run again)."""
    import pyarrow.parquet as pq

    grids = [V.grid_values(v) for v in spec.vary] if spec.method == "grid" else None
    n_chunks = math.ceil(n / spec.chunk)
    done = set()
    for path in sorted((folder / "table").glob("chunk-*.parquet")):
        try:
            c = int(path.stem.split("-")[1])
            ids = pq.read_table(path, columns=["variant_id"]).column(0).to_pylist()
        except (ValueError, OSError, KeyError, IndexError):
            path.unlink()
            continue
        expected = [V.variant_id(i, V.variant(spec, i, grids)) for i in V.chunk_range(spec, c, n)]
        if c >= n_chunks or ids != expected:
            path.unlink()
            continue
        done.add(c)
    return done


@checked(folder=PATH)
def read_table(folder: Path):
    """The sweep's table: every finished chunk, in variant order. A folder with unfinished chunks
    gives its finished variants and a :class:`~acdrive.errors.Notice` saying how to resume."""
    import warnings

    import pandas as pd

    from acdrive.errors import Notice

    hint = resume_hint(folder)
    if hint:
        warnings.warn(f"sweep {Path(folder).name} is unfinished: {hint}", Notice, stacklevel=2)
    files = sorted((Path(folder) / "table").glob("chunk-*.parquet"))
    if not files:
        return pd.DataFrame()
    import pyarrow.parquet as pq

    frames = [pd.read_parquet(f) for f in files]
    units = {}
    for f in files:
        units.update(json.loads((pq.read_schema(f).metadata or {}).get(UNITS_KEY, b"{}")))
    table = pd.concat(frames, ignore_index=True)
    table = table.sort_values("variant", kind="stable").reset_index(drop=True)
    table.attrs["units"] = {c: units.get(c, "") for c in table.columns}
    return table


# --- backends --------------------------------------------------------------------------------


def _local(payload, pending):
    for c in pending:
        yield c, run_chunk(payload, c)


def connect(address: str, timeout: float = CONNECT_TIMEOUT_S):
    """A ``distributed.Client`` of the scheduler at ``address``, or a one-line ``InputError``
    after at most ``timeout`` seconds."""
    if not isinstance(address, str) or not address.startswith(("tcp://", "tls://", "inproc://")):
        raise InputError("scheduler", "must be an address such as tcp://host:8786")
    try:
        from distributed import Client
    except ImportError:
        raise InputError(
            "scheduler", "needs dask.distributed: pip install 'acdrive[dask]'"
        ) from None
    import logging

    logging.getLogger("distributed").setLevel(logging.CRITICAL)  # one line, not a log
    try:
        return Client(address, timeout=f"{timeout}s", set_as_default=False)
    except (OSError, TimeoutError) as exc:
        raise InputError(
            "scheduler",
            f"no Dask scheduler answered at {address} within {timeout:g} s ({type(exc).__name__})",
        ) from None


def _dask(payload, pending, client):
    from distributed import as_completed

    threads = max(sum(client.nthreads().values()), 1)
    queue = list(pending)
    if not queue:
        return
    chunk_of = {}

    def submit():
        c = queue.pop(0)
        future = client.submit(run_chunk, payload, c, pure=False)
        chunk_of[future.key] = c
        return future

    with client.as_current():  # as_completed looks for the current client
        window = as_completed([submit() for _ in range(min(2 * threads, len(queue)))])
        for future in window:
            c = chunk_of.pop(future.key)
            result = future.result()
            future.release()
            if queue:
                window.add(submit())
            yield c, result


# --- the sweep -------------------------------------------------------------------------------


@checked(
    spec=Instance(SweepSpec), out=PATH, scheduler=Text(optional=True), timeout=POSITIVE,
    progress=FLAG, report=FLAG, command=Text(optional=True),
)
def run_sweep(spec: SweepSpec, out: Path, *, scheduler: str | None = None,
              timeout: float = CONNECT_TIMEOUT_S, progress: bool = True,
              report: bool = True, command: str | None = None) -> Path:  # fmt: skip
    """Run (or resume) ``spec`` into ``out/<name>``; returns that folder. ``command`` (the
    shell command that runs this sweep, given by ``acdrive sweep``) is kept in the manifest, so
    every later message about the unfinished folder can quote it."""
    from acdrive._output import require_out

    folder = require_out("out", out) / spec.name
    n = V.count(spec)
    if n < 1:
        raise InputError("vary", "gives no variant")
    check_size(spec, folder, n)
    client = connect(scheduler, timeout) if scheduler else None  # fail before writing
    lock = None
    try:
        _open_folder(folder)
        lock = _Lock(folder)
        chunk = _prepare_folder(spec, folder, n, command)
        if chunk != spec.chunk:
            import dataclasses

            spec = dataclasses.replace(spec, chunk=chunk)
        done = finished_chunks(spec, folder, n)
        n_chunks = math.ceil(n / spec.chunk)
        pending = [c for c in range(n_chunks) if c not in done]
        finished = sum(len(V.chunk_range(spec, c, n)) for c in done)
        if done and pending:
            import warnings

            from acdrive.errors import Notice

            warnings.warn(
                f"resuming sweep {spec.name}: {finished} of {n} variants were done, running the "
                f"other {n - finished}", Notice, stacklevel=2,
            )  # fmt: skip
        payload = spec.to_payload()
        from tqdm import tqdm

        bar = tqdm(total=n, initial=finished, unit="variant", file=sys.stderr,
                   disable=not progress, desc=spec.name)  # fmt: skip
        stream = _local(payload, pending) if client is None else _dask(payload, pending, client)
        for c, (table, traces) in stream:
            if traces is not None:
                write_atomic(traces, folder / "traces" / _chunk_name(c))
            write_atomic(table, folder / "table" / _chunk_name(c))
            bar.update(len(table))
        bar.close()
        if report:
            from acdrive.sweep._report import write_report

            write_report(spec, folder, read_table(folder))
    finally:
        if client is not None:
            client.close()
        if lock is not None:
            lock.release()
    return folder
