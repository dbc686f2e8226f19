"""The matched cage-induction-motor cases against motulator 0.18: averaged converter and PWM.

The case is motulator's 2.2 kW speed drive (``peers/motulator_im.py`` says how it is taken from
motulator's example), run by motulator in its own virtualenv and by acdrive from parts with the
same machine, sample time (125 us), model time (1.5 s), speed reference and load (``MATCHED``
lists every number and every difference). Two converters:

* ``averaged`` (``ratio_vs_motulator``): motulator's ``pwm=False`` (the duty ratios held over the
  sample); acdrive's ``plant.AveragedConverter``, the inverter's averaged counterpart
  (the command held over the sample within the linear range |v| <= V_dc / sqrt(2)) at the same
  540 V; one held segment per sample on both sides;
* ``pwm`` (``ratio_vs_motulator_pwm``): motulator's ``pwm=True`` (carrier comparison, exact
  switching instants); acdrive's ``plant.Inverter`` (centred SVPWM, exact switching
  instants) at the same 4 kHz carrier (N = 2 control samples per carrier period; N = 1 is reported
  as a variant).

Both simulators' accuracy is measured against references of the same plant equations
(``IMEquations``, machines._cage_part's equations plus the shaft) driven by each simulator's own
segment sequence from its own initial state (``acdrive._bench.reference``): Radau at rtol 1e-10,
and an extended-precision sixth-order reference where both errors lie below the Radau
reference's own resolution.

Integration on acdrive's side: one step of the sixth-order method (``System(method="rk6")``) per
held segment (``INTEGRATOR``, ``SUBSTEPS``; the measurements behind the choice are in
docs/speed.md, "The benchmark suite").
"""

from __future__ import annotations

import math
import os
import shutil
import tempfile
import time

import numpy as np

# The suite's machinery (references: scipy; peers; timing) is imported where the case runs, so
# that the first-result race's child process (``_bench.first_result``), which builds this case
# from these definitions, imports what acdrive's own run needs and nothing more.

#: integration of the matched cases: one step of the sixth-order method per held segment
INTEGRATOR = "rk6"
SUBSTEPS = 1
K = math.sqrt(1.5)  # |space vector| power-invariant / peak-value scaling (frames.K_PEAK)

# --- the matched case (motulator's numbers: peers/motulator_im.py) ---------------------------
T_S = 125e-6  # s
DURATION = 1.5  # s
U_DC = 540.0  # V
J = 0.015  # kg m^2
N_P = 2
# inverse-Gamma parameters of motulator's 2.2 kW machine [ohm, H]
R_S, R_R, L_SGM, L_M = 3.7, 2.1, 0.021, 0.224
# the same machine as acdrive's T-model (machines._cage_part): an inverse-Gamma model is a T-model
# with no rotor leakage, so L_m = L_r = L_M, L_s = L_M + L_sgm, R_r = R_R; then sigma L_s = L_sgm,
# R_s + (L_m/L_r)^2 R_r = R_s + R_R, L_r/R_r = L_M/R_R and acdrive's rotor flux psi_r is
# motulator's psi_R. Impedances do not depend on the space-vector scaling; voltages, currents and
# fluxes are sqrt(3/2) times larger in acdrive's power-invariant scaling.
MACHINE = {"R_s": R_S, "R_r": R_R, "L_s": L_M + L_SGM, "L_r": L_M, "L_m": L_M, "n_p": N_P}
NOM_TAU = 14.6  # N m, rated torque
BASE_I = math.sqrt(2.0) * 5.0  # A, peak (motulator's base current)
BASE_PSI = math.sqrt(2.0 / 3.0) * 400.0 / (2 * math.pi * 50.0)  # V s, peak
W_REF = 0.5 * 2 * math.pi * 50.0 / N_P  # rad/s, 0.5 p.u. mechanical
T_STEP = 0.2 + 0.5 * T_S  # s
T_LOAD, LOAD_RAMP = 0.75, 1e-3  # s
# control: motulator's current reference generator gives i_sd = psi_s_nom / (L_M + L_sgm) with
# psi_s_nom = 0.95 psi_base, limited to i_s_max = 1.5 i_base (peak); in acdrive's IFOC the flux
# reference is the rotor flux L_M i_sd (power-invariant), the same current
I_SD = 0.95 * BASE_PSI / (L_M + L_SGM)  # A, peak
PSI_REF = K * L_M * I_SD  # Wb, power-invariant
I_MAX = K * 1.5 * BASE_I  # A, power-invariant
# largest torque within the current limit at that flux (where motulator's current limit caps the
# speed PI's torque); acdrive's speed PI clamps there, a hair below, so its own anti-windup acts
TAU_MAX = 0.999 * N_P * PSI_REF * math.sqrt(I_MAX**2 - (K * I_SD) ** 2)
# motulator's 2DOF complex-vector PI current controller, alpha_c = 2 pi 200 rad/s:
# u = k_t i_ref - k_p i + (k_i + j w_c k_t)/s (i_ref - i) in synchronous coordinates
ALPHA_C = 2 * math.pi * 200.0
K_T, K_PC, K_IC = ALPHA_C * L_SGM, 2 * ALPHA_C * L_SGM, ALPHA_C**2 * L_SGM
W0 = N_P * W_REF  # rad/s, electrical frequency at the reference speed, no load

