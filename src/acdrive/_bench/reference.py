"""Tight references for the benchmark's accuracy figures: the same equations as a simulator's
plant, driven by the same held inputs, integrated segment by segment far more accurately.

A run is described by its *segments*: ``t`` (the sampling instants), ``counts`` (segments per
sample), ``dt`` (every segment's length) and an ``inputs`` function giving the held inputs of
segment j from the state at its start (a rotor voltage held in a frame that depends on the rotor
angle needs the state; most inputs ignore it). Two references:

* ``radau_segments``: ``scipy.integrate.solve_ivp`` (Radau, the issue's rtol 1e-10) restarted at
  every segment boundary, where the inputs jump;
* ``extended_rk6_segments``: the same equations in extended precision (``np.longdouble``, a 64-bit
  mantissa on x86-64) by ``substeps`` steps of the sixth-order Runge-Kutta method per segment.
  Where both simulators' errors are below the Radau reference's own error (~1e-11 of the peak),
  this one decides; its own error is bounded by its difference from the run at half the substeps
  (order six: the error is about 1/63 of that difference).

``errors`` compares state rows (Re i_s, Im i_s, Re psi_r, Im psi_r, w, ...) at the sampling
instants: the current relative to the peak reference current, the speed absolute and relative to
the peak reference speed, the rotor flux relative to its peak.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
from scipy.integrate import solve_ivp


def radau_segments(rhs, x0, t, counts, dt, inputs, rtol=1e-10, atol=1e-12, jac=None):
    """States (rows) at t[0], ..., t[-1] and at the end of the last sample: every segment
    integrated by Radau from the state at its start, ``rhs(t, y, *inputs(j, y))``."""
    out = np.empty((t.size + 1, len(x0)))
    y = np.array(x0, dtype=float)
    at = 0
    for k in range(t.size):
        out[k] = y
        tau = float(t[k])
        for j in range(at, at + counts[k]):
            h = float(dt[j])
            if h <= 0.0:
                continue
            sol = solve_ivp(
                rhs,
                (tau, tau + h),
                y,
                method="Radau",
                rtol=rtol,
                atol=atol,
                jac=jac,
                args=inputs(j, y),
            )
            if not sol.success:
                raise RuntimeError(f"reference failed at t = {tau:.9g} s: {sol.message}")
            y = sol.y[:, -1]
            tau += h
        at += counts[k]
    out[-1] = y
    return out


def rk6_tableau_extended():
    """Butcher's sixth-order tableau of ``acdrive.sim._integrators`` (RK6_*), its rational coefficients
    recovered exactly and rounded to extended precision."""
    from acdrive.sim._integrators import RK6_A, RK6_B, RK6_C

    def ld(x: float):
        f = Fraction(x).limit_denominator(1000)
        if abs(float(f) - x) > 1e-15:
            raise ValueError(f"RK6 coefficient {x!r} is not a small rational")
        return np.longdouble(f.numerator) / np.longdouble(f.denominator)

    return ([ld(c) for c in RK6_C], [[ld(a) for a in row] for row in RK6_A], [ld(b) for b in RK6_B])


def extended_rk6_segments(rhs_ld, x0, t, counts, dt, inputs_ld, substeps=4):
    """As ``radau_segments`` with ``rhs_ld`` (the same equations on np.longdouble arrays) and
    ``substeps`` sixth-order steps per segment in extended precision; rows returned as float."""
    c, a, b = rk6_tableau_extended()
    stages = len(b)
    ld = np.longdouble
    out = np.empty((t.size + 1, len(x0)))
    y = np.array(x0, dtype=ld)
    at = 0
    for k in range(t.size):
        out[k] = y.astype(float)
        tau = ld(t[k])
        for j in range(at, at + counts[k]):
            if dt[j] <= 0.0:
                continue
            h = ld(dt[j]) / substeps
            args = inputs_ld(j, y)
            for m in range(substeps):
                t_m = tau + m * h
                ks = []
                for i in range(stages):
                    yi = y
                    for jj, coef in enumerate(a[i]):
                        if coef != 0:
                            yi = yi + h * coef * ks[jj]
                    ks.append(rhs_ld(t_m + c[i] * h, yi, *args))
                incr = ks[0] * b[0]
                for i in range(1, stages):
                    if b[i] != 0:
                        incr = incr + ks[i] * b[i]
                y = y + h * incr
            tau += ld(dt[j])
        at += counts[k]
    out[-1] = y.astype(float)
    return out


def errors(sim_states: np.ndarray, ref_states: np.ndarray) -> dict:
    """Current error relative to the peak reference current, speed error absolute and relative to
    the peak reference speed, rotor-flux error relative to its peak, at every sampling instant
    (rows: Re i_s, Im i_s, Re psi_r, Im psi_r, w, ...)."""
    i_sim = sim_states[:, 0] + 1j * sim_states[:, 1]
    i_ref = ref_states[:, 0] + 1j * ref_states[:, 1]
    psi_sim = sim_states[:, 2] + 1j * sim_states[:, 3]
    psi_ref = ref_states[:, 2] + 1j * ref_states[:, 3]
    w_sim, w_ref = sim_states[:, 4], ref_states[:, 4]
    dw = float(np.max(np.abs(w_sim - w_ref)))
    peak_w = float(np.max(np.abs(w_ref)))
    return {
        "current_rel_peak": float(np.max(np.abs(i_sim - i_ref)) / np.max(np.abs(i_ref))),
        "speed_abs_rad_s": dw,
        "speed_rel_peak": dw / peak_w if peak_w > 0.0 else None,
        "rotor_flux_rel_peak": float(np.max(np.abs(psi_sim - psi_ref)) / np.max(np.abs(psi_ref))),
        "samples_compared": int(i_sim.size),
    }


#: the error figures that verdicts compare
KEYS = ("current_rel_peak", "speed_abs_rad_s")


def accuracy(
    states,
    seg,
    n,
    model,
    rtol=1e-10,
    tight_rtol=None,
    extended_substeps=4,
    cache=None,
    log=None,
) -> dict:
    """Errors of ``states`` (rows at the first n sampling instants and the end of sample n - 1)
    against references of ``model``'s equations driven by ``seg`` from ``states[0]``:

    * ``reference``: Radau at ``rtol`` (atol ``rtol`` / 100);
    * ``tight_reference`` (if ``tight_rtol``): Radau at that tolerance;
    * ``extended_reference`` (if ``extended_substeps``): the sixth-order method in extended
      precision; ``extended_resolution``: its difference from the run at half the substeps.

    ``reference_resolution`` is the Radau reference's difference from the tightest one computed:
    errors below it cannot be told apart by the Radau reference. ``model`` has ``rhs``, ``jac``
    (or None), ``rhs_ld`` and ``inputs(seg, ld)`` returning the segment-input function.
    ``cache``: a folder of ``_bench.refcache`` entries; the reference trajectories are read from
    it when every input is unchanged (``reference_inputs_key``), else computed and stored
    (``cached_from_disk`` says which); ``log`` receives its one-line notices."""
    seg_n = int(np.sum(seg["counts"][:n]))
    t, counts, dt = seg["t"][:n], seg["counts"][:n], seg["dt"][:seg_n]
    sim = states[: n + 1]
    x0 = states[0]
    name = reference_inputs_key(x0, seg, n, model, rtol, tight_rtol, extended_substeps)

    def compute():
        return reference_trajectories(x0, t, counts, dt, seg, model, rtol, tight_rtol,
                                      extended_substeps)  # fmt: skip

    from acdrive._bench.refcache import cached

    refs, hit = cached(cache, name, compute, log or (lambda _m: None))
    out = {
        "reference": {
            "method": "Radau",
            "rtol": rtol,
            "atol": rtol * 1e-2,
            "wall_s": float(refs["radau_wall_s"]),
            **errors(sim, refs["radau"]),
        },
        "segments": seg_n,
        "max_segments_per_sample": int(counts.max()),
        "reference_inputs_key": name,
        "cached_from_disk": hit,
    }
    tightest = None
    if tight_rtol:
        out["tight_reference"] = {
            "method": "Radau",
            "rtol": tight_rtol,
            "atol": tight_rtol * 1e-2,
            "wall_s": float(refs["tight_wall_s"]),
            **errors(sim, refs["tight"]),
        }
        tightest = refs["tight"]
    if extended_substeps:
        out["extended_reference"] = {
            "method": "sixth-order Runge-Kutta in np.longdouble",
            "substeps_per_segment": extended_substeps,
            "wall_s": float(refs["extended_wall_s"]),
            **errors(sim, refs["extended"]),
        }
        out["extended_resolution"] = errors(refs["extended_half"], refs["extended"])
        tightest = refs["extended"]
    if tightest is not None:
        out["reference_resolution"] = errors(refs["radau"], tightest)
    return out


def reference_inputs_key(x0, seg, n, model, rtol, tight_rtol, extended_substeps) -> str:
    """The cache key of a reference (``_bench.refcache``): the initial state, every array of the
    segment sequence and the compared samples, the settings, the model's equations and
    parameters (``refcache.model_identity``) and this module's source."""
    import inspect
    import sys

    from acdrive._bench import refcache

    return refcache.key(
        x0=np.asarray(x0, dtype=float),
        segments={k: np.asarray(v) for k, v in seg.items()},
        samples=int(n),
        rtol=rtol,
        tight_rtol=tight_rtol,
        extended_substeps=extended_substeps,
        model=refcache.model_identity(model),
        reference_code=inspect.getsource(sys.modules[__name__]),
    )


