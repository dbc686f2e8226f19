"""Phase-current sensing (acdrive.plant.CurrentSensing): the ADC's rounding error within half an
LSB, clipping at the ends of its range with its event, the third phase computed from two, and
the analytic DC component of the measured space vector from the sensors' offsets."""

from __future__ import annotations

import numpy as np
import pytest
from test_sensor_encoder import column, step_through

from acdrive.errors import InputError
from acdrive.plant import CurrentSensing

ALPHA = np.exp(2j * np.pi / 3)
K_3C = np.sqrt(2 / 3)


def _phases(i_s: np.ndarray) -> np.ndarray:
    """The zero-sum phase currents of power-invariant space vectors (Bodson (2))."""
    return K_3C * np.stack([i_s.real, (i_s * ALPHA**2).real, (i_s * ALPHA).real], axis=1)


def _read(part, i_s: np.ndarray):
    y, events = step_through(part, np.stack([i_s.real, i_s.imag], axis=1))
    phases = y[:, [column(part, n) for n in ("i_a", "i_b", "i_c")]]
    vector = y[:, column(part, "i_s")] + 1j * y[:, column(part, "i_s") + 1]
    return phases, vector, events


def test_the_quantisation_error_is_within_half_an_lsb():
    """Currents spread over the ADC's range, three phases sensed, no offset or gain error: each
    phase read is a whole number of LSBs q = 2 full_scale / 2^bits within q/2 of the current,
    and the half LSB is reached (rounding, not truncation); nothing clipped."""
    full_scale, bits = 25.0, 10
    sensing = CurrentSensing("cs", bits=bits, full_scale=full_scale)
    rng = np.random.default_rng(3)
    i_s = rng.uniform(0, 0.95 * full_scale / K_3C, 20_000) * np.exp(1j * rng.uniform(0, 7, 20_000))
    phases, _, events = _read(sensing, i_s)
    q = 2 * full_scale / 2**bits
    error = phases - _phases(i_s)
    assert np.max(np.abs(error)) <= q / 2 * (1 + 1e-12)
    assert np.max(np.abs(error)) > 0.99 * q / 2 and error.min() < -0.49 * q
    assert np.allclose(phases / q, np.round(phases / q), rtol=0, atol=1e-9)
    assert not events.any()


def test_clipping_holds_the_end_codes_and_raises_the_event():
    """Beyond the range the code is held at -2^(bits-1) or 2^(bits-1) - 1 and ``clipped`` is
    raised on exactly those samples."""
    full_scale, bits = 10.0, 8
    sensing = CurrentSensing("cs", bits=bits, full_scale=full_scale)
    q = 2 * full_scale / 2**bits
    i_a = np.linspace(-15.0, 15.0, 3001)
    i_s = i_a / K_3C + 0j  # phase a = i_a, phases b and c = -i_a / 2
    phases, _, events = _read(sensing, i_s)
    code = np.floor(i_a / q + 0.5)
    outside = (code > 2 ** (bits - 1) - 1) | (code < -(2 ** (bits - 1)))
    assert np.array_equal(events == 1, outside)
    assert phases[:, 0].max() == full_scale - q and phases[:, 0].min() == -full_scale
    assert np.all(np.abs(phases[~outside, 0] - i_a[~outside]) <= q / 2)


@pytest.mark.parametrize("sensed", [3, 2])
def test_offsets_give_the_analytic_dc_component(sensed):
    """A rotating current over whole periods through sensors with offsets (32 bits: the LSB
    negligible): the measured vector's mean is sqrt(2/3) (o_a + alpha o_b + alpha^2 o_c) with
    three phases sensed, sqrt(2/3) ((1 - alpha^2) o_a + (alpha - alpha^2) o_b) with two (the
    computed phase carries -(o_a + o_b)); with two, i_c = -(i_a + i_b)."""
    o_a, o_b, o_c = 0.12, -0.05, 0.08
    sensing = CurrentSensing("cs", phases=sensed, bits=32, full_scale=100.0, offset_a=o_a,
                             offset_b=o_b, offset_c=o_c)  # fmt: skip
    i_s = 20.0 * np.exp(1j * 2 * np.pi * np.arange(1000) / 1000)
    phases, vector, _ = _read(sensing, i_s)
    if sensed == 3:
        expected = K_3C * (o_a + ALPHA * o_b + ALPHA**2 * o_c)
    else:
        expected = K_3C * ((1 - ALPHA**2) * o_a + (ALPHA - ALPHA**2) * o_b)
        assert np.array_equal(phases[:, 2], -(phases[:, 0] + phases[:, 1]))
    assert abs(np.mean(vector) - expected) < 1e-7 * abs(expected)
    assert abs(np.mean(vector)) > 0.05  # an offset, not the rounding


def test_a_gain_error_gives_the_negative_sequence_of_the_analytic_size():
    """Gain 1 + d on phase a only (three sensed): m = i + sqrt(2/3) d i_a, whose negative
    sequence (the e^{-j w t} component) has magnitude |i| d / 3."""
    d = 0.03
    sensing = CurrentSensing("cs", bits=32, full_scale=100.0, gain_a=1 + d)
    angle = 2 * np.pi * np.arange(1000) / 1000
    i_s = 20.0 * np.exp(1j * angle)
    _, vector, _ = _read(sensing, i_s)
    negative = np.mean(vector * np.exp(1j * angle))
    assert abs(negative) == pytest.approx(20.0 * d / 3, rel=1e-6)


@pytest.mark.parametrize(("field", "value"), [("bits", 0), ("bits", 33), ("bits", 12.5),
                                              ("phases", 1), ("phases", 4),
                                              ("full_scale", 0.0), ("gain_b", -1.0)])  # fmt: skip
def test_bad_parameters_are_refused_naming_the_field(field, value):
    with pytest.raises(InputError, match=rf"^cs\.{field}: "):
        CurrentSensing("cs", **{"full_scale": 10.0, field: value})
