"""``acdrive.drives.run_scenario(load_scenario(name))`` runs a built-in scenario of every drive
kind through the registry and returns that drive's outcome, whose runs do what the scenario
asks: a speed drive's speed ends on its reference, a current step's response ends on its step.
One drive's own names (``simulate``, ``DFIMDrive``, ``run_im_scenario``, ...) refuse another
drive's setup in one ``InputError`` naming the argument and ``run_scenario``."""

from __future__ import annotations

import numpy as np
import pytest

from acdrive.drives import run_scenario
from acdrive.errors import InputError
from acdrive.scenarios import load_scenario

#: one built-in speed-drive scenario per drive kind: (name, the outcome's class, its run labels)
SPEED_SCENARIOS = {
    "dfim": ("bodson-step", "ScenarioOutcome", ("voltage", "current")),
    "cage-im": ("im-foc-speed", "IMOutcome", ("paper-20",)),
    "pm": ("pm-bly171d-speed", "PMOutcome", ("run",)),
}
#: the last fraction of a run judged, and the largest |w - w_ref| over it as a fraction of the
#: final reference: every scenario's speed PI has an integrator and its load is constant there,
#: so the error settles to zero (measured: at most 6.4e-5 of the reference, the cage IM's)
TAIL_FRACTION = 0.1
SPEED_TOLERANCE = 1e-3


def _speed_and_reference(result) -> tuple[np.ndarray, np.ndarray]:
    """(shaft speed, speed reference) [rad/s] of one run: a DFIM or cage-IM result by its
    signal names, a PM run (the engine's SystemResult) by its parts' outputs."""
    if hasattr(result, "shaft"):
        return np.asarray(result.shaft.w), np.asarray(result.speed_reference.w_ref)
    return result.signal("w"), result.signal("w_ref")


@pytest.mark.parametrize("kind", list(SPEED_SCENARIOS))
def test_a_scenario_of_every_drive_kind_runs_and_its_speed_ends_on_the_reference(kind):
    from acdrive.drives import for_setup

    name, outcome_type, labels = SPEED_SCENARIOS[kind]
    setup = load_scenario(name)
    assert for_setup(setup).kind == kind
    announced = []
    outcome = run_scenario(setup, on_run=announced.append)
    assert type(outcome).__name__ == outcome_type and announced
    assert tuple(outcome.results) == labels and isinstance(outcome.summary, dict)
    for label, result in outcome.results.items():
        w, w_ref = _speed_and_reference(result)
        t = np.asarray(result.t)
        tail = t >= t[-1] * (1.0 - TAIL_FRACTION)
        reference = abs(float(w_ref[-1]))
        assert reference > 100.0, label  # a step of 150 to 300 rad/s was asked for and reached
        error = float(np.max(np.abs(w - w_ref)[tail]))
        assert error <= SPEED_TOLERANCE * reference, (label, error)


@pytest.mark.slow
def test_the_pm_current_step_scenario_runs_and_its_step_response_ends_on_the_step():
    """Seed 001's current step (``drives.pm._icad_step``): the two runs differ by the step
    response, which a PI loop ends on the step itself, d axis r_d, q axis 0 (|.| < 1e-4 r_d)."""
    setup = load_scenario("pm-pmsg-2mw-icad-coupling")
    outcome = run_scenario(setup)
    assert type(outcome).__name__ == "PMOutcome" and tuple(outcome.results) == ("step", "base")
    step, base = outcome.results["step"], outcome.results["base"]
    response = np.asarray(step.machine.i_dq)[-1] - np.asarray(base.machine.i_dq)[-1]
    asked = np.asarray(step.reference.i)[-1] - np.asarray(base.reference.i)[-1]
    assert abs(asked) > 0.0
    assert abs(response - asked) < 1e-4 * abs(asked)


def _dfim_names():
    from acdrive.drives import DFIMDrive, simulate, simulate_slow
    from acdrive.drives.dfim import run_scenario as dfim_run_scenario

    return {"acdrive.drives.simulate": simulate, "acdrive.drives.simulate_slow": simulate_slow,
            "acdrive.drives.DFIMDrive": DFIMDrive,
            "acdrive.drives.dfim.run_scenario": dfim_run_scenario}  # fmt: skip


def _cage_im_names():
    from acdrive.drives import IMDrive, run_im_scenario

    return {"acdrive.drives.run_im_scenario": run_im_scenario, "acdrive.drives.IMDrive": IMDrive}


def _pm_names():
    from acdrive.drives.pm import run, run_scenario as pm_run_scenario

    return {"acdrive.drives.pm.run_scenario": pm_run_scenario, "acdrive.drives.pm.run": run}


#: each drive's own names, and a scenario of another drive handed to them
OWN_NAMES = [
    (_dfim_names, "pm-bly171d-speed", "pm"),
    (_dfim_names, "im-foc-speed", "cage-im"),
    (_cage_im_names, "bodson-step", "dfim"),
    (_pm_names, "im-foc-speed", "cage-im"),
]


@pytest.mark.parametrize(("names", "scenario", "kind"), OWN_NAMES)
def test_a_drives_own_name_refuses_another_drives_setup_naming_run_scenario(names, scenario, kind):
    setup = load_scenario(scenario)
    for function, call in names().items():
        with pytest.raises(InputError) as caught:
            call(setup)
        message = str(caught.value)
        assert message.startswith("setup: ") and "\n" not in message, message
        assert f'drive "{kind}"' in message and function in message, message
        assert "acdrive.drives.run_scenario(setup)" in message, message


@pytest.mark.parametrize("value", [None, {"drive": "pm"}, "pm-bly171d-speed", 3.0])
def test_run_scenario_refuses_what_is_no_setup_naming_the_argument(value):
    with pytest.raises(InputError, match=r"^setup: must be the setup of a registered drive"):
        run_scenario(value)


def test_run_scenario_refuses_an_on_run_that_cannot_be_called():
    with pytest.raises(InputError, match=r"^on_run: must be callable"):
        run_scenario(load_scenario("pm-bly171d-speed"), on_run="progress")


def test_the_getting_started_example_runs_as_printed(tmp_path, monkeypatch):
    """docs/getting-started.md's Python example, run as printed (a PM scenario): each run's data
    and columns are saved under its label."""
    import re
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg")
    text = (Path(__file__).resolve().parents[1] / "docs" / "getting-started.md").read_text()
    code = re.search(r"## From Python\n\n```python\n(.*?)```", text, re.DOTALL).group(1)
    monkeypatch.chdir(tmp_path)
    scope: dict = {}
    exec(compile(code, "getting-started.md", "exec"), scope)  # noqa: S102  (the page's example)
    labels = list(scope["outcome"].results)
    assert labels
    for label in labels:
        assert (tmp_path / "my-run" / label / "data.mat").exists()
        assert (tmp_path / "my-run" / label / "columns.md").exists()
    assert "units" in scope["frame"].attrs