CONVERTERS = ("averaged", "pwm")
#: motulator-export's sides of the case: side name -> its loop (peers/motulator_export_im.py)
EXPORT_SIDES = {"motulator_export_c": "c", "motulator_export_callbacks": "callbacks"}

MATCHED = {
    "source": "motulator 0.18 examples/drive/current_vector/plot_2kw_im_sat_cvc.py "
    "(acdrive/_bench/peers/motulator_im.py)",
    "machine": {
        "motulator_inverse_gamma": {"R_s": R_S, "R_R": R_R, "L_sgm": L_SGM, "L_M": L_M, "n_p": N_P},
        "acdrive_T_model": MACHINE,
        "conversion": "inverse-Gamma = T-model without rotor leakage: L_m = L_r = L_M, "
        "L_s = L_M + L_sgm, R_r = R_R (identical equations: sigma L_s = L_sgm, "
        "R_s + (L_m/L_r)^2 R_r = R_s + R_R, L_r/R_r = L_M/R_R, psi_r = psi_R); parameters are "
        "scaling-free, signals are sqrt(3/2) times motulator's peak-value space vectors; "
        "torque 1.5 n_p Im(psi* i) (peak) = n_p Im(psi* i) (power-invariant)",
        "J_kg_m2": J,
        "note": "the example's saturated Gamma model replaced by its own unsaturated "
        "inverse-Gamma alternative on both sides",
    },
    "dc_link_v": U_DC,
    "sample_time_s": T_S,
    "duration_s": DURATION,
    "speed_reference": f"0 until {T_STEP:g} s, then 0.5 p.u. = {W_REF:.6g} rad/s (step at the "
    "first sample after 0.2 s)",
    "load": f"0 until {T_LOAD} s, ramp over {LOAD_RAMP * 1e3:g} ms to the rated {NOM_TAU} N m "
    "(motulator's example: a step at 0.75 s)",
    "converter": {
        "averaged": {
            "motulator": "pwm=False: the duty ratios held over the sample (zero-order hold), one "
            "sample computational delay in the control system",
            "acdrive": "plant.AveragedConverter (V_dc = 540 V): the command held over "
            "the sample within |v| <= V_dc / sqrt(2) (the inverter's averaged counterpart), no "
            "computational delay",
        },
        "pwm": {
            "motulator": "pwm=True: carrier comparison, carrier period 2 T_s = 250 us (4 kHz), "
            "duty ratios updated every T_s (double update), one sample computational delay, "
            "duties quantised to 2^-12; at most 3 switching instants per sample",
            "acdrive": "plant.Inverter, centred SVPWM, carrier period N T_s; primary "
            "N = 2 (250 us, 4 kHz, the same pulse pattern: one edge per leg per sample, at most 3 "
            "instants per sample), command latched once per carrier period (single update), no "
            "computational delay; variant N = 1 (125 us, 8 kHz: command updated every sample as "
            "motulator's, twice the switching instants)",
        },
    },
    "control": {
        "motulator": "sensored current-vector control: reduced-order flux observer (measured "
        "speed), rotor-flux orientation, 2DOF complex PI current controller in synchronous "
        "coordinates (alpha_c = 2 pi 200 rad/s, angle advance 1.5 T_s w_c), "
        "i_sd = 0.95 psi_base/(L_M + L_sgm), |i_s| <= 1.5 i_base, speed PI k_p = 1, k_i = 10 "
        "(anti-windup on the current-limited torque)",
        "acdrive": "control.IndirectFOC (flux model, same i_d and current limit) -> "
        "control.StationaryCurrentController running motulator's current controller "
        "with its integrator turning at the fixed frequency w0 = n_p w_ref (stationary frame: "
        "K(s) = k_p + (k_i + j w0 k_t)/(s - j w0) on the error, k_p = 2 alpha_c L_sgm, "
        "k_t = alpha_c L_sgm, k_i = alpha_c^2 L_sgm; Tustin pre-warped at w0; back-calculation "
        "anti-windup) <- control.SpeedPI (K_P = 1, K_I = 10, clamping at the torque the "
        "current limit allows) <- shaft speed sampled ideally, encoder angle ideal",
        "differences": [
            (
                "indirect FOC (rotor-flux model from the current reference) instead of "
                "motulator's reduced-order observer on the measured speed, current and the "
                "realized voltage"
            ),
            (
                "current controller on the error only (1DOF: k_p on i_ref - i) with a "
                "fixed-frequency integrator discretised by Tustin; motulator's is 2DOF (k_t on "
                "i_ref, k_p on i), in synchronous coordinates, its integrator turning at the "
                "estimated synchronous frequency and updated by forward Euler with anti-windup "
                "from the realized voltage"
            ),
            (
                "no computational delay in acdrive (the command applies from the sample "
                "instant); motulator delays the duty ratios by one sample and advances the "
                "voltage angle by 1.5 T_s w_c"
            ),
            (
                "acdrive's speed PI clamps its integral at a torque limit; motulator's "
                "integrates the torque the current limit realised, and its current limit also "
                "caps i_sq at psi_R / L_sgm + i_sd (breakdown)"
            ),
            (
                "motulator's field-weakening integrator on i_sd is absent in acdrive; it acts "
                "only while the unlimited |u_s_ref| exceeds k_u u_dc / sqrt(3) = 296 V (the "
                "back-emf w_s psi_s_nom at 0.5 p.u. is about 155 V)"
            ),
            (
                "pwm only: single update of the duty ratios per carrier period (N = 2) instead "
                "of double update"
            ),
        ],
        "measured_as": "the speed-trajectory difference between the two simulators on this "
        "case (cases.*.trajectories.speed_difference: RMS and largest, over the whole run and "
        "per phase), read from motulator's recorded run and acdrive's timed one",
    },
}


