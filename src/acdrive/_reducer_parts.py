"""The reducer parts of ``acdrive.batch``: sampled parts appended to a drive's system that read
its outputs at the samples a single run logs and accumulate metrics in their discrete state.

One "stats" part (peak, mean, RMS, exceed count, final value, one channel per signal,
reference, window and limit; its step generated for its channels by ``_stats_source``), one
part per oscillation metric (``oscillation_step``: the band-limited RMS in two late windows) and
one per speed error (``speed_error_step``: the kernel of ``sim._metrics`` that a single run's
summary runs on its logged samples) and one per step response (``step_response_step``: the
kernel of ``sim._step_response``, the figures a single run's summary computes).

``Reducer`` is the metric these parts compute, as a batch or a drive's robustness map declares it
(re-exported by ``acdrive.batch``). It lives here, below the drives, because a drive names its
own default metrics.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from acdrive._jit import jit, njit
from acdrive.core._parts import SampledPart
from acdrive.core._signals import Layout, cplx, real
from acdrive.sim._codegen import load_module
from acdrive.sim._metrics import (
    LATE_WINDOW_S,
    NO_CLOSING,
    OSCILLATION_BAND_HZ,
    SPEED_ERROR_STATES,
    TrackingRule,
    speed_error_figures,
    speed_error_update,
)

from acdrive.sim._step_response import (
    EVENT_PARAMS,
    EVENT_STATES,
    NOT_YET,
    event_params,
    figures,
    flat,
    initial_state,
    step_response_update,
)

REDUCER_KINDS = ("peak", "mean", "rms", "exceed", "final", "oscillation", "speed_error",
                 "step_response")  # fmt: skip


@dataclass(frozen=True)
class Reducer:
    """A metric computed inside the loop.

    ``kind``: ``peak`` (max |x|; also ``<name>_time``), ``mean``, ``rms``, ``exceed`` (samples
    with |x| > ``limit``; also ``<name>_first_time``, NaN if none), ``final`` (x at the last
    sample of the window), ``oscillation`` (RMS of x in ``band_hz`` over the last ``window`` s of
    the run; also ``<name>_growth``: the ratio to the RMS over the ``window`` s before),
    ``speed_error`` (``signal`` a speed, ``reference`` its reference, ``gate`` the relay state or
    None: the columns of ``sim._metrics.speed_error_figures`` in ``unit``, ``suffix`` appended,
    the tracking window by ``rule``; ``name`` is not used), ``step_response`` (``signal`` a
    speed, ``reference`` its reference, ``steps`` the events of ``sim._step_response.events``,
    each as a tuple of its (key, value) items: the columns of ``sim._step_response.flat`` in
    ``unit``, ``suffix`` appended; ``name`` is not used). ``x`` is
    ``signal`` ("part.output") minus ``reference`` if given; a space vector's magnitude. The
    window is [``start``, ``stop``] (``stop`` None: the end of the run). The value is multiplied
    by ``scale`` (e.g. rad/s -> rpm); ``limit`` is in the signal's unit.
    """

    name: str
    kind: str
    signal: str
    reference: str | None = None
    start: float = 0.0
    stop: float | None = None
    limit: float = 0.0
    scale: float = 1.0
    band_hz: tuple[float, float] = OSCILLATION_BAND_HZ
    window: float = LATE_WINDOW_S
    gate: str | None = None
    rule: TrackingRule | None = None
    unit: str = "rpm"
    suffix: str = ""
    steps: tuple = ()

    def step_events(self) -> list[dict]:
        """The events of a ``step_response`` reducer, as ``sim._step_response.events`` gives
        them."""
        return [dict(e) for e in self.steps]

    def column_units(self, signal_unit: str) -> dict[str, str]:
        """Column -> unit of this reducer's metrics, given the unit of its signal: the signal's
        unit when the value is not rescaled (``scale`` +-1), else the unit the column's name
        declares (``acdrive.columns.unit_from_name``: ``_rpm``, ``_a``, ...); times in s, sample
        counts and ratios dimensionless; a speed error's columns by their names."""
        from acdrive.columns import unit_from_name

        if self.kind in ("speed_error", "step_response"):
            return {k: unit_from_name(k.removesuffix(self.suffix)) for k in self.columns()}
        value = signal_unit if abs(self.scale) == 1.0 else unit_from_name(self.name)
        if self.kind == "exceed":
            return {self.name: "", f"{self.name}_first_time": "s"}
        extra = {"peak": {f"{self.name}_time": "s"}, "oscillation": {f"{self.name}_growth": ""}}
        return {self.name: value, **extra.get(self.kind, {})}

    def columns(self) -> list[str]:
        if self.kind == "speed_error":
            state = np.ones(len(SPEED_ERROR_STATES))
            return [k + self.suffix for k in speed_error_figures(state, 1.0, self.unit)]
        if self.kind == "step_response":
            return list(self.reduce(initial_state(len(self.steps))))
        extra = {"peak": ["_time"], "exceed": ["_first_time"], "oscillation": ["_growth"]}
        return [self.name] + [self.name + s for s in extra.get(self.kind, [])]

    def reduce(self, state) -> dict:
        """A ``step_response`` reducer's columns from its part's final state."""
        found = self.step_events()
        step = {"events": figures(found, np.asarray(state), abs(self.scale), self.unit)}
        return {k + self.suffix: v for k, v in flat(step, self.unit).items()}


