"""The one compilation setting of acdrive's compiled code, and numba loaded only when used.

``error_model="numpy"``: floating-point division by zero gives inf/NaN instead of raising (and
costs no check per division); the engine checks the state for non-finite values every sample, so
nothing non-finite goes unnoticed. ``cache=True``: a second run does not pay the compile time.

**Lazy kernels.** Importing numba costs about 0.35 CPU-s and its first use (even a load from the
cache) another 0.4 s; a run in the native tier (``sim._native``) needs neither. So the
decorators here do not import numba: they wrap the function in a :class:`LazyKernel`, which
keeps the Python function (``py_func``, what the code generators read) and creates numba's
dispatcher on first need: a call from Python, or any attribute of a dispatcher asked for. numba
compiling a kernel that names another as a global sees the dispatcher behind it: typing a global
asks for its ``_numba_type_``, which the LazyKernel hands over from its dispatcher (created
then), and ``register_with_numba`` (run when the first dispatcher is made) registers the same
answer with numba's ``typeof``. A kernel pickles by reference (its module and name), as numba's
dispatchers do.
"""

from __future__ import annotations

import functools
import os
import threading

import numpy as np

#: ACDRIVE_STRICT_MATH=1 compiles the fast-math functions with strict IEEE arithmetic instead
#: (no flag of ``FAST_MATH_FLAGS``), as the exported C is compiled: that is how two
#: implementations are compared bit for bit (benchmarks/compare_engines.py). It has its own
#: cache folder (acdrive/__init__.py).
STRICT_MATH = os.environ.get("ACDRIVE_STRICT_MATH") == "1"

#: LLVM's fast-math flags of the fast functions: no NaN and no infinity inside (``nnan``,
#: ``ninf``; the engine checks the state for non-finite values outside, every sample) and the
#: sign of a zero not significant (``nsz``). Not granted: reassociation, contraction into fused
#: multiply-adds and reciprocal approximations (``reassoc``, ``contract``, ``arcp``), whose use
#: depends on what surrounds an operation after inlining, so the same kernel would round one way
#: in the single loop and another in the lockstep lanes. With these flags every finite result
#: (up to the sign of a zero) depends only on the written order of operations: the tiers, the
#: exported C and the lockstep batch agree bit for bit. Measured (docs/design.md, "Fast-math
#: flags and bit identity"): ``contract`` bought no speed; ``arcp`` was worth 6 % on
#: im-foc-speed, which the cage IM's kernel now gets from reciprocals it writes itself.
FAST_MATH_FLAGS = frozenset() if STRICT_MATH else frozenset({"nnan", "ninf", "nsz"})

#: ``FAST_MATH_FLAGS`` as the ``fastmath`` option of a generated module's source (sorted, so
#: that the source, and with it the cache entry, is the same in every process)
FAST_MATH_SOURCE = (
    "{" + ", ".join(repr(f) for f in sorted(FAST_MATH_FLAGS)) + "}" if FAST_MATH_FLAGS else "False"
)

_registered = False
#: how deep this thread is inside a Python call of a ``python_from_python`` kernel: the kernels
#: it calls run as Python too
_python_calls = threading.local()


def register_with_numba() -> None:
    """Teach numba's ``typeof`` that a :class:`LazyKernel` is typed as its dispatcher (run by
    :meth:`LazyKernel.dispatcher` when the first dispatcher is made)."""
    global _registered
    if _registered:
        return
    from numba.core.typing.typeof import typeof_impl

    @typeof_impl.register(LazyKernel)
    def _typeof_lazy(value, context):
        return typeof_impl(value.dispatcher, context)

    _registered = True


