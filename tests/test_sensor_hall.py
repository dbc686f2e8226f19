"""Hall sensors (acdrive.plant.HallSensors): the three signals' 60-degree sectors with the
mounting offset, and at a constant speed the interpolated angle and the speed from the time
between edges within their analytic bounds."""

from __future__ import annotations

import numpy as np
import pytest
from test_sensor_encoder import column, step_through, wrapped

from acdrive.errors import InputError
from acdrive.plant import HallSensors

TWO_PI = 2.0 * np.pi
T_S = 1e-4
SECTOR = np.pi / 3


def test_the_signals_mark_sixty_degree_sectors_from_the_offset():
    """h_a high on [0, pi), h_b on [2 pi/3, 5 pi/3), h_c on [4 pi/3, 2 pi) and [0, pi/3) of
    pole_pairs theta + offset; one signal changes at each edge; the codes run 101, 100, 110,
    010, 011, 001 through the sectors 0 .. 5."""
    hall = HallSensors("hall", pole_pairs=2, offset=0.4)
    theta = np.linspace(0.0, TWO_PI, 20_001)[:-1]
    y, _ = step_through(hall, theta)
    x = (2 * theta + 0.4) % TWO_PI
    h = y[:, [column(hall, n) for n in ("h_a", "h_b", "h_c")]]
    assert np.array_equal(h[:, 0], (x < np.pi).astype(float))
    assert np.array_equal(h[:, 1], ((x >= 2 * np.pi / 3) & (x < 5 * np.pi / 3)).astype(float))
    assert np.array_equal(h[:, 2], ((x >= 4 * np.pi / 3) | (x < np.pi / 3)).astype(float))
    assert np.max(np.abs(np.diff(h, axis=0)).sum(axis=1)) == 1.0
    sector = y[:, column(hall, "sector")]
    codes = {(1, 0, 1): 0, (1, 0, 0): 1, (1, 1, 0): 2, (0, 1, 0): 3, (0, 1, 1): 4, (0, 0, 1): 5}
    assert all(codes[tuple(int(v) for v in row)] == k for row, k in zip(h, sector, strict=True))


@pytest.mark.parametrize("w", [150.0, -90.0, 400.0])
def test_the_interpolated_angle_and_the_speed_keep_their_bounds_at_constant_speed(w):
    """At a constant speed (D = (pi/3) / |w_e| between edges): before the first edge the angle
    is the sector's centre (within pi/6); between the first and second edges within
    pi/3 + |w_e| T_s; from the second edge on the speed within |w| T_s / (D - T_s) and the angle
    within |w_e| T_s (1 + (D + T_s) / (D - T_s)), the bound of the module's docstring; and that
    bound is below the half sector a reading of the sector's centre may be off by."""
    n_p, offset = 3, 0.25
    hall = HallSensors("hall", pole_pairs=n_p, offset=offset)
    theta = 0.1 + w * np.arange(round(0.1 / T_S)) * T_S
    y, events = step_through(hall, theta)
    w_e = abs(n_p * w)
    D = SECTOR / w_e
    error = np.abs(wrapped(y[:, column(hall, "theta_e")] - (n_p * theta + offset)))
    speed = y[:, column(hall, "w")]
    edges = np.nonzero(events & 1)[0]
    assert len(edges) > 10 and not np.any(events & 2)
    first, second = edges[0], edges[1]
    assert np.max(error[:first]) <= SECTOR / 2 + 1e-12
    assert np.max(error[first:second]) <= SECTOR + w_e * T_S + 1e-12
    assert np.all(speed[:second] == 0.0)
    assert np.max(np.abs(speed[second:] - w)) <= abs(w) * T_S / (D - T_S) * (1 + 1e-9)
    bound = w_e * T_S * (1 + (D + T_S) / (D - T_S))
    assert np.max(error[second:]) <= bound * (1 + 1e-9)
    assert bound < SECTOR / 2  # below the error of the sector centre without interpolation


def test_a_reversal_restarts_the_speed_and_a_stopped_shaft_reads_a_falling_speed():
    """The speed is zero after a reversal until two edges in the new direction, then negative;
    after the shaft stops, the speed decays as (pi/3) / (t - t_edge)."""
    hall = HallSensors("hall")
    w = np.where(np.arange(6000) < 3000, 200.0, -200.0)
    w[5000:] = 0.0
    theta = np.cumsum(w) * T_S
    y, events = step_through(hall, theta)
    speed = y[:, column(hall, "w")]
    edges = np.nonzero(events & 1)[0]
    back = edges[edges >= 3000]
    assert speed[back[0]] == 0.0 and speed[back[1]] < -100.0
    last = edges[edges < 5000][-1]
    t = np.arange(6000) * T_S
    late = np.arange(6000) > last + 200
    assert np.allclose(speed[late], -SECTOR / (t[late] - t[last]), rtol=1e-12)


def test_bad_parameters_are_refused_naming_the_field():
    with pytest.raises(InputError, match=r"^hall\.pole_pairs: "):
        HallSensors("hall", pole_pairs=1.5)