#: an over-limit count counts the samples more than this fraction above the limit (1 %): a
#: current loop at its limit rides on it within its ripple and rounding (the Bodson drive's
#: 6.002 A peak on a 6 A limit, +0.04 %), which is no excursion
OVER_LIMIT_TOLERANCE = 0.01


def over_limit(name: str, signal: str, limit: float) -> Reducer:
    """The ``exceed`` reducer ``name`` counting the samples of |``signal``| above ``limit`` (in
    the signal's unit) by more than OVER_LIMIT_TOLERANCE."""
    return Reducer(name, "exceed", signal, limit=limit * (1.0 + OVER_LIMIT_TOLERANCE))


def as_steps(found: list[dict]) -> tuple:
    """``Reducer.steps`` of the events ``found`` (``sim._step_response.events``)."""
    return tuple(tuple(e.items()) for e in found)


REDUCER_PARAMS = Layout(
    real("start", "s", "start of the window the metric is taken over"),
    real("stop", "s", "end of the window (inclusive)"),
    real("split", "s", "oscillation: start of the late window (the early one ends there)"),
    real("limit", "", "stats: threshold on |x| in the signal's unit (exceed count)"),
    real("a_hp", "", "oscillation: tau/(tau + T_s) of the high-pass sections (backward Euler)"),
    real("b_lp", "", "oscillation: T_s/(tau + T_s) of the low-pass section (backward Euler)"),
    real("is_complex", "", "1 if the signal is a space vector (its magnitude is reduced)"),
    real("has_ref", "", "1 if a reference is subtracted from the signal"),
    real("every", "", "the metric reads every every-th control sample (the logged ones)"),
)
_EVERY = REDUCER_PARAMS.slot("every")
_START, _STOP, _SPLIT = (REDUCER_PARAMS.slot(n) for n in ("start", "stop", "split"))
_LIMIT, _A, _B = (REDUCER_PARAMS.slot(n) for n in ("limit", "a_hp", "b_lp"))
_CPLX, _REF = REDUCER_PARAMS.slot("is_complex"), REDUCER_PARAMS.slot("has_ref")

_inline = njit(cache=True, error_model="numpy", inline="always")


@_inline
def _difference(u, at, ref_at, is_space_vector):
    """The quantity every reducer reads: the signal at input slot ``at`` minus the reference at
    ``ref_at`` (none if negative); for a space vector (two slots each) the magnitude of that
    difference. Signed for a real signal."""
    if is_space_vector:
        re, im = u[at], u[at + 1]
        if ref_at >= 0:
            re -= u[ref_at]
            im -= u[ref_at + 1]
        return math.sqrt(re * re + im * im)
    if ref_at >= 0:
        return u[at] - u[ref_at]
    return u[at]


@_inline
def _reduced_value(u, p):
    """The signal a one-signal reducer part reads: its input ``x`` minus its input ``ref``."""
    is_space_vector = p[_CPLX] > 0.5
    ref_at = (2 if is_space_vector else 1) if p[_REF] > 0.5 else -1
    return _difference(u, 0, ref_at, is_space_vector)


