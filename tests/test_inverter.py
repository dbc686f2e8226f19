"""The two-level SVPWM inverter (plant/_inverter.py) against physics and analytic results: the
volt-second balance, the exact switching instants of centred space-vector PWM, the overmodulation
limit shared with the averaged converter, the mean error of dead time and device drops, and an
RL load driven through a compiled system against the exact solution of its linear ODE over the
same segments (Amezquita-Brooks et al., section VI: 310 V link, 5 kHz SVPWM, 50 kHz sampling)."""

import cmath
import math
from itertools import pairwise

import numpy as np
import pytest
from rl_load import RLLoad

from acdrive import _frames as frames
from acdrive.control import VoltageProgram
from acdrive.errors import InputError
from acdrive.plant import DCSource
from acdrive.plant._converter import AVERAGED_OUTPUTS, AveragedConverter, averaged_segments
from acdrive.plant._inverter import INPUTS, OUTPUTS, Inverter, inverter_segments
from acdrive.sim import System

V_DC = 310.0
F_PWM = 5000.0
T_PWM = 1.0 / F_PWM
ALPHA = cmath.exp(2j * math.pi / 3)
#: the largest magnitude inside the hexagon's inscribed circle: sqrt(3/2) times the phase peak
#: V_dc / sqrt(3) that a min-max modulated leg reaches
V_LIMIT = math.sqrt(1.5) * V_DC / math.sqrt(3.0)


# --- analytic references, written independently of the module ---------------------------------
def phase_values(v):
    """Zero-sum phase values x_k whose transform sqrt(2/3) sum alpha^k x_k is ``v``."""
    return [math.sqrt(2.0 / 3.0) * (v * ALPHA ** (-k)).real for k in range(3)]


def min_max_duties(v, v_dc):
    """Centred SVPWM = carrier comparison of the phase values with the min-max offset."""
    x = phase_values(v)
    middle = 0.5 * (max(x) + min(x))
    return [0.5 + (xk - middle) / v_dc for xk in x]


def state_vector(poles):
    """Phase-to-neutral space vector of pole voltages (from the negative rail), isolated star."""
    return math.sqrt(2.0 / 3.0) * sum(e * ALPHA**k for k, e in enumerate(poles))


def run_kernel(inv, T_s, samples, v_ref, v_dc=V_DC, i_s=0j, state=None):
    """Call the kernel directly for ``samples`` control samples with constant inputs; returns
    (segments [(start, length, value, m_a)], event bits per sample, state)."""
    u = np.zeros(INPUTS.size())
    u[INPUTS.slot("v_ref")], u[INPUTS.slot("v_ref") + 1] = v_ref.real, v_ref.imag
    u[INPUTS.slot("v_dc")] = v_dc
    u[INPUTS.slot("i_s")], u[INPUTS.slot("i_s") + 1] = i_s.real, i_s.imag
    s = inv.initial_state() if state is None else state
    dt = np.zeros(Inverter.MAX_SEGMENTS)
    v = np.zeros((Inverter.MAX_SEGMENTS, OUTPUTS.size()))
    segments, events = [], []
    a, m = OUTPUTS.slot("v"), OUTPUTS.slot("m_a")
    for k in range(samples):
        n, bits = inverter_segments(T_s, u, inv.p, s, dt, v)
        assert 1 <= n <= Inverter.MAX_SEGMENTS
        assert np.all(dt[:n] > 0.0)
        assert math.fsum(dt[:n]) == pytest.approx(T_s, rel=1e-15, abs=0.0)
        start = k * T_s
        for i in range(n):
            segments.append((start, dt[i], complex(v[i, a], v[i, a + 1]), v[i, m]))
            start += dt[i]
        events.append(bits)
    return segments, events, s


def mean_voltage(segments, duration):
    return sum(length * value for _, length, value, _ in segments) / duration


