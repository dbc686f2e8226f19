"""A user's own parts, written with the public API only (a sampled soft-start voltage program, a
modulator that holds its command with a gain, a winding thermal model), are first-class: the
system runs on the native tier from C generated from their kernels, the same controller runs as
exported C in acdrive's loop (software in the loop) with the same bits, and the controller and
plant FMUs built from the same C, stepped by a Gauss-Seidel master, reproduce the run."""

from __future__ import annotations

import math
import shutil
from typing import ClassVar

import numpy as np
import pytest
from numba import njit

from acdrive.core import ContinuousPart, Layout, Modulator, SampledPart, cplx, real
from acdrive.machines import UGALDE_IM_300W, CageInductionMachine
from acdrive.plant import PrescribedSpeed
from acdrive.sim import System

pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc is not installed")

# --- a sampled part: v_ref = V(t) e^{j theta}, V ramping to V_max, theta advancing 2 pi f T_s,
# --- no voltage once the winding is hotter than T_trip (a closed loop through the thermal part)
SOFT_PARAMS = Layout(
    real("V_max", "V", "final voltage magnitude", "positive"),
    real("f", "Hz", "frequency", "positive"),
    real("ramp", "s", "time to reach V_max", "positive"),
    real("T_trip", "K", "winding temperature above which the voltage is off", "positive"),
)
SOFT_STATES = Layout(real("theta", "rad", "angle of the next command"))
SOFT_INPUTS = Layout(real("T", "K", "winding temperature"))
SOFT_OUTPUTS = Layout(cplx("v_ref", "V", "commanded voltage"))
_V_MAX, _F, _RAMP, _T_TRIP = (SOFT_PARAMS.slot(n) for n in ("V_max", "f", "ramp", "T_trip"))
_THETA, _V_REF = SOFT_STATES.slot("theta"), SOFT_OUTPUTS.slot("v_ref")
_AT_FULL, _TRIPPED = 1, 2


@njit
def soft_start_step(t, T_s, u, p, s, y):
    """The command of this sample; the event ``full`` once the ramp is over, ``tripped`` while
    the winding is too hot."""
    events = 0
    V = p[_V_MAX] * t / p[_RAMP]
    if V >= p[_V_MAX]:
        V = p[_V_MAX]
        events |= _AT_FULL
    if u[0] > p[_T_TRIP]:
        V = 0.0
        events |= _TRIPPED
    y[_V_REF], y[_V_REF + 1] = V * math.cos(s[_THETA]), V * math.sin(s[_THETA])
    s[_THETA] = (s[_THETA] + 2.0 * math.pi * p[_F] * T_s) % (2.0 * math.pi)
    return events


class SoftStart(SampledPart):
    """Open-loop voltage command ramping to V_max at frequency f."""

    PARAMS, STATES, INPUTS, OUTPUTS = SOFT_PARAMS, SOFT_STATES, SOFT_INPUTS, SOFT_OUTPUTS
    EVENTS = ("full", "tripped")
    step = soft_start_step


# --- a modulator: the command held over the sample, scaled by a gain --------------------------
HOLD_PARAMS = Layout(real("gain", "", "voltage gain of the stage", "positive"))
HOLD_INPUTS = Layout(cplx("v_ref", "V", "commanded voltage"))
HOLD_OUTPUTS = Layout(cplx("v", "V", "applied voltage"))


@njit
def hold_segments(T_s, u, p, s, dt, v):
    dt[0] = T_s
    v[0, 0], v[0, 1] = p[0] * u[0], p[0] * u[1]
    return 1, 0


class GainHold(Modulator):
    """A zero-order hold with a gain."""

    PARAMS, INPUTS, OUTPUTS = HOLD_PARAMS, HOLD_INPUTS, HOLD_OUTPUTS
    MAX_SEGMENTS = 1
    segments = hold_segments


# --- a continuous part: C_th dT/dt = R_s |i_s|^2 - (T - T_amb) / R_th ---------------------------
HEAT_PARAMS = Layout(
    real("R_s", "ohm", "winding resistance", "positive"),
    real("R_th", "K/W", "thermal resistance to the ambient", "positive"),
    real("C_th", "J/K", "thermal capacitance", "positive"),
    real("T_amb", "K", "ambient temperature", "positive"),
)
HEAT_STATES = Layout(real("T", "K", "winding temperature"))
HEAT_INPUTS = Layout(cplx("i_s", "A", "stator current"))
HEAT_OUTPUTS = Layout(real("T", "K", "winding temperature"))


