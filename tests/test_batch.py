"""Batch simulation (acdrive.batch): equality with single runs, on-line reducers against the
logged signals, invalid variants reported with their reason."""

import math

import numpy as np
import pytest

from acdrive._reducer_parts import band_coefficients, oscillation_step
from acdrive.batch import (
    Reducer,
    apply_overrides,
    build_variant_setup,
    get_field,
    prepare_variant,
    simulate_batch,
)
from acdrive.drives.dfim import DFIMDrive
from acdrive.scenarios import read_scenario

BASE = "bodson-ramp"
SHORT = {"simulation.duration": 0.12}
LOGGED = ["shaft0.w", "reference0.w_ref", "dfim0.i_s", "dfim0.tau_e"]


def _variants():
    return [
        {**SHORT, "motor[0].load_torque": 0.0},
        {**SHORT, "motor[0].load_torque": 0.08, "motor[0].controller.speed_bandwidth": 150.0},
        {**SHORT, "motor[0].params.R_r": 1.2, "initial:shaft0.w": 20.0},
    ]


def _alone(overrides):
    """The variant run alone by the drive's own single-run path (DFIMDrive.run)."""
    fields = {k: v for k, v in overrides.items() if ":" not in k}
    setup = build_variant_setup(apply_overrides(read_scenario(BASE), fields))
    drive = DFIMDrive(setup)
    initial, held = drive.initial()
    for key, value in overrides.items():
        if key.startswith("initial:"):
            part, state = key[len("initial:") :].split(".")
            initial[part] = {**initial.get(part, {}), state: value}
    compiled = drive.compile()
    return compiled.run(setup.duration, setup.sample_time, setup.substeps, initial=initial,
                        held=held, log=[compiled.system.part(p.split(".")[0]).out.__getattr__(
                            p.split(".")[1]) for p in LOGGED])  # fmt: skip


@pytest.mark.slow
def test_batch_without_reducers_equals_single_runs_bit_for_bit():
    variants = _variants()
    batch = simulate_batch(BASE, variants, reducers=[], log=LOGGED, log_every=1)
    assert batch.groups == 1 and all(row["status"] == "ok" for row in batch.rows)
    for i, v in enumerate(variants):
        alone = _alone(v)
        assert np.array_equal(batch.traces[i].final_state, alone.final_state)
        assert np.array_equal(batch.traces[i].data, alone.data)
    # the variants really differ (a batch of copies would pass the test above trivially)
    assert not np.array_equal(batch.traces[0].data, batch.traces[1].data)
    assert batch.traces[2].data[0, 0] == 20.0  # the initial-state override took effect


@pytest.mark.slow
def test_batch_with_reducers_equals_each_variant_alone():
    """With the reducers in the loop, a variant in a batch equals the same variant alone (the
    same compiled loop, one variant), metrics and states alike; and its plant states are the
    single run's without reducers, bit for bit (the reducers only read, and the fast-math flags
    let no larger compiled loop round the plant differently: acdrive._jit.FAST_MATH_FLAGS)."""
    variants = _variants()
    batch = simulate_batch(BASE, variants, log=["shaft0.w"], log_every=1)
    for i, v in enumerate(variants):
        alone = simulate_batch(BASE, [v], log=["shaft0.w"], log_every=1)
        assert np.array_equal(batch.traces[i].final_state, alone.traces[0].final_state)
        assert np.array_equal(batch.traces[i].final_state, _alone(v).final_state)
        for key, value in alone.rows[0].items():
            if key == "variant":
                continue
            same = value == batch.rows[i][key] or (
                isinstance(value, float) and math.isnan(value) and math.isnan(batch.rows[i][key])
            )
            assert same, key