COMMANDS = [
    0j,
    0.3 * V_LIMIT * cmath.exp(0.1j),
    0.77 * V_LIMIT * cmath.exp(1.0j),
    0.5 * V_LIMIT * cmath.exp(2.5j),
    0.95 * V_LIMIT * cmath.exp(-2.0j),
    V_LIMIT * cmath.exp(1j * math.pi / 6),  # touches the hexagon: duties 0 and 1
    V_LIMIT * cmath.exp(-0.4j),
]


# --- volt-second balance and the switching pattern ---------------------------------------------
@pytest.mark.parametrize("n_samples", [1, 10])
@pytest.mark.parametrize("command", COMMANDS)
def test_mean_over_a_carrier_period_is_the_command_and_the_averaged_converter(n_samples, command):
    inv = Inverter("inv", f_pwm=F_PWM)
    assert inv.check_sample_time(T_PWM / n_samples) == n_samples
    segments, events, _ = run_kernel(inv, T_PWM / n_samples, n_samples, command)
    mean = mean_voltage(segments, T_PWM)
    assert abs(mean - command) < 1e-12 * V_DC
    if abs(command) < (1.0 - 1e-9) * V_LIMIT:  # on the limit itself, rounding decides
        assert events == [0] * n_samples  # inside the linear range
    averaged = AveragedConverter("avg", V_dc=V_DC)
    dt, v = np.zeros(1), np.zeros((1, AVERAGED_OUTPUTS.size()))
    n, _ = averaged_segments(T_PWM, np.array([command.real, command.imag]), averaged.p,
                             np.zeros(0), dt, v)  # fmt: skip
    assert n == 1 and abs(mean - complex(v[0, 0], v[0, 1])) < 1e-12 * V_DC


@pytest.mark.parametrize("n_samples", [1, 10])
@pytest.mark.parametrize("command", COMMANDS)
def test_segments_are_the_centred_svpwm_pattern_at_exact_instants(n_samples, command):
    """Each leg is high for d_k T_pwm centred in the period (min-max duties); every segment
    carries the switch-state vector of that instant; every edge (1 -/+ d_k) T_pwm / 2 is a segment
    boundary to rounding, not to an integration grid."""
    T_s = T_PWM / n_samples
    segments, _, _ = run_kernel(Inverter("inv"), T_s, n_samples, command)
    duties = min_max_duties(command, V_DC)
    assert all(-1e-12 <= d <= 1.0 + 1e-12 for d in duties)
    boundaries = [start for start, _, _, _ in segments] + [T_PWM]
    for start, length, value, m_a in segments:
        middle = start + 0.5 * length
        poles = [V_DC if abs(middle - T_PWM / 2) < d * T_PWM / 2 else 0.0 for d in duties]
        assert abs(value - state_vector(poles)) < 1e-12 * V_DC
        assert m_a == pytest.approx(2.0 * duties[0] - 1.0, abs=1e-13)
    for d in duties:
        if 1e-12 < d < 1.0 - 1e-12:  # a leg that switches: both its edges are boundaries
            for edge in ((1.0 - d) * T_PWM / 2, (1.0 + d) * T_PWM / 2):
                assert min(abs(b - edge) for b in boundaries) < 1e-15 * T_PWM * 4
    # apart from the sample boundaries of N > 1, each boundary switches one leg or (equal
    # duties) several legs together, and the period is symmetric about its centre
    values = [value for _, _, value, _ in segments]
    switching = [values[0]] + [b for a, b in pairwise(values) if abs(b - a) > 1e-9]
    assert len(switching) <= 7 and len(switching) % 2 == 1
    assert np.allclose(switching, switching[::-1], atol=1e-12 * V_DC, rtol=0.0)
    if min(duties) > 1e-12:  # (on the hexagon's edge one leg stays low all period)
        assert abs(switching[0]) < 1e-12 * V_DC  # starts (and ends) with the zero state 000


