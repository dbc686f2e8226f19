"""The sampled current loop of the cage induction motor drive as the compiled loop runs it, for
the loader's pre-check (``drives.cage_im._schema``): its spectral radius over one carrier period.

The loop is the drive's own current-mode topology (``drives.cage_im._drive``) with the averaged
inverter: the machine (1) of the simulated plant on a shaft held at a constant speed, the
discretised ``StationaryCurrentController`` following a zero current reference, the inverter's
``CarrierLatch`` taking its command at the first of the ``n_carrier`` samples of each carrier
period and the ``DCFedConverter`` holding it. One carrier period of that compiled system is a
map of its state (stator current and rotor flux, the controller's states, the latched command),
a :class:`~acdrive.analysis._linearise.SampleMap` run ``n_carrier`` times; at the origin the map
is linear (no limit is reached), so its Jacobian is the loop's period map and the largest
magnitude of its eigenvalues the loop's spectral radius: below 1 the loop is stable at that speed.
"""

from __future__ import annotations

import numpy as np

from acdrive.analysis._linearise import SampleMap, jacobian
from acdrive.control._current import CurrentProgram, StationaryCurrentController
from acdrive.machines._cage_part import CageInductionMachine
from acdrive.machines._induction import IMParams
from acdrive.plant._converter import DCFedConverter
from acdrive.plant._inverter import CarrierLatch
from acdrive.plant._mechanics import PrescribedSpeed
from acdrive.plant._sources import DCSource
from acdrive.sim._system import System

#: DC link of the map [V]: any positive value (the limits v_dc / sqrt(2) are never reached at
#: the origin, where the Jacobian is taken)
_V_DC = 1000.0


class CarrierPeriodMap(SampleMap):
    """One carrier period (``n_carrier`` samples from t = 0) of the compiled current loop at
    shaft speed ``w_mech`` [rad/s], as a map of the machine's ``i_s``, ``psi_r``, the
    controller's states and the latched command (module docstring)."""

    def __init__(self, plant: IMParams, w_mech: float, controller: StationaryCurrentController,
                 n_carrier: int, substeps: int = 4):  # fmt: skip
        T_s = controller.discrete.T_s
        machine = CageInductionMachine.from_params("machine", plant)
        shaft = PrescribedSpeed("shaft", w=float(w_mech))
        reference = CurrentProgram("reference")  # zero reference
        latch = CarrierLatch("latch", f_pwm=1.0 / (n_carrier * T_s))
        converter, dc = DCFedConverter("inverter"), DCSource("dc", V=_V_DC)
        wires = [
            (shaft.out.w, machine.inp.w),
            (machine.out.i_s, controller.inp.i_meas),
            (reference.out.i, controller.inp.i_ref),
            (dc.out.v_dc, controller.inp.v_dc),
            (controller.out.v_ref, latch.inp.v_ref),
            (latch.out.v_ref, converter.inp.v_ref),
            (dc.out.v_dc, converter.inp.v_dc),
            (converter.out.v, machine.inp.v_s),
        ]
        system = System([dc, machine, shaft, reference, controller, latch, converter], wires)
        super().__init__(system.compile(), T_s, substeps)
        self.n_carrier = int(n_carrier)
        order = controller.discrete.order
        self.coordinates = (
            self.coordinate(machine, "x", "i_s"),
            self.coordinate(machine, "x", "psi_r"),
            *(self.coordinate(controller, "s", f"x_{i}") for i in range(order)),
            self.coordinate(latch, "s", "v"),
        )

    def __call__(self, z: np.ndarray) -> np.ndarray:
        """The state after one carrier period from ``z`` at its start (the latch at sample 0)."""
        self.load(z)
        for k in range(self.n_carrier):
            self.t = k * self.T
            self.run_sample()
        self.t = 0.0
        return self.read()

    def period_matrix(self) -> np.ndarray:
        """The Jacobian of the carrier-period map at the origin (the loop's period map)."""
        z0 = np.zeros(len(self.names))
        return jacobian(self, z0, np.ones_like(z0))


def current_loop_radius(plant: IMParams, w_mech: float, controller: StationaryCurrentController,
                        n_carrier: int, substeps: int = 4) -> float:  # fmt: skip
    """Spectral radius of the compiled sampled current loop over one carrier period of
    ``n_carrier`` samples at shaft speed ``w_mech`` (:class:`CarrierPeriodMap`); below 1 the loop
    is stable at that speed."""
    F = CarrierPeriodMap(plant, w_mech, controller, n_carrier, substeps).period_matrix()
    return float(np.max(np.abs(np.linalg.eigvals(F))))
