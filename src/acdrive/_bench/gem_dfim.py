"""The matched open-loop DFIM case against gym-electric-motor (GEM) 3.0.3.

Both simulators run the same doubly-fed induction machine (acdrive's DFIM parameters, Bodson
section IV-A), the same viscous load, the same control period (1e-4 s) and the same open-loop
commands for the same model time:

* the **actions** (``actions``): GEM's normalised bridge commands in [-1, 1], stator phases
  a, b, c then rotor phases d, e, f (rotor coordinates): a stator voltage rotating at a frequency
  ramped from 0 to 60 Hz (V/f with a boost) and a rotor voltage of constant amplitude rotating
  slowly in rotor coordinates. GEM's averaged B6 bridges turn action x into the phase voltage
  x u_sup / 2 (well inside their limits here); acdrive's parts take the same voltages as
  space vectors, ``acdrive_voltages`` (power-invariant: sqrt(3/2) times GEM's amplitude-invariant
  vectors; the parameters are scaling-free);
* acdrive: ``_bench.parts.HeldSequence`` (the command of each control period, by index) ->
  ``machines.DoublyFedMachine`` (stator connected from the start) <->
  ``plant.Shaft`` (J, viscous B); GEM: ``Cont-SC-DFIM-v0`` with a ``PolynomialStaticLoad``
  of the same J and B (``peers/gem_dfim.py``).

**The one difference in the equations.** A rotor converter holds its voltage in *rotor*
coordinates over a control period; acdrive's DFIM applies it so (v_r e^{j n_p theta(t)}, the
rotor turning during the period). GEM turns the rotor voltage into the stator frame once per step,
at the angle the rotor had at the step's start, and holds that stationary-frame vector over the
step. The two are different ODEs with the same inputs (they differ by O(n_p w T_s) in the rotor
voltage's angle). Each simulator's integration error is therefore measured against a reference of
its *own* equations (``DFIMEquations(rotor_frame="rotor")`` for acdrive, ``"stator_at_step_start"``
for GEM), and GEM's difference from the rotor-frame reference is reported as well
(``error_vs_rotor_frame_reference``: how far GEM's convention moves it from the rotor-converter
model). The target compares the integration errors.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import tempfile
import time

import numpy as np

from acdrive._bench.reference import accuracy, error_verdicts, short_errors
from acdrive._bench.venvs import PeerFailed, PeerProcess
from acdrive._bench.windows import Clock, local_side, ratio_spread, time_sides

K = math.sqrt(1.5)  # power-invariant / peak-value space-vector scaling
T_S = 1e-4  # s, the sample time for this case
DURATION = 1.0  # s
INTEGRATOR, SUBSTEPS = "rk6", 1
U_SUP = 30.0  # V, DC supply of both of GEM's bridges
J_LOAD = 1e-5  # kg m^2, GEM needs a load inertia; J_rotor = J - J_LOAD, the total is J
B_LOAD = 6e-4  # N m s/rad, viscous load (about 0.1 N m at 1500 rpm)
# stator: V/f ramp from 0 to 60 Hz between 5 % and 65 % of the run, then held
F_END, NOM_F, NOM_U_S, U_BOOST = 60.0, 60.0, 11.1, 1.5  # Hz, Hz, V peak, V peak
# rotor: a voltage of constant amplitude rotating at F_ROTOR in rotor coordinates
U_ROTOR, F_ROTOR = 0.5, 2.0  # V peak, Hz


def machine() -> dict:
    """acdrive's DFIM (Bodson IV-A) as a dict of T-model parameters."""
    from acdrive.machines._dfim import BODSON_DFIM as m

    return {
        "R_s": m.R_s,
        "R_r": m.R_r,
        "L_s": m.L_s,
        "L_r": m.L_r,
        "M": m.M,
        "n_p": m.n_p,
        "J": m.J,
    }


