"""The cage-IM summary says what happened to the drive by the DFIM's rule (``sim._recovery``):
each load, brake or DC-link disturbance of the scenario judged for its largest speed error,
recovery and recovery time, reversal and stall; a loss of control is a warning by that name. A
position run judges the position error instead."""

import math

import numpy as np
import pytest

from acdrive._toml import constant
from acdrive.core import Profile
from acdrive.drives.cage_im import IMDriveResult
from acdrive.drives.cage_im._outcome import run_im_scenario, warnings_of
from acdrive.drives.cage_im._recovery import im_disturbances
from acdrive.drives.cage_im._setup import IMDriveSetup, Mechanics, SpeedPISetup
from acdrive.scenarios import load_scenario
from acdrive.sim._metrics import RPM_PER_RAD_S, SETTLE_TIME_CONSTANTS, SLEW_MARGIN
from acdrive.sim._recovery import (
    HOLD_S,
    POSITION_RECOVERY_MIN_RAD,
    PRE_WINDOW_S,
    RECOVERY_MIN_RPM,
    RECOVERY_P99_FACTOR,
    RECOVERY_REFERENCE_FRACTION,
)


def _recovered_at(t, err, judged, band):
    """The first judged sample after the last one outside the band (the rule, from the data)."""
    outside = t[judged & (err > band)]
    return float(t[judged & (t > outside[-1])][0])


def test_the_brake_step_of_im_foc_speed_recovers_as_the_logged_speed_shows():
    setup = load_scenario("im-foc-speed")
    out = run_im_scenario(setup)
    r, speed = out.main, out.summary["speed_outcome"]
    (d,) = speed["disturbances"]
    assert (d["what"], d["start_s"], d["cleared_s"]) == (
        "brake coefficient 0 -> 0.00277 N m s/rad", 0.6, None
    )  # fmt: skip
    # the tracking window from the scenario's numbers: the 150 rad/s step at 0.05 s slews at the
    # torque limit, then settles in 6 / a with a = K_P / (2 J) (both PI roots at -50 rad/s)
    pi, J = setup.speed_pi, setup.mechanics.J
    a = pi.K_P / (2 * J)
    assert a == pytest.approx(50.0)
    excluded_until = 0.05 + SLEW_MARGIN * J * 150.0 / pi.tau_max + SETTLE_TIME_CONSTANTS / a
    t = r.t
    tracked = t >= excluded_until
    err = np.abs(r.signal("w_ref") - r.signal("w")) * RPM_PER_RAD_S  # rpm, the rule's unit
    before = tracked & (t >= 0.6 - PRE_WINDOW_S) & (t < 0.6)
    cap = RECOVERY_REFERENCE_FRACTION * 150.0 * RPM_PER_RAD_S
    band = max(min(RECOVERY_P99_FACTOR * np.percentile(err[before], 99), cap), RECOVERY_MIN_RPM)
    assert d["band_rpm"] == pytest.approx(band)
    after = t >= 0.6
    assert d["largest_speed_error_rpm"] == pytest.approx(np.max(err[after]))
    assert d["largest_speed_error_rpm"] > band  # the brake is felt: recovery is not vacuous
    assert d["recovered"] is True and d["reversal_at_s"] is None and d["stall_at_s"] is None
    at = _recovered_at(t, err, after, band)
    assert d["recovered_at_s"] == pytest.approx(at)
    assert d["recovery_time_s"] == pytest.approx(at - 0.6)
    assert np.all(err[t >= at] <= band) and t[-1] - at >= HOLD_S
    # physics: the load torque tau_L = k_b w steps in; with both PI roots at -a the speed dip is
    # (tau_L / J) t e^{-a t}: largest tau_L / (J a e) at 1 / a, back within the band when
    # (tau_L / J) t e^{-a t} = band (the brake torque falling with the dip, the current loop and
    # the PWM make the simulation differ by a few per cent)
    tau_l = 2.77e-3 * 150.0
    assert d["largest_speed_error_rpm"] / RPM_PER_RAD_S == pytest.approx(
        tau_l / (J * a * math.e), rel=0.06
    )
    assert d["largest_at_s"] - 0.6 == pytest.approx(1.0 / a, rel=0.1)
    ts = np.linspace(1.0 / a, 1.0, 200001)
    dip = tau_l / J * ts * np.exp(-a * ts) * RPM_PER_RAD_S
    assert d["recovery_time_s"] == pytest.approx(ts[np.argmax(dip <= band)], rel=0.1)
    # the older figure of the same dip agrees (it is relative to the speed before, in rad/s)
    (change,) = out.summary["load_changes"]
    assert abs(change["max_deviation_rad_s"]) * RPM_PER_RAD_S == pytest.approx(
        d["largest_speed_error_rpm"], rel=0.01
    )
    assert speed["end_of_run"]["reversal_at_s"] is None
    assert not [w for w in out.summary.get("warnings", []) if "loss of control" in w]
    assert out.summary["runs"]["paper-20"]["speed_outcome"] is speed  # one figure, one place


