"""The peers' side of the suite's timed windows (imported by the peer scripts, never by acdrive).

A peer script started with ``--serve`` stays alive and answers one command per stdin line, a
JSON object ``{"cmd": name, "args": {...}}``, with one stdout line ``REPLY_PREFIX`` + JSON (other
output of the peer, if any, is ignored by the suite). ``{"cmd": "quit"}`` ends it. The suite
(``acdrive._bench.venvs.PeerProcess``) thereby runs the peer's windows interleaved with acdrive's
in one long-lived process, and the peer measures its own CPU time (``cpu_window``).
"""

from __future__ import annotations

import json
import sys
import time

REPLY_PREFIX = "ACDRIVE-BENCH "


def cpu_window(prepare, simulate, runs: int) -> dict:
    """``runs`` runs; each ``prepare()`` (untimed: building the model) then ``simulate(model)``
    (timed), which returns the control steps it ran. The process CPU time (``process_time``)
    summed over the simulations, their wall time, the steps of one run, and the process CPU
    time of the whole window, building included (the suite's load accounting)."""
    cpu = wall = 0.0
    steps = None
    start = time.process_time()
    for _ in range(max(int(runs), 1)):
        model = prepare()
        c0, w0 = time.process_time(), time.perf_counter()
        steps = simulate(model)
        cpu += time.process_time() - c0
        wall += time.perf_counter() - w0
    return {
        "cpu_s": cpu,
        "wall_s": wall,
        "steps_per_run": steps,
        "runs": runs,
        "process_cpu_s": time.process_time() - start,
    }


def serve(handlers: dict) -> None:
    """Answer commands from stdin until ``quit`` or end of input (module docstring). An
    exception in a handler is answered as ``{"error": ...}`` and the loop goes on."""
    for line in sys.stdin:
        line = line.strip()
        if not line:
            continue
        msg = json.loads(line)
        if msg.get("cmd") == "quit":
            break
        try:
            result = handlers[msg["cmd"]](**msg.get("args", {}))
        except Exception as exc:  # noqa: BLE001 - reported to the suite as the reason
            result = {"error": f"{type(exc).__name__}: {exc}"}
        sys.stdout.write(REPLY_PREFIX + json.dumps(result) + "\n")
        sys.stdout.flush()
