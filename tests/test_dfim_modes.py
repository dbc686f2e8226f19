"""Current-command mode, synchronisation, several motors, reactive power, faults (Bodson III-C to
III-E, IV), checked against the paper's analytic results and physical invariants."""

import math

import numpy as np
import pytest

from acdrive.drives.dfim import DFIMDrive, run_scenario, simulate
from acdrive.errors import InputError
from acdrive.machines._dfim import BODSON_DFIM, L_R, L_S, M_SR, machine_vector
from acdrive.scenarios import build_setup

PAPER_PARAMS = {"R_s": 0.66, "R_r": 0.94, "L_s": 13.1e-3, "L_r": 9.8e-3, "M": 9.7e-3, "n_p": 2}


def motor(**extra):
    base = {"speed_reference_rpm": [[0, 0], [1, 0]]}
    base.update(extra)
    return base


def test_current_loop_gains_match_paper_table():
    from acdrive.control import current_loop_gains

    K_PC, K_IC = current_loop_gains(BODSON_DFIM.sigma, BODSON_DFIM.L_r, 1.0, 3142.0)
    assert round(K_PC, 2) == 8.22 and round(K_IC) == 3142


def test_rotor_current_loop_is_first_order():
    """(50): i_R / i_R,COM = a_D,CUR / (s + a_D,CUR). A torque step at constant speed (huge inertia)
    steps the rotor current command; the measured rotor current follows the first-order response
    (sampling at 20 us so that the zero-order hold is negligible against a_D,CUR = 1000 rad/s)."""
    a = 1000.0
    T_s = 20e-6
    data = {
        "simulation": {"duration": 0.03, "sample_time": T_s, "substeps": 2},
        "motor": [
            motor(
                params={**PAPER_PARAMS, "J": 100.0},
                speed_reference_rpm=[[0, 0], [0.02, 0], [0.02, 0.5], [1, 0.5]],
                controller={
                    "mode": "current",
                    "current_bandwidth": a,
                    "speed_bandwidth": 0.02,
                    "K_F": 1.0,
                    "design_inertia": 100.0,
                },
            )
        ],
    }
    r = simulate(build_setup(data))
    command = r.signal("i_r_com_d") + 1j * r.signal("i_r_com_q")
    measured = r.signal("i_r_d") + 1j * r.signal("i_r_q")
    # exact discretisation of a/(s+a) driven by the sampled command (held over each period)
    after = r.t > 0.02
    start = np.argmax(after) - 1  # last sample before the step, after the start-up transient

    def first_order(bandwidth):
        decay = math.exp(-bandwidth * T_s)
        out = np.empty_like(command)
        out[: start + 1] = measured[: start + 1]
        for k in range(start + 1, len(command)):
            out[k] = decay * out[k - 1] + (1 - decay) * command[k - 1]
        return out

    model = first_order(a)
    step = np.max(np.abs(command[after] - command[0]))
    assert step > 0.05  # the step is real
    assert np.max(np.abs(measured[after] - model[after])) < 0.05 * step
    # and not a faster or slower loop: a 2x different bandwidth misses by far more
    for other in (2 * a, a / 2):
        assert np.max(np.abs(measured[after] - first_order(other)[after])) > 0.1 * step


@pytest.mark.parametrize(
    "offset, rpm", [(0.0, 0.0), (1.7, 0.0), (4.4, 0.0), (2.9, 900.0), (5.8, -400.0)]
)
def test_synchronisation_aligns_encoder_and_closes_softly(offset, rpm):
    data = {
        "simulation": {"duration": 0.6},
        "motor": [
            motor(
                encoder_offset=offset,
                initial_speed_rpm=rpm,
                speed_reference_rpm=[[0, rpm], [1, rpm]],
                controller={"speed_bandwidth": 100.0, "sync": {"enabled": True}},
            )
        ],
    }
    outcome = run_scenario(build_setup(data))
    sync = outcome.summary["synchronisation"]
    assert sync["relay_closed"]
    assert sync["closing_current_fraction_of_limit"] < 0.10
    # theta_adj estimates n_p * offset (up to the small phase of the model error and ZOH)
    error = math.remainder(
        sync["theta_adj_rad"] - sync["encoder_offset_electrical_rad"], 2 * math.pi
    )
    assert abs(error) < 0.15
    result = outcome.main
    assert abs(result.speed_rpm()[-1] - rpm) < 2.0
    opened = result.signal("relay_closed") == 0
    assert np.all(result.signal("i_s_mag")[opened] == 0.0)  # open stator carries no current


