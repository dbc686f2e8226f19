"""Phase-current sensing as a drive has it: each sensed phase with its offset and gain error,
converted by an ADC of a stated resolution and full scale (rounding to the nearest code,
clipping at the ends of its range), the third phase computed from two when only two are sensed,
and the measured space vector.

The phase currents are those of the stator current space vector ``i_s`` (power-invariant,
Bodson (2)): i_a = sqrt(2/3) Re i_s, i_b = sqrt(2/3) Re(i_s alpha^2), i_c = sqrt(2/3)
Re(i_s alpha) with alpha = exp(j 2 pi / 3). Each sensed phase k reads

    x_k = gain_k i_k + offset_k,   q = 2 full_scale / 2^bits,
    code_k = floor(x_k / q + 1/2) clipped to [-2^(bits-1), 2^(bits-1) - 1],   m_k = q code_k  (C1)

so the ADC spans [-full_scale, full_scale) in 2^bits codes of one LSB q, and inside that span
|m_k - x_k| <= q / 2. A code at either end raises ``clipped``. With ``phases = 2`` phases a and b
are sensed and m_c = -(m_a + m_b) (a winding without a neutral connection); with 3 all three.
The measured vector is Bodson (1), m = sqrt(2/3) (m_a + alpha m_b + alpha^2 m_c).

A constant offset o_k gives the vector a DC component sqrt(2/3) (o_a + alpha o_b + alpha^2 o_c)
with three sensed phases, and sqrt(2/3) ((1 - alpha^2) o_a + (alpha - alpha^2) o_b) with two (the
computed phase carries -(o_a + o_b)); a gain error gives a negative-sequence component."""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from acdrive._jit import jit
from acdrive.core._parts import SampledPart
from acdrive.core._signals import Layout, cplx, real

PARAMS = Layout(
    real("phases", "", "sensed phases: 2 (a and b; c computed) or 3", "count"),
    real("bits", "", "ADC resolution, 1 to 32 bits", "count"),
    real("full_scale", "A", "the ADC spans [-full_scale, full_scale)", "positive"),
    real("gain_a", "", "measured / true of phase a's sensor", "positive"),
    real("gain_b", "", "measured / true of phase b's sensor", "positive"),
    real("gain_c", "", "measured / true of phase c's sensor (3 phases sensed)", "positive"),
    real("offset_a", "A", "offset of phase a's sensor", ""),
    real("offset_b", "A", "offset of phase b's sensor", ""),
    real("offset_c", "A", "offset of phase c's sensor (3 phases sensed)", ""),
)
INPUTS = Layout(cplx("i_s", "A", "stator current space vector, stationary frame"))
OUTPUTS = Layout(
    cplx("i_s", "A", "measured stator current space vector"),
    real("i_a", "A", "measured phase a current"),
    real("i_b", "A", "measured phase b current"),
    real("i_c", "A", "measured (3 phases) or computed (2 phases) phase c current"),
)
(_PHASES, _BITS, _FULL_SCALE, _GAIN_A, _GAIN_B, _GAIN_C, _OFFSET_A, _OFFSET_B,
 _OFFSET_C) = (PARAMS.slot(v.name) for v in PARAMS)  # fmt: skip
_I_S_IN = INPUTS.slot("i_s")
_I_S, _I_A, _I_B, _I_C = (OUTPUTS.slot(n) for n in ("i_s", "i_a", "i_b", "i_c"))
_CLIPPED = 1  # event bit: bit k is EVENTS[k]
K_3C = np.sqrt(2.0 / 3.0)  # Bodson (1)
SQRT3_2 = np.sqrt(3.0) / 2.0
MAX_BITS = 32


@jit
def adc_read(x, lsb, top):
    """(C1): ``x`` rounded to the nearest code of ``lsb``, clipped to [-top, top - 1] codes;
    returns the value read and 1.0 if clipped (else 0.0)."""
    code = np.floor(x / lsb + 0.5)
    clipped = 0.0
    if code > top - 1.0:
        code, clipped = top - 1.0, 1.0
    elif code < -top:
        code, clipped = -top, 1.0
    return code * lsb, clipped


@jit
def current_sensing_step(t, T_s, u, p, s, y):
    """The phase currents of i_s through (C1), the third computed if two are sensed, and the
    measured space vector."""
    codes = 1.0
    for k in range(MAX_BITS):
        if k < p[_BITS]:
            codes = codes * 2.0
    top = 0.5 * codes
    lsb = 2.0 * p[_FULL_SCALE] / codes
    re, im = u[_I_S_IN], u[_I_S_IN + 1]
    i_a = K_3C * re
    i_b = K_3C * (-0.5 * re + SQRT3_2 * im)
    i_c = K_3C * (-0.5 * re - SQRT3_2 * im)
    m_a, clip_a = adc_read(p[_GAIN_A] * i_a + p[_OFFSET_A], lsb, top)
    m_b, clip_b = adc_read(p[_GAIN_B] * i_b + p[_OFFSET_B], lsb, top)
    clip_c = 0.0
    if p[_PHASES] >= 3.0:
        m_c, clip_c = adc_read(p[_GAIN_C] * i_c + p[_OFFSET_C], lsb, top)
    else:
        m_c = -(m_a + m_b)
    y[_I_A], y[_I_B], y[_I_C] = m_a, m_b, m_c
    y[_I_S] = K_3C * (m_a - 0.5 * (m_b + m_c))
    y[_I_S + 1] = K_3C * (SQRT3_2 * (m_b - m_c))
    if clip_a + clip_b + clip_c > 0.0:
        return _CLIPPED
    return 0


class CurrentSensing(SampledPart):
    """Two or three phase-current sensors with offsets and gain errors through an ADC of
    ``bits`` over [-full_scale, full_scale) (rounding, clipping raises ``clipped``); outputs the
    measured phase currents and space vector."""

    SOURCE = ("phase-current sensors with offset, gain and ADC quantisation; Bodson (1)-(2) "
              "(plant._current_sensing.current_sensing_step)")  # fmt: skip

    PARAMS, INPUTS, OUTPUTS = PARAMS, INPUTS, OUTPUTS
    DEFAULTS: ClassVar[dict] = {"phases": 3.0, "bits": 12.0, "gain_a": 1.0, "gain_b": 1.0,
                                "gain_c": 1.0, "offset_a": 0.0, "offset_b": 0.0,
                                "offset_c": 0.0}  # fmt: skip
    EVENTS = ("clipped",)
    step = current_sensing_step

    def check(self) -> None:
        from acdrive.errors import InputError

        phases, bits = self.values["phases"], self.values["bits"]
        if phases not in (2.0, 3.0):
            raise InputError(f"{self.name}.phases", f"must be 2 or 3 sensed phases, got {phases:g}")
        if bits > MAX_BITS:
            raise InputError(f"{self.name}.bits", f"must be from 1 to {MAX_BITS}, got {bits:g}")
