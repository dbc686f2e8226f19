"""The slow path: the same sampled-data loop driven from Python.

Any Python controller can be plugged in (an object with
``step(k, t, v_s, v_g, theta_meas, w_ref, i_s, i_r_rotor)`` returning the rotor voltage in rotor
coordinates for motor k; an attribute ``close`` set True asks for the relay to close), and the plant can be integrated
either by the engine's RK4 or by ``scipy.integrate.solve_ivp`` (Radau) between samples, which is
how the compiled engine's accuracy is checked. Meant for prototyping and verification, not speed.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from acdrive.control import dfim as ctl
from acdrive.plant.converter import converter_output
from acdrive.plant.dfim_bus import STATES_PER_MOTOR, THETA, plant_derivatives, project_phasors
from acdrive.plant.profiles import profile_at
from acdrive.plant.sensors import encoder_angle
from acdrive.sim import engine
from acdrive.sim.result import DriveResult
from acdrive.sim.setup import DriveSetup, build_arrays, n_steps


class CompiledController:
    """The engine's own controller, called sample by sample from Python."""

    def __init__(self, arrays: dict):
        self.p_est, self.cp, self.cs = arrays["p_est"], arrays["cp"], arrays["cs"]

    def step(self, k, t, v_s, v_g, theta_meas, w_ref, i_s=0j, i_r_rotor=0j):
        v_r, _, self.close = ctl.controller_step(
            self.p_est[k], self.cp[k], self.cs[k], v_s, v_g, i_s, i_r_rotor, theta_meas, w_ref
        )
        return v_r


def simulate_slow(
    setup: DriveSetup,
    controller=None,
    integrator: str = "rk4",
    rtol: float = 1e-10,
    atol: float = 1e-12,
) -> DriveResult:
    """Run ``setup`` with a Python loop; ``integrator`` is "rk4" (engine steps) or "radau"."""
    a = build_arrays(setup)
    controller = controller or CompiledController(a)
    x, T_s, n = a["x"], setup.sample_time, len(setup.motors)
    args = (a["machines"], a["bus"], a["supply"], a["load_t"], a["load_tau"])
    v_term = np.zeros(n, dtype=complex)
    v_r = np.array([complex(a["cs"][k, ctl.CS_VR_RE], a["cs"][k, ctl.CS_VR_IM]) for k in range(n)])
    steps = n_steps(setup)
    log = np.zeros((steps, n, engine.N_LOG))
    dx = np.empty_like(x)
    for step in range(steps):
        t = step * T_s
        project_phasors(x, a["machines"])
        v_g = plant_derivatives(t, x, dx, *args, v_r, a["closed"], v_term)
        for k in range(n):
            o = STATES_PER_MOTOR * k
            theta_meas = encoder_angle(
                x[o + THETA],
                a["sensors"][k, engine.SN_ENC_OFFSET],
                a["sensors"][k, engine.SN_ENC_CPR],
            )
            w_ref = profile_at(a["ref_t"][k], a["ref_w"][k], t)
            i_s, i_r_rotor = engine.measured_currents(a["machines"][k], x, o, a["closed"][k])
            command = controller.step(k, t, v_term[k], v_g, theta_meas, w_ref, i_s, i_r_rotor)
            v_r[k], _ = converter_output(command, a["sensors"][k, engine.SN_V_R_MAX])
            engine.log_sample(log[step, k], a["machines"][k], x, o, a["closed"][k], v_term[k], v_g,
                              v_r[k], w_ref, a["cs"][k], 0)  # fmt: skip
            if getattr(controller, "close", False):
                a["closed"][k] = True
        if integrator == "rk4":
            work = np.empty((5, x.size))
            engine.advance_plant(t, x, T_s, setup.substeps, *args, v_r, a["closed"], work, v_term)
        elif integrator == "radau":
            held = v_r.copy()

            def rhs(tt, xx, held=held):
                out = np.empty_like(xx)
                plant_derivatives(tt, xx, out, *args, held, a["closed"], np.zeros(n, dtype=complex))
                return out

            sol = solve_ivp(rhs, (t, t + T_s), x, method="Radau", rtol=rtol, atol=atol)
            x[:] = sol.y[:, -1]
        else:
            raise ValueError(f"integrator must be 'rk4' or 'radau', got {integrator!r}")
        if not np.all(np.isfinite(x)):
            raise RuntimeError(f"simulation diverged at t = {t + T_s:.6f} s")
    return DriveResult(
        name=setup.name, t=np.arange(steps) * T_s, signals=log, sample_time=T_s, final_state=x
    )