# --- acdrive's side ----------------------------------------------------------------------------
def current_controller_lti():
    """motulator's complex PI (error path) with its integrator at the fixed frequency W0, as a
    2 x 2 real stationary-frame LTI: dx/dt = j W0 x + e, v = k_p e + (k_i + j W0 k_t) x."""
    from acdrive.control._lti_matrix import LTIMatrix

    A = [[0.0, -W0], [W0, 0.0]]
    C = [[K_IC, -W0 * K_T], [W0 * K_T, K_IC]]
    return LTIMatrix.ss(A, np.eye(2), C, K_PC * np.eye(2), name="complex-pi-w0")


def build_foc_drive(
    machine,
    J,
    v_dc,
    f_pwm,
    T_s,
    controller,
    method,
    prewarp,
    speed_pi,
    ifoc,
    w_ref,
    load,
    integrator="rk4",
    converter="pwm",
    encoder=True,
):
    """dc -> converter -> cage machine -> shaft; encoder; speed reference -> speed PI (ideal
    speed sample) -> IFOC -> stationary current controller -> converter. ``converter``: "pwm"
    (``plant.Inverter`` at ``f_pwm``, fed from a ``DCSource``) or "averaged"
    (``plant.AveragedConverter`` with the fixed DC-link voltage ``v_dc``; ``f_pwm``
    unused). ``encoder=False``: the IFOC reads the shaft angle directly (the same part kinds
    less one, another topology: ``_bench.targets``' compile-free first result). Returns
    (System, parts by role)."""
    from acdrive.control._current import StationaryCurrentController
    from acdrive.control._foc import IndirectFOC, SpeedPI
    from acdrive.control._speed import SpeedReference
    from acdrive.machines._cage_part import CageInductionMachine
    from acdrive.plant._converter import AveragedConverter
    from acdrive.plant._inverter import Inverter
    from acdrive.plant._mechanics import Shaft
    from acdrive.plant._sensors import Encoder
    from acdrive.plant._sources import DCSource
    from acdrive.sim._system import System

    if converter not in CONVERTERS:
        raise ValueError(f"converter must be one of {CONVERTERS}")
    p = {
        "im": CageInductionMachine("im", **machine),
        "shaft": Shaft("shaft", J=J, load=load),
        "encoder": Encoder("encoder"),
        "ref": SpeedReference("ref", w=w_ref),
        "speed_pi": SpeedPI("speed_pi", **(speed_pi or {})),
        "ifoc": IndirectFOC(
            "ifoc",
            R_r=machine["R_r"],
            L_r=machine["L_r"],
            L_m=machine["L_m"],
            n_p=machine["n_p"],
            **ifoc,
        ),
        "current": StationaryCurrentController(
            "current", controller, T_s, method, prewarp, v_max=v_dc / math.sqrt(2.0)
        ),
    }
    if not encoder:
        del p["encoder"]
    if converter == "pwm":
        p["dc"] = DCSource("dc", V=v_dc)
        p["inverter"] = Inverter("inverter", f_pwm=f_pwm)
    else:
        p["inverter"] = AveragedConverter("inverter", V_dc=v_dc)
    im, shaft, pi, ifoc_, cc, inv = (
        p[k] for k in ("im", "shaft", "speed_pi", "ifoc", "current", "inverter")
    )
    angle = p["encoder"].out.theta if encoder else shaft.out.theta
    wires = [
        (shaft.out.w, im.inp.w),
        (im.out.tau_e, shaft.inp.tau_e),
        *([(shaft.out.theta, p["encoder"].inp.theta)] if encoder else []),
        (p["ref"].out.w_ref, pi.inp.w_ref),
        (shaft.out.w, pi.inp.w),
        (pi.out.tau_ref, ifoc_.inp.tau_ref),
        (angle, ifoc_.inp.theta),
        (ifoc_.out.i_s_ref, cc.inp.i_ref),
        (im.out.i_s, cc.inp.i_meas),
        (cc.out.v_ref, inv.inp.v_ref),
        (inv.out.v, im.inp.v_s),
    ]
    if converter == "pwm":
        wires += [(p["dc"].out.v_dc, inv.inp.v_dc), (im.out.i_s, inv.inp.i_s)]
    return System(list(p.values()), wires, method=integrator), p