def test_a_sample_time_that_does_not_divide_the_carrier_is_refused_and_the_kernel_copes():
    inv = Inverter("inv", f_pwm=F_PWM)
    assert inv.check_sample_time(2e-5) == 10  # the paper: 5 kHz PWM, 50 kHz sampling
    for bad in (3e-5, 4e-4, 0.0, float("nan")):
        with pytest.raises(InputError, match=r"^sample_time: "):
            inv.check_sample_time(bad)
    with pytest.raises(InputError, match=r"inv\.f_pwm"):
        inv.check_sample_time(3e-5)
    # unchecked, the kernel rounds: a carrier of round(T_pwm / T_s) = 7 samples, still balanced
    T_s = T_PWM / 6.7
    command = 0.6 * V_LIMIT * cmath.exp(0.7j)
    segments, _, _ = run_kernel(inv, T_s, 7, command)
    assert abs(mean_voltage(segments, 7 * T_s) - command) < 1e-12 * V_DC


# --- overmodulation -------------------------------------------------------------------------------
@pytest.mark.parametrize("angle", [0.0, 0.3, math.pi / 6, 1.9, -2.7])
@pytest.mark.parametrize("n_samples", [1, 10])
def test_overmodulation_is_limited_like_the_averaged_converter_and_reported(angle, n_samples):
    inv = Inverter("inv")
    T_s = T_PWM / n_samples
    direction = cmath.exp(1j * angle)
    inside = (1.0 - 1e-9) * V_LIMIT * direction
    _, events, state = run_kernel(inv, T_s, n_samples, inside)
    assert events == [0] * n_samples
    for factor in (1.0 + 1e-6, 1.3, 3.0):
        command = factor * V_LIMIT * direction
        segments, events, state = run_kernel(inv, T_s, n_samples, command, state=state)
        assert events == [1] * n_samples  # every sample of the limited carrier period
        mean = mean_voltage(segments, T_PWM)
        assert abs(mean - V_LIMIT * direction) < 1e-12 * V_DC  # magnitude clipped, angle kept
        dt, v = np.zeros(1), np.zeros((1, AVERAGED_OUTPUTS.size()))
        averaged = AveragedConverter("avg", V_dc=V_DC)
        _, saturated = averaged_segments(T_PWM, np.array([command.real, command.imag]),
                                         averaged.p, np.zeros(0), dt, v)  # fmt: skip
        assert saturated == 1 and abs(mean - complex(v[0, 0], v[0, 1])) < 1e-12 * V_DC
    # back inside: the next carrier period is not reported
    _, events, _ = run_kernel(inv, T_s, n_samples, 0.5 * inside, state=state)
    assert events == [0] * n_samples


def test_a_dc_link_at_zero_applies_nothing():
    segments, events, _ = run_kernel(Inverter("inv"), T_PWM, 1, 10.0 + 5j, v_dc=0.0)
    assert all(value == 0 for _, _, value, _ in segments) and events == [1]


# --- dead time and device drops -----------------------------------------------------------------
@pytest.mark.parametrize("current_angle", [0.0, 0.9, 2.2, -1.3, 3.0])
@pytest.mark.parametrize(("t_d", "v_drop"), [(3e-6, 0.0), (0.0, 1.5), (2e-6, 0.8)])
@pytest.mark.parametrize("n_samples", [1, 10])
def test_dead_time_and_drop_mean_error_is_the_analytic_value(current_angle, t_d, v_drop,
                                                             n_samples):  # fmt: skip
    """Per carrier period a leg loses (i > 0) or gains (i < 0) t_d of its high pulse: its mean
    pole voltage is off by -sign(i_k) t_d f_pwm V_dc, and by -sign(i_k) v_drop from the
    conducting device; the star point removes the common part, the rest is the space vector of
    these phase errors."""
    inv = Inverter("inv", f_pwm=F_PWM, t_d=t_d, v_drop=v_drop)
    command = 0.4 * V_LIMIT * cmath.exp(0.5j)
    duties = min_max_duties(command, V_DC)  # away from the extremes the rule needs
    assert all(t_d <= d * T_PWM and t_d <= (1 - d) * T_PWM / 2 for d in duties)
    i_s = 7.0 * cmath.exp(1j * current_angle)
    signs = [math.copysign(1.0, x) for x in phase_values(i_s)]
    assert all(abs(x) > 1e-3 for x in phase_values(i_s))  # a known polarity in every phase
    per_phase = t_d * F_PWM * V_DC + v_drop
    expected = state_vector([-s * per_phase for s in signs])
    segments, _, _ = run_kernel(inv, T_PWM / n_samples, n_samples, command, i_s=i_s)
    error = mean_voltage(segments, T_PWM) - command
    assert abs(expected) > 0.5 * per_phase
    assert abs(error - expected) < 1e-10 * V_DC


