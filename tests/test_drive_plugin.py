"""A drive kind defined here, outside acdrive, registered with ``acdrive.drives.register`` and run
through ``acdrive run``, a batch and a sweep with no other edit of acdrive (issue 20, item 1).

The toy drive: a balanced three-phase source (``plant.ThreePhaseSource``, v = sqrt(3/2) V_pk
e^{j w t}) feeding a star-connected series R-L load, L di/dt = v - R i (space vectors), a part
declared outside acdrive (``tests/rl_load.py``). In steady state the current is the phasor
quotient i = v / (R + j w L): a space vector of constant magnitude sqrt(3/2) V_pk / |R + j w L|,
lagging v by atan(w L / R). The transient decays as exp(-t R / L); every figure checked below is
taken after 20 time constants, where it is below 1e-8 of the amplitude.
"""

from __future__ import annotations

import cmath
import json
import math
from dataclasses import dataclass

import numpy as np
import pandas as pd
import pytest
from rl_load import RLLoad

from acdrive.batch import Reducer, simulate_batch
from acdrive.cli import main
from acdrive.drives import Drive, for_data, get, kinds, register, unregister
from acdrive.errors import InputError, require_positive
from acdrive.plant import ThreePhaseSource
from acdrive.sim import System
from acdrive.sweep import load_sweep, read_table, run_sweep

KIND = "toy-rl"
#: relative agreement of a simulated steady amplitude with the phasor formula: RK4 at
#: h w = 2 pi 50 x 25 us = 0.008 rad has a local error ~ (h w)^5 / 120, far below this
TOL = 1e-7


# --- the drive --------------------------------------------------------------------------------


@dataclass(frozen=True)
class ToySetup:
    R: float
    L: float
    V_pk: float
    f: float
    duration: float
    sample_time: float
    name: str = "toy"
    substeps: int = 4
    integrator: str = "rk4"
    log_every: int = 1

    def steady_amplitude(self) -> float:
        """|i| = sqrt(3/2) V_pk / |R + j w L| (module docstring)."""
        return math.sqrt(1.5) * self.V_pk / abs(complex(self.R, 2 * math.pi * self.f * self.L))

    def settled_from(self) -> float:
        """20 time constants L / R after the start."""
        return 20.0 * self.L / self.R


class ToyBuilt:
    def __init__(self, setup: ToySetup):
        self.setup = setup
        self.grid = ThreePhaseSource("grid", V_pk=setup.V_pk, f=setup.f)
        self.load = RLLoad("load", R=setup.R, L=setup.L)
        self.system = System(
            [self.grid, self.load], [(self.grid.out.v, self.load.inp.v)], method=setup.integrator
        )

    def initial(self):
        return {}, {}


@dataclass
class ToyOutcome:
    setup: ToySetup
    results: dict
    summary: dict


class ToyDrive(Drive):
    kind = KIND
    setup_types = (ToySetup,)

    def load(self, data):
        unknown = set(data) - {"drive", "name", "circuit", "source", "simulation"}
        if unknown:
            raise InputError(min(unknown), "is not a key of a toy-rl scenario")

        def number(table, key):
            return require_positive(f"{table}.{key}", data.get(table, {}).get(key))

        return ToySetup(
            R=number("circuit", "R"), L=number("circuit", "L"),
            V_pk=number("source", "voltage_pk"), f=number("source", "frequency_hz"),
            duration=number("simulation", "duration"),
            sample_time=number("simulation", "sample_time"), name=data.get("name", "toy"),
        )  # fmt: skip

    def build(self, setup):
        return ToyBuilt(setup)

    def run(self, setup, on_run=None):
        if on_run is not None:
            on_run("the one run")
        built = ToyBuilt(setup)
        result = built.system.compile().run(
            setup.duration, setup.sample_time, substeps=setup.substeps, log_every=setup.log_every
        )
        i = result.signal(built.load.out.i_s)
        settled = result.t >= setup.settled_from()
        summary = {"current_amplitude_a": float(np.mean(np.abs(i[settled]))),
                   "current_amplitude_spread_a": float(np.ptp(np.abs(i[settled])))}  # fmt: skip
        return ToyOutcome(setup, {"main": result}, summary)

    def write(self, outcome, folder, figures=True, fmt="parquet"):
        outcome.results["main"].save(folder, fmt)
        (folder / "summary.json").write_text(json.dumps(outcome.summary))
        return outcome.summary

    def headline(self, outcome, summary):
        return f"toy {outcome.setup.name}", [("current", f"{summary['current_amplitude_a']:g} A")]

    def reducers(self, setup):
        return [Reducer("peak_current_a", "peak", "load.i_s", start=setup.settled_from()),
                Reducer("final_current_a", "final", "load.i_s")]  # fmt: skip


SCENARIO = f"""drive = "{KIND}"
name = "toy"
[circuit]
R = 2.0
L = 0.01
[source]
voltage_pk = 10.0
frequency_hz = 50.0
[simulation]
duration = 0.3
sample_time = 1e-4
"""


@pytest.fixture
def toy(tmp_path):
    drive = register(ToyDrive())
    path = tmp_path / "toy.toml"
    path.write_text(SCENARIO)
    try:
        yield drive, path
    finally:
        unregister(KIND)


