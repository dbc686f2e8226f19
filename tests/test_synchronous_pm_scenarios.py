"""Every built-in PM drive scenario run with the synchronous machine of linear magnetics
(``machines.SynchronousMachine``, flux states) in place of ``PermanentMagnetMachine`` (current
states) gives the same run: the same drive, controller and converter, only the machine part
swapped where the drive builds it (``drives.pm._build``, ``drives.pm._icad_step``).

Runge-Kutta commutes with the affine change of state psi = L i + psi_pm, so the two runs differ
by rounding, carried through the closed loop (the speed and current controllers, a switching
inverter's instants, an encoder's counts): every logged signal agrees to 1e-8 of its largest
value and every number of the summaries to 1e-6. A model that differed (a magnet flux without
sqrt(3/2), a torque off by 3/2 or by sign) would move them by orders of magnitude more.
"""

from __future__ import annotations

import numpy as np
import pytest

from acdrive.drives.pm import _build, _icad_step, builtin
from acdrive.drives.pm._entry import run_scenario
from acdrive.drives.pm._schema import builtin_names
from acdrive.machines import SynchronousMachine


class LinearSynchronousMachine:
    """Builds the linear synchronous machine from a PM record, as the drives build the PM part."""

    @staticmethod
    def from_params(name, params):
        return SynchronousMachine(name, saturation=0, R_s=params.R_s, L_d=params.L_d,
                                  L_q=params.L_q, psi_m=params.psi_m, n_p=params.n_p)  # fmt: skip


def numbers_of(summary, prefix=""):
    """The numbers of a (nested) summary by their key paths."""
    out = {}
    items = summary.items() if isinstance(summary, dict) else enumerate(summary)
    for key, value in items:
        path = f"{prefix}/{key}"
        if isinstance(value, (dict, list, tuple)):
            out.update(numbers_of(value, path))
        elif isinstance(value, (int, float)) and not isinstance(value, bool):
            out[path] = float(value)
    return out


@pytest.mark.parametrize("name", builtin_names())
def test_pm_scenario_runs_the_same_with_the_linear_synchronous_machine(name, monkeypatch):
    setup = builtin(name)
    reference, reference_summary = run_scenario(setup)
    monkeypatch.setattr(_build, "PermanentMagnetMachine", LinearSynchronousMachine)
    monkeypatch.setattr(_icad_step, "PermanentMagnetMachine", LinearSynchronousMachine)
    swapped, swapped_summary = run_scenario(setup)
    assert swapped.data.shape == reference.data.shape
    scale = np.max(np.abs(reference.data), axis=0)
    moving = scale > 0.0  # a signal that stays zero (a zero reference) stays zero
    assert np.count_nonzero(moving) >= 4
    assert np.all(swapped.data[:, ~moving] == 0.0)
    worst = np.max(np.abs(swapped.data[:, moving] - reference.data[:, moving]), axis=0)
    assert np.all(worst < 1e-8 * scale[moving]), np.max(worst / scale[moving])
    expected, got = numbers_of(reference_summary), numbers_of(swapped_summary)
    assert expected.keys() == got.keys() and len(expected) > 3
    for key, value in expected.items():
        assert got[key] == pytest.approx(value, rel=1e-6, abs=1e-9), key
