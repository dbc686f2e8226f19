"""The sensor parts (quadrature encoder, resolver, Hall sensors, current sensing) run on the
native tier from the C generated from their kernels, equal bit for bit to numba's specialised
loop, events included, and as exported C in acdrive's loop (software in the loop), in one
system: a shaft at a speed profile through zero read by the three position sensors, an R-L
load's current read by two sensors through a clipping ADC."""

from __future__ import annotations

import numpy as np
import pytest
from rl_load import RLLoad

from acdrive.plant import (CurrentSensing, HallSensors, PrescribedSpeed, QuadratureEncoder,
                           Resolver, ThreePhaseSource)  # fmt: skip
from acdrive.sim import System, _native

needs_cc = pytest.mark.skipif(_native.compiler() is None, reason="no C compiler on this machine")


def _system() -> tuple[System, list]:
    rotor = PrescribedSpeed("rotor", w=[[0.0, 0.0], [0.03, 400.0], [0.06, -300.0]])
    encoder = QuadratureEncoder("enc", lines=256, pole_pairs=3, offset=0.3, index=1.0,
                                lose_every=50, centred=1.0)  # fmt: skip
    resolver = Resolver("res", bandwidth=2000.0, pole_pairs=3, imbalance=0.02, quadrature=0.01,
                        offset_sin=0.01, eccentricity=0.002)  # fmt: skip
    hall = HallSensors("hall", pole_pairs=3, offset=0.1)
    source = ThreePhaseSource("src", V_pk=100.0, f=50.0)
    load = RLLoad("load", R=1.0, L=0.01)
    sensing = CurrentSensing("cs", phases=2, bits=10, full_scale=20.0, offset_a=0.1, gain_b=1.02)
    theta = rotor.out.theta
    wires = [(theta, encoder.inp.theta), (theta, resolver.inp.theta), (theta, hall.inp.theta),
             (source.out.v, load.inp.v), (load.out.i_s, sensing.inp.i_s)]  # fmt: skip
    log = [encoder.out.theta, encoder.out.theta_e, encoder.out.w, resolver.out.theta,
           resolver.out.w, hall.out.theta_e, hall.out.w, sensing.out.i_s,
           sensing.out.i_c]  # fmt: skip
    return System([rotor, encoder, resolver, hall, source, load, sensing], wires), log


@needs_cc
@pytest.mark.slow
def test_the_sensors_run_natively_equal_to_numba_bit_for_bit(monkeypatch):
    system, log = _system()
    runs = {}
    for tier in ("native", "specialised"):
        monkeypatch.setenv("ACDRIVE_LOOP_TIER", tier)
        compiled = system.compile()
        assert compiled.tier == tier
        runs[tier] = compiled.run(0.06, 1e-4, log=log)
    native, reference = runs["native"], runs["specialised"]
    raised = native.raised_events()
    # the run reaches every path: a revolution's index, lost edges, Hall edges, clipping
    assert {"enc.index", "enc.edge_lost", "hall.edge", "cs.clipped"} <= set(raised)
    assert native.raised_events() == reference.raised_events()
    assert np.array_equal(native.data, reference.data)


@needs_cc
@pytest.mark.slow
def test_the_sensors_as_exported_c_in_the_loop_equal_the_native_run(monkeypatch):
    """Software in the loop: the sensors' chain exported as C (``acdrive.export.to_c``) and run
    in acdrive's loop in place of the compiled parts gives the native run's bits."""
    from acdrive.export import run_in_loop, to_c

    monkeypatch.setenv("ACDRIVE_LOOP_TIER", "native")
    system, log = _system()
    compiled = system.compile()
    native = compiled.run(0.06, 1e-4, log=log)
    sil = run_in_loop(compiled, to_c(system, 1e-4, name="sensors"), 0.06, 1e-4, log=log)
    assert sil.raised_events() == native.raised_events()
    assert np.array_equal(sil.data, native.data)