def test_dead_time_must_be_shorter_than_half_the_carrier_period():
    Inverter("inv", f_pwm=F_PWM, t_d=0.999 * T_PWM / 2)
    with pytest.raises(InputError, match=r"^inv\.t_d: must be shorter than half the carrier"):
        Inverter("inv", f_pwm=F_PWM, t_d=T_PWM / 2)
    with pytest.raises(InputError, match=r"^inv\.t_d: must be >= 0"):
        Inverter("inv", t_d=-1e-6)
    with pytest.raises(InputError, match=r"^inv\.t_d: must be shorter"):
        Inverter("inv", t_d=1e-6).with_params(f_pwm=1e6)
    with pytest.raises(InputError, match=r"^inv\.v_drop: must be >= 0"):
        Inverter("inv", v_drop=-0.1)


# --- an RL load driven through a compiled system ------------------------------------------------
R_LOAD, L_LOAD = 1.0, 0.5e-3  # time constant 0.5 ms: 2.5 carrier periods
V_PK = 150.0  # phase peak: |v_ref| = 184 V, inside the 219 V limit


@pytest.fixture(scope="module")
def rl_system():
    program = VoltageProgram("program", V_pk=V_PK, f=50.0)
    dc = DCSource("dc", V=V_DC)
    inv = Inverter("inv", f_pwm=F_PWM)
    load = RLLoad("load", R=R_LOAD, L=L_LOAD)
    wires = [
        (program.out.v_ref, inv.inp.v_ref),
        (dc.out.v_dc, inv.inp.v_dc),
        (load.out.i_s, inv.inp.i_s),
        (inv.out.v, load.inp.v),
    ]
    system = System([program, dc, inv, load], wires)
    return system.compile(), program, inv, load


def exact_rl_currents(inv, T_s, v_refs):
    """The RL current at every sample instant, propagated exactly (exponential of the linear ODE)
    through the segments the inverter kernel gives for the same commands and current signs."""
    state = inv.initial_state()
    i = 0j
    out = np.empty(len(v_refs), dtype=complex)
    for k, v_ref in enumerate(v_refs):
        out[k] = i
        segments, _, state = run_kernel(inv, T_s, 1, v_ref, i_s=i, state=state)
        for _, length, value, _ in segments:
            target = value / R_LOAD
            i = target + (i - target) * math.exp(-length * R_LOAD / L_LOAD)
    return out


@pytest.mark.slow
@pytest.mark.parametrize(("t_d", "v_drop"), [(0.0, 0.0), (2e-6, 1.2)])
@pytest.mark.parametrize("n_samples", [1, 10])
def test_rl_load_is_integrated_over_the_exact_segments_with_fourth_order_rk4(rl_system, t_d,
                                                                             v_drop, n_samples):  # fmt: skip
    compiled, program, inv, load = rl_system
    T_s = T_PWM / n_samples
    assert inv.check_sample_time(T_s) == n_samples
    variant = inv.with_params(t_d=t_d, v_drop=v_drop)
    duration = 0.02  # one 50 Hz period, 100 carrier periods
    ladder = [2, 4, 8, 16] if n_samples == 1 else [1, 2, 4, 8]
    errors, reference = [], None
    for substeps in ladder:
        result = compiled.run(duration, T_s, substeps, log=[program.out.v_ref, load.out.i_s],
                              parts=[variant])  # fmt: skip
        assert result.events["inv"]["overmodulation"] == 0
        if reference is None:
            reference = exact_rl_currents(variant, T_s, result.signal(program.out.v_ref))
            scale = np.max(np.abs(reference))
            assert scale > 50.0  # a real current: |v| / |R + j w L| ~ 180 A
        errors.append(np.max(np.abs(result.signal(load.out.i_s) - reference)) / scale)
    orders = [math.log2(a / b) for a, b in pairwise(errors)]
    assert all(3.7 < order < 4.3 for order in orders), (errors, orders)
    assert errors[-1] < 1e-10


