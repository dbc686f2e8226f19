"""The two closed loops the whole-drive linearisation (``drives.dfim._linearisation._stability``) differentiates,
both on the DFIM drive's own build of the setup (``acdrive.drives.get("dfim").build``):

* ``_Continuous``: the continuous-time controller laws of Bodson (20)+(22) or (22)+(43)+(45)-(47)
  evaluated with the sampled controller's own functions, on the compiled plant right-hand side
  (``_Plant``), in the frame that turns with the supply;
* ``_Sampled``: one sample of the compiled drive as a ``SampleMap``, re-referenced every sample.

Each reads the drive through a ``DriveView`` (``drives.dfim._linearisation._view``): the setup's motor 0
held at its operating point.
"""

from __future__ import annotations

import numpy as np

from acdrive.analysis._linearise import (
    Coordinate,
    SampleMap,
    get_complex,
    newton,
    set_complex,
    slot,
)
from acdrive.control._bodson import rotor_current_loop
from acdrive.control._speed import speed_pi
from acdrive.drives.dfim._drive import DFIMDrive
from acdrive.drives.dfim._linearisation._view import DriveView
from acdrive.errors import InputError
from acdrive.machines._dfim import (
    DFIMParams,
    machine_vector,
    rotor_current_for,
    rotor_voltage_for,
    stator_current_command,
)


def _drive(model: DriveView) -> DFIMDrive:
    """The DFIM drive's own build of the view's setup (one motor: parts ``dfim0``, ``shaft0``,
    ..., ``controller0``, and ``grid``, ``bus``), through the registry."""
    from acdrive.drives import get

    return get("dfim").build(model.setup)


class _Plant:
    """The compiled plant right-hand side of the drive (``derivatives`` of the generated loop),
    with the converter's output held at a given rotor voltage and the relay closed.

    The supply angle theta_g and the rotor angle are zero at the instant of evaluation: the
    stationary frame is then the frame that rotates with the supply (v_g real), rotor coordinates
    coincide with it, and the supply-frame derivatives are the stationary ones minus j w_e x.
    """

    def __init__(self, model: DriveView):
        self.drive = drive = _drive(model)
        system, parts = drive.system, drive.motors[0]
        self.parts, self.module = parts, drive.compile().module
        self.P, self.PO = system.pack_params()
        self.X, _ = system.pack_initial()  # angles zero, phasors e^{j 0}
        self.Y = system.pack_held({parts["sync"].name: {"closed": 1.0}})
        self.U = np.zeros(system.sizes["u"])
        self.dX = np.empty_like(self.X)
        dfim, shaft = parts["dfim"], parts["shaft"]
        self.i_psi_s = slot(system, dfim, "x", "psi_s")
        self.i_psi_r = slot(system, dfim, "x", "psi_r")
        self.i_w = slot(system, shaft, "x", "w")
        self.i_v_r = slot(system, parts["converter"], "y", "v")
        self.i_v_s = slot(system, parts["relay"], "y", "v")  # what the controller measures
        self.i_i_s = slot(system, dfim, "y", "i_s")
        self.i_i_r = slot(system, dfim, "y", "i_r")
        self.w_e = model.w_e

    def load(self, psi_s: complex, psi_r: complex, w: float) -> None:
        """Set the fluxes and the speed (angles stay zero) and evaluate the plant outputs."""
        X = self.X
        set_complex(X, self.i_psi_s, psi_s)
        set_complex(X, self.i_psi_r, psi_r)
        X[self.i_w] = w
        self.module.project(X, self.P, self.PO)
        self.module.plant_outputs(0.0, X, self.P, self.PO, self.Y, self.U)

    def evaluate(self, v_r: complex):
        """(d psi_s/dt, d psi_r/dt, dw/dt) in the supply frame and the stator terminal voltage,
        for the state last given to ``load`` and the rotor voltage ``v_r`` (supply frame)."""
        X, dX = self.X, self.dX
        set_complex(self.Y, self.i_v_r, v_r)
        self.module.derivatives(0.0, X, self.P, self.PO, self.Y, self.U, dX)
        psi_s, psi_r = get_complex(X, self.i_psi_s), get_complex(X, self.i_psi_r)
        dpsi_s = get_complex(dX, self.i_psi_s) - 1j * self.w_e * psi_s
        dpsi_r = get_complex(dX, self.i_psi_r) - 1j * self.w_e * psi_r
        return dpsi_s, dpsi_r, dX[self.i_w], get_complex(self.Y, self.i_v_s)

    def terminal_voltage(self, v_r: complex) -> complex:
        return self.evaluate(v_r)[3]

    def currents(self) -> tuple[complex, complex]:
        """(i_s, i_r) of the loaded state: the machine part's outputs (flux-current relation (9))."""
        return get_complex(self.Y, self.i_i_s), get_complex(self.Y, self.i_i_r)


