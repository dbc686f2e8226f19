"""
Writing your own part: a thermal model of the stator winding
=============================================================

A part declares its parameters, states, inputs and outputs once (name, unit, kind, one-line doc,
rule) and gives its equations as module-level compiled kernels; ``System`` wires it to the
built-in parts like any other and compiles one loop for the whole topology.

Here a first-order thermal model of a cage induction machine's stator winding (Ugalde-Loo et
al.'s 300 W machine, rotor locked, fed through the averaged converter): the copper losses heat
a thermal capacitance ``C_th`` that loses heat to the ambient through a thermal resistance
``R_th``::

    C_th dT/dt = P_cu - (T - T_amb) / R_th,   P_cu = R_s(T) |i_s|^2,
    R_s(T) = R_s (1 + alpha (T - T_ref))

``|i_s|^2`` is the power-invariant space vector of acdrive (Bodson (8)), so ``R_s |i_s|^2`` is
the loss of all three phases (``3/2 R_s |i_s|^2`` in the amplitude-invariant scaling). The
winding temperature does not change the machine's own resistance here (one-way coupling): the
electrical model keeps its parameter ``R_s``, the thermal part evaluates ``R_s(T)`` for the loss.
The thermal time constant is made short (1 s) so that the run is short; a real winding's is minutes.
"""

from typing import ClassVar

import matplotlib.pyplot as plt
import numpy as np
from numba import njit

from acdrive.control import VoltageProgram
from acdrive.core import ContinuousPart, Layout, cplx, real
from acdrive.machines import UGALDE_IM_300W, CageInductionMachine
from acdrive.plant import AveragedConverter, PrescribedSpeed
from acdrive.sim import System

# %%
# The declarations: everything else (array slots, ports, units, ``repr``, ``describe()``,
# validation of the values) is derived from them.
PARAMS = Layout(
    real("R_s", "ohm", "stator resistance at T_ref (the machine's R_s)", "positive"),
    real("alpha", "1/K", "temperature coefficient of R_s (copper 3.93e-3)", "nonnegative"),
    real("T_ref", "K", "temperature at which R_s is given", "positive"),
    real("R_th", "K/W", "thermal resistance from the winding to the ambient", "positive"),
    real("C_th", "J/K", "thermal capacitance of the winding", "positive"),
    real("T_amb", "K", "ambient temperature", "positive"),
)
STATES = Layout(real("T", "K", "winding temperature"))
INPUTS = Layout(cplx("i_s", "A", "stator current space vector"))
OUTPUTS = Layout(
    real("T", "K", "winding temperature"),
    real("R_hot", "ohm", "stator resistance at the winding temperature"),
    real("P_cu", "W", "stator copper losses R_s(T) |i_s|^2"),
)
_R_S, _ALPHA, _T_REF, _R_TH, _C_TH, _T_AMB = (
    PARAMS.slot(n) for n in ("R_s", "alpha", "T_ref", "R_th", "C_th", "T_amb")
)
_T, _I_S = STATES.slot("T"), INPUTS.slot("i_s")
_Y_T, _Y_R, _Y_P = (OUTPUTS.slot(n) for n in ("T", "R_hot", "P_cu"))


@njit
def thermal_state_outputs(t, x, p, y):
    """The outputs that depend on the state only: T and R_s(T)."""
    y[_Y_T] = x[_T]
    y[_Y_R] = p[_R_S] * (1.0 + p[_ALPHA] * (x[_T] - p[_T_REF]))


@njit
def thermal_direct_outputs(t, x, u, p, y):
    """P_cu = R_s(T) |i_s|^2 (reads the input i_s, hence a direct output)."""
    y[_Y_P] = y[_Y_R] * (u[_I_S] * u[_I_S] + u[_I_S + 1] * u[_I_S + 1])


@njit
def thermal_rhs(t, x, u, p, y, dx):
    """C_th dT/dt = P_cu - (T - T_amb) / R_th."""
    dx[_T] = (y[_Y_P] - (x[_T] - p[_T_AMB]) / p[_R_TH]) / p[_C_TH]


class WindingThermal(ContinuousPart):
    """First-order thermal model of a stator winding heated by its copper losses."""

    PARAMS, STATES, INPUTS, OUTPUTS = PARAMS, STATES, INPUTS, OUTPUTS
    DEFAULTS: ClassVar[dict] = {"alpha": 0.0, "T_ref": 293.15, "T_amb": 293.15}
    DIRECT_FROM, DIRECT_OUTPUTS = ("i_s",), ("P_cu",)
    state_outputs = thermal_state_outputs
    direct_outputs = thermal_direct_outputs
    rhs = thermal_rhs

    def initial_state(self, **values):
        """The winding starts at the ambient temperature unless told otherwise."""
        return super().initial_state(**{"T": self.values["T_amb"], **values})