def test_the_registry_selects_the_toy_drive_by_its_kind(toy):
    drive, _ = toy
    assert KIND in kinds() and get(KIND) is drive and for_data({"drive": KIND}) is drive
    with pytest.raises(ValueError, match="registered already"):
        register(ToyDrive())
    with pytest.raises(ValueError, match="registered already"):
        register(type("Other", (ToyDrive,), {"kind": "dfim"})())


def test_an_unknown_drive_names_the_field_and_the_kinds():
    with pytest.raises(InputError, match=r'^drive: must be one of "dfim", "cage-im"'):
        for_data({"drive": KIND})  # not registered outside the fixture


@pytest.mark.slow
def test_acdrive_run_runs_the_toy_drive(toy, tmp_path, capsys):
    _, path = toy
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out), "--no-figures"]) == 0
    printed = capsys.readouterr().out
    summary = json.loads((out / "toy" / "summary.json").read_text())
    frame = pd.read_parquet(out / "toy" / "data.parquet")
    setup = ToySetup(R=2.0, L=0.01, V_pk=10.0, f=50.0, duration=0.3, sample_time=1e-4)
    expected = setup.steady_amplitude()
    assert summary["current_amplitude_a"] == pytest.approx(expected, rel=TOL)
    assert summary["current_amplitude_spread_a"] < TOL * expected
    assert "toy toy" in printed and "current" in printed
    # the phase of the logged current against the source: i / v = 1 / (R + j w L)
    t = frame["t"].to_numpy()
    i = frame["load.i_s.re"].to_numpy() + 1j * frame["load.i_s.im"].to_numpy()
    v = frame["grid.v.re"].to_numpy() + 1j * frame["grid.v.im"].to_numpy()
    late = t >= setup.settled_from()
    ratio = i[late] / v[late]
    z = complex(setup.R, 2 * math.pi * setup.f * setup.L)
    assert np.max(np.abs(ratio * z - 1.0)) < TOL
    assert cmath.phase(np.mean(ratio)) == pytest.approx(-math.atan2(z.imag, z.real), abs=TOL)


def test_run_scenario_runs_a_registered_drive_from_python(toy):
    """``acdrive.drives.run_scenario`` asks the registry: the toy's own outcome, whose current
    amplitude is the phasor formula's."""
    from acdrive.drives import run_scenario
    from acdrive.scenarios import load_scenario

    _, path = toy
    outcome = run_scenario(load_scenario(path))
    assert isinstance(outcome, ToyOutcome) and list(outcome.results) == ["main"]
    expected = outcome.setup.steady_amplitude()
    assert outcome.summary["current_amplitude_a"] == pytest.approx(expected, rel=TOL)


def test_an_invalid_toy_scenario_is_one_line_naming_the_field(toy, tmp_path, capsys):
    _, path = toy
    path.write_text(SCENARIO.replace("R = 2.0", "R = -1.0"))
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 2
    assert capsys.readouterr().err.startswith("acdrive: error: circuit.R: must be")


@pytest.mark.slow
def test_a_batch_of_the_toy_drive_follows_the_phasor_formula(toy):
    _, path = toy
    resistances = [1.0, 2.0, 8.0]
    batch = simulate_batch(str(path), [{"circuit.R": r} for r in resistances] + [{"circuit.R": -1}])
    rows = batch.rows
    assert [r["valid"] for r in rows] == [True, True, True, False]
    assert rows[3]["reason"].startswith("circuit.R")
    for r, row in zip(resistances, rows, strict=False):
        setup = ToySetup(R=r, L=0.01, V_pk=10.0, f=50.0, duration=0.3, sample_time=1e-4)
        assert row["status"] == "ok" and row["stable"] is None  # the toy has no verdict
        assert row["peak_current_a"] == pytest.approx(setup.steady_amplitude(), rel=TOL)
        assert row["final_current_a"] == pytest.approx(setup.steady_amplitude(), rel=TOL)
    # a larger resistance draws less current, as |R + j w L| grows
    assert rows[0]["peak_current_a"] > rows[1]["peak_current_a"] > rows[2]["peak_current_a"]


def test_a_sweep_of_the_toy_drive_follows_the_phasor_formula(toy, tmp_path):
    _, path = toy
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(
        f'name = "toy-sweep"\nbase = "{path.name}"\n[sampling]\nmethod = "grid"\n'
        '[[vary]]\nfield = "source.frequency_hz"\nvalues = [25.0, 50.0, 100.0]\n'
        '[metrics]\nsummary = ["current_amplitude_a"]\n'
    )
    folder = run_sweep(load_sweep(str(sweep)), tmp_path / "out", progress=False)
    table = read_table(folder)
    assert (folder / "report.md").is_file()
    assert list(table["status"]) == ["ok"] * 3
    for _, row in table.iterrows():
        f = row["vary.source.frequency_hz"]
        setup = ToySetup(R=2.0, L=0.01, V_pk=10.0, f=f, duration=0.3, sample_time=1e-4)
        assert row["peak_current_a"] == pytest.approx(setup.steady_amplitude(), rel=TOL)
        assert row["summary.current_amplitude_a"] == pytest.approx(row["peak_current_a"], rel=TOL)