def fluxes(params: DFIMParams, i_s: complex, i_r: complex) -> tuple[complex, complex]:
    """psi_s = L_s i_s + M i_r, psi_r = M i_s + L_r i_r (Bodson (9))."""
    return params.L_s * i_s + params.M * i_r, params.M * i_s + params.L_r * i_r


# ---------------------------------------------------------------------------------------------
# continuous-time controller laws (Bodson (20)+(22); (22)+(43)+(45)-(47))
# ---------------------------------------------------------------------------------------------


def _voltage_law(p, w_e, w_hat, v_s_mag, tau_com):
    """Rotor voltage (20) for the stator current command (22) with Q = 0 (stator-voltage frame);
    ``p``: the controller's parameter array (its machine estimates)."""
    i_s_com, _ = stator_current_command(p, w_e, v_s_mag, tau_com, 0.0)
    return rotor_voltage_for(p, w_e, w_hat, v_s_mag, i_s_com)


def _current_law(p, s, i_int, w_e, w_hat, v_s_mag, tau_com, i_s, i_r, z):
    """Rotor current loop (46)-(47) around the command (43), continuous time; returns
    (v_r, d z / dt) in the stator-voltage frame, z being the integral of the current error.

    The sampled controller's own ``rotor_current_loop`` (control._bodson) is evaluated on the
    ``SpeedController``'s parameter array ``p`` without voltage limit (prepared so by the caller)
    and its state array ``s`` (the integral at ``s[i_int]``), with a unit step: one forward-Euler
    step of length 1 then returns the integrand, d z / dt = (z after the step) - z.
    """
    i_s_com, _ = stator_current_command(p, w_e, v_s_mag, tau_com, 0.0)
    i_r_com = rotor_current_for(p, w_e, v_s_mag, i_s_com)
    set_complex(s, i_int, z)
    v_r, _ = rotor_current_loop(p, s, 1.0, w_e, w_hat, v_s_mag, i_s, i_r, i_r_com)
    return v_r, get_complex(s, i_int) - z


# ---------------------------------------------------------------------------------------------
# continuous-time closed loop
# ---------------------------------------------------------------------------------------------