# %%
# The new part explains itself like the built-in ones.
machine = UGALDE_IM_300W
thermal = WindingThermal("winding", R_s=machine.R_s, R_th=2.0, C_th=0.5)
print(repr(thermal))
print(thermal.inp)
print(thermal.describe())

# %%
# Wired to a locked-rotor machine fed with a 50 Hz voltage through the averaged converter.
im = CageInductionMachine.from_params("im", machine)
program = VoltageProgram("program", V_pk=20.0, f=50.0)
converter = AveragedConverter("converter", V_dc=310.0)
rotor = PrescribedSpeed("rotor", w=0.0)  # locked
system = System(
    [program, converter, im, rotor, thermal],
    [
        (program.out.v_ref, converter.inp.v_ref),
        (converter.out.v, im.inp.v_s),
        (rotor.out.w, im.inp.w),
        (im.out.i_s, thermal.inp.i_s),
    ],
)
compiled = system.compile()
tau = thermal.values["R_th"] * thermal.values["C_th"]  # thermal time constant [s]
duration, sample_time = 10.0 * tau, 1e-4
log = [thermal.out.T, thermal.out.P_cu, im.out.i_s]
result = compiled.run(duration, sample_time, log=log)
t, T, P = result.t, result.signal(thermal.out.T), result.signal(thermal.out.P_cu)

# %%
# Checks, from the model's own equations:
#
# * steady state (the last time constant, where exp(-9) < 1.3e-4 of the rise is left): the
#   temperature rise equals ``R_th`` times the losses;
# * the time constant: ``ln(1 - rise / steady rise)`` falls with slope ``-1 / (R_th C_th)``
#   (fitted between 0.5 and 3 time constants; a slope is blind to the few milliseconds the
#   currents take to settle);
# * energy: the heat stored, ``C_th (T_end - T_0)``, equals the losses minus the heat given to
#   the ambient, both integrated over the run (trapezoidal rule on the logged samples, the only
#   approximation here; 1e-3 of the total losses bounds it).
R_th, C_th, T_amb = (thermal.values[k] for k in ("R_th", "C_th", "T_amb"))
settled = t >= duration - tau
rise, expected_rise = T[settled].mean() - T_amb, R_th * P[settled].mean()
print(f"steady rise {rise:.4f} K, R_th P_cu {expected_rise:.4f} K")
assert abs(rise - expected_rise) < 1e-3 * expected_rise

fit = (t >= 0.5 * tau) & (t <= 3.0 * tau)
slope = np.polyfit(t[fit], np.log(1.0 - (T[fit] - T_amb) / rise), 1)[0]
print(f"time constant {-1.0 / slope:.4f} s, R_th C_th {tau:.4f} s")
assert abs(-1.0 / slope - tau) < 1e-2 * tau

stored = C_th * (T[-1] - T[0])
balance = np.trapezoid(P - (T - T_amb) / R_th, t)
print(f"heat stored {stored:.4f} J, losses minus heat to ambient {balance:.4f} J")
assert abs(stored - balance) < 1e-3 * np.trapezoid(P, t)

# %%
# With the copper's temperature coefficient the hot winding loses more, so it settles higher:
# the steady state of ``T - T_amb = R_th R_s (1 + alpha (T - T_ref)) |i_s|^2`` with the same
# currents (the electrical model does not see the temperature). Same topology, so the compiled
# loop is reused with the new parameter.
copper = thermal.with_params(alpha=3.93e-3)
hot = compiled.run(duration, sample_time, log=log, parts=[copper])
T_hot = hot.signal(thermal.out.T)
i2 = np.mean(np.abs(hot.signal(im.out.i_s)[settled]) ** 2)
a, R_s, T_ref = copper.values["alpha"], copper.values["R_s"], copper.values["T_ref"]
gain = R_th * R_s * i2  # K per unit of R_s(T) / R_s
expected_hot = gain * (1.0 + a * (T_amb - T_ref)) / (1.0 - a * gain)
hot_rise = T_hot[settled].mean() - T_amb
print(f"steady rise with alpha {hot_rise:.4f} K, closed form {expected_hot:.4f} K")
assert abs(hot_rise - expected_hot) < 1e-3 * expected_hot

fig, axes = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
axes[0].plot(t, T - T_amb, label="alpha = 0")
axes[0].plot(t, T_hot - T_amb, label="alpha = 3.93e-3 1/K")
axes[0].axhline(expected_rise, ls=":", color="k", lw=0.8)
axes[0].set_ylabel("T - T_amb [K]")
axes[0].legend()
axes[1].plot(t, P, lw=0.6, label="alpha = 0")
axes[1].plot(t, hot.signal(thermal.out.P_cu), lw=0.6, label="alpha = 3.93e-3 1/K")
axes[1].set_ylabel("P_cu [W]")
axes[1].set_xlabel("time [s]")
fig.tight_layout()