#: every peak / mean / rms / exceed / final metric of a system is served by one "stats" part
#: with one channel per (signal, reference, window, exceed limit) (``_with_reducers``): the cost
#: of a reducer part is mostly per part per sample (about 35 ns), not in its arithmetic.
STATS_CHANNEL = (
    ("n", "", "samples in the window"),
    ("peak", "", "largest |x| in the window"),
    ("t_peak", "s", "time of the peak"),
    ("sum", "", "sum of x over the window"),
    ("sum_sq", "", "sum of x^2 over the window"),
    ("count", "", "samples with |x| > limit in the window"),
    ("t_first", "s", "time of the first such sample (-1: none)"),
    ("last", "", "x at the last sample of the window"),
)
STATS_PARAMS = (
    ("start", "s", "start of the window"),
    ("stop", "s", "end of the window (inclusive)"),
    ("limit", "", "threshold on |x| for the exceed count"),
)
_NS, _NP = len(STATS_CHANNEL), len(STATS_PARAMS)


@_inline
def _logged_time(t, T_s, every):
    """(True and the time the single run logs, if control sample t is one it logs (every
    ``every``-th, ``SystemResult.t``'s arithmetic); else False and t). The metrics of a batch
    are taken on the samples a single run of the variant logs, so both give the same figures."""
    k = math.floor(t / T_s + 0.5)
    q = math.floor(k / every)  # k // every: exact, k and every are whole numbers below 2^53
    if k - q * every != 0.0:  # k % every, in floating point: vectorises over lockstep lanes
        return False, t
    return True, q * T_s * every


@_inline
def _stats_channel(t, v, p, s, q, k):
    """One channel of the stats part at a logged sample t: the channel's parameters start at
    ``p[q]`` (``STATS_PARAMS``), its state at ``s[k]`` (``STATS_CHANNEL``), ``v`` is its value."""
    if p[q] <= t <= p[q + 1]:
        a = abs(v)
        s[k] += 1.0
        if s[k] == 1.0 or a > s[k + 1]:
            s[k + 1] = a
            s[k + 2] = t
        s[k + 3] += v
        s[k + 4] += v * v
        if a > p[q + 2]:
            if s[k + 5] == 0.0:
                s[k + 6] = t
            s[k + 5] += 1.0
        s[k + 7] = v


def _stats_source(channels: tuple[tuple[str, bool, bool], ...], inputs: Layout) -> str:
    """The stats part's step for ``channels``, one statement per channel with its input slots
    and its kind (magnitude or signed value) written as numbers: every statement is the same
    for all lanes of a lockstep block, so the lane loop vectorises (sim._lockstep_source),
    where a loop over channels reading their slots from the parameters stays scalar."""
    lines = [
        f'"""Generated by acdrive._reducer_parts for the stats channels {channels!r}."""',
        "from acdrive._jit import jit",
        "from acdrive._reducer_parts import _difference, _logged_time, _stats_channel",
        "",
        "",
        "@jit",
        "def stats_step(t, T_s, u, p, s, y):",
        "    logged, t = _logged_time(t, T_s, p[0])",
        "    if not logged:",
        "        return 0",
    ]
    for c, (_unit, is_complex, has_ref) in enumerate(channels):
        at = inputs.slot(f"x{c}")
        ref_at = inputs.slot(f"ref{c}") if has_ref else -1
        value = f"_difference(u, {at}, {ref_at}, {is_complex})"
        lines.append(f"    _stats_channel(t, {value}, p, s, {1 + _NP * c}, {_NS * c})")
    lines.append("    return 0")
    return "\n".join(lines) + "\n"


#: the part classes made at run time, one per layout. Each carries ``FACTORY_KEY`` (its
#: factory's name and key): a name for the class that pickles, which the class itself does not
#: (a batch prepared in forked workers groups its variants by it, ``acdrive.batch``)
_STATS_CLASSES: dict[tuple, type] = {}


def _stats_class(channels: tuple[tuple[str, bool, bool], ...]) -> type:
    """The stats part for ``channels`` = ((unit, is complex, has reference), ...): inputs
    ``x<c>`` (and ``ref<c>``) declared in each signal's unit (the wiring checks units)."""
    if channels not in _STATS_CLASSES:
        inputs, states = [], []
        params = [
            real("every", "", "the metrics read every every-th control sample (the logged ones)"),
        ]
        for c, (unit, is_complex, has_ref) in enumerate(channels):
            make = cplx if is_complex else real
            inputs.append(make(f"x{c}", unit, f"signal of channel {c}"))
            if has_ref:
                inputs.append(make(f"ref{c}", unit, f"reference of channel {c}"))
            params += [real(f"{n}{c}", u, d) for n, u, d in STATS_PARAMS]
            states += [real(f"{n}{c}", u, d) for n, u, d in STATS_CHANNEL]
        inputs = Layout(*inputs)
        _STATS_CLASSES[channels] = type(
            "Reducer_stats",
            (SampledPart,),
            {
                "__doc__": "On-line peak, mean, RMS, exceed count and final value (acdrive.batch).",
                "FACTORY_KEY": ("stats", channels),
                "PARAMS": Layout(*params),
                "STATES": Layout(*states),
                "INPUTS": inputs,
                "OUTPUTS": Layout(),
                "INITIAL": {f"t_first{c}": -1.0 for c in range(len(channels))},
                "step": load_module(_stats_source(channels, inputs)).stats_step,
            },
        )
    return _STATS_CLASSES[channels]


