"""Two-level voltage-source inverter with centred space-vector PWM, as a modulator part.

The inverter of Amezquita-Brooks et al., section VI: a DC link (310 V, wired from a DC source's
output), a two-level IGBT bridge switched by 5 kHz space-vector modulation, the controller
sampling at 50 kHz. Where the averaged converter (``plant._converter``) holds the command over the
sample, this part returns the switching pattern itself: the piecewise-constant voltage applied to
an isolated-star load, with exact switching instants, which the system loop integrates segment by
segment.

**Scaling.** Leg x (a, b, c) connects its output to the positive rail (state h_x = 1) or the
negative rail (h_x = 0); its pole voltage, measured from the negative rail, is e_x = v_dc h_x. The
star point of the load floats, so the phase-to-neutral voltages are the pole voltages less their
mean, and their space vector (Bodson (1), power invariant) is

    v = sqrt(2/3) (e_a + alpha e_b + alpha^2 e_c),    alpha = exp(j 2 pi / 3),

the common mean dropping out. The six active states give |v| = sqrt(2/3) v_dc (the corners of the
hexagon), the two zero states v = 0. A balanced phase voltage of peak V has |v| = sqrt(3/2) V
(``frames.K_PEAK``).

**Modulation** (centred, symmetric SVPWM = min-max zero-sequence injection). At the start of each
carrier period T_pwm = 1/f_pwm the part latches the command v_ref and the DC-link voltage v_dc,
limits the command, takes its zero-sum phase values (Bodson (2)) x_a, x_b, x_c, adds the
zero-sequence offset -(max + min)/2 and sets the duty cycles

    d_x = 1/2 + (x_x - (max + min) / 2) / v_dc   in [0, 1].

Leg x is high for d_x T_pwm centred in the carrier period, from (1 - d_x) T_pwm / 2 to
(1 + d_x) T_pwm / 2 (a triangular carrier compared with d_x). The period therefore runs through
the seven states 000, one leg, two legs, 111, two legs, one leg, 000 with equal halves of the two
zero vectors: classic SVPWM. The pattern's mean pole voltages are d_x v_dc, whose space vector is
the limited command exactly: the volt-second balance holds over every carrier period.

**Carrier and control samples.** The carrier period holds N control samples: N = T_pwm / T_s must
be an integer >= 1 (N = 10 in the paper). ``Inverter.check_sample_time`` refuses any other
sample time before every run (the system calls it through ``check_run``); the kernel itself uses N = max(1, round(T_pwm / T_s)), i.e. a carrier
period of N T_s (equal to T_pwm whenever the check passes), so it never fails mid-run. The state
holds the sample index within the carrier period and the latched duty cycles; in each control
sample the kernel returns the segments of the pattern inside [t_k, t_k + T_s], the lengths
``dt[:n]`` summing to T_s. The command is latched once per carrier period (a PWM unit's shadow
registers loaded at the period start): the controller's outputs of the other N - 1 samples are
not applied. The DC-link voltage is read at every sample instant and held over the sample: the
switching times come from the latched value, the applied voltages from the present one (a link
that sags between samples is seen with a delay of at most T_s).

**Overmodulation.** A command beyond the circle inscribed in the hexagon, |v_ref| > v_dc / sqrt(2)
(``plant._converter.max_voltage_magnitude``), is scaled back along its own direction to that
magnitude, the rule of the averaged converter, so both apply the same mean voltage. The part
reports the event ``overmodulation`` on every sample of a carrier period whose command was
limited. A command within a few ulps above the limit (``_frames.beyond_limit``, relative
tolerance ``_frames.LIMIT_RTOL``) is at the limit, not beyond it: a controller that limited its
command to v_dc / sqrt(2) itself hands over such a rounded magnitude, which is neither changed
nor counted. (Min-max modulation could reach the hexagon's corners; the circle keeps the output
sinusoidal for a rotating command and equal to the averaged converter's.)

**Dead time and device drops** (both default 0). Phase current i_x > 0 flows out of the leg into
the load. Switching a leg, the outgoing device turns off at the commanded instant and the
incoming one turns on t_d later; in between the current freewheels through a diode, which ties
the pole to the negative rail if i_x > 0 and to the positive rail if i_x < 0. Hence with i_x > 0
the high interval becomes [(1 - d_x) T_pwm / 2 + t_d, (1 + d_x) T_pwm / 2] (its rising edge
delayed), with i_x < 0 it becomes [(1 - d_x) T_pwm / 2, (1 + d_x) T_pwm / 2 + t_d] (its falling
edge delayed), each pulse confined to its carrier period; a leg with d_x = 0 or 1 does not switch
and has no dead interval. Each conducting device (IGBT or diode alike) drops v_drop in the
direction of the current: e_x = v_dc h_x - v_drop sign(i_x). Away from the duty-cycle extremes
(t_d <= d_x T_pwm for i_x > 0, t_d <= (1 - d_x) T_pwm / 2 for i_x < 0) the mean pole voltage of a
carrier period is therefore off by -sign(i_x) (t_d f_pwm v_dc + v_drop), and the space vector of
these three errors (their common mean drops out) is the inverter's average voltage error.
The current signs are those of the input i_s (the plant's phase currents, zero-sum: Bodson (2))
at the sample instant, held over the sample. This is an approximation near a current zero
crossing: a current that changes sign within a sample keeps its old polarity until the next
sample (at most T_s, not a carrier period), and a current of exactly zero takes the ideal edges
and no drop.

**Outputs.** ``v``, the applied phase-to-neutral voltage space vector of each segment (the loop
logs the first segment of a sample, i.e. the voltage just after t_k); ``v_lim``, the latched
command after the limit (the ideal mean of ``v`` over the carrier period); ``m_a``, ``m_b``,
``m_c``, the phase modulation signals 2 d_x - 1 in [-1, 1] (pole-voltage reference over v_dc / 2,
with the min-max zero sequence), held over the carrier period: ``m_a`` is the signal of the
paper's Fig. 13(d).

**Worst case.** A leg switches at most twice per carrier period, so at most six instants fall
inside one control sample: ``MAX_SEGMENTS`` = 7 (reached with N = 1).
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from acdrive._frames import K_3C
from acdrive._jit import jit, jit_inline, python_from_python
from acdrive.core._parts import Modulator, SampledPart
from acdrive.core._signals import Layout, cplx, real
from acdrive.errors import InputError
from acdrive.plant._converter import converter_output, max_voltage_magnitude

PARAMS = Layout(
    real("f_pwm", "Hz", "carrier (switching) frequency of the space-vector modulation", "positive"),
    real("t_d", "s", "dead time between the two devices of a leg", "nonnegative"),
    real("v_drop", "V", "on-state voltage of a conducting device (IGBT or diode)", "nonnegative"),
)
STATES = Layout(
    real("k", "", "index of the next control sample within the carrier period"),
    real("d_a", "", "latched duty cycle of leg a"),
    real("d_b", "", "latched duty cycle of leg b"),
    real("d_c", "", "latched duty cycle of leg c"),
    cplx("v_lim", "V", "latched command after the limit"),
    real("limited", "", "1 if the latched command was limited"),
)
INPUTS = Layout(
    cplx("v_ref", "V", "commanded voltage space vector, stationary frame"),
    real("v_dc", "V", "DC-link voltage"),
    cplx("i_s", "A", "phase currents out of the inverter as a space vector (their polarity)"),
)
OUTPUTS = Layout(
    cplx("v", "V", "applied phase-to-neutral voltage space vector, per segment"),
    cplx("v_lim", "V", "latched command after the limit (the ideal mean of v)"),
    real("m_a", "", "phase a modulation signal 2 d_a - 1, held over the carrier period"),
    real("m_b", "", "phase b modulation signal 2 d_b - 1, held over the carrier period"),
    real("m_c", "", "phase c modulation signal 2 d_c - 1, held over the carrier period"),
)
_F_PWM, _T_D, _V_DROP = (PARAMS.slot(n) for n in ("f_pwm", "t_d", "v_drop"))
_K, _D_A, _D_B, _D_C, _S_V_LIM, _LIMITED = (
    STATES.slot(n) for n in ("k", "d_a", "d_b", "d_c", "v_lim", "limited")
)
_V_REF, _V_DC, _I_S = (INPUTS.slot(n) for n in ("v_ref", "v_dc", "i_s"))
_V, _V_LIM, _M_A, _M_B, _M_C = (OUTPUTS.slot(n) for n in ("v", "v_lim", "m_a", "m_b", "m_c"))
EVENT_OVERMODULATION = 1
_HALF_SQRT3 = math.sqrt(3.0) / 2.0
_INV_SQRT2 = 1.0 / math.sqrt(2.0)
#: relative tolerance of the rule "T_pwm / T_s is an integer"
_N_TOLERANCE = 1e-9


@python_from_python
@jit_inline
def carrier_samples(f_pwm, T_s):
    """Control samples per carrier period, N = max(1, round(1 / (f_pwm T_s)))."""
    return max(1.0, np.floor(1.0 / (f_pwm * T_s) + 0.5))


@jit_inline
def _polarity(x):
    if x > 0.0:
        return 1.0
    if x < 0.0:
        return -1.0
    return 0.0


@jit_inline
def _duty(x, offset, v_dc):
    """Pole duty cycle of a phase value ``x`` with zero-sequence ``offset`` (clamped to [0, 1])."""
    if v_dc <= 0.0:
        return 0.5
    d = 0.5 + (x + offset) / v_dc
    return min(max(d, 0.0), 1.0)


@jit_inline
def _pulse(d, polarity, n_carrier, delta):
    """(start, end) of a leg's high interval, in control samples from the carrier start, for
    duty ``d``, current ``polarity`` and dead time ``delta`` (in samples); (0, 0): never high."""
    if d <= 0.0:
        return 0.0, 0.0
    if d >= 1.0:
        return 0.0, n_carrier
    start = 0.5 * (1.0 - d) * n_carrier
    end = 0.5 * (1.0 + d) * n_carrier
    if polarity > 0.0:
        start += delta  # rising edge delayed: the lower diode holds the pole low
        if start >= end:
            return 0.0, 0.0
    elif polarity < 0.0:
        end = min(end + delta, n_carrier)  # falling edge delayed: the upper diode holds it high
    return start, end


@jit_inline
def _add_edges(start, end, j, dt, m):
    """Append the pulse edges strictly inside control sample ``j`` (as fractions of it) to
    ``dt[m:]``; returns the new count."""
    if start < end:
        e = start - j
        if 0.0 < e < 1.0:
            dt[m] = e
            m += 1
        e = end - j
        if 0.0 < e < 1.0:
            dt[m] = e
            m += 1
    return m


@jit
def inverter_segments(T_s, u, p, s, dt, v):
    """The switching pattern inside one control sample (module docstring); no allocation: the
    switching instants are sorted in ``dt`` itself before it receives the segment lengths."""
    n_carrier = carrier_samples(p[_F_PWM], T_s)
    j = s[_K]
    if j < 0.0 or j >= n_carrier:
        j = 0.0
    v_dc = max(u[_V_DC], 0.0)
    if j == 0.0:  # start of a carrier period: latch the limited command as duty cycles
        applied, limited = converter_output(
            complex(u[_V_REF], u[_V_REF + 1]), max_voltage_magnitude(v_dc)
        )
        re, im = applied.real, applied.imag
        x_a = K_3C * re
        x_b = K_3C * (-0.5 * re + _HALF_SQRT3 * im)
        x_c = K_3C * (-0.5 * re - _HALF_SQRT3 * im)
        offset = -0.5 * (max(x_a, x_b, x_c) + min(x_a, x_b, x_c))
        s[_D_A] = _duty(x_a, offset, v_dc)
        s[_D_B] = _duty(x_b, offset, v_dc)
        s[_D_C] = _duty(x_c, offset, v_dc)
        s[_S_V_LIM], s[_S_V_LIM + 1] = re, im
        s[_LIMITED] = 1.0 if limited else 0.0
    s[_K] = j + 1.0 if j + 1.0 < n_carrier else 0.0

    # current polarity of each phase (Bodson (2) without its positive factor sqrt(2/3))
    i_re, i_im = u[_I_S], u[_I_S + 1]
    sig_a = _polarity(i_re)
    sig_b = _polarity(-0.5 * i_re + _HALF_SQRT3 * i_im)
    sig_c = _polarity(-0.5 * i_re - _HALF_SQRT3 * i_im)
    delta = p[_T_D] / T_s
    a0, a1 = _pulse(s[_D_A], sig_a, n_carrier, delta)
    b0, b1 = _pulse(s[_D_B], sig_b, n_carrier, delta)
    c0, c1 = _pulse(s[_D_C], sig_c, n_carrier, delta)

    # switching instants inside this sample, sorted (insertion sort, at most six)
    m = _add_edges(a0, a1, j, dt, 0)
    m = _add_edges(b0, b1, j, dt, m)
    m = _add_edges(c0, c1, j, dt, m)
    for i in range(1, m):
        e = dt[i]
        q = i - 1
        while q >= 0 and dt[q] > e:
            dt[q + 1] = dt[q]
            q -= 1
        dt[q + 1] = e

    drop = p[_V_DROP]
    lim_re, lim_im = s[_S_V_LIM], s[_S_V_LIM + 1]
    m_a, m_b, m_c = 2.0 * s[_D_A] - 1.0, 2.0 * s[_D_B] - 1.0, 2.0 * s[_D_C] - 1.0
    n = 0
    previous = 0.0
    used = 0.0
    for i in range(m + 1):
        e = dt[i] if i < m else 1.0  # read before dt[n] (n <= i) is overwritten
        if e <= previous:
            continue  # two legs switching at the same instant
        middle = j + 0.5 * (previous + e)
        e_a = (v_dc if a0 < middle < a1 else 0.0) - drop * sig_a
        e_b = (v_dc if b0 < middle < b1 else 0.0) - drop * sig_b
        e_c = (v_dc if c0 < middle < c1 else 0.0) - drop * sig_c
        length = (e - previous) * T_s if i < m else T_s - used
        dt[n] = length
        used += length
        v[n, _V] = K_3C * (e_a - 0.5 * (e_b + e_c))
        v[n, _V + 1] = _INV_SQRT2 * (e_b - e_c)
        v[n, _V_LIM], v[n, _V_LIM + 1] = lim_re, lim_im
        v[n, _M_A], v[n, _M_B], v[n, _M_C] = m_a, m_b, m_c
        n += 1
        previous = e
    return n, EVENT_OVERMODULATION if s[_LIMITED] != 0.0 else 0


class Inverter(Modulator):
    """Two-level voltage-source inverter with centred space-vector PWM (Amezquita-Brooks et al.,
    section VI): exact switching instants within each control sample, the command latched once
    per carrier period, limited to |v| <= v_dc / sqrt(2) (event ``overmodulation``), optional
    dead time ``t_d`` and device drop ``v_drop`` (module docstring).

    The control sample time must divide the carrier period: every run checks it
    (``check_run``); the kernel itself would round the number of samples per carrier period.
    """

    SOURCE = (
        "two-level inverter, centred SVPWM, dead time and device drops; Amezquita-Brooks et al. VI "
        "(plant._inverter.inverter_segments)"
    )

    PARAMS, STATES, INPUTS, OUTPUTS = PARAMS, STATES, INPUTS, OUTPUTS
    DEFAULTS: ClassVar[dict] = {"f_pwm": 5000.0, "t_d": 0.0, "v_drop": 0.0}
    EVENTS = ("overmodulation",)
    MAX_SEGMENTS = 7
    segments = inverter_segments

    def check(self) -> None:
        f_pwm, t_d = self.values["f_pwm"], self.values["t_d"]
        if t_d >= 0.5 / f_pwm:
            raise InputError(
                f"{self.name}.t_d",
                f"must be shorter than half the carrier period 1 / (2 f_pwm) = {0.5 / f_pwm:g} s, "
                f"got {t_d:g}",
            )

    def carrier_period(self) -> float:
        """T_pwm = 1 / f_pwm [s]."""
        return 1.0 / self.values["f_pwm"]

    def check_run(self, sample_time: float) -> None:
        """Before every run (``core.Part.check_run``): the sample time divides the carrier
        period."""
        self.check_sample_time(sample_time)

    def check_sample_time(self, sample_time: float) -> int:
        """N = T_pwm / sample_time, the control samples per carrier period, if it is an integer
        >= 1 (relative tolerance 1e-9); otherwise an ``InputError`` naming ``sample_time``."""
        period = self.carrier_period()
        if (
            isinstance(sample_time, bool)
            or not isinstance(sample_time, (int, float))
            or not math.isfinite(sample_time)
            or sample_time <= 0.0
        ):
            raise InputError("sample_time", "must be a finite number > 0")
        ratio = period / sample_time
        n = round(ratio)
        if n < 1 or abs(ratio - n) > _N_TOLERANCE * ratio:
            raise InputError(
                "sample_time",
                f"must be the carrier period of {self.name} (1 / {self.name}.f_pwm = {period:g} s) "
                f"divided by an integer >= 1, got {sample_time:g} s (ratio {ratio:.6g})",
            )
        return int(n)


# --- the PWM unit's latch, in front of an averaged converter -----------------------------------------------------

LATCH_PARAMS = Layout(real("f_pwm", "Hz", "carrier frequency", "positive"))
LATCH_STATES = Layout(
    real("k", "", "index of the next control sample within the carrier period"),
    cplx("v", "V", "command latched at the carrier period start"),
)
LATCH_INPUTS = Layout(cplx("v_ref", "V", "voltage command of the controller, every sample"))
LATCH_OUTPUTS = Layout(cplx("v_ref", "V", "command latched at the carrier period start"))
_LA_F = LATCH_PARAMS.slot("f_pwm")
_LA_K, _LA_V = LATCH_STATES.slot("k"), LATCH_STATES.slot("v")


@jit
def latch_step(t, T_s, u, p, s, y):
    """At the first sample of each carrier period take the command; hold it for N samples (the
    rule of ``plant._inverter.inverter_segments``, same N)."""
    n = carrier_samples(p[_LA_F], T_s)
    j = s[_LA_K]
    if j < 0.0 or j >= n:
        j = 0.0
    if j == 0.0:
        s[_LA_V], s[_LA_V + 1] = u[0], u[1]
    s[_LA_K] = j + 1.0 if j + 1.0 < n else 0.0
    y[0], y[1] = s[_LA_V], s[_LA_V + 1]
    return 0


class CarrierLatch(SampledPart):
    """The PWM unit's shadow register: the controller's command taken once per carrier period
    1 / f_pwm (N = T_pwm / T_s samples) and held, as ``plant.Inverter`` latches it; in
    front of an averaged converter it makes the carrier-period average of the inverter."""

    SOURCE = (
        "the PWM unit's shadow register, N = max(1, round(1 / (f_pwm T_s))) samples "
        "(plant._inverter.latch_step)"
    )

    PARAMS, STATES, INPUTS, OUTPUTS = LATCH_PARAMS, LATCH_STATES, LATCH_INPUTS, LATCH_OUTPUTS
    DEFAULTS: ClassVar[dict] = {"f_pwm": 5000.0}
    step = latch_step

    def check_run(self, sample_time: float) -> None:
        Inverter(self.name, f_pwm=self.values["f_pwm"]).check_sample_time(sample_time)