@pytest.mark.slow
def test_reducers_agree_with_the_logged_signals():
    rpm = 30 / math.pi
    reducers = [
        Reducer("rms", "rms", "shaft0.w", "reference0.w_ref", scale=rpm),
        Reducer("mean_w", "mean", "shaft0.w", start=0.02, stop=0.1),
        Reducer("peak_is", "peak", "dfim0.i_s"),
        Reducer("over", "exceed", "dfim0.i_s", limit=0.3),
        Reducer("last_tau", "final", "dfim0.tau_e"),
    ]
    v = {**SHORT, "motor[0].load_torque": 0.05}
    batch = simulate_batch(BASE, [v], reducers=reducers, log=LOGGED, log_every=1)
    row, tr = batch.rows[0], batch.traces[0]
    t, w, ref = tr.t, tr.signal("shaft0.w"), tr.signal("reference0.w_ref")
    i_s = np.abs(tr.signal("dfim0.i_s"))
    assert row["rms"] == pytest.approx(np.sqrt(np.mean((w - ref) ** 2)) * rpm, rel=1e-12)
    window = (t >= 0.02) & (t <= 0.1)
    assert row["mean_w"] == pytest.approx(np.mean(w[window]), rel=1e-12)
    assert row["peak_is"] == pytest.approx(i_s.max(), rel=1e-14)
    assert row["peak_is_time"] == t[np.argmax(i_s)]
    assert row["over"] == np.count_nonzero(i_s > 0.3) > 0
    assert row["over_first_time"] == t[np.argmax(i_s > 0.3)]
    assert row["last_tau"] == tr.signal("dfim0.tau_e")[-1]


def test_oscillation_reducer_measures_a_sinusoid_through_its_band_filter():
    """A 50 Hz sinusoid of amplitude A: the late-window RMS equals A/sqrt(2) times the gain at
    50 Hz of the band filter (two backward-Euler high-pass sections at 20 Hz, one low-pass at
    200 Hz, sampled at 5 kHz: its exact discrete transfer function), within 0.5 % (what is left
    of the start transient, the window's partial periods); constant amplitude -> growth 1."""
    T = 200e-6
    a, b = band_coefficients((20.0, 200.0), T)
    p = np.array([0.5, 1.0, 0.75, 0.0, a, b, 0.0, 0.0, 1.0])  # every control sample
    s = np.zeros(9)
    A, f = 3.0, 50.0
    for k in range(int(1.0 / T) + 1):
        t = k * T
        oscillation_step.py_func(t, T, np.array([A * np.sin(2 * np.pi * f * t)]), p, s, None)
    z1 = np.exp(-2j * np.pi * f * T)  # z^-1 on the unit circle
    tau_h, tau_l = 1 / (2 * np.pi * 20.0), 1 / (2 * np.pi * 200.0)
    assert (a, b) == (tau_h / (tau_h + T), T / (tau_l + T))
    gain = abs((a * (1 - z1) / (1 - a * z1)) ** 2 * b / (1 - (1 - b) * z1))
    late, early = math.sqrt(s[7] / s[8]), math.sqrt(s[5] / s[6])
    assert late == pytest.approx(A / math.sqrt(2) * gain, rel=0.005)
    assert late / early == pytest.approx(1.0, abs=0.01)


def test_invalid_variants_are_reported_with_their_reason_and_the_batch_goes_on():
    variants = [
        {**SHORT, "motor[0].params.M": 20e-3},  # sigma = 1 - M^2/(L_s L_r) < 0
        {**SHORT, "motor[0].params.R_s": -0.5},
        {**SHORT, "part:shaft0.J": 0.0},
        {**SHORT},
    ]
    rows = simulate_batch(BASE, variants).rows
    assert [r["valid"] for r in rows] == [False, False, False, True]
    assert rows[0]["reason"].startswith("motor[0].params.M:") and "sigma" in rows[0]["reason"]
    assert rows[1]["reason"].startswith("motor[0].params.R_s:")
    assert rows[2]["reason"].startswith("shaft0.J:")
    assert math.isnan(rows[0]["speed_rms_error_tracking_rpm"]) and rows[0]["status"] == "invalid"
    assert rows[3]["status"] == "ok" and rows[3]["stable"] is True
    assert np.isfinite(rows[3]["speed_rms_error_tracking_rpm"])


@pytest.mark.parametrize(
    ("key", "rule"),
    [
        ("motor[0].no_such_field", "unknown key"),
        ("simulation.durationx", "unknown key"),
        ("no_such_table.x", "no_such_table: unknown key"),
        ("motor[3].load_torque", "the base scenario has no motor[3]"),
        ("part:no_such_part.w", "part:no_such_part: no part of this name"),
        ("initial:no_such_part.w", "initial:no_such_part: no part of this name"),
        ("part:shaft0.no_such_parameter", "shaft0.no_such_parameter: is not declared"),
        ("initial:shaft0.no_such_state", "shaft0 initial state.no_such_state: is not declared"),
    ],
)
def test_an_override_of_a_field_that_does_not_exist_is_refused_naming_it(key, rule):
    """A misspelt override is no variant to record as invalid: the batch refuses it, naming
    the variant and its key, before any variant runs."""
    from acdrive.errors import InputError

    with pytest.raises(InputError) as refused:
        simulate_batch(BASE, [dict(SHORT), {**SHORT, key: 1.0}])
    assert refused.value.field == f"variants[1][{key!r}]"
    assert refused.value.rule.startswith(rule), refused.value.rule