def test_the_load_of_im_foc_position_is_judged_on_the_position_error():
    setup = load_scenario("im-foc-position")
    out = run_im_scenario(setup)
    r, pos = out.main, out.summary["position_outcome"]
    assert "speed_outcome" not in out.summary and pos["speed_not_judged"]
    (d,) = pos["disturbances"]
    assert (d["what"], d["start_s"]) == ("load torque 0 -> 0.415 N m", 1.0)
    t = r.t
    # the 6.28 rad step at 0.05 s is excluded while it slews at w_max and settles in 6 / K_theta
    end = 0.05 + SLEW_MARGIN * 6.28 / setup.position.w_max + SETTLE_TIME_CONSTANTS / 10.0
    assert pos["windows_s"] == [[0.05, pytest.approx(end)]]
    tracked = t >= end
    err = np.abs(r.signal("theta_ref") - r.signal("theta") - setup.sensors.offset)
    before = tracked & (t >= 0.5) & (t < 1.0)
    band = max(min(2 * np.percentile(err[before], 99), 0.05 * 6.28), POSITION_RECOVERY_MIN_RAD)
    assert d["band_rad"] == pytest.approx(band)
    after = t >= 1.0
    assert d["largest_position_error_rad"] == pytest.approx(np.max(err[after]))
    assert d["largest_position_error_rad"] > band
    assert d["recovered"] is True
    at = _recovered_at(t, err, after, band)
    assert d["recovery_time_s"] == pytest.approx(at - 1.0)


def _synthetic_reversal():
    """A speed-PI IM drive at 100 rad/s whose shaft a 2 N m load (beyond the 0.83 N m torque
    limit) from 0.3 s decelerates at (2 - 0.83) / J and drives backwards: the logged signals
    written from that motion, no simulation."""
    J, tau_max, load = 0.000711, 0.83, 2.0
    setup = IMDriveSetup(
        mode="speed-pi",
        speed_reference=constant(100.0),
        mechanics=Mechanics(J=J, load=Profile.step(0.3, 0.0, load)),
        speed_pi=SpeedPISetup.design(J, 50.0, tau_max=tau_max),
        duration=0.6,
        sample_time=1e-4,
    )
    t = np.arange(0.0, 0.6, 1e-4)
    w = np.where(t < 0.3, 100.0, 100.0 - (load - tau_max) / J * (t - 0.3))
    n = t.size
    signals = {
        "w": w, "w_ref": np.full(n, 100.0), "i_s": np.ones(n, complex),
        "i_ref": np.ones(n, complex), "v_ref": np.ones(n, complex),
        "tau_e": np.where(t < 0.3, 0.0, tau_max),
    }  # fmt: skip
    signals["tau_load"] = setup.mechanics.external_torque(t, w)
    signals["tau_friction"] = setup.mechanics.friction_torque(w)
    flags = {"saturated": np.zeros(n, bool), "overmodulation": np.zeros(n, bool)}
    events = {"current_controller_saturation": 0, "overmodulation": 0, "current_limit": 0}
    return setup, IMDriveResult(setup, "synthetic", t, signals, {}, events, flags)


def test_a_reversed_im_shaft_is_a_loss_of_control_warning():
    setup, r = _synthetic_reversal()
    assert [(d["what"], d["start_s"]) for d in im_disturbances(setup)] == [
        ("load torque 0 -> 2 N m", 0.3)
    ]
    summary = r.summary
    (d,) = summary["speed_outcome"]["disturbances"]
    # the data: w crosses 0 at 0.3 + 100 J / (2 - 0.83); reversed beyond 5 rpm a little later
    t_zero = 0.3 + 100.0 * 0.000711 / (2.0 - 0.83)
    assert d["reversal_at_s"] == pytest.approx(t_zero + (5.0 / RPM_PER_RAD_S) * 0.000711 / 1.17,
                                               abs=2e-4)  # fmt: skip
    assert d["recovered"] is False
    warnings = warnings_of(setup, {"synthetic": r}, {"synthetic": summary})
    lost = [w for w in warnings if w.startswith("loss of control: ")]
    assert len(lost) == 1 and "synthetic after the load torque 0 -> 2 N m at 0.3 s" in lost[0]
    assert (
        "reversed" in lost[0] and f"ends at {r.signal('w')[-1] * RPM_PER_RAD_S:.0f} rpm" in lost[0]
    )
    assert "warnings" not in summary["speed_outcome"]  # moved into the summary's warnings
