"""The sensors guide's example (docs/guide/sensors.md) runs as printed, and what it shows holds:
the encoder's speed is within one count per sample of the shaft's, the resolver's electrical
angle within its imbalance's error of the shaft's."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

GUIDE = Path(__file__).resolve().parent.parent / "docs" / "guide" / "sensors.md"


def test_the_guides_example_runs_and_reads_the_shaft(monkeypatch):
    monkeypatch.setenv("ACDRIVE_LOOP_TIER", "auto")  # native where a C compiler is, as a user runs
    code = re.search(r"```python\n(.*?)```", GUIDE.read_text(), re.S).group(1)
    names: dict = {}
    exec(compile(code, str(GUIDE), "exec"), names)  # noqa: S102 (the guide's own example)
    result, encoder, resolver = (names[n] for n in ("result", "encoder", "resolver"))
    t = result.t
    w = np.interp(t, [0.0, 0.05], [0.0, 300.0])
    theta = np.concatenate([[0.0], np.cumsum((w[1:] + w[:-1]) / 2 * np.diff(t))])
    one_count = 2 * np.pi / 4096 / 1e-4
    late = t > 0.06
    assert np.max(np.abs(result.signal(encoder.out.w)[late] - 300.0)) <= one_count
    error = (result.signal(resolver.out.theta_e) - 4 * theta + np.pi) % (2 * np.pi) - np.pi
    assert np.max(np.abs(error[late])) < 4 * 0.01  # (a/2) sin 2 th, a = 0.01, times pole_pairs