def test_machine_parameter_override_expands_the_built_in_machine():
    data = read_scenario(BASE)
    assert get_field(data, "motor[0].params.R_s") == 0.66  # Bodson's DFIM
    setup, *_ = prepare_variant(BASE, {**SHORT, "motor[0].params.R_s": 0.99})
    assert setup.motors[0].machine.R_s == 0.99 and setup.motors[0].machine.L_s == 13.1e-3


@pytest.mark.slow
def test_cage_im_variants_equal_single_runs():
    from acdrive.drives.cage_im import IMDrive

    variants = [
        {"simulation.duration": 0.01, "machine.J": 0.0015},
        {"simulation.duration": 0.01, "machine.params.R_s": -1.0},
    ]
    batch = simulate_batch("im-foc-speed", variants, reducers=[], log=["shaft.w"], log_every=1)
    assert batch.rows[1]["reason"].startswith("machine.params.R_s:")
    setup = build_variant_setup(apply_overrides(read_scenario("im-foc-speed"), variants[0]))
    drive = IMDrive(setup)
    initial, held = drive.initial()
    alone = drive.compile().run(setup.duration, setup.sample_time, setup.substeps,
                                initial=initial, held=held, log=[drive.parts["shaft"].out.w])  # fmt: skip
    assert np.array_equal(batch.traces[0].final_state, alone.final_state)
    assert np.array_equal(batch.traces[0].data, alone.data)


@pytest.mark.slow
def test_cage_im_speed_figures_are_the_single_runs():
    """A cage-IM speed loop: the batch row's speed error columns are the single run's summary
    figures of the same names (one kernel, ``sim._metrics``; the samples the run logs, here every
    fifth): equal to the last bits of the compiled loop (rel 1e-9)."""
    from acdrive.drives.cage_im import run_im_scenario

    variant = {"simulation.duration": 0.1}
    row = simulate_batch("im-foc-speed", [variant]).rows[0]
    setup = build_variant_setup(apply_overrides(read_scenario("im-foc-speed"), variant))
    assert setup.log_every == 5
    summary = run_im_scenario(setup).summary
    keys = [k for k in summary if k.startswith("speed_") and ("_error_" in k)]
    assert {"speed_rms_error_tracking_rad_s", "speed_rms_error_whole_run_rad_s"} <= set(keys)
    for key in keys:
        if key == "speed_steady_error_rad_s":  # the mean over the steady end, single run only
            continue
        expected = summary[key]
        if expected is None:
            assert math.isnan(row[key]), key
        else:
            assert row[key] == pytest.approx(expected, rel=1e-9, abs=1e-12), key


def test_an_unknown_base_scenario_is_refused_before_any_variant_is_built():
    """The base is read once for the whole batch: a scenario that does not exist is one
    ``InputError`` naming it, not a batch of rows each marked invalid."""
    from acdrive.batch import simulate_batch
    from acdrive.errors import InputError

    with pytest.raises(InputError, match="no-such-scenario"):
        simulate_batch("no-such-scenario", [{}, {"motor[0].load_torque": 0.05}])


def test_a_batch_groups_by_topology_and_the_topology_fixes_the_generated_loop():
    """Variants that differ in parameters and initial states share a topology and the same
    generated loop (the batch groups them without generating each one's source); other
    metrics (another reducer part) or another integrator make another topology and another
    loop."""
    a, b, c = (prepare_variant(BASE, v)[2] for v in _variants())
    assert a.topology() == b.topology() == c.topology()
    assert a.source() == b.source() == c.source()
    fewer = prepare_variant(BASE, SHORT, reducers=[Reducer("peak_w", "peak", "shaft0.w")])[2]
    rk6 = prepare_variant(BASE, SHORT, integrator="rk6")[2]
    for other in (fewer, rk6):
        assert other.topology() != a.topology()
        assert other.source() != a.source()