class _Continuous:
    """Right-hand side of the continuous closed loop in the supply frame.

    State: Re/Im psi_s, Re/Im psi_r, [w], [e_I], [w_f], [Re/Im z]: speed unless frozen, speed-PI
    integrator if the speed loop is closed, speed-filter state if speed_filter_tau > 0, rotor
    current-loop integrator in current mode.
    """

    def __init__(self, model: DriveView):
        self.model, self.point = model, model.point
        self.plant = _Plant(model)
        ctrl = self.plant.parts["controller"]
        # the SpeedController part's arrays: parameters (machine estimates, gains) and a state
        # for the current loop's integral; no voltage limit in the continuous law (see
        # _current_law)
        self.p = ctrl.p
        self.p_unlimited = ctrl.p.copy()
        self.p_unlimited[ctrl.PARAMS.slot("v_r_max")] = np.inf
        self.s = ctrl.initial_state()
        self.i_int = ctrl.STATES.slot("ir_int")
        self.K_P, self.K_I, self.K_F = (ctrl.values[n] for n in ("K_P", "K_I", "K_F"))
        names = ["psi_s.re", "psi_s.im", "psi_r.re", "psi_r.im"]
        if model.speed_loop != "frozen":
            names.append("w")
        if model.speed_loop == "closed":
            names.append("e_I")
        if model.speed_filter_tau > 0.0:
            names.append("w_f")
        if model.mode == "current":
            names += ["z.re", "z.im"]
        self.names = tuple(names)
        self.tau_hold = 0.0
        self.w_ref = model.point.speed  # the speed reference (an input of ``to_control``)

    def unpack(self, x):
        s = dict(zip(self.names, x))
        w = s.get("w", self.point.speed)
        return (
            complex(s["psi_s.re"], s["psi_s.im"]),
            complex(s["psi_r.re"], s["psi_r.im"]),
            w,
            s.get("e_I", 0.0),
            s.get("w_f", w),
            complex(s.get("z.re", 0.0), s.get("z.im", 0.0)),
        )

    def torque_command(self, x) -> float:
        """The speed PI (25) without limits (the controller's own ``speed_pi``)."""
        _, _, _, e_I, w_f, _ = self.unpack(x)
        if self.model.speed_loop != "closed":
            return self.tau_hold
        return speed_pi(self.K_P, self.K_I, self.K_F, e_I, self.w_ref, w_f, -np.inf,
                        np.inf, 1.0)[0]  # fmt: skip

    def rhs(self, x) -> np.ndarray:
        m, plant = self.model, self.plant
        psi_s, psi_r, w, _, w_f, z = self.unpack(x)
        tau = self.torque_command(x)
        plant.load(psi_s, psi_r, w)
        i_s, i_r = plant.currents()
        # the controller uses the measured stator terminal voltage, which depends on the rotor
        # voltage through the supply inductance: solve this algebraic loop by fixed-point iteration
        v_s = m.v_g - m.supply_resistance * i_s
        for _ in range(200):
            v_r, dz = self._law(v_s, w_f, tau, i_s, i_r, z)
            v_new = plant.terminal_voltage(v_r)
            change = abs(v_new - v_s)
            v_s = v_new
            if change <= 1e-15 * m.v_g:
                break
        else:
            raise RuntimeError("the measured stator voltage does not converge (supply inductance)")
        v_r, dz = self._law(v_s, w_f, tau, i_s, i_r, z)
        dpsi_s, dpsi_r, dw, _ = plant.evaluate(v_r)
        self.last_dw = dw  # the torque balance (26), also when the speed is frozen
        self.last_v_s, self.last_v_r = v_s, v_r
        out = {
            "psi_s.re": dpsi_s.real,
            "psi_s.im": dpsi_s.imag,
            "psi_r.re": dpsi_r.real,
            "psi_r.im": dpsi_r.imag,
            "w": dw,
            "e_I": self.w_ref - w_f,
            "w_f": (w - w_f) / m.speed_filter_tau if m.speed_filter_tau > 0 else 0.0,
            "z.re": dz.real,
            "z.im": dz.imag,
        }
        return np.array([out[n] for n in self.names])

    def _law(self, v_s, w_hat, tau, i_s, i_r, z):
        """Rotor voltage in the supply frame: the law in the measured stator-voltage frame."""
        m = self.model
        v_mag = abs(v_s)
        to_supply = v_s / v_mag
        if m.mode == "voltage":
            return _voltage_law(self.p, m.w_e, w_hat, v_mag, tau) * to_supply, 0j
        v_r, dz = _current_law(self.p_unlimited, self.s, self.i_int, m.w_e, w_hat, v_mag, tau,
                               i_s / to_supply, i_r / to_supply, z)  # fmt: skip
        return v_r * to_supply, dz

    def guess(self) -> np.ndarray:
        """Equilibrium of the drive with exact controller parameters and no supply impedance."""
        m, pt = self.model, self.point
        p = machine_vector(m.machine)
        tau = pt.load_torque + m.machine.B * pt.speed
        self.tau_hold = tau
        i_s, _ = stator_current_command(p, m.w_e, m.v_g, tau, 0.0)
        i_r = rotor_current_for(p, m.w_e, m.v_g, i_s)
        psi_s, psi_r = fluxes(m.machine, i_s, i_r)
        g = m.gains
        e_I = (tau - g.K_F * g.K_P * pt.speed + g.K_P * pt.speed) / g.K_I
        z = m.R_T * i_r / m.current_gains[1]
        values = {
            "psi_s.re": psi_s.real,
            "psi_s.im": psi_s.imag,
            "psi_r.re": psi_r.real,
            "psi_r.im": psi_r.imag,
            "w": pt.speed,
            "e_I": e_I,
            "w_f": pt.speed,
            "z.re": z.real,
            "z.im": z.imag,
        }
        return np.array([values[n] for n in self.names])

    def scales(self) -> np.ndarray:
        m = self.model
        psi = m.v_g / m.w_e
        scale = {"w": 100.0, "e_I": 0.1, "w_f": 100.0}
        return np.array([scale.get(n, psi if n.startswith("psi") else 0.01) for n in self.names])