def matched_acdrive_system(
    converter: str = "pwm", integrator: str = INTEGRATOR, encoder: bool = True
):
    """acdrive's side of the matched case (module docstring, ``MATCHED``); ``encoder=False``
    the same drive with the IFOC reading the shaft angle (``build_foc_drive``)."""
    return build_foc_drive(
        machine=MACHINE,
        J=J,
        v_dc=U_DC,
        f_pwm=1.0 / (2 * T_S),
        T_s=T_S,
        controller=current_controller_lti(),
        method="tustin",
        prewarp=W0,
        speed_pi={"K_P": 1.0, "K_I": 10.0, "K_F": 1.0, "tau_max": TAU_MAX},
        ifoc={"i_max": I_MAX, "psi_ref": PSI_REF},
        w_ref=[[0.0, 0.0], [T_STEP, 0.0], [T_STEP, W_REF]],
        load=[[0.0, 0.0], [T_LOAD, 0.0], [T_LOAD + LOAD_RAMP, NOM_TAU]],
        integrator=integrator,
        converter=converter,
        encoder=encoder,
    )


def log_ports(p) -> list:
    return [
        p["im"].out.i_s,
        p["im"].out.psi_r,
        p["shaft"].out.w,
        p["current"].out.v_ref,
        p["ifoc"].out.i_s_ref,
    ]


def prepare_acdrive(
    converter: str,
    duration: float,
    integrator: str = INTEGRATOR,
    substeps: int = SUBSTEPS,
) -> dict:
    """acdrive's side compiled and warmed up, ready to be timed: per variant (pwm: carrier
    N = 2, the primary, and N = 1; averaged: one) a ``run_once()`` returning the control steps
    of one run of ``duration`` and keeping that run's result (``last``) for the accuracy."""
    system, p = matched_acdrive_system(converter, integrator)
    ports = log_ports(p)
    start = time.perf_counter()
    compiled = system.compile()
    compiled.run(min(0.01, duration), T_S, substeps=substeps, log=ports)
    out = {
        "integrator": integrator,
        "substeps": substeps,
        "variants": {},
        "first_run_s": time.perf_counter() - start,
        "primary": "N2" if converter == "pwm" else "averaged",
        "_ports": p,
        "_system": system,
    }
    carriers = (2, 1) if converter == "pwm" else (None,)
    for n_carrier in carriers:
        modulator = (
            p["inverter"]
            if n_carrier is None
            else p["inverter"].with_params(f_pwm=1.0 / (n_carrier * T_S))
        )
        variant: dict = {"carrier_samples": n_carrier, "_modulator": modulator}

        def run_once(modulator=modulator, variant=variant):
            raw = compiled.run(duration, T_S, substeps=substeps, log=ports, parts=[modulator])
            variant["_raw"] = raw
            return raw.steps

        run_once()  # warm-up
        variant["_run_once"] = run_once
        out["variants"]["averaged" if n_carrier is None else f"N{n_carrier}"] = variant
    return out


def describe_variant(variant: dict, ports: dict, duration: float) -> dict:
    """What a variant's last run did (for the JSON): carrier, steps, final speed, peak current."""
    raw = variant["_raw"]
    n = variant["carrier_samples"]
    return {
        "carrier_samples": n,
        "pwm_frequency_hz": None if n is None else 1.0 / (n * T_S),
        "control_steps": raw.steps,
        "model_time_s": duration,
        "final_speed_rad_s": float(raw.signal(ports["shaft"].out.w)[-1]),
        "peak_current_a_peak_scaling": float(np.max(np.abs(raw.signal(ports["im"].out.i_s))) / K),
        "events": raw.events,
    }


def acdrive_segments(raw, ports, modulator) -> dict:
    """Every segment of every sample: the logged command sequence run again through the
    modulator's own kernel (the compiled loop logs only the first segment of each sample)."""
    from acdrive.plant._converter import AveragedConverter, averaged_segments
    from acdrive.plant._inverter import inverter_segments

    averaged = isinstance(modulator, AveragedConverter)
    kernel = averaged_segments if averaged else inverter_segments
    v_ref = raw.signal(ports["current"].out.v_ref)
    n = v_ref.size
    s = modulator.initial_state()
    p = modulator.p
    dt = np.zeros(modulator.MAX_SEGMENTS)
    v = np.zeros((modulator.MAX_SEGMENTS, modulator.OUTPUTS.size()))
    u = np.zeros(modulator.INPUTS.size())
    counts = np.zeros(n, dtype=np.int64)
    seg_dt, seg_v = [], []
    for k in range(n):
        u[0], u[1] = v_ref[k].real, v_ref[k].imag
        if not averaged:
            u[2] = U_DC  # the inverter's v_dc input; i_s has no effect without t_d and drop
        m, _ = kernel(T_S, u, p, s, dt, v)
        counts[k] = m
        seg_dt.extend(dt[:m])
        seg_v.extend(v[:m, 0] + 1j * v[:m, 1])
    return {"t": raw.t.copy(), "counts": counts, "dt": np.array(seg_dt), "v": np.array(seg_v)}