def test_sensor_failure_falls_back_to_voltage_command():
    data = {
        "simulation": {"duration": 1.0},
        "motor": [
            motor(
                speed_reference_rpm=[[0, 0], [0.1, 0], [0.9, 600], [1.0, 600]],
                current_sensor_fault_time=0.5,
                controller={"mode": "current", "speed_bandwidth": 100.0},
            )
        ],
    }
    outcome = run_scenario(build_setup(data))
    r = outcome.main
    assert outcome.summary["sensor_fallback_time_s"] == pytest.approx(0.5, abs=2.1e-4)
    assert np.all(r.signal("mode")[r.t < 0.5] == 1.0) and np.all(r.signal("mode")[r.t > 0.5] == 0.0)
    assert np.all(np.isfinite(r.signals))
    assert np.max(np.abs(r.speed_rpm() - r.reference_rpm())) < 10.0


def test_reactive_power_loop_removes_model_error():
    """With controller parameters 15 % off, the open-loop law misses Q; the PI on measured Q
    (gains set for a unity plant) drives it to the command."""
    wrong = {
        **PAPER_PARAMS,
        "L_s": 13.1e-3 * 1.15,
        "M": 9.7e-3 * 1.1,
        "L_r": 9.8e-3 * 1.1,
        "J": 3.5e-4,
    }

    def q_after(ki, key="reactive_power_ki"):
        data = {
            "simulation": {"duration": 1.5},
            "motor": [
                motor(
                    speed_reference_rpm=[[0, 300], [2, 300]],
                    initial_speed_rpm=300,
                    controller={"speed_bandwidth": 60.0, "reactive_power": 20.0, key: ki},
                )
            ],
        }
        setup = build_setup(data)
        import dataclasses

        from acdrive.machines import DFIMParams

        m = setup.motors[0]
        m = dataclasses.replace(
            m, controller=dataclasses.replace(m.controller, params=DFIMParams(**wrong))
        )
        r = simulate(dataclasses.replace(setup, motors=(m,)))
        return np.mean(r.signal("q_s")[r.t > 1.2])

    assert abs(q_after(0.0) - 20.0) > 2.0  # the model error is visible open loop
    assert q_after(30.0) == pytest.approx(20.0, abs=0.3)
    # gains from a bandwidth with a unity plant assumed (Bodson III-B): K_I = a_Q
    assert q_after(30.0, "reactive_power_bandwidth") == pytest.approx(20.0, abs=0.3)


def test_bus_voltage_solves_shared_impedance_equation():
    """v_bus = v_g - R_g sum(i_s) - L_g sum(d i_s / dt) holds exactly at an arbitrary state."""
    data = {"supply": {"resistance": 0.3, "inductance": 1e-3}, "motor": [motor(), motor(), motor()]}
    drive = DFIMDrive(build_setup(data))
    compiled, system = drive.compile(), drive.system
    rng = np.random.default_rng(1)
    X = rng.normal(size=system.sizes["x"]) * 0.02
    held = system.pack_held(
        {f"converter{k}": {"v": complex(*rng.normal(size=2))} for k in range(3)}
    )
    Y, dX = compiled.evaluate(0.01, X, held)
    p = machine_vector(BODSON_DFIM)
    det = p[L_S] * p[L_R] - p[M_SR] ** 2
    sum_i, sum_di = 0j, 0j
    for k in range(3):
        o = system.slots[f"dfim{k}"].x[0]
        psi_s, psi_r = complex(X[o], X[o + 1]), complex(X[o + 2], X[o + 3])
        dpsi_s, dpsi_r = complex(dX[o], dX[o + 1]), complex(dX[o + 2], dX[o + 3])
        sum_i += (p[L_R] * psi_s - p[M_SR] * psi_r) / det
        sum_di += (p[L_R] * dpsi_s - p[M_SR] * dpsi_r) / det
        v_term = compiled.output(Y, drive.motors[k]["relay"].out.v)
        assert v_term == compiled.output(Y, drive.bus.out.v)  # every relay closed
    v_g = compiled.output(Y, drive.grid.out.v)
    v_bus = compiled.output(Y, drive.bus.out.v)
    assert v_bus == pytest.approx(v_g - 0.3 * sum_i - 1e-3 * sum_di, rel=1e-12, abs=1e-12)


