"""The dead-time compensation of the cage IM's standstill fit (identify._winding, _polarity,
_impedance) on the other built-in windings: a PM machine's axes and the DFIM's rotor seen from its
converter, with the same inverter (2 us dead time, 1 V per device) as tests/test_identify_dead_time:

- the sample shift is the winding's free response over t_d / 2: for an RL branch the admittance
  is multiplied by e^{R t_d / (2 L)};
- uncompensated, the dead-time voltage -U sign(i) opposes the current: R comes out high, by the
  extra resistance Re(U P_k / I_k) its Fourier coefficients P_k predict at the tones, and far
  beyond its own interval;
- compensated (the DC steps' U_err, the simulated sign and the programmed dead time), the 95 %
  intervals hold the machine's own values.

The tone amplitudes are those at which the injection is not drowned by U_err (about 1.7 V on
these 24 V and 30 V benches): at the ideal-inverter plans' 0.15 V and 0.3 V the current spends
most of the test clamped near zero and the estimator refuses the fit (docs/guide/
identification.md, the dead-time rows of the coverage study).
"""

import dataclasses
import math

import numpy as np
import pytest

from acdrive.drives.pm import BLY171D
from acdrive.identify import (
    StandstillPlan,
    axis_test,
    dc_test,
    dfim_test,
    identify_dfim,
    identify_pm_standstill,
    rl_admittance,
)
from acdrive.identify._impedance import spectrum
from acdrive.machines import BODSON_DFIM

T_D, DROP = 2e-6, 1.0


def voltage_error(plan):
    """plant._inverter: phase a loses 4/3 (t_d f_pwm v_dc + v_drop) with i_b = i_c = -i_a / 2."""
    return 4.0 / 3.0 * (plan.t_d * plan.f_pwm * plan.v_dc + plan.v_drop)


def raised(plan):
    """The DC levels raised by U_err: the plateaus carry the currents of the ideal inverter."""
    U = voltage_error(plan)
    return dataclasses.replace(plan, dc_levels=tuple(v + U for v in plan.dc_levels))


#: BLY171D on its 24 V link, tones of 0.9 V (about three times its 1.8 A rated peak at most)
PM_PLAN = raised(StandstillPlan(dc_levels=(0.3, 0.6, 0.9), dc_step=0.5, base_frequency=2.0,
                                tone_amplitude=0.9, settle=0.5, v_dc=24.0, t_d=T_D,
                                v_drop=DROP))  # fmt: skip
#: Bodson's DFIM on its 30 V link, tones of 1.5 V
DFIM_PLAN = raised(StandstillPlan(dc_levels=(1.0, 2.0, 3.0), tone_amplitude=1.5, v_dc=30.0,
                                  t_d=T_D, v_drop=DROP))  # fmt: skip


def test_the_rl_windings_sample_shift_is_its_free_response_over_half_the_dead_time():
    """In the zero vector the shorted RL branch decays as e^{-R t / L}: sampled t_d / 2 before
    the zero vector's middle, the current reads e^{R t_d / (2 L)} of the model's, at any tone."""
    R, L, hold = BLY171D.R_s, BLY171D.L_d, 2e-4
    w = 2.0 * math.pi * np.array([0.0, 2.0, 320.0])
    shifted = rl_admittance((R, L), w, hold, dead_time=T_D)
    np.testing.assert_allclose(shifted / rl_admittance((R, L), w, hold),
                               math.exp(R * T_D / (2.0 * L)), rtol=1e-12)  # fmt: skip
    assert rl_admittance((R, L), 0.0, hold) == pytest.approx(1.0 / R, rel=1e-12)


def extra_resistance(log, plan):
    """Re(U P_k / I_k) at the tones: the dead-time voltage -U sign(i) as a resistance."""
    spec = spectrum(log, plan.base_frequency, plan.settle)
    return (voltage_error(plan) * spec.polarity / spec.current).real


@pytest.mark.slow
def test_pm_standstill_dead_time_bias_uncompensated_and_removed():
    machine, plan = BLY171D, PM_PLAN
    truth = {"R_s": machine.R_s, "L_d": machine.L_d, "L_q": machine.L_q}
    d = axis_test(machine, plan, "d", seed=1).log
    q = axis_test(machine, plan, "q", seed=2).log
    dc = dc_test(machine, plan, seed=0)
    raw = identify_pm_standstill(d, q, plan.base_frequency, plan.settle, bootstrap=20,
                                 check=False)  # fmt: skip
    R_s = raw.estimates[0]
    assert R_s.jacobian[0] > machine.R_s, R_s  # high, beyond its interval
    extra = extra_resistance(d, plan)
    assert np.all(extra > 0.0)
    assert extra.min() < raw.d.estimates[0].value - machine.R_s < extra.max()
    fit = identify_pm_standstill(d, q, plan.base_frequency, plan.settle, dc=dc, bootstrap=20,
                                 dead_time=plan.t_d)  # fmt: skip
    for e in fit.estimates:
        assert e.covers(truth[e.name]), e
        # every relative error below the uncompensated R_s's
        assert abs(e.value / truth[e.name] - 1.0) < R_s.value / machine.R_s - 1.0


@pytest.mark.slow
def test_dfim_rotor_side_dead_time_bias_uncompensated_and_removed():
    m, plan = BODSON_DFIM, DFIM_PLAN
    truth = {"R_r": m.R_r, "L_r": m.L_r, "L_sigma_r": m.L_r - m.M**2 / m.L_s,
             "R_S": m.R_s * (m.M / m.L_s) ** 2, "L_M": m.M**2 / m.L_s}  # fmt: skip
    opened = dfim_test(m, plan, "open", "injection", seed=1)
    shorted = dfim_test(m, plan, "shorted", "injection", seed=2)
    dc = dfim_test(m, plan, "open", "dc", seed=0)
    raw = identify_dfim(opened, shorted, plan.base_frequency, plan.settle, bootstrap=20,
                        check=False)  # fmt: skip
    R_r = raw.estimates[0]
    assert R_r.jacobian[0] > m.R_r, R_r
    extra = extra_resistance(opened, plan)
    assert np.all(extra > 0.0)
    assert extra.min() < raw.open.estimates[0].value - m.R_r < extra.max()
    fit = identify_dfim(opened, shorted, plan.base_frequency, plan.settle, dc=dc, bootstrap=20,
                        dead_time=plan.t_d)  # fmt: skip
    assert {e.name for e in fit.estimates} == set(truth)
    for e in fit.estimates:
        assert e.covers(truth[e.name]), e
        assert abs(e.value / truth[e.name] - 1.0) < R_r.value / m.R_r - 1.0