def final_plant_state(system, X: np.ndarray) -> np.ndarray:
    """(Re i_s, Im i_s, Re psi_r, Im psi_r, w) of the machine and shaft in a state vector X."""
    a, _ = system.slots["im"].x
    s, _ = system.slots["shaft"].x
    return np.array([X[a], X[a + 1], X[a + 2], X[a + 3], X[s]])


def acdrive_states(variant: dict, ports: dict, system) -> np.ndarray:
    raw = variant["_raw"]
    i_s = raw.signal(ports["im"].out.i_s)
    psi = raw.signal(ports["im"].out.psi_r)
    w = raw.signal(ports["shaft"].out.w)
    states = np.column_stack([i_s.real, i_s.imag, psi.real, psi.imag, w])
    return np.vstack([states, final_plant_state(system, raw.final_state)])


# --- the reference equations -------------------------------------------------------------------
def _load(t: float) -> float:
    return NOM_TAU * min(max((t - T_LOAD) / LOAD_RAMP, 0.0), 1.0)


class IMEquations:
    """machines._cage_part's equations (power-invariant, stationary frame) plus the shaft with the
    matched load, y = (Re i_s, Im i_s, Re psi_r, Im psi_r, w), the stator voltage held per
    segment: the right-hand side, its Jacobian and the same in extended precision."""

    def __init__(self, params: dict = MACHINE):
        R_s, R_r, L_s, L_r, L_m, n_p = (
            params[k] for k in ("R_s", "R_r", "L_s", "L_r", "L_m", "n_p")
        )
        self.c = {
            "sls": L_s - L_m * L_m / L_r,
            "r_sig": R_s + L_m * L_m * R_r / (L_r * L_r),
            "k_r": L_m / L_r,
            "a": R_r / L_r,
            "b": L_m * R_r / L_r,
            "n_p": n_p,
        }

    def rhs(self, t, y, v_re, v_im):
        c = self.c
        i_r, i_i, p_r, p_i, w = y
        wm = c["n_p"] * w
        k_r, a, sls = c["k_r"], c["a"], c["sls"]
        return np.array(
            [
                (v_re - c["r_sig"] * i_r + k_r * (a * p_r + wm * p_i)) / sls,
                (v_im - c["r_sig"] * i_i + k_r * (a * p_i - wm * p_r)) / sls,
                c["b"] * i_r - a * p_r - wm * p_i,
                c["b"] * i_i - a * p_i + wm * p_r,
                (c["n_p"] * k_r * (p_r * i_i - p_i * i_r) - _load(t)) / J,
            ]
        )

    def jac(self, t, y, v_re, v_im):
        c = self.c
        i_r, i_i, p_r, p_i, w = y
        n_p, k_r, a, b, sls, r_sig = (c[k] for k in ("n_p", "k_r", "a", "b", "sls", "r_sig"))
        wm = n_p * w
        kt = n_p * k_r / J
        return np.array(
            [
                [-r_sig / sls, 0.0, k_r * a / sls, k_r * wm / sls, k_r * n_p * p_i / sls],
                [0.0, -r_sig / sls, -k_r * wm / sls, k_r * a / sls, -k_r * n_p * p_r / sls],
                [b, 0.0, -a, -wm, -n_p * p_i],
                [0.0, b, wm, -a, n_p * p_r],
                [-kt * p_i, kt * p_r, kt * i_i, -kt * i_r, 0.0],
            ]
        )

    def rhs_ld(self, t, y, v_re, v_im):
        ld = np.longdouble
        c = {k: ld(v) for k, v in self.c.items()}
        i_r, i_i, p_r, p_i, w = y
        wm = c["n_p"] * w
        k_r, a, sls = c["k_r"], c["a"], c["sls"]
        load = ld(NOM_TAU) * min(max((t - ld(T_LOAD)) / ld(LOAD_RAMP), ld(0)), ld(1))
        return np.array(
            [
                (v_re - c["r_sig"] * i_r + k_r * (a * p_r + wm * p_i)) / sls,
                (v_im - c["r_sig"] * i_i + k_r * (a * p_i - wm * p_r)) / sls,
                c["b"] * i_r - a * p_r - wm * p_i,
                c["b"] * i_i - a * p_i + wm * p_r,
                (c["n_p"] * k_r * (p_r * i_i - p_i * i_r) - load) / ld(J),
            ],
            dtype=ld,
        )

    def inputs(self, seg: dict, extended: bool):
        v = seg["v"]
        if extended:
            ld = np.longdouble
            return lambda j, y: (ld(v[j].real), ld(v[j].imag))
        return lambda j, y: (float(v[j].real), float(v[j].imag))


