"""What the IM time-domain report (``acdrive reproduce im``) compares against: the built-in
scenario of each experiment of Amezquita-Brooks et al., secs. VI-VIII, the numbers the paper prints
there, the tolerances of the verdicts, the coupling-measurement settings, and the percentage format
the report's sentences use.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from acdrive._report.markdown import fmt

#: The built-in scenario of each experiment (paper figure -> scenario).
EXPERIMENTS = {
    "fig11": "im-locked-rotor",
    "fig13": "im-foc-speed",
    "fig14": "im-foc-position",
    "fig16": "im-icad-vs-pi",
    "fig18_20": "im-step-responses",
    "fig23": "im-perturbed",
}


@dataclass(frozen=True)
class PrintedValue:
    """A number the paper prints for its time-domain half, as printed, and where."""

    text: str
    where: str
    unit: str = ""

    @property
    def value(self) -> float:
        return float(self.text)


#: Numbers printed in secs. VI-VIII (the frequency-domain ones live in ``_report.icad_targets``).
PRINTED = {
    "dc_link": PrintedValue("310", "sec. VI", "V"),
    "pwm": PrintedValue("5", "sec. VI", "kHz"),
    "sampling": PrintedValue("50", "sec. VI", "kHz"),
    "fig11_frequency": PrintedValue("300", "sec. VI-A, Fig. 11", "rad/s"),
    "fig13_speed": PrintedValue("150", "sec. VI-B, Fig. 13(a)", "rad/s"),
    "fig14_position": PrintedValue("6.28", "sec. VI-C, Fig. 14(a)", "rad"),
    "fig14_load_time": PrintedValue("2.5", "sec. VI-C, Fig. 14(b)", "s"),
    "fig16_speed": PrintedValue("376", "sec. VI-D, Fig. 16", "rad/s"),
    "pi_kp": PrintedValue("360", "sec. VI-D"),
    "pi_ki": PrintedValue("9000", "sec. VI-D"),
    "w_r_steps": PrintedValue("375", "sec. VII, Figs. 17-20", "rad/s"),
    "fig23_frequency": PrintedValue("300", "sec. VIII, Fig. 23", "rad/s"),
}

#: Tolerances of the verdicts (each printed in the sentence that uses it).
TOLERANCES = {
    # a current loop tracks "with a low degree of error" (Figs. 11, 13(c), 14(c), 23) when the
    # RMS phase error is at most this fraction of the RMS reference
    "tracking_rel": 0.05,
    # a final speed [rad/s] / position [rad] reaches the printed reference within
    "speed_abs": 1.0,
    "position_abs": 0.01,
    # the load is "rejected" when the speed after it settles back within speed_abs and its
    # largest dip stays below this fraction of the reference ("good transient response")
    "load_dip_rel": 0.05,
    # "slight transient deviation" of the position (Fig. 14): below this fraction of the step
    "position_dip_rel": 0.05,
    # tau_E = tau_L + tau_F at constant speed (sec. VI-B): residual [N m]
    "torque_balance_abs": 0.01,
    # (20) with (21) follows the ideal constant-torque ramp (Fig. 16(a)): slope within
    "ramp_slope_rel": 0.05,
    # "significantly closer to the ideal" / "greater error levels" (Fig. 16): ratio at least
    "better_ratio": 2.0,
    # a simulated step overshoot equals the linear ICAD model's within (fraction of the step)
    "overshoot_abs": 0.05,
    # one controller "overshoots more" than another (Figs. 18, 20) when its overshoot is larger
    # by at least (fraction of the step)
    "overshoot_order_abs": 0.01,
    # ringing of the inner PI against (20) (Fig. 20), of the lower-gain inner PI against the
    # high-K_I PI (Fig. 18): ratio of late RMS deviations at least
    "ringing_ratio": 1.5,
    # the load change "reflects as an amplitude change in the references" (Fig. 13(c)): the
    # reference amplitude changes by at least this fraction of its value before the load, and
    # equals the field-oriented prediction from the torque within amplitude_prediction_rel
    "amplitude_change_rel": 0.05,
    "amplitude_prediction_rel": 0.05,
    # a scenario's setting equals the printed number within (relative)
    "setting_rel": 1e-9,
    # a steady-state claim is judged on the summary's steady window (the last 10 % of the run,
    # at least 50 ms) only if the signal is settled there: it drifts (least-squares slope times
    # the window length, ``acdrive._verdicts.settling``) by at most [rad/s] / [rad]
    "settled_speed_abs": 0.02,
    "settled_position_abs": 0.001,
    # a steady-state speed error is "large" (sec. VII, Fig. 16) from this fraction of the
    # reference on (3.76 rad/s at 376 rad/s)
    "large_steady_rel": 0.01,
    # the modulation signal lies "clearly" within the limits |m_a| <= 1 (Fig. 13(d)) when its
    # peak leaves at least this fraction of the range unused
    "modulation_margin": 0.05,
    # measured coupling against (10): relative complex difference, at injection frequencies up
    # to coupling_w_max [rad/s] (well below the 50 kHz sampling: 1/300 of it)
    "coupling_rel": 0.02,
    "coupling_w_max": 1000.0,
    # the 5 kHz hold "amplifies" the coupling at a frequency where it raises it by more than [dB]
    "coupling_change_db": 0.1,
}

#: Coupling measurement: injection frequencies [rad/s] (IM around the rotor speed, PMSG over
#: its current-loop band) and the PMSG's dq PI bandwidth [rad/s] (no controller is printed).
IM_FREQUENCIES = (100.0, 200.0, 300.0, 375.0, 450.0, 600.0, 1000.0, 2000.0)
PMSG_FREQUENCIES = (20.0, 50.0, 100.0, 200.0, 500.0, 1000.0, 2000.0)
PMSG_BANDWIDTH = 1000.0
PMSG_SPEED = 2.0 * math.pi * 50.0  # rated 50 Hz electrical (w_gen = 157 rad/s)
PMSG_AMPLITUDE = 100.0  # A, phase peak
#: the window before the Fig. 14 load change over which the position step must have settled [s]
PRELOAD_WINDOW = 0.2
#: the window before the Fig. 13 load change over which the reference amplitude is averaged [s]
FIG13_BEFORE_LOAD_WINDOW = 0.1


def pct(x: float) -> str:
    return f"{fmt(100.0 * x, 3)} %"
