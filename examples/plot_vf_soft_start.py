"""
Writing your own controller: a V/f drive with a frequency ramp
==============================================================

A sampled part written with the public API only (``docs/guide/adding-a-part.md`` explains each
line): a volts-per-hertz controller that ramps the stator frequency towards its reference at a
limited rate and commands a voltage proportional to it, up to a ceiling::

    f_k = f_{k-1} + clip(f_ref(t_k) - f_{k-1}, -slew T_s, slew T_s)
    V_k = min(V_boost + V_per_Hz |f_k|, V_max),     v_ref = sqrt(3/2) V_k e^{j theta_k}
    theta_{k+1} = theta_k + 2 pi f_k T_s              (kept in [0, 2 pi))

``V`` is a peak phase voltage and ``sqrt(3/2)`` turns it into acdrive's power-invariant space
vector (Bodson (8)). The step returns two event bits: ``slewing`` while the ramp limits the
frequency, ``voltage_limit`` while the ceiling limits the voltage (above the base frequency
``(V_max - V_boost) / V_per_Hz``: field weakening).

It feeds the built-in cage induction machine (Ugalde-Loo et al.'s 300 W machine) through the
averaged converter; its C is generated from its kernel on first use, so the system runs on the
native tier. The run is checked against the machine's steady-state equivalent circuit.
"""

from typing import ClassVar

import matplotlib.pyplot as plt
import numpy as np
from numba import njit
from scipy.optimize import brentq

from acdrive.core import Layout, SampledPart, cplx, real, table, table_at
from acdrive.machines import UGALDE_IM_300W, CageInductionMachine
from acdrive.plant import AveragedConverter, Shaft
from acdrive.sim import System

# %%
# The part: declarations, slots, kernel, class.
PARAMS = Layout(
    real("V_per_Hz", "V/Hz", "peak phase voltage per hertz of the ramped frequency", "positive"),
    real("V_boost", "V", "peak phase voltage at zero frequency", "nonnegative"),
    real("V_max", "V", "largest peak phase voltage commanded", "positive"),
    real("slew", "Hz/s", "largest rate of change of the frequency", "positive"),
    table("f_ref", "Hz", "stator frequency reference profile"),
)
STATES = Layout(
    real("f", "Hz", "stator frequency after the ramp"),
    real("theta", "rad", "angle of the voltage vector, in [0, 2 pi)"),
)
OUTPUTS = Layout(
    cplx("v_ref", "V", "commanded stator voltage space vector"),
    real("f", "Hz", "commanded stator frequency"),
)
_V_PER_HZ, _V_BOOST, _V_MAX, _SLEW = (
    PARAMS.slot(n) for n in ("V_per_Hz", "V_boost", "V_max", "slew")
)
_F_REF = PARAMS.table_start
_F, _THETA = STATES.slot("f"), STATES.slot("theta")
_V_REF, _Y_F = OUTPUTS.slot("v_ref"), OUTPUTS.slot("f")
_SLEWING, _VOLTAGE_LIMIT = 1, 2  # event bits: bit k is EVENTS[k]
SQRT_3_2 = np.sqrt(1.5)  # peak phase value -> power-invariant space vector (Bodson (8))


@njit
def vf_step(t, T_s, u, p, s, y):
    """Ramp the frequency, command V(f) at the present angle, advance the angle."""
    events = 0
    largest = p[_SLEW] * T_s
    change = table_at(p, _F_REF, t) - s[_F]
    if change > largest:
        change, events = largest, events | _SLEWING
    elif change < -largest:
        change, events = -largest, events | _SLEWING
    s[_F] += change
    V = p[_V_BOOST] + p[_V_PER_HZ] * abs(s[_F])
    if V > p[_V_MAX]:
        V, events = p[_V_MAX], events | _VOLTAGE_LIMIT
    v = SQRT_3_2 * V * complex(np.cos(s[_THETA]), np.sin(s[_THETA]))
    y[_V_REF], y[_V_REF + 1] = v.real, v.imag
    y[_Y_F] = s[_F]
    theta = s[_THETA] + 2.0 * np.pi * s[_F] * T_s
    s[_THETA] = theta - 2.0 * np.pi * np.floor(theta / (2.0 * np.pi))
    return events


class VoltsPerHertz(SampledPart):
    """Open-loop V/f controller with a frequency ramp and a voltage ceiling."""

    PARAMS, STATES, OUTPUTS = PARAMS, STATES, OUTPUTS
    DEFAULTS: ClassVar[dict] = {"V_boost": 0.0}
    EVENTS = ("slewing", "voltage_limit")
    step = vf_step