# --- motulator's side ---------------------------------------------------------------------------
def motulator_states(rec) -> tuple[np.ndarray, dict]:
    """motulator's recorded states at its sampling instants (plus the final state) as
    power-invariant (i_s, psi_R, w_M) rows, and its segment sequence as voltages."""
    g = L_M / (L_M + L_SGM)
    psi_s = np.append(rec["psi_s"], rec["final_psi_s"])
    psi_R = g * np.append(rec["psi_r"], rec["final_psi_r"])  # inverse-Gamma rotor flux
    i_s = (psi_s - psi_R) / L_SGM  # psi_s = L_sgm i_s + psi_R
    w = np.append(rec["w_M"], rec["final_w_M"])
    states = np.column_stack([K * i_s.real, K * i_s.imag, K * psi_R.real, K * psi_R.imag, w])
    q = rec["q"]
    alpha = np.exp(2j * np.pi / 3)
    u_peak = float(rec["u_dc"]) * (2.0 / 3.0) * (q[:, 0] + alpha * q[:, 1] + alpha**2 * q[:, 2])
    seg = {"t": rec["t"], "counts": rec["n"], "dt": rec["dt"], "v": K * u_peak}
    return states, seg


def export_states(rec) -> np.ndarray:
    """motulator-export's recorded states (``peers/motulator_export_im.py``: motulator's layout
    without the segments) as the rows of ``motulator_states``."""
    g = L_M / (L_M + L_SGM)
    psi_s = np.append(rec["psi_s"], rec["final_psi_s"])
    psi_R = g * np.append(rec["psi_r"], rec["final_psi_r"])
    i_s = (psi_s - psi_R) / L_SGM
    w = np.append(rec["w_M"], rec["final_w_M"])
    return np.column_stack([K * i_s.real, K * i_s.imag, K * psi_R.real, K * psi_R.imag, w])


def state_difference(a: np.ndarray, b: np.ndarray) -> dict:
    """Largest |a - b| of two runs' state rows at their common sampling instants: the speed
    [rad/s] and the current [A, peak-value scaling], absolute and relative to b's peak."""
    n = min(a.shape[0], b.shape[0]) - 1
    dw = np.abs(a[:n, 4] - b[:n, 4])
    di = np.abs((a[:n, 0] - b[:n, 0]) + 1j * (a[:n, 1] - b[:n, 1])) / K
    w_peak = float(np.max(np.abs(b[:n, 4])))
    i_peak = float(np.max(np.abs(b[:n, 0] + 1j * b[:n, 1])) / K)
    return {
        "compared_samples": n,
        "speed_max_abs_rad_s": float(dw.max()),
        "speed_rms_rad_s": float(np.sqrt(np.mean(dw**2))),
        "speed_max_rel_to_peak": float(dw.max()) / w_peak,
        "current_max_abs_a": float(di.max()),
        "current_max_rel_to_peak": float(di.max()) / i_peak,
    }


def speed_difference(a_w: np.ndarray, m_w: np.ndarray, t: np.ndarray) -> dict:
    """RMS and largest |acdrive's speed - motulator's| [rad/s and rpm] at the common sampling
    instants ``t``, over the whole run and over each phase of the case that it reaches:
    standstill (before the speed step), the step response (step to load) and under load."""
    d = a_w - m_w
    rpm = 60.0 / (2.0 * np.pi)
    phases = {
        "whole_run": np.ones(t.size, dtype=bool),
        "before_speed_step": t < T_STEP,
        "speed_step_to_load": (t >= T_STEP) & (t < T_LOAD),
        "under_load": t >= T_LOAD,
    }
    out = {}
    for name, m in phases.items():
        if not m.any():
            continue
        rms = float(np.sqrt(np.mean(d[m] ** 2)))
        top = float(np.max(np.abs(d[m])))
        out[name] = {
            "from_s": float(t[m][0]),
            "to_s": float(t[m][-1]),
            "samples": int(m.sum()),
            "rms_rad_s": rms,
            "max_abs_rad_s": top,
            "rms_rpm": rms * rpm,
            "max_abs_rpm": top * rpm,
        }
    return out


