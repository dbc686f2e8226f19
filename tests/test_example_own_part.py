"""The gallery example that writes its own part (a winding thermal model) runs, and its
results obey the model's physics: steady rise R_th P_cu, time constant R_th C_th, the heat
balance, and the closed-form steady state with a temperature-dependent resistance."""

from __future__ import annotations

import runpy
from pathlib import Path

import numpy as np
import pytest

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "plot_winding_thermal.py"


@pytest.mark.slow
def test_the_thermal_part_example_obeys_its_physics():
    import matplotlib

    matplotlib.use("Agg")
    scope = runpy.run_path(str(EXAMPLE), run_name="__main__")
    thermal, tau = scope["thermal"], scope["tau"]
    R_th, C_th = thermal.values["R_th"], thermal.values["C_th"]
    assert tau == R_th * C_th
    # steady state over the last time constant (9 to 10 tau: exp(-9) of the rise left)
    assert scope["rise"] == pytest.approx(R_th * scope["P"][scope["settled"]].mean(), rel=1e-3)
    assert -1.0 / scope["slope"] == pytest.approx(tau, rel=1e-2)
    losses = np.trapezoid(scope["P"], scope["t"])
    assert abs(scope["stored"] - scope["balance"]) < 1e-3 * losses
    assert scope["hot_rise"] == pytest.approx(scope["expected_hot"], rel=1e-3)
    assert scope["hot_rise"] > scope["rise"] > 1.0  # a visible rise, higher when R_s grows
    rows = scope["thermal"].describe().section("inputs").rows
    assert [(r.name, r.unit, r.kind) for r in rows] == [("i_s", "A", "complex")]
    plt = pytest.importorskip("matplotlib.pyplot")
    plt.close("all")