def test_motors_on_a_shared_supply_interact_through_the_bus():
    """Starting motor 2 sags the voltage motor 1 sees; with a stiff bus it does not."""

    def sag(resistance):
        data = {
            "simulation": {"duration": 0.6},
            "supply": {"resistance": resistance, "inductance": 0.0},
            "motor": [
                motor(controller={"speed_bandwidth": 60.0}),
                motor(
                    speed_reference_rpm=[[0, 0], [0.2, 0], [0.2, 1500], [1, 1500]],
                    controller={"speed_bandwidth": 60.0},
                ),
            ],
        }
        r = simulate(build_setup(data))
        v1 = r.signal("v_s_mag", 0)
        return np.mean(v1[r.t < 0.19]) - np.min(v1[(r.t > 0.2) & (r.t < 0.4)])

    assert sag(0.0) < 1e-9
    assert sag(0.3) > 0.1


def test_varying_supply_limits_follow_measured_voltage():
    from acdrive.machines import torque_window

    data = {
        "simulation": {"duration": 1.2},
        "supply": {
            "voltage_pk_profile": [[0, 11.1], [0.2, 11.1], [0.5, 7.0], [1.2, 7.0]],
            "frequency_hz_profile": [[0, 60], [0.2, 60], [0.5, 50], [1.2, 50]],
        },
        "motor": [motor(speed_reference_rpm=[[0, 0], [0.6, 0], [0.6, 1200], [1.2, 1200]])],
    }
    r = simulate(build_setup(data))
    late = r.t > 0.6
    p, i_max = machine_vector(BODSON_DFIM), math.sqrt(1.5) * 6.0
    limit = torque_window(p, 2 * math.pi * 50, math.sqrt(1.5) * 7.0, i_max, i_max)[1]
    assert np.max(r.signal("tau_com")[late]) <= limit * 1.02
    assert np.max(r.signal("tau_com")[late]) >= limit * 0.9  # the step drives it to the limit


@pytest.mark.parametrize(
    "controller, field",
    [
        ({"sync": {"enabled": True, "tolerance_magnitude": 0.0}}, "sync.tolerance_magnitude"),
        ({"sync": {"enabled": True, "tolerance_phase_deg": -1}}, "sync.tolerance_phase_deg"),
        ({"current_bandwidth": -10.0}, "current_bandwidth"),
        ({"rotor_current_limit_pk": 2.5}, "rotor_current_limit_pk"),
        ({"mode": "torque"}, "mode"),
    ],
)
def test_unworkable_settings_are_rejected(controller, field):
    with pytest.raises(InputError, match=field.replace(".", r"\.")):
        build_setup({"motor": [motor(controller=controller)]})


def test_lossless_law_39_tracks_with_reactive_power_and_case2_limits():
    """The R_s = 0 law (39) on the real machine: the integral action removes the R_s error, and the
    torque command respects the case-2 window (40)-(42) at the commanded Q."""
    from acdrive.machines import torque_limit_case2

    Q = 15.0
    data = {
        "simulation": {"duration": 2.0},
        "motor": [
            motor(
                speed_reference_rpm=[[0, 0], [0.2, 0], [0.2, 1200], [2, 1200]],
                controller={"lossless_law": True, "reactive_power": Q, "speed_bandwidth": 60.0},
            )
        ],
    }
    r = simulate(build_setup(data))
    assert abs(r.speed_rpm()[-1] - 1200) < 1.0
    p, i_max, v_s = machine_vector(BODSON_DFIM), math.sqrt(1.5) * 6, math.sqrt(1.5) * 11.1
    tau_2, tau_3 = torque_limit_case2(p, 2 * math.pi * 60, v_s, Q, i_max, i_max)
    assert np.max(r.signal("tau_com")) <= min(tau_2, tau_3) + 1e-9
    assert np.max(r.signal("tau_com")) >= 0.99 * min(tau_2, tau_3)  # the step reaches the limit