OSC_STATES = Layout(
    real("started", "", "1 once the filters hold the first sample"),
    real("x_prev", "", "previous input of the first high-pass section"),
    real("h1", "", "output of the first high-pass section"),
    real("h2", "", "output of the second high-pass section"),
    real("band", "", "band-limited signal (low-pass output)"),
    real("early_sq", "", "sum of band^2 over [start, split)"),
    real("early_n", "", "samples in the early window"),
    real("late_sq", "", "sum of band^2 over [split, stop]"),
    real("late_n", "", "samples in the late window"),
)


@jit
def oscillation_step(t, T_s, u, p, s, y):
    logged, t = _logged_time(t, T_s, p[_EVERY])
    if not logged:
        return 0
    x = _reduced_value(u, p)
    if s[0] == 0.0:
        s[0] = 1.0
        s[1] = x
    a, b = p[_A], p[_B]
    h1 = a * (s[2] + x - s[1])
    h2 = a * (s[3] + h1 - s[2])
    s[4] += b * (h2 - s[4])
    s[1], s[2], s[3] = x, h1, h2
    band = s[4]
    if p[_START] <= t < p[_SPLIT]:
        s[5] += band * band
        s[6] += 1.0
    elif p[_SPLIT] <= t <= p[_STOP]:
        s[7] += band * band
        s[8] += 1.0
    return 0


def band_coefficients(band_hz, sample_time: float) -> tuple[float, float]:
    """(a, b) of the backward-Euler high-pass (lower edge) and low-pass (upper edge) sections."""
    tau_h, tau_l = 1.0 / (2.0 * math.pi * band_hz[0]), 1.0 / (2.0 * math.pi * band_hz[1])
    return tau_h / (tau_h + sample_time), sample_time / (tau_l + sample_time)


#: no exceed metric on a stats part: a limit no finite |x| passes
NO_LIMIT = 1e300
_KERNELS = {"oscillation": (oscillation_step, OSC_STATES)}
_CLASSES: dict[tuple, type] = {}


def _reducer_class(kind: str, unit: str, is_complex: bool, has_ref: bool) -> type:
    """The sampled part of one reducer kind ("oscillation") reading a signal of ``unit`` (the wiring checks units, so the input is declared in the signal's own unit)."""
    key = (kind, unit, is_complex, has_ref)
    if key not in _CLASSES:
        make = cplx if is_complex else real
        inputs = [make("x", unit, "the reduced signal")]
        if has_ref:
            inputs.append(make("ref", unit, "reference subtracted from the signal"))
        step, states = _KERNELS[kind]
        _CLASSES[key] = type(
            f"Reducer_{kind}",
            (SampledPart,),
            {
                "__doc__": f"On-line {kind} of a signal (acdrive.batch).",
                "FACTORY_KEY": ("reducer", key),
                # the class's own values (its key): its C is written for them
                "STRUCTURAL": ("is_complex", "has_ref"),
                "PARAMS": REDUCER_PARAMS,
                "STATES": states,
                "INPUTS": Layout(*inputs),
                "OUTPUTS": Layout(),
                "DEFAULTS": {
                    "split": 0.0,
                    "limit": NO_LIMIT,
                    "a_hp": 0.0,
                    "b_lp": 0.0,
                    "every": 1.0,
                },
                "INITIAL": {},
                "step": step,
            },
        )
    return _CLASSES[key]


#: the speed-error part's parameters before its reference-change windows
SPEED_ERROR_PARAMS = (
    ("every", "", "the metric reads every every-th control sample (the logged ones)"),
    ("slew", "s s/rad", "SLEW_MARGIN J / tau: window per rad/s of error at a relay closing"),
    ("settle", "s", "SETTLE_TIME_CONSTANTS / a_D,VEL: settling after a change"),
    ("has_gate", "", "1 if the relay state is an input (else always closed)"),
)
_SE_NP = len(SPEED_ERROR_PARAMS)