def compare_trajectories(a_states: np.ndarray, m_states: np.ndarray) -> dict:
    """How far apart the two simulators' runs of the case are, the remaining differences of their
    controllers (``MATCHED["control"]["differences"]``) included: the speed difference
    (``speed_difference``) and, for each, the speed and current magnitude (peak-value scaling)
    at a few instants and the speed dip under the load."""
    n = min(a_states.shape[0], m_states.shape[0]) - 1
    t = np.arange(n) * T_S
    after = t >= T_LOAD
    out = {
        "compared_samples": n,
        "speed_difference": speed_difference(a_states[:n, 4], m_states[:n, 4], t),
    }
    for name, s in (("acdrive", a_states), ("motulator", m_states)):
        w = s[:n, 4]
        i = np.abs(s[:n, 0] + 1j * s[:n, 1]) / K
        out[name] = {
            "speed_rad_s_at": {
                f"{t:g}": float(w[round(t / T_S)])
                for t in (0.21, 0.25, 0.3, 0.7, 1.0, 1.49)
                if round(t / T_S) < n
            },
            "peak_speed_rad_s": float(np.max(w)),
            "min_speed_after_load_rad_s": float(np.min(w[after])) if after.any() else None,
            "current_a_peak_at": {
                f"{t:g}": float(i[round(t / T_S)]) for t in (0.19, 0.7, 1.49) if round(t / T_S) < n
            },
        }
    return out


