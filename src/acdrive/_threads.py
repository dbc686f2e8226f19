"""One BLAS thread for numpy in an ``acdrive`` command.

acdrive's matrices are small (a controller's state space, a machine's 2 x 2 blocks) and its
long arrays go through element-wise operations. But a single BLAS call on a long vector (a dot
product of a logged trace) wakes OpenBLAS's thread pool, and its threads then spin while they
wait for more work. Measured on a warm ``acdrive run bodson-ramp --no-figures`` (6 interleaved
pairs, 2-core machine): 0.52 CPU-s with numpy's default threads, 0.42 with one. A batch's numba
workers would share the cores with those spinning threads.

``one_blas_thread`` loads numpy with ``OPENBLAS_NUM_THREADS=1`` and then removes the variable
again, so processes the command starts (a peer in ``acdrive bench``, a compiler) see
the user's environment unchanged. Nothing is changed when numpy is already loaded, or when the
user set ``OPENBLAS_NUM_THREADS`` or ``OMP_NUM_THREADS`` (their choice stands).
"""

from __future__ import annotations

import os
import sys

#: the variables OpenBLAS reads for its thread count when it is loaded
_BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")


def one_blas_thread() -> bool:
    """Load numpy with one OpenBLAS thread (module docstring); True if it was done here."""
    if "numpy" in sys.modules or any(v in os.environ for v in _BLAS_THREAD_VARIABLES):
        return False
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
    try:
        import numpy  # noqa: F401  (OpenBLAS reads the variable as numpy loads it)
    finally:
        del os.environ["OPENBLAS_NUM_THREADS"]
    return True


def usable_cores() -> int:
    """The cores this process may run on (its affinity where the system tells it)."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return cores or 1