# ---------------------------------------------------------------------------------------------
# sampled-data closed loop: one sample of the compiled drive
# ---------------------------------------------------------------------------------------------


class _Sampled(SampleMap):
    """One sample of the compiled drive as a map of the state at the sample instant.

    The frame is re-referenced at every sample (supply angle theta_g and rotor angle zero at
    t_k), so the map is autonomous. Its state z holds the system's own quantities (named
    ``<part>.<quantity>``, ``.re``/``.im`` for complex ones), at t_k in that frame:

    * ``dfim0.psi_s``, ``dfim0.psi_r``: the machine's flux linkages, stationary frame rotated by
      -theta_g (plant state); ``shaft0.w``: the shaft speed (plant state);
    * ``speed0.theta_prev``: the encoder reading the speed estimator keeps from the previous
      sample, relative to the present shaft angle (minus the angle travelled over the last
      period: its backward difference); ``controller0.e_int``: the speed-PI integral (25);
      ``speed0.w``: the speed estimate (the filter state);
    * ``converter0.v``: the rotor voltage the converter held over the last period (its output, in
      rotor coordinates rotated by n_p theta - theta_g): the plant outputs the sensors read at t_k
      depend on it through the supply impedance;
    * in current mode, ``controller0.ir_int``: the rotor current-loop integral (47);
    * with one sample of computation delay, ``delay0.stored``: the controller's command of the
      previous sample, waiting in the drive's ``ComputationDelay`` part between controller and
      converter (rotor coordinates, likewise rotated).

    The discrete states outside z are those the loop sets on its first sample and then keeps
    (started flags, the synchroniser's closed relay and adjustments, the controller's mode and
    handover flag, the supply-frequency estimate at its nominal start): the template ``S0``,
    ``Y0`` is one sample of the compiled loop from the drive's own initial state. Besides, the
    supply-frequency estimator's previous grid voltage is v_g(t_k) e^{-j w_e T_s} in the frame of
    t_k, so that its estimate is w_e at every sample (the grid alone drives that estimator: its
    mode does not couple into the loop, and z leaves it out).
    """

    def __init__(self, model: DriveView, drive: DFIMDrive | None = None):
        if model.speed_loop != "closed":
            raise InputError("speed_loop", "the sampled-data model needs the closed speed loop")
        point = model.point
        drive = drive or _drive(model)
        super().__init__(drive.compile(), model.sample_time, model.substeps)
        self.model, self.point, self.drive = model, point, drive
        self.parts = parts = drive.motors[0]
        dfim, shaft, speed, conv, ctrl = (
            parts[k] for k in ("dfim", "shaft", "speed", "converter", "controller")
        )
        # the map state, by role (class docstring)
        self.c = c = {
            "psi_s": self.coordinate(dfim, "x", "psi_s", "stationary"),
            "psi_r": self.coordinate(dfim, "x", "psi_r", "stationary"),
            "w": self.coordinate(shaft, "x", "w"),
            "theta_prev": self.coordinate(speed, "s", "theta_prev", "shaft angle"),
            "e_int": self.coordinate(ctrl, "s", "e_int"),
            "w_est": self.coordinate(speed, "s", "w"),
            "v_held": self.coordinate(conv, "y", "v", "rotor"),
            "ir_int": self.coordinate(ctrl, "s", "ir_int"),
        }
        roles = list(c)[:-1] + (["ir_int"] if model.mode == "current" else [])
        if "delay" in parts:  # the drive's ComputationDelay part (model.delay_samples = 1)
            c["delay"] = self.coordinate(parts["delay"], "s", "stored", "rotor")
            roles.append("delay")
        self.coordinates = tuple(c[r] for r in roles)
        self.n_p = dfim.values["n_p"]
        self.i_theta_g = self.slot(drive.grid, "x", "theta_g")
        self.i_theta = self.slot(dfim, "x", "theta")  # the angle of rotor coordinates
        self.i_shaft_theta = self.slot(shaft, "x", "theta")  # what the encoder reads
        self.i_tau = self.slot(ctrl, "s", "tau_com")
        self.i_v_g_prev = self.slot(parts["frequency"], "s", "v_prev")
        # the loop's own start-up: one sample from the drive's initial state
        initial, held = drive.initial()
        self.X[:], self.S[:] = self.system.pack_initial(initial)
        self.Y[:] = self.system.pack_held(held)
        self.run_sample()
        self.S0, self.Y0 = self.S.copy(), self.Y.copy()
        self.X0, _ = self.system.pack_initial()  # angles zero, phasors e^{j 0}
        # the first sample stored v_g(0), the grid voltage at theta_g = 0
        v_g_prev = get_complex(self.S0, self.i_v_g_prev) * np.exp(-1j * model.w_e * self.T)
        set_complex(self.S0, self.i_v_g_prev, v_g_prev)
        self.torque_command = 0.0

    def read(self) -> np.ndarray:
        """The map state at t_k + T_s, re-referenced to the frame of that instant."""
        X = self.X
        theta_g = X[self.i_theta_g]
        self.back = np.exp(-1j * theta_g)  # stationary frame at t_k -> frame of the next sample
        self.rotor = np.exp(1j * (self.n_p * X[self.i_theta] - theta_g))  # rotor coordinates
        self.torque_command = self.S[self.i_tau]
        return super().read()

    def rereference(self, c: Coordinate, value):
        if c.frame == "stationary":
            return value * self.back
        if c.frame == "rotor":
            return value * self.rotor
        if c.frame == "shaft angle":
            return value - self.X[self.i_shaft_theta]
        return value

    def held_voltage(self, z: np.ndarray) -> complex:
        """The converter's output (rotor voltage held over the last period) in map state ``z``."""
        return self.value(z, self.c["v_held"].name)

    def guess(self, cont_state: np.ndarray, cont: _Continuous) -> np.ndarray:
        """The continuous equilibrium, with the rotor voltage of the law (20)."""
        psi_s, psi_r, w, e_I, _, integral = cont.unpack(cont_state)
        m = self.model
        tau = cont.torque_command(cont_state)
        v_r = _voltage_law(cont.p, m.w_e, w, m.v_g, tau)
        values = {"psi_s": psi_s, "psi_r": psi_r, "w": w, "theta_prev": -w * self.T,
                  "e_int": e_I, "w_est": w, "v_held": v_r, "ir_int": integral,
                  "delay": v_r}  # fmt: skip
        return self.vector({self.c[role].name: v for role, v in values.items() if role in self.c})

    def scales(self) -> np.ndarray:
        m = self.model
        psi = m.v_g / m.w_e
        scale = {"psi_s": psi * (1 + 1j), "psi_r": psi * (1 + 1j), "w": 100.0,
                 "theta_prev": 100.0 * self.T, "e_int": 0.1, "w_est": 100.0,
                 "v_held": 10.0 + 10j, "ir_int": 0.01 + 0.01j, "delay": 10.0 + 10j}  # fmt: skip
        return self.vector({self.c[role].name: v for role, v in scale.items() if role in self.c})


def _continuous_equilibrium(model: DriveView):
    cont = _Continuous(model)
    x0 = cont.guess()
    if model.speed_loop == "closed":
        x = newton(cont.rhs, x0, cont.scales())
        return cont, x
    # held torque command: solve for it (with the electrical states) so that the torque balances
    # the load (26), the speed staying at the operating point
    free = [i for i, n in enumerate(cont.names) if n != "w"]

    def residual(v):
        x = x0.copy()
        x[free] = v[:-1]
        cont.tau_hold = v[-1]
        return np.append(cont.rhs(x)[free], cont.last_dw)

    v = newton(residual, np.append(x0[free], cont.tau_hold), np.append(cont.scales()[free], 0.1))
    x = x0.copy()
    x[free] = v[:-1]
    cont.tau_hold = v[-1]
    return cont, x