@pytest.mark.slow
@pytest.mark.parametrize("t_d", [0.0, 2e-6])
def test_the_sixth_order_method_converges_at_order_six_over_the_same_segments(t_d):
    """``System(method="rk6")``: Butcher's seven-stage method over the exact segments."""
    program = VoltageProgram("program", V_pk=V_PK, f=50.0)
    dc = DCSource("dc", V=V_DC)
    inv = Inverter("inv", f_pwm=F_PWM, t_d=t_d, v_drop=1.2 if t_d else 0.0)
    load = RLLoad("load", R=R_LOAD, L=L_LOAD)
    wires = [
        (program.out.v_ref, inv.inp.v_ref),
        (dc.out.v_dc, inv.inp.v_dc),
        (load.out.i_s, inv.inp.i_s),
        (inv.out.v, load.inp.v),
    ]
    compiled = System([program, dc, inv, load], wires, method="rk6").compile()
    errors, reference = [], None
    for substeps in [1, 2, 4]:
        result = compiled.run(0.02, T_PWM, substeps, log=[program.out.v_ref, load.out.i_s])
        if reference is None:
            reference = exact_rl_currents(inv, T_PWM, result.signal(program.out.v_ref))
            scale = np.max(np.abs(reference))
        errors.append(np.max(np.abs(result.signal(load.out.i_s) - reference)) / scale)
    orders = [math.log2(a / b) for a, b in pairwise(errors)]
    assert all(5.6 < order < 6.4 for order in orders), (errors, orders)


def test_an_unknown_integration_method_is_refused():
    with pytest.raises(InputError, match=r"^method: must be one of rk4, rk6"):
        System([DCSource("dc", V=V_DC)], [], method="euler")


# --- the limit's tolerance of a few ulps (acdrive._frames.beyond_limit) ------------------------
@pytest.mark.parametrize("angle", [0.0, 0.7, -2.2])
def test_a_command_at_the_limit_to_rounding_is_not_counted_but_one_beyond_it_is(angle):
    """A controller that limits its own command hands the inverter a magnitude that rounds a few
    ulps above v_dc / sqrt(2): that is not overmodulation. 1e-9 above the limit is."""
    limit = V_DC / math.sqrt(2.0)
    direction = cmath.exp(1j * angle)
    # the command as a controller limits it: scaled back from far outside, then rounded
    rescaled = (3.0 * limit * direction) * (limit / abs(3.0 * limit * direction))
    one_ulp = math.nextafter(limit, math.inf) * direction
    for command in (rescaled, one_ulp, limit * direction):
        assert abs(command) <= limit * (1.0 + frames.LIMIT_RTOL)
        _, events, _ = run_kernel(Inverter("inv"), T_PWM, 1, command)
        assert events == [0]
        averaged = AveragedConverter("avg", V_dc=V_DC)
        dt, v = np.zeros(1), np.zeros((1, AVERAGED_OUTPUTS.size()))
        _, saturated = averaged_segments(T_PWM, np.array([command.real, command.imag]),
                                         averaged.p, np.zeros(0), dt, v)  # fmt: skip
        assert saturated == 0 and complex(v[0, 0], v[0, 1]) == command  # applied unchanged
    beyond = (1.0 + 1e-9) * limit * direction
    _, events, _ = run_kernel(Inverter("inv"), T_PWM, 1, beyond)
    assert events == [1]
