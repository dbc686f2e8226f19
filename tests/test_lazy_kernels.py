"""acdrive's kernels are compiled by numba on first use (``acdrive._jit.LazyKernel``): importing
them imports no numba, a kernel inside another compiles as before, a scalar formula marked
``python_from_python`` answers a Python call as numba's dispatcher did (Python numbers), and a
kernel pickles by reference."""

import math
import pickle
import subprocess
import sys

from acdrive.machines._dfim import torque_limits_case1
from acdrive.plant._converter import max_voltage_magnitude
from acdrive.sim._metrics import speed_error_update


def test_a_kernel_pickles_by_reference():
    """A sweep's workers get the same kernel, as with numba's dispatchers."""
    for kernel in (torque_limits_case1, speed_error_update):
        assert pickle.loads(pickle.dumps(kernel)) is kernel


def test_a_python_call_of_a_scalar_formula_gives_python_numbers():
    """The largest voltage of a converter on a 311 V link, v_dc / sqrt(2): a Python float (its
    repr is a number a TOML file can hold), equal to numba's compiled result."""
    value = max_voltage_magnitude(311.0)
    assert type(value) is float and value == 311.0 / math.sqrt(2.0)
    assert max_voltage_magnitude.dispatcher(311.0) == value


def test_importing_the_parts_imports_no_numba():
    code = ("import sys; import acdrive.machines._cage_part, acdrive.plant._inverter, "
            "acdrive.control._current, acdrive.sim._system; print('numba' in sys.modules)")  # fmt: skip
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True, timeout=300)  # fmt: skip
    assert done.stdout.strip() == "False"