def case(duration: float = DURATION) -> dict:
    """Everything the peer needs (``peers/gem_dfim.py --case``) and the JSON reports."""
    m = machine()
    return {
        "machine": {k: m[k] for k in ("R_s", "R_r", "L_s", "L_r", "M", "n_p")},
        "J": m["J"],
        "j_load": J_LOAD,
        "B": B_LOAD,
        "tau": T_S,
        "duration_s": duration,
        "u_sup": U_SUP,
        "limits": {"i": 100.0, "omega": 1000.0},
        "stator": f"V/f: frequency ramped 0 -> {F_END:g} Hz between 5 % and 65 % of the run, "
        f"amplitude {U_BOOST:g} V + {NOM_U_S - U_BOOST:g} V f/{NOM_F:g} Hz (peak phase voltage)",
        "rotor": f"{U_ROTOR:g} V peak rotating at {F_ROTOR:g} Hz in rotor coordinates",
        "initial_state": "all zero (standstill, no flux)",
    }


def actions(n: int) -> np.ndarray:
    """The action of each control step, shape (n, 6) (module docstring)."""
    t = np.arange(n) * T_S
    seconds = n * T_S
    t_0, t_1 = 0.05 * seconds, 0.65 * seconds
    f = F_END * np.clip((t - t_0) / (t_1 - t_0), 0.0, 1.0)
    theta = 2.0 * np.pi * np.cumsum(f) * T_S
    m_s = (U_BOOST + (NOM_U_S - U_BOOST) * f / NOM_F) / (U_SUP / 2.0)
    m_r = U_ROTOR / (U_SUP / 2.0)
    theta_r = 2.0 * np.pi * F_ROTOR * t
    out = np.zeros((n, 6))
    for k in range(3):
        out[:, k] = m_s * np.cos(theta - 2.0 * np.pi * k / 3.0)
        out[:, 3 + k] = m_r * np.cos(theta_r - 2.0 * np.pi * k / 3.0)
    return out


