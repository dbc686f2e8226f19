"""A function mapped over a list on all cores: forked workers take shares, the parent one too.

For CPU-bound Python work on many independent items, such as preparing a batch's variants
(``acdrive.batch``: each variant's scenario validated, its system built and packed, about 1.5 ms
each, while the compiled loop waits). ``fork`` starts a worker with the parent's memory, so
nothing is imported again and neither the function nor the items need to be picklable; only the
results travel back, pickled through a pipe. The items are split into contiguous shares in
order, the parent works through the first share while the workers do the others, and the
results come back in the order of the items: the same list as ``[fn(x) for x in items]``.

It runs serially, in the parent, off Linux, in a daemonic process, with one core, below
``min_per_worker`` items per worker, or with ``ACDRIVE_PREPARE_WORKERS=1`` (the variable caps
the number of processes). An exception in a worker is raised again in the parent (as a
``RuntimeError`` carrying the worker's traceback when the exception cannot be pickled).
"""

from __future__ import annotations

import multiprocessing
import os
import pickle
import sys
import traceback

from acdrive._threads import usable_cores

#: the environment variable capping the processes (the parent counts as one)
WORKERS_VARIABLE = "ACDRIVE_PREPARE_WORKERS"


def worker_count(n_items: int, min_per_worker: int) -> int:
    """Processes to use for ``n_items`` (the parent included): one per core, at most one per
    ``min_per_worker`` items, capped by ``ACDRIVE_PREPARE_WORKERS``; 1 off Linux (``fork`` is
    missing on Windows and unsafe with macOS's system libraries) and inside a daemonic process
    (which may not start children)."""
    if not sys.platform.startswith("linux") or multiprocessing.current_process().daemon:
        return 1
    n = min(usable_cores(), n_items // max(min_per_worker, 1))
    cap = os.environ.get(WORKERS_VARIABLE, "").strip()
    if cap:
        try:
            n = min(n, int(cap))
        except ValueError:
            pass  # not a number: no cap (the variable is a tuning knob, not an input)
    return max(n, 1)


def _share(fn, items, start: int, stop: int, conn) -> None:
    """A worker's body: its results, or its exception, down the pipe."""
    try:
        payload = ("ok", [fn(x) for x in items[start:stop]])
    except BaseException as exc:  # noqa: BLE001 -- everything goes back to the parent
        text = traceback.format_exc()
        try:
            pickle.dumps(exc)
            payload = ("error", exc, text)
        except Exception:  # noqa: BLE001 -- an unpicklable exception travels as its text
            payload = ("error", None, text)
    conn.send(payload)
    conn.close()


def forked_map(fn, items: list, min_per_worker: int = 128) -> list:
    """``[fn(x) for x in items]``, computed on all cores (module docstring)."""
    n = worker_count(len(items), min_per_worker)
    if n == 1:
        return [fn(x) for x in items]
    ctx = multiprocessing.get_context("fork")
    bounds = [round(k * len(items) / n) for k in range(n + 1)]
    workers = []
    try:
        for k in range(1, n):
            receive, send = ctx.Pipe(duplex=False)
            process = ctx.Process(target=_share, args=(fn, items, bounds[k], bounds[k + 1], send),
                                  daemon=True)  # fmt: skip
            process.start()
            send.close()  # the parent's copy: the pipe ends when the worker's end closes
            workers.append((process, receive))
        results = [fn(x) for x in items[bounds[0] : bounds[1]]]
        for process, receive in workers:
            try:
                payload = receive.recv()
            except EOFError:
                raise RuntimeError(
                    f"a preparing worker ended without a result (exit code {process.exitcode})"
                ) from None
            if payload[0] == "error":
                _, exc, text = payload
                if exc is not None:
                    raise exc
                raise RuntimeError(f"a preparing worker failed:\n{text}")
            results += payload[1]
        return results
    finally:
        for process, receive in workers:
            receive.close()
            process.join(timeout=5.0)
            if process.is_alive():
                process.kill()
                process.join()
