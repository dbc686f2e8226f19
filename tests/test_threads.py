"""An acdrive command loads numpy with one BLAS thread and leaves the environment as it was."""

import json
import os
import subprocess
import sys

_CHILD = """
import ctypes, glob, json, os, sys
from acdrive._threads import one_blas_thread
done = one_blas_thread()
threads = None
if "numpy" in sys.modules:
    import numpy
    for path in glob.glob(os.path.join(os.path.dirname(numpy.__file__) + ".libs", "*openblas*.so*")):
        lib = ctypes.CDLL(path)
        for name in ("scipy_openblas_get_num_threads64_", "openblas_get_num_threads64_",
                     "openblas_get_num_threads"):
            if hasattr(lib, name):
                threads = getattr(lib, name)()
print(json.dumps({"done": done, "numpy": "numpy" in sys.modules, "threads": threads,
                  "variable": os.environ.get("OPENBLAS_NUM_THREADS")}))
"""


def _child(**env_changes):
    env = {
        k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")
    }
    env.update(env_changes)
    out = subprocess.run([sys.executable, "-c", _CHILD], env=env, capture_output=True, text=True,
                         check=True)  # fmt: skip
    return json.loads(out.stdout)


def test_numpy_is_loaded_with_one_blas_thread_and_the_variable_is_removed_again():
    got = _child()
    assert got["done"] and got["numpy"]
    assert got["variable"] is None  # a process the command starts sees the user's environment
    if got["threads"] is not None:  # numpy's OpenBLAS found: it runs one thread
        assert got["threads"] == 1


def test_a_users_own_thread_count_stands():
    got = _child(OPENBLAS_NUM_THREADS="2")
    assert not got["done"] and not got["numpy"]
    assert got["variable"] == "2"