# --- the case ----------------------------------------------------------------------------------
def run_case(
    converter: str,
    peer: dict,
    rounds: int,
    duration: float,
    reference: bool,
    extended_substeps: int = 4,
    log=None,
    timing: dict | None = None,
    clock=None,
    reference_cache=None,
    export_peer: dict | None = None,
) -> dict:
    """The matched case with ``converter``: acdrive and motulator (if ``peer`` is available:
    ``venvs.ensure_venv``'s answer) timed in ``rounds`` rounds of interleaved CPU-time windows
    (``windows.time_sides``), the ratio and its spread, motulator's recorded run and the
    speed-trajectory difference between the two, and both simulators' errors (if
    ``reference``). ``timing``: ``solo_window_cpu_s`` and ``min_calibration_cpu_s``; ``clock``: a
    ``windows.Clock``; ``reference_cache``: the folder of cached references (``_bench.refcache``,
    None: computed every time); ``export_peer``: motulator-export's venv (``ensure_venv``), whose
    native loop runs the same case beside motulator (``export_sides``)."""
    from acdrive._bench.reference import accuracy, error_verdicts, short_errors
    from acdrive._bench.venvs import PeerFailed, PeerProcess
    from acdrive._bench.windows import Clock, local_side, ratio_spread, time_sides

    say = log or (lambda _m: None)
    clock = clock or Clock()
    timing = {"solo_window_cpu_s": 1.0, "min_calibration_cpu_s": 0.1, **(timing or {})}
    out: dict = {"converter": converter, "duration_s": duration, "sample_time_s": T_S}
    acd = prepare_acdrive(converter, duration)
    ports = acd["_ports"]
    names = {"averaged": "acdrive", "N2": "acdrive", "N1": "acdrive_N1"}
    local = {names[k]: local_side(v["_run_once"], clock) for k, v in acd["variants"].items()}
    pairs = {"acdrive_vs_motulator": ("acdrive", "motulator")}
    if converter == "pwm":
        pairs["acdrive_N1_vs_motulator"] = ("acdrive_N1", "motulator")
    tmp = tempfile.mkdtemp(prefix="acdrive_bench_")
    record = os.path.join(tmp, "motulator_run.npz")
    mot: dict = {"available": False, "reason": peer.get("reason", "not run")}
    export_peer = export_peer or {"available": False, "reason": "not run"}
    mex: dict = {"available": False, "reason": export_peer.get("reason", "not run")}
    proc = mex_proc = None
    try:
        if export_peer.get("available"):
            try:
                mex_proc = PeerProcess(export_peer["python"], "motulator_export_im.py", cwd=tmp)
                mex = {"available": True, **mex_proc.ask("about"), "converter": converter}
            except PeerFailed as exc:
                mex = {"available": False, "reason": str(exc)}
        if peer.get("available"):
            try:
                proc = PeerProcess(peer["python"], "motulator_im.py", cwd=tmp)
                mot = {"available": True, **proc.ask("about"), "converter": converter}
            except PeerFailed as exc:
                mot = {"available": False, "reason": str(exc)}

        def motulator_window(runs):
            return proc.ask("window", converter=converter, seconds=duration, runs=runs)

        def export_window(loop):
            return lambda runs: mex_proc.ask(
                "window", converter=converter, seconds=duration, runs=runs, loop=loop
            )

        peers = {"motulator": motulator_window} if mot["available"] else {}
        if mex["available"]:
            for side, loop in EXPORT_SIDES.items():
                peers[side] = export_window(loop)
                pairs[f"acdrive_vs_{side}"] = ("acdrive", side)
                if mot["available"]:
                    pairs[f"{side}_vs_motulator"] = (side, "motulator")
        say(f"{converter}: interleaved CPU-time windows ({', '.join(['acdrive', *peers])})")
        try:
            t = time_sides(local, peers, pairs, rounds, clock, log=say, **timing)
            if mot["available"]:
                say(f"motulator {converter}: recording a run")
                mot.update(proc.ask("record", converter=converter, seconds=duration, out=record))
            if mex["available"]:
                mex["records"] = {}
                for side, loop in EXPORT_SIDES.items():
                    say(f"motulator-export {converter}: recording a run ({loop} loop)")
                    got = mex_proc.ask(
                        "record", converter=converter, seconds=duration, loop=loop,
                        out=os.path.join(tmp, f"{side}.npz"),
                    )  # fmt: skip
                    mex["records"][side] = got
        except PeerFailed as exc:
            mot = {"available": False, "reason": str(exc)}
            mex = {"available": False, "reason": str(exc)}
            pairs = {k: v for k, v in pairs.items() if "motulator" not in k}
            t = time_sides(local, {}, {}, rounds, clock, log=say, **timing)
        out["timing"] = t
        out["acdrive"] = {
            "integrator": acd["integrator"],
            "substeps_per_segment": acd["substeps"],
            "first_run_s": acd["first_run_s"],
            "primary": acd["primary"],
            "variants": {
                k: {
                    **describe_variant(v, ports, duration),
                    "steps_per_cpu_s": t["sides"][names[k]]["steps_per_cpu_s"],
                    "per_run_cpu_s": t["sides"][names[k]]["per_run_cpu_s"],
                }
                for k, v in acd["variants"].items()
            },
            "steps_per_cpu_s": t["sides"]["acdrive"]["steps_per_cpu_s"]["median"],
        }
        if mot["available"]:
            mot["steps_per_cpu_s"] = t["sides"]["motulator"]["steps_per_cpu_s"]["median"]
            mot["per_run_cpu_s"] = t["sides"]["motulator"]["per_run_cpu_s"]
            out["ratio"] = t["ratios"]["acdrive_vs_motulator"]["ratio"]
            out["ratio_spread"] = ratio_spread(t["ratios"]["acdrive_vs_motulator"])
            if converter == "pwm":
                out["ratio_N1"] = t["ratios"]["acdrive_N1_vs_motulator"]["ratio"]
                out["ratio_N1_spread"] = ratio_spread(t["ratios"]["acdrive_N1_vs_motulator"])
        out["motulator"] = mot
        if mex["available"]:
            mex["sides"] = {}
            for side in EXPORT_SIDES:
                mex["sides"][side] = {
                    "steps_per_cpu_s": t["sides"][side]["steps_per_cpu_s"]["median"],
                    "per_run_cpu_s": t["sides"][side]["per_run_cpu_s"],
                    "acdrive_ratio": t["ratios"][f"acdrive_vs_{side}"]["ratio"],
                    "acdrive_ratio_spread": ratio_spread(t["ratios"][f"acdrive_vs_{side}"]),
                }
                if mot["available"]:
                    r = t["ratios"][f"{side}_vs_motulator"]
                    mex["sides"][side]["ratio_vs_motulator"] = r["ratio"]
                    mex["sides"][side]["ratio_vs_motulator_spread"] = ratio_spread(r)
            out["ratio_vs_motulator_export_c"] = mex["sides"]["motulator_export_c"]["acdrive_ratio"]
        out["motulator_export"] = mex
        primary = acd["variants"][acd["primary"]]
        system = acd["_system"]
        a_states = acdrive_states(primary, ports, system)
        m_states = m_seg = None
        if mot["available"]:
            m_states, m_seg = motulator_states(dict(np.load(record)))
            out["trajectories"] = compare_trajectories(a_states, m_states)
        if mex["available"]:
            mex["trajectories"] = {}
            for side in EXPORT_SIDES:
                x_states = export_states(dict(np.load(os.path.join(tmp, f"{side}.npz"))))
                mex["trajectories"][side] = {
                    "vs_acdrive": state_difference(x_states, a_states),
                    **(
                        {"vs_motulator": state_difference(x_states, m_states)}
                        if m_states is not None
                        else {}
                    ),
                }
        if reference:
            model = IMEquations()
            say(f"acdrive {converter}: accuracy against the references")
            a_seg = acdrive_segments(primary["_raw"], ports, primary["_modulator"])
            a_err = accuracy(
                a_states,
                a_seg,
                a_seg["t"].size,
                model,
                extended_substeps=extended_substeps,
                cache=reference_cache,
                log=say,
            )
            out["acdrive"]["error"] = a_err
            out["acdrive"]["error_summary"] = short_errors(a_err)
            if m_states is not None:
                say(f"motulator {converter}: accuracy against the references")
                m_err = accuracy(
                    m_states,
                    m_seg,
                    m_seg["t"].size,
                    model,
                    extended_substeps=extended_substeps,
                    cache=reference_cache,
                    log=say,
                )
                mot["error"] = m_err
                mot["error_summary"] = short_errors(m_err)
                out["error_verdicts"] = error_verdicts(a_err, m_err)
    finally:
        for p in (proc, mex_proc):
            if p is not None:
                p.close()
        shutil.rmtree(tmp, ignore_errors=True)  # the run's own temporary folder (mkdtemp)
    out["matched_case"] = MATCHED
    return out
