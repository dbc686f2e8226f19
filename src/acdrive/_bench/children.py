"""Whole processes timed from outside: a child's CPU time, read when the suite reaps it.

The first-result race (``_bench.first_result``) and the whole-command targets (``_bench.targets``)
time everything a user waits for: interpreter start, imports, building, compiling or loading,
simulating, writing. The measuring process cannot see inside the child, so it reads the child's
resource usage as the kernel reports it when the child is reaped (``os.wait4``: user + system
CPU time of the child and of every descendant it waited for), with the wall time around it.
Unlike ``resource.getrusage(RUSAGE_CHILDREN)`` deltas, this counts that one child only, even
while a peer's long-lived process (``venvs.PeerProcess``) runs beside it.

``child_side`` turns a command into a side for ``windows.interleave``: its window is one run
of the process, ``steps_per_run`` is 1 (one result), so a side's ``steps_per_cpu_s`` is results
per CPU second and a ratio of two sides (``windows.summarise_windows``) is the inverse ratio of
their times.
"""

from __future__ import annotations

import os
import subprocess
import tempfile
import time

#: environment variables that would point a child at the suite's own caches
CACHE_VARIABLES = ("NUMBA_CACHE_DIR", "ACDRIVE_NUMBA_CACHE_DIR", "XDG_CACHE_HOME")


class ChildFailed(RuntimeError):
    """A timed child process could not start or ended with a non-zero exit code."""


def can_time_children() -> bool:
    """Whether this platform reports a reaped child's own resource usage (``os.wait4``)."""
    return hasattr(os, "wait4")


def run_child(cmd: list[str], env: dict, cwd: str | None = None) -> dict:
    """Run ``cmd`` to its end; its CPU time (user + system, from ``os.wait4``), wall time, exit
    code and the last lines of its stdout and stderr. Raises ``ChildFailed`` if it cannot start
    or exits with an error (quoting the end of its stderr)."""
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        wall0 = time.perf_counter()
        try:
            proc = subprocess.Popen(cmd, stdout=out, stderr=err, env=env, cwd=cwd)
        except OSError as exc:
            raise ChildFailed(f"{cmd[0]} could not start: {exc}") from exc
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - wall0
        proc.returncode = os.waitstatus_to_exitcode(status)  # reaped here, not by Popen
        out.seek(0)
        err.seek(0)
        stdout = out.read().decode("utf-8", "replace").strip().splitlines()
        stderr = err.read().decode("utf-8", "replace").strip().splitlines()
    if proc.returncode != 0:
        tail = " | ".join(stderr[-3:]) or "no message"
        raise ChildFailed(f"{' '.join(cmd[:3])} exited with {proc.returncode}: {tail}")
    return {
        "cpu_s": usage.ru_utime + usage.ru_stime,
        "user_s": usage.ru_utime,
        "system_s": usage.ru_stime,
        "wall_s": wall,
        "max_rss_mb": usage.ru_maxrss / 1024.0,
        "stdout_last": stdout[-1] if stdout else "",
    }


def child_env(base: dict, cache_home: str | None) -> dict:
    """``base`` without the cache variables (``CACHE_VARIABLES``), with ``XDG_CACHE_HOME`` set to
    ``cache_home`` if given: the child then keys every cache of its own by that folder."""
    env = {k: v for k, v in base.items() if k not in CACHE_VARIABLES}
    if cache_home is not None:
        env["XDG_CACHE_HOME"] = cache_home
    return env


def child_side(start, record=None):
    """A side for ``windows.interleave``: each window runs ``start()`` (which returns the
    ``run_child`` answer of one whole process; it may prepare and clean a folder around it) once
    per run. ``record``, if given, receives every run's answer (its stdout, memory, wall time)."""

    def window(runs: int) -> dict:
        cpu = 0.0
        for _ in range(runs):
            got = start()
            cpu += got["cpu_s"]
            if record is not None:
                record.append(got)
        return {"cpu_s": cpu, "process_cpu_s": cpu, "steps_per_run": 1}

    return window