def reference_trajectories(x0, t, counts, dt, seg, model, rtol, tight_rtol, extended_substeps):
    """The reference runs of ``accuracy`` as arrays (states at the sampling instants) with the
    wall time each took: ``radau``, ``tight`` (if ``tight_rtol``), ``extended`` and
    ``extended_half`` (if ``extended_substeps``)."""
    import time

    out = {}
    start = time.perf_counter()
    out["radau"] = radau_segments(
        model.rhs, x0, t, counts, dt, model.inputs(seg, False), rtol, rtol * 1e-2, model.jac
    )
    out["radau_wall_s"] = np.array(time.perf_counter() - start)
    if tight_rtol:
        start = time.perf_counter()
        out["tight"] = radau_segments(
            model.rhs,
            x0,
            t,
            counts,
            dt,
            model.inputs(seg, False),
            tight_rtol,
            tight_rtol * 1e-2,
            model.jac,
        )
        out["tight_wall_s"] = np.array(time.perf_counter() - start)
    if extended_substeps:
        start = time.perf_counter()
        inputs_ld = model.inputs(seg, True)
        out["extended"] = extended_rk6_segments(
            model.rhs_ld, x0, t, counts, dt, inputs_ld, extended_substeps
        )
        out["extended_wall_s"] = np.array(time.perf_counter() - start)
        out["extended_half"] = extended_rk6_segments(
            model.rhs_ld, x0, t, counts, dt, inputs_ld, max(extended_substeps // 2, 1)
        )
    return out


def short_errors(e: dict) -> dict:
    """The figures of an ``accuracy`` result that the summary quotes, per reference."""
    keys = ("current_rel_peak", "speed_abs_rad_s", "speed_rel_peak")
    out = {f"radau_rtol_{e['reference']['rtol']:g}": {k: e["reference"][k] for k in keys}}
    if "tight_reference" in e:
        out[f"radau_rtol_{e['tight_reference']['rtol']:g}"] = {
            k: e["tight_reference"][k] for k in keys
        }
    if "extended_reference" in e:
        out["extended_precision"] = {k: e["extended_reference"][k] for k in keys}
        out["extended_precision_resolution"] = {k: e["extended_resolution"][k] for k in keys}
    if "reference_resolution" in e:
        out["radau_resolution"] = {k: e["reference_resolution"][k] for k in keys}
    return out


def error_verdicts(a: dict, m: dict) -> dict:
    """acdrive's errors (``a``) against the peer's (``m``), per figure (current, speed):
    ``*_not_larger``: against the Radau reference, an error below that reference's own
    resolution counting as equal to it; ``*_not_larger_extended`` (if both have it): strictly,
    against the extended-precision reference. ``decisive`` names the verdicts to judge by: the
    extended-precision ones when present (the tightest comparison), else the Radau ones."""
    out = {}
    for name, key in (("current", "current_rel_peak"), ("speed", "speed_abs_rad_s")):
        resolution = 0.0
        if "reference_resolution" in a and "reference_resolution" in m:
            resolution = max(a["reference_resolution"][key], m["reference_resolution"][key])
        out[f"{name}_error_not_larger"] = bool(
            a["reference"][key] <= max(m["reference"][key], resolution)
        )
        if "extended_reference" in a and "extended_reference" in m:
            out[f"{name}_error_not_larger_extended"] = bool(
                a["extended_reference"][key] <= m["extended_reference"][key]
            )
    suffix = "_extended" if "current_error_not_larger_extended" in out else ""
    out["decisive"] = [f"current_error_not_larger{suffix}", f"speed_error_not_larger{suffix}"]
    return out
