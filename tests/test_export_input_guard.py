"""The exported C's optional input guard (``-DACDRIVE_GUARD_INPUTS``, docs/guide/export.md): one
non-finite ADC sample does not poison a controller's state.

im-foc-speed's exported controller (IFOC, speed PI, the ICAD controller (20)) runs in acdrive's
loop in place of its compiled sampled parts (``export._sil.run_in_loop``). A NaN current sample at
one instant, during the speed step:

* without the guard, every later voltage command is NaN (the current controller's state holds
  it; the modulator then switches as its comparisons with NaN fall);
* with the guard, the closed loop is bit for bit the loop in which that sample is replaced by the
  previous sample's value (the last finite one the controller saw), and the step that saw it
  reports the input's bit in ``input_faults``, the next step none.
"""

from __future__ import annotations

import ctypes
import math
import shutil

import numpy as np
import pytest

from acdrive.export._scenario import built, c_name, shortened
from acdrive.export._sil import _load, build_library, run_in_loop
from acdrive.scenarios._loader import load_scenario
from acdrive.sim._ccode._c_source import to_c

pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc is not installed")

BAD_STEP = 600  # t = 0.06 s at T_s = 100 us: after the speed step at 0.05 s


@pytest.fixture(scope="module")
def drive():
    setup = shortened(load_scenario("im-foc-speed"), 0.08)
    d, initial, held = built(setup)
    export = to_c(d.system, setup.sample_time, initial, held, name=c_name(setup.name))
    compiled = d.system.compile()
    return setup, compiled, export, initial, held


def _current_input(export) -> str:
    """The chain's first complex input (the measured stator current)."""
    model = export.chains[0]
    names = [m.name for m in model.inputs if m.spec == "complex"]
    assert names, [m.name for m in model.inputs]
    return names[0]


def _run(drive, replace, guard: bool):
    """The closed loop with the chain's current input at ``BAD_STEP`` replaced by
    ``replace(previous value)`` (a complex number)."""
    setup, compiled, export, initial, held = drive
    name = _current_input(export)
    seen = {"k": -1, "previous": None}

    def on_inputs(chain, inputs):
        seen["k"] += 1
        z = getattr(inputs, name)
        if seen["k"] == BAD_STEP:
            new = replace(seen["previous"])
            z.re, z.im = new.real, new.imag
        seen["previous"] = complex(z.re, z.im)

    return run_in_loop(compiled, export, setup.duration, setup.sample_time, setup.substeps,
                       initial=initial, held=held, on_inputs=on_inputs, guard=guard)  # fmt: skip


def test_a_nan_sample_poisons_the_unguarded_controller(drive):
    run = _run(drive, lambda previous: complex(math.nan, 0.0), guard=False)
    v_ref = run.data[:, run.columns.index("current.v_ref.re")]
    assert np.all(np.isfinite(v_ref[:BAD_STEP])) and np.all(np.isnan(v_ref[BAD_STEP:]))


def test_the_guard_holds_the_last_finite_sample(drive):
    held = _run(drive, lambda previous: previous, guard=False)
    guarded = _run(drive, lambda previous: complex(math.nan, math.inf), guard=True)
    assert held.columns == guarded.columns
    assert np.all(np.isfinite(guarded.data))
    assert np.array_equal(held.data, guarded.data)
    speed = held.columns.index("speed.w")
    assert held.data[-1, speed] > 10.0  # the speed step moved the shaft: the loop was closed


def test_the_guard_flags_the_input_at_its_step_only(drive, tmp_path):
    _, compiled, export, _, _ = drive
    library = build_library(export, tmp_path, "double", guard=True)
    (chain,) = _load(export, library, "double", compiled.system, guard=True)
    refs = [ctypes.byref(x) for x in (chain.params, chain.state, chain.inputs, chain.outputs)
            if x is not None]  # fmt: skip
    names = [m.name for m in chain.model.inputs]
    k = names.index(_current_input(export))
    z = getattr(chain.inputs, names[k])
    z.re, z.im = 0.5, -0.25
    chain.step(0.0, *refs)
    assert chain.state.input_faults == 0
    last = getattr(chain.state.last_finite, names[k])
    assert (last.re, last.im) == (0.5, -0.25)
    z.re = math.nan
    chain.step(1e-4, *refs)
    assert chain.state.input_faults == 1 << min(k, 31)
    last = getattr(chain.state.last_finite, names[k])
    assert (last.re, last.im) == (0.5, -0.25)  # the last finite value is kept
    z.re = 0.75
    chain.step(2e-4, *refs)
    assert chain.state.input_faults == 0