@njit
def heat_outputs(t, x, p, y):
    y[0] = x[0]


@njit
def heat_rhs(t, x, u, p, y, dx):
    dx[0] = (p[0] * (u[0] * u[0] + u[1] * u[1]) - (x[0] - p[3]) / p[1]) / p[2]


class Winding(ContinuousPart):
    """First-order thermal model of a winding heated by its copper losses."""

    PARAMS, STATES, INPUTS, OUTPUTS = HEAT_PARAMS, HEAT_STATES, HEAT_INPUTS, HEAT_OUTPUTS
    INITIAL: ClassVar[dict] = {"T": 300.0}
    state_outputs = heat_outputs
    rhs = heat_rhs


T_S, DURATION, T_TRIP = 1e-4, 0.06, 305.0


def _system():
    machine = UGALDE_IM_300W
    program = SoftStart("program", V_max=40.0, f=50.0, ramp=0.03, T_trip=T_TRIP)
    stage = GainHold("stage", gain=1.5)
    im = CageInductionMachine.from_params("im", machine)
    rotor = PrescribedSpeed("rotor", w=0.0)
    winding = Winding("winding", R_s=machine.R_s, R_th=2.0, C_th=0.05, T_amb=300.0)
    wires = [(program.out.v_ref, stage.inp.v_ref), (stage.out.v, im.inp.v_s),
             (rotor.out.w, im.inp.w), (im.out.i_s, winding.inp.i_s),
             (winding.out.T, program.inp.T)]  # fmt: skip
    return System([program, stage, im, rotor, winding], wires), im, winding


@pytest.mark.slow
def test_a_users_parts_run_natively_in_the_loop_and_in_fmus(monkeypatch, tmp_path):
    from fmpy.validation import validate_fmu

    from acdrive.export import run_in_loop, to_c
    from acdrive.export._fmu import build_fmu, controller_model, plant_model
    from acdrive.export._fmu_check import _closed_loop
    from acdrive.sim._ccode._plant_source import to_plant_c

    monkeypatch.setenv("ACDRIVE_LOOP_TIER", "auto")
    system, im, winding = _system()
    compiled = system.compile()
    assert compiled.tier == "native"  # every part's C generated, the users' among them
    log = [im.out.i_s, winding.out.T]
    native = compiled.run(DURATION, T_S, 4, log=log)
    T = native.signal(winding.out.T)
    raised = native.raised_events()
    # it heats, trips, cools below the trip and drives again: the loop through the user's parts
    assert T.max() > T_TRIP and raised["program.tripped"] > 0 and raised["program.full"] > 0
    assert np.count_nonzero(np.diff((T > T_TRIP).astype(int)) == -1) >= 1

    # software in the loop: the controller as exported C in place of the compiled part
    export = to_c(system, T_S, name="users_controller")
    sil = run_in_loop(compiled, export, DURATION, T_S, 4, log=log)
    assert np.array_equal(sil.data, native.data)

    # the controller and the plant as FMUs, stepped by a Gauss-Seidel master
    plant_export = to_plant_c(system, T_S, 4, name="users_plant")
    models = {"controller": controller_model(export, T_S, DURATION, "users' controller"),
              "plant": plant_model(plant_export, system, None, T_S, DURATION, "users' plant")}  # fmt: skip
    paths = {k: build_fmu(m, tmp_path / f"{m.identifier}.fmu") for k, m in models.items()}
    assert all(validate_fmu(str(p)) == [] for p in paths.values())
    n = round(DURATION / T_S)
    fmu = _closed_loop(paths, n, T_S)
    i_s = native.signal(im.out.i_s)
    for name, reference in (("im.i_s.re", i_s.real), ("im.i_s.im", i_s.imag),
                            ("winding.T", T)):  # fmt: skip
        peak = np.max(np.abs(reference))
        assert np.max(np.abs(fmu[name] - reference)) <= 1e-9 * peak, name