def acdrive_voltages(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(stator voltage, stationary frame; rotor voltage, rotor coordinates) per step as
    power-invariant space vectors of the phase voltages a u_sup / 2."""
    alpha = np.exp(2j * np.pi / 3.0)
    u = a * (U_SUP / 2.0)
    v_s = K * (2.0 / 3.0) * (u[:, 0] + alpha * u[:, 1] + alpha**2 * u[:, 2])
    v_r = K * (2.0 / 3.0) * (u[:, 3] + alpha * u[:, 4] + alpha**2 * u[:, 5])
    return v_s, v_r


def build_system(v_s: np.ndarray, v_r: np.ndarray, integrator: str = INTEGRATOR):
    """stator and rotor command tables -> DFIM <-> shaft; relay closed from the start."""
    from acdrive._bench.parts import HeldSequence
    from acdrive.machines._dfim_part import DoublyFedMachine
    from acdrive.plant._mechanics import Shaft
    from acdrive.plant._network import RelayCommand
    from acdrive.sim._system import System

    m = machine()
    p = {
        "stator": HeldSequence("stator", v_s),
        "rotor": HeldSequence("rotor", v_r),
        "relay": RelayCommand("relay", close_at=0.0),
        "dfim": DoublyFedMachine(
            "dfim", **{k: m[k] for k in ("R_s", "R_r", "L_s", "L_r", "M", "n_p")}
        ),
        "shaft": Shaft("shaft", J=m["J"], B=B_LOAD),
    }
    d, s = p["dfim"], p["shaft"]
    wires = [
        (p["stator"].out.v_ref, d.inp.v_s),
        (p["rotor"].out.v_ref, d.inp.v_r),
        (p["relay"].out.closed, d.inp.connected),
        (s.out.w, d.inp.w),
        (d.out.tau_e, s.inp.tau_e),
    ]
    return System(list(p.values()), wires, method=integrator), p


def acdrive_states(raw, system, p) -> np.ndarray:
    """(Re i_s, Im i_s, Re psi_r, Im psi_r, w, theta) rows at the sampling instants and the
    end, power-invariant."""
    m = machine()
    i_s = raw.signal(p["dfim"].out.i_s)
    i_r = raw.signal(p["dfim"].out.i_r)
    psi_r = m["M"] * i_s + m["L_r"] * i_r
    w = raw.signal(p["shaft"].out.w)
    theta = raw.signal(p["shaft"].out.theta)
    rows = np.column_stack([i_s.real, i_s.imag, psi_r.real, psi_r.imag, w, theta])
    X = raw.final_state
    a, _ = system.slots["dfim"].x
    sh, _ = system.slots["shaft"].x
    psi_s_f = complex(X[a], X[a + 1])
    psi_r_f = complex(X[a + 2], X[a + 3])
    det = m["L_s"] * m["L_r"] - m["M"] ** 2
    i_s_f = (m["L_r"] * psi_s_f - m["M"] * psi_r_f) / det
    final = [i_s_f.real, i_s_f.imag, psi_r_f.real, psi_r_f.imag, X[sh], X[sh + 1]]
    return np.vstack([rows, final])


def gem_states(rec) -> np.ndarray:
    """GEM's recorded ODE states (omega, i_s, psi_r, epsilon; peak-value) as acdrive's rows."""
    s = rec["states"]
    n_p = machine()["n_p"]
    return np.column_stack(
        [K * s[:, 1], K * s[:, 2], K * s[:, 3], K * s[:, 4], s[:, 0], s[:, 5] / n_p]
    )


class DFIMEquations:
    """The DFIM (``machines._dfim_part``'s equations in the variables i_s, psi_r) with the shaft,
    y = (Re i_s, Im i_s, Re psi_r, Im psi_r, w, theta), power-invariant, stationary frame:

        dpsi_s/dt = v_s - R_s i_s,  dpsi_r/dt = v_r' - R_r i_r + j n_p w psi_r,
        i_r = (psi_r - M i_s) / L_r,  psi_s = sigma L_s i_s + (M / L_r) psi_r,
        J dw/dt = n_p (M / L_r) Im(conj(psi_r) i_s) - B w,  dtheta/dt = w,

    with the rotor voltage v_r' in the stator frame: ``rotor_frame="rotor"`` (acdrive, a rotor
    converter): v_r' = v_r e^{j n_p theta(t)}, v_r held in rotor coordinates; ``"stator_at_step
    _start"`` (GEM): v_r' = v_r e^{j n_p theta(t_k)} held over the step."""

    def __init__(self, rotor_frame: str):
        m = machine()
        self.rotor_frame = rotor_frame
        self.m = m
        self.sls = m["L_s"] - m["M"] ** 2 / m["L_r"]
        self.kr = m["M"] / m["L_r"]

    def _rhs(self, y, v_s, v_r, lib_exp, ld=None):
        m = self.m
        one = (lambda x: x) if ld is None else ld
        n_p, R_s, R_r, L_r, M, J = (one(m[k]) for k in ("n_p", "R_s", "R_r", "L_r", "M", "J"))
        sls, kr, B = one(self.sls), one(self.kr), one(B_LOAD)
        i_a, i_b, p_a, p_b, w, th = y
        if self.rotor_frame == "rotor":
            c, s = lib_exp(n_p * th)
            vr_a = v_r[0] * c - v_r[1] * s
            vr_b = v_r[0] * s + v_r[1] * c
        else:
            vr_a, vr_b = v_r
        ir_a = (p_a - M * i_a) / L_r
        ir_b = (p_b - M * i_b) / L_r
        dpr_a = vr_a - R_r * ir_a - n_p * w * p_b
        dpr_b = vr_b - R_r * ir_b + n_p * w * p_a
        dps_a = v_s[0] - R_s * i_a
        dps_b = v_s[1] - R_s * i_b
        tau = n_p * kr * (p_a * i_b - p_b * i_a)
        return [
            (dps_a - kr * dpr_a) / sls,
            (dps_b - kr * dpr_b) / sls,
            dpr_a,
            dpr_b,
            (tau - B * w) / J,
            w,
        ]

    def rhs(self, t, y, vs_a, vs_b, vr_a, vr_b):
        return np.array(
            self._rhs(y, (vs_a, vs_b), (vr_a, vr_b), lambda x: (math.cos(x), math.sin(x)))
        )

    jac = None  # Radau's finite-difference Jacobian (6 states)

    def rhs_ld(self, t, y, vs_a, vs_b, vr_a, vr_b):
        ld = np.longdouble
        return np.array(
            self._rhs(y, (vs_a, vs_b), (vr_a, vr_b), lambda x: (np.cos(x), np.sin(x)), ld), dtype=ld
        )

    def inputs(self, seg: dict, extended: bool):
        v_s, v_r = seg["v_s"], seg["v_r"]
        n_p = self.m["n_p"]
        if extended:
            ld = np.longdouble

            def at(j, y):
                if self.rotor_frame == "rotor":
                    return ld(v_s[j].real), ld(v_s[j].imag), ld(v_r[j].real), ld(v_r[j].imag)
                c, s = np.cos(ld(n_p) * y[5]), np.sin(ld(n_p) * y[5])
                a, b = ld(v_r[j].real), ld(v_r[j].imag)
                return ld(v_s[j].real), ld(v_s[j].imag), a * c - b * s, a * s + b * c

            return at

        def at_f(j, y):
            if self.rotor_frame == "rotor":
                return v_s[j].real, v_s[j].imag, v_r[j].real, v_r[j].imag
            r = v_r[j] * complex(math.cos(n_p * y[5]), math.sin(n_p * y[5]))
            return v_s[j].real, v_s[j].imag, r.real, r.imag

        return at_f


def run_case(
    peer: dict,
    rounds: int,
    duration: float,
    reference: bool,
    extended_substeps: int = 4,
    log=None,
    timing: dict | None = None,
    clock: Clock | None = None,
    reference_cache=None,
) -> dict:
    """acdrive and GEM (if ``peer`` is available) timed in ``rounds`` rounds of interleaved
    CPU-time windows (``windows.time_sides``: acdrive, GEM's ``physical_system.simulate``, GEM's
    ``env.step``), the ratios and their spread; both simulators' integration errors against
    references of their own equations (if ``reference``). ``timing``: ``solo_window_cpu_s`` and
    ``min_calibration_cpu_s``; ``reference_cache``: the folder of cached references
    (``_bench.refcache``, None: computed every time)."""
    say = log or (lambda _m: None)
    clock = clock or Clock()
    timing = {"solo_window_cpu_s": 1.0, "min_calibration_cpu_s": 0.1, **(timing or {})}
    n = round(duration / T_S)
    act = actions(n)
    v_s, v_r = acdrive_voltages(act)
    system, p = build_system(v_s, v_r)
    ports = [p["dfim"].out.i_s, p["dfim"].out.i_r, p["shaft"].out.w, p["shaft"].out.theta]
    start = time.perf_counter()
    compiled = system.compile()
    compiled.run(min(0.01, duration), T_S, substeps=SUBSTEPS, log=ports)
    first = time.perf_counter() - start
    last: dict = {}

    def run_once():
        last["raw"] = compiled.run(duration, T_S, substeps=SUBSTEPS, log=ports)
        return last["raw"].steps

    run_once()  # warm-up
    tmp = tempfile.mkdtemp(prefix="acdrive_bench_gem_")
    record = os.path.join(tmp, "gem_run.npz")
    gem: dict = {"available": False, "reason": peer.get("reason", "not run")}
    proc = None
    pairs = {
        "acdrive_vs_physical_system": ("acdrive", "gem_physical_system"),
        "acdrive_vs_env_step": ("acdrive", "gem_env_step"),
    }
    try:
        if peer.get("available"):
            case_path = os.path.join(tmp, "case.json")
            act_path = os.path.join(tmp, "actions.npy")
            with open(case_path, "w", encoding="utf-8") as f:
                json.dump(case(duration), f)
            np.save(act_path, act)
            try:
                proc = PeerProcess(peer["python"], "gem_dfim.py", cwd=tmp)
                gem = {"available": True, **proc.ask("about")}
                proc.ask("load", case=case_path, actions=act_path)
            except PeerFailed as exc:
                gem = {"available": False, "reason": str(exc)}
        peers = {}
        if gem["available"]:
            peers = {
                "gem_physical_system": lambda runs: proc.ask("window", kind="physical", runs=runs),
                "gem_env_step": lambda runs: proc.ask("window", kind="env", runs=runs),
            }
        say("gem_dfim: interleaved CPU-time windows")
        local = {"acdrive": local_side(run_once, clock)}
        try:
            t = time_sides(local, peers, pairs, rounds, clock, log=say, **timing)
            if peers:
                say("gym-electric-motor: recording a run")
                gem.update(proc.ask("record", out=record))
        except PeerFailed as exc:
            gem = {"available": False, "reason": str(exc)}
            t = time_sides(local, {}, {}, rounds, clock, log=say, **timing)
        raw = last["raw"]
        out: dict = {
            "case": case(duration),
            "timing": t,
            "acdrive": {
                "integrator": INTEGRATOR,
                "substeps_per_segment": SUBSTEPS,
                "first_run_s": first,
                "control_steps": raw.steps,
                "steps_per_cpu_s": t["sides"]["acdrive"]["steps_per_cpu_s"]["median"],
                "per_run_cpu_s": t["sides"]["acdrive"]["per_run_cpu_s"],
                "final_speed_rad_s": float(raw.signal(p["shaft"].out.w)[-1]),
            },
        }
        if gem["available"]:
            sides = t["sides"]
            gem["steps_per_cpu_s"] = sides["gem_physical_system"]["steps_per_cpu_s"]["median"]
            gem["steps_per_cpu_s_is"] = "physical_system.simulate (the faster of GEM's two loops)"
            gem["env_step_steps_per_cpu_s"] = sides["gem_env_step"]["steps_per_cpu_s"]["median"]
            gem["per_run_cpu_s"] = sides["gem_physical_system"]["per_run_cpu_s"]
            gem["env_step_per_run_cpu_s"] = sides["gem_env_step"]["per_run_cpu_s"]
            main_ratio = t["ratios"]["acdrive_vs_physical_system"]
            out["ratio"] = main_ratio["ratio"]
            out["ratio_spread"] = ratio_spread(main_ratio)
            env_ratio = t["ratios"]["acdrive_vs_env_step"]
            out["ratio_env_step"] = env_ratio["ratio"]
            out["ratio_env_step_spread"] = ratio_spread(env_ratio)
        out["gym-electric-motor"] = gem
        _accuracy(out, reference, raw, system, p, n, v_s, v_r, gem, record, extended_substeps, say,
                  reference_cache)  # fmt: skip
    finally:
        if proc is not None:
            proc.close()
        shutil.rmtree(tmp, ignore_errors=True)  # the run's own temporary folder (mkdtemp)
    return out


def _accuracy(out, reference, raw, system, p, n, v_s, v_r, gem, record, extended_substeps, say,
              cache=None):  # fmt: skip
    """Both simulators' errors against references of their own equations (``run_case``)."""
    if reference:
        a_states = acdrive_states(raw, system, p)
        seg = {
            "t": raw.t.copy(),
            "counts": np.ones(n, dtype=np.int64),
            "dt": np.full(n, T_S),
            "v_s": v_s,
            "v_r": v_r,
        }
        say("acdrive gem_dfim: accuracy against the references")
        a_err = accuracy(
            a_states,
            seg,
            n,
            DFIMEquations("rotor"),
            extended_substeps=extended_substeps,
            cache=cache,
            log=say,
        )
        out["acdrive"]["error"] = a_err
        out["acdrive"]["error_summary"] = short_errors(a_err)
        if gem.get("available"):
            rec = dict(np.load(record))
            g_states = gem_states(rec)
            # GEM's own voltages equal the ones the references use (to rounding)?
            n_p = machine()["n_p"]
            eps = rec["states"][:-1, 5]
            out["voltage_check"] = {
                "max_stator_difference_v": float(np.max(np.abs(K * rec["u_s"] - v_s))),
                "max_rotor_difference_v": float(
                    np.max(np.abs(K * rec["u_r"] - v_r * np.exp(1j * eps)))
                ),
                "note": "GEM's applied voltages (x sqrt(3/2)) against the stator voltage and "
                "the rotor voltage turned by GEM's own rotor angle at each step's start "
                f"(epsilon = n_p theta, n_p = {n_p})",
            }
            say("gym-electric-motor: accuracy against the references")
            g_err = accuracy(
                g_states,
                seg,
                n,
                DFIMEquations("stator_at_step_start"),
                extended_substeps=extended_substeps,
                cache=cache,
                log=say,
            )
            gem["error"] = g_err
            gem["error_summary"] = short_errors(g_err)
            g_phys = accuracy(
                g_states, seg, n, DFIMEquations("rotor"), extended_substeps=0, cache=cache, log=say
            )
            gem["error_vs_rotor_frame_reference"] = short_errors(g_phys)
            out["error_verdicts"] = error_verdicts(a_err, g_err)