# %%
# Wired to the machine: 3 V/Hz up to 150 V (a base frequency of 50 Hz), a reference of 60 Hz
# reached at 120 Hz/s, and a load of 0.4 N m from 0.6 s.
machine = UGALDE_IM_300W
vf = VoltsPerHertz("vf", V_per_Hz=3.0, V_max=150.0, slew=120.0, f_ref=60.0)
converter = AveragedConverter("converter", V_dc=310.0)
im = CageInductionMachine.from_params("im", machine)
shaft = Shaft("shaft", J=machine.J, B=1e-4, load=[[0.0, 0.0], [0.6, 0.0], [0.6, 0.4]])
system = System(
    [vf, converter, im, shaft],
    [
        (vf.out.v_ref, converter.inp.v_ref),
        (converter.out.v, im.inp.v_s),
        (shaft.out.w, im.inp.w),
        (im.out.tau_e, shaft.inp.tau_e),
    ],
)
sample_time = 1e-4
result = system.compile().run(2.5, sample_time, log=[vf.out.f, shaft.out.w, im.out.tau_e])
print(result.tier, result.raised_events())
t, f, w = result.t, result.signal(vf.out.f), result.signal(shaft.out.w)

# %%
# The steady state the machine must reach, from its equivalent circuit: at the stator angular
# frequency ``w_e = 2 pi f`` and the rotor's ``w_2 = w_e - n_p w`` (the slip frequency),
#
#     (R_s + j w_e L_s) I_s + j w_e L_m I_r = V_s,    j w_2 L_m I_s + (R_r + j w_2 L_r) I_r = 0,
#
# and the torque ``n_p (L_m / L_r) Im(conj(psi_r) I_s)`` with ``psi_r = L_m I_s + L_r I_r``
# (Amezquita-Brooks et al. (2)) balances ``B w + tau_load``. The held voltage (constant over
# each sample) has the fundamental ``sin(x) / x`` times the command, x = w_e T_s / 2.


def steady_speed(V_pk, f_s, tau_load, B):
    """Shaft speed at which the machine's torque balances the load, below synchronism."""
    p, w_e = machine, 2.0 * np.pi * f_s
    x = 0.5 * w_e * sample_time
    V_s = SQRT_3_2 * V_pk * np.sin(x) / x

    def torque_margin(w):
        w_2 = w_e - p.n_p * w
        Z = np.array([[p.R_s + 1j * w_e * p.L_s, 1j * w_e * p.L_m],
                      [1j * w_2 * p.L_m, p.R_r + 1j * w_2 * p.L_r]])  # fmt: skip
        i_s, i_r = np.linalg.solve(Z, [V_s, 0.0])
        psi_r = p.L_m * i_s + p.L_r * i_r
        return p.n_p * p.L_m / p.L_r * (np.conj(psi_r) * i_s).imag - B * w - tau_load

    synchronous = w_e / p.n_p
    return brentq(torque_margin, 0.5 * synchronous, synchronous, xtol=1e-12)


V_pk = min(vf.values["V_boost"] + vf.values["V_per_Hz"] * 60.0, vf.values["V_max"])
settled = t >= 2.0
expected = steady_speed(V_pk, 60.0, 0.4, shaft.values["B"])
slip = 2.0 * np.pi * 60.0 - w[settled].mean()
print(f"speed {w[settled].mean():.4f} rad/s, equivalent circuit {expected:.4f} rad/s")
print(f"slip {slip:.4f} rad/s, predicted {2.0 * np.pi * 60.0 - expected:.4f} rad/s")
assert abs(w[settled].mean() - expected) < 1e-4 * slip

# %%
# The ramp: 120 Hz/s from zero, so 60 Hz at 0.5 s; the events count the samples on which the
# ramp and the ceiling acted.
ramp = np.minimum(120.0 * (t + sample_time), 60.0)
print(f"largest departure from the ramp {np.max(np.abs(f - ramp)):.3g} Hz")
assert np.max(np.abs(f - ramp)) < 1e-9
events = result.events["vf"]
assert events["slewing"] == np.count_nonzero(f < 60.0)
assert events["voltage_limit"] == np.count_nonzero(3.0 * f > 150.0)

fig, axes = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
axes[0].plot(t, f)
axes[0].set_ylabel("f [Hz]")
axes[1].plot(t, w, label="simulated")
axes[1].axhline(expected, ls=":", color="k", lw=0.8, label="equivalent circuit")
axes[1].set_ylabel("w [rad/s]")
axes[1].set_xlabel("time [s]")
axes[1].legend()
fig.tight_layout()
