"""The linearised closed DFIM drive (``drives.dfim._linearisation._stability``) as a python-control
``StateSpace``, with the speed reference and the load torque as inputs.

The state matrix is the linearisation's own Jacobian (the continuous right-hand side or the
compiled one-sample map at its equilibrium); the input columns are central differences of the
same function in the speed reference (the ``SpeedReference`` part's profile in the sampled loop,
the speed PI's reference in the continuous law) and in the load torque (the ``Shaft`` part's load
profile, read by the compiled plant in both); the output rows are central differences of the
shaft speed and of the machine part's currents i_s, i_r (its outputs at the sample instant, in the
frame of the supply, the linearisation's frame). Nothing is re-derived by hand: every column is
the compiled drive's.
"""

from __future__ import annotations

import numpy as np

from acdrive.analysis._linearise import get_complex, jacobian, slot
from acdrive.drives.dfim._linearisation._loops import _continuous_equilibrium, _Sampled

INPUTS = ("w_ref", "tau_L")
OUTPUTS = ("w", "i_s_re", "i_s_im", "i_r_re", "i_r_im")
#: central-difference scales of the inputs: rad/s and N m
_INPUT_SCALES = np.array([100.0, 0.1])


def _packer(system, parts: dict):
    """u = (w_ref, tau_L) -> the system's parameter array with those constant profiles."""

    def pack(u) -> np.ndarray:
        changed = [parts["reference"].with_params(w=float(u[0])),
                   parts["shaft"].with_params(load=float(u[1]))]  # fmt: skip
        return system.pack_params(changed)[0]

    return pack


def _currents(system, parts, Y) -> list[float]:
    dfim = parts["dfim"]
    i_s = get_complex(Y, slot(system, dfim, "y", "i_s"))
    i_r = get_complex(Y, slot(system, dfim, "y", "i_r"))
    return [i_s.real, i_s.imag, i_r.real, i_r.imag]


def _continuous(result):
    cont, x0 = _continuous_equilibrium(result.view)
    plant = cont.plant
    system, parts = plant.drive.system, plant.parts
    pack = _packer(system, parts)
    u0 = np.array([cont.w_ref, result.point.load_torque])

    def f(x, u):
        cont.w_ref = u[0]
        plant.P[:] = pack(u)
        try:
            return cont.rhs(x)
        finally:
            cont.w_ref = u0[0]
            plant.P[:] = pack(u0)

    def g(x, u):
        psi_s, psi_r, w, *_ = cont.unpack(x)
        plant.P[:] = pack(u)
        plant.load(psi_s, psi_r, w)
        plant.P[:] = pack(u0)
        return np.array([w, *_currents(system, parts, plant.Y)])

    return x0, u0, f, g, cont.scales(), None


def _sampled(result):
    smp = _Sampled(result.view)
    system, parts = smp.system, smp.parts
    pack = _packer(system, parts)
    u0 = np.array([result.point.speed, result.point.load_torque])
    z_w = smp.names.index(smp.c["w"].name)

    def f(z, u):
        smp.P[:] = pack(u)
        try:
            return smp(z)
        finally:
            smp.P[:] = pack(u0)

    def g(z, u):
        smp.P[:] = pack(u)
        smp.load(z)
        smp.sensors()  # the plant outputs at the sample instant
        smp.P[:] = pack(u0)
        return np.array([z[z_w], *_currents(system, parts, smp.Y)])

    return result.state, u0, f, g, smp.scales(), smp.T


def to_control(result):
    """``StabilityResult`` -> ``control.StateSpace`` (module docstring; ``result.to_control()``)."""
    import control

    x0, u0, f, g, scales, dt = (_sampled if result.kind == "sampled" else _continuous)(result)
    A = jacobian(lambda x: f(x, u0), x0, scales)
    B = jacobian(lambda u: f(x0, u), u0, _INPUT_SCALES)
    C = jacobian(lambda x: g(x, u0), x0, scales)
    D = jacobian(lambda u: g(x0, u), u0, _INPUT_SCALES)
    return control.ss(A, B, C, D, dt=dt or 0, inputs=list(INPUTS), outputs=list(OUTPUTS),
                      states=[n.replace(".", "_") for n in result.state_names], name=f"dfim-{result.kind}")  # fmt: skip