class LazyKernel:
    """A function numba compiles with ``options`` when it is first needed (module docstring).

    ``py_func`` is the Python function; calling the kernel, or asking for any attribute of a
    numba dispatcher (``overloads``, ``targetoptions``, ``stats`` ...), creates the dispatcher.
    """

    def __init__(self, py_func, options: dict):
        self.py_func = py_func
        self._options = dict(options)
        self._dispatcher = None
        #: a call from Python runs ``py_func`` (``python_from_python``)
        self.python_from_python = False
        functools.update_wrapper(self, py_func)

    @property
    def dispatcher(self):
        """numba's dispatcher of this kernel (numba is imported here, once)."""
        if self._dispatcher is None:
            import numba

            register_with_numba()
            names = self.py_func.__globals__
            if names.get("prange") is prange:  # the stand-in below: numba's own from now on
                names["prange"] = numba.prange
            self._dispatcher = numba.njit(**self._options)(self.py_func)
        return self._dispatcher

    def __call__(self, *args, **kwargs):
        depth = getattr(_python_calls, "depth", 0)
        if self.python_from_python or depth:
            _python_calls.depth = depth + 1
            try:
                result = self.py_func(*args, **kwargs)
            finally:
                _python_calls.depth = depth
            # the caller gets what numba's dispatcher returns: Python scalars, not NumPy's (a
            # kernel called by this one keeps NumPy's, as its compiled callee would see them)
            return result if depth else _as_numba_returns(result)
        return self.dispatcher(*args, **kwargs)

    def __getattr__(self, name: str):
        if name.startswith("__") or name in ("py_func", "_options", "_dispatcher",
                                             "python_from_python"):  # fmt: skip
            raise AttributeError(name)
        return getattr(self.dispatcher, name)

    def __repr__(self) -> str:
        return f"<acdrive kernel {self.py_func.__module__}.{self.py_func.__qualname__}>"

    def __reduce__(self):
        return _kernel_named, (self.py_func.__module__, self.py_func.__qualname__)


def _kernel_named(module: str, qualname: str):
    """The kernel ``module.qualname`` (a LazyKernel unpickled: the one its module holds)."""
    import importlib

    found = importlib.import_module(module)
    for name in qualname.split("."):
        found = getattr(found, name)
    return found


def _as_numba_returns(value):
    """``value`` as numba's dispatcher returns it to Python: a NumPy scalar (float64, int64,
    bool_, complex128 ...) as the Python float, int, bool or complex of the same value, inside
    tuples too; arrays and anything else as they are."""
    if isinstance(value, (np.number, np.bool_)):
        return value.item()
    if type(value) is tuple:
        return tuple(_as_numba_returns(v) for v in value)
    return value


def prange(*args):
    """numba's ``prange`` before numba is imported: ``range`` when Python runs the loop; a module
    that imports this name has it replaced by ``numba.prange`` when its first kernel is
    compiled (``LazyKernel.dispatcher``), which is the object numba parallelises a loop over."""
    return range(*args)


def python_from_python(kernel: LazyKernel) -> LazyKernel:
    """Mark ``kernel`` (a scalar formula that setup or summary code also calls a few times) so
    that a call from Python runs its Python function: loading numba for it would cost about
    0.4 CPU-s where the formula costs microseconds. Inside compiled code it is compiled as
    before; the kernels it calls run as Python inside such a call. Only for kernels compiled
    without fast-math or whose expression leaves the compiler nothing to reorder, so that both
    give the same IEEE result."""
    kernel.python_from_python = True
    return kernel


def njit(function=None, **options):
    """numba's ``njit`` with numba imported on first use (:class:`LazyKernel`): ``@njit``,
    ``@njit(**options)`` and ``njit(**options)(function)``."""
    if function is not None:
        return LazyKernel(function, options)
    return lambda f: LazyKernel(f, options)


def serial_twin(kernel: LazyKernel, name: str) -> LazyKernel:
    """``kernel``'s Python function compiled with its options but without ``parallel``, under
    the module-level name ``name``: for calls whose work is too small to pay for starting a
    parallel region (the OpenMP workers wake, and spin after it ends). Its loops run in order;
    every point's arithmetic is the kernel's. numba names a function's disk cache after its
    qualified name and does not key it on ``parallel``: two dispatchers compiled from one
    Python function would read and write the same cache entry, and whichever compiled first
    would serve both; the renamed copy has its own."""
    import types

    function = kernel.py_func
    twin = types.FunctionType(
        function.__code__, function.__globals__, name, function.__defaults__, function.__closure__
    )
    twin.__qualname__ = name
    twin.__doc__ = function.__doc__
    options = {k: v for k, v in kernel._options.items() if k != "parallel"}
    return LazyKernel(twin, options)


jit = njit(cache=True, error_model="numpy")

#: the plant's right-hand side and its integrator: fast-math with ``FAST_MATH_FLAGS`` (no NaN/inf
#: special cases inside); the engine checks finiteness outside it.
jit_fast = njit(cache=True, error_model="numpy", fastmath=set(FAST_MATH_FLAGS))

#: small helpers of the plant's kernels: inlined into the compiled loop at numba-IR level (numba
#: does not inline one compiled function into another by itself; a call per table lookup or per
#: current computation costs more than the arithmetic)
jit_inline = njit(cache=True, error_model="numpy", fastmath=set(FAST_MATH_FLAGS), inline="always")