@jit
def speed_error_step(t, T_s, u, p, s, y):
    """The whole-run and tracking speed error (``sim._metrics.speed_error_update``, the kernel a
    single run's summary runs on its logged samples) on line: inputs w, w_ref (and the relay
    state)."""
    logged, t = _logged_time(t, T_s, p[0])
    if not logged:
        return 0
    closed = u[2] if p[3] > 0.5 else 1.0
    speed_error_update(t, u[1] - u[0], closed, p[1], p[2], p[_SE_NP:], s)
    return 0


_SPEED_ERROR_CLASSES: dict[tuple, type] = {}


def _speed_error_class(unit: str, gated: bool, n_windows: int) -> type:
    key = (unit, gated, n_windows)
    if key not in _SPEED_ERROR_CLASSES:
        inputs = [real("x", unit, "speed"), real("ref", unit, "speed reference")]
        if gated:
            inputs.append(real("gate", "", "relay state: 1 closed, 0 open"))
        params = [real(n, u, d) for n, u, d in SPEED_ERROR_PARAMS]
        for j in range(n_windows):
            params += [real(f"start{j}", "s", f"start of excluded window {j}"),
                       real(f"end{j}", "s", f"end of excluded window {j}")]  # fmt: skip
        _SPEED_ERROR_CLASSES[key] = type(
            "Reducer_speed_error",
            (SampledPart,),
            {
                "__doc__": "On-line whole-run and tracking speed error (acdrive.batch).",
                "FACTORY_KEY": ("speed_error", key),
                "STRUCTURAL": ("has_gate",),  # the class's own value (its key): its C is for it
                "PARAMS": Layout(*params),
                "STATES": Layout(*(real(n, u, d) for n, u, d in SPEED_ERROR_STATES)),
                "INPUTS": Layout(*inputs),
                "OUTPUTS": Layout(),
                "INITIAL": {"until": NO_CLOSING},
                "step": speed_error_step,
            },
        )
    return _SPEED_ERROR_CLASSES[key]


@jit
def step_response_step(t, T_s, u, p, s, y):
    """The step-response figures (``sim._step_response.step_response_update``, the rule a single
    run's summary applies to its logged samples) on line: inputs w, w_ref."""
    logged, t = _logged_time(t, T_s, p[0])
    if not logged:
        return 0
    step_response_update(t, u[0], u[1], p[1:], s)
    return 0


_STEP_RESPONSE_CLASSES: dict[tuple, type] = {}


def _step_response_class(unit: str, n_events: int) -> type:
    """The step-response part reading a speed in ``unit`` for ``n_events`` events."""
    key = (unit, n_events)
    if key not in _STEP_RESPONSE_CLASSES:
        params = [real("every", "", "the metric reads every every-th control sample")]
        states, initial = [], {}
        for j in range(n_events):
            params += [real(f"{n}{j}", u, f"event {j}: {d}") for n, u, d in EVENT_PARAMS]
            states += [real(f"{n}{j}", u, f"event {j}: {d}") for n, u, d in EVENT_STATES]
            initial |= {f"{n}{j}": v for n, v in zip(
                (n for n, _, _ in EVENT_STATES), initial_state(1), strict=True) if v == NOT_YET}
        _STEP_RESPONSE_CLASSES[key] = type(
            "Reducer_step_response",
            (SampledPart,),
            {
                "__doc__": "On-line step-response figures of a speed (acdrive.batch).",
                "FACTORY_KEY": ("step_response", key),
                "PARAMS": Layout(*params),
                "STATES": Layout(*states),
                "INPUTS": Layout(real("x", unit, "speed"), real("ref", unit, "speed reference")),
                "OUTPUTS": Layout(),
                "INITIAL": initial,
                "step": step_response_step,
            },
        )
    return _STEP_RESPONSE_CLASSES[key]


def step_response_part(r: Reducer, unit: str, name: str, every: int) -> SampledPart:
    """The part ``name`` that measures the step responses of ``r`` (a ``step_response``
    reducer) on line, reading a speed in ``unit`` every ``every``-th control sample: one set of
    ``EVENT_PARAMS`` per event of ``r.step_events()``."""
    found = r.step_events()
    values = {"every": float(every)}
    for j, v in enumerate(event_params(found).reshape(len(found), len(EVENT_PARAMS))):
        values |= {f"{n}{j}": float(a) for (n, _, _), a in zip(EVENT_PARAMS, v, strict=True)}
    return _step_response_class(unit, len(found))(name, **values)
