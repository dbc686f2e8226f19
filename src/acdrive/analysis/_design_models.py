"""Design models A-D of the IM stator-current channel, Amezquita-Brooks et al. sec. V-A.

The four SISO models a designer may use for the loop v_alpha_s -> i_alpha_s, from the most to
the least complete:

- A: individual channel 1 of ICAD with the other loop ideal (h_2 = 1), i.e.
  c_1 / k_1 = g_11 (1 - gamma) = det G / g_22. Keeps the multivariable structure, the rotor
  speed and the rotor states. This is the model of their design procedure (sec. V-C: "k_1 = k_2
  designed as a SISO controller for (7) with h_j = 1").
- B: g_11 = n_11 / d at the speed w_r: drops the multivariable coupling (gamma).
- C: g_11 at w_r = 0: drops the coupling and the rotor speed.
- D: 1 / (L_s s + R_s): drops the coupling, the speed and the rotor states (the usual textbook
  model; note that it uses the self inductance L_s, so its high-frequency gain differs from
  the others' 1/(sigma L_s s) by the factor sigma).

Every model is a state-space ``LTI`` (the SISO class of ``acdrive.analysis._freqresp``).
Model A is realised exactly: holding y_2 = 0 with an ideal second loop forces
u_2 = -(C_2 B_2)^-1 C_2 (A x + B_1 u_1) (C_2 B_2 != 0: g_22 has relative degree one), which keeps
x in the kernel of C_2; restricted to that 3-dimensional subspace the dynamics are those of
det G / g_22 (poles: the zeros of g_22; zeros: the transmission zeros of G).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from acdrive._arguments import REAL, Array, Instance, checked
from acdrive.analysis._freqresp import LTI, check_frequency_grid
from acdrive.analysis._plants import Plant2x2, as_plant, plant_from_params
from acdrive.errors import InputError, require_finite
from acdrive.machines._induction import IMParams

MODEL_NAMES = ("A", "B", "C", "D")

#: What each model keeps / neglects (Amezquita-Brooks et al. sec. V-A).
NEGLECTS = {
    "A": "nothing (ICAD channel 1 with h_2 = 1: coupling, rotor speed and rotor states kept)",
    "B": "the multivariable coupling (g_11 = n_11/d at the same w_r)",
    "C": "the coupling and the rotor speed (g_11 at w_r = 0)",
    "D": "the coupling, the rotor speed and the rotor states (1/(L_s s + R_s))",
}


@dataclass(frozen=True)
class DesignModel:
    """One design model: ``name`` in A-D, the SISO ``model`` v_alpha_s -> i_alpha_s, the speed it
    was built at (None for speed-independent models) and what it neglects."""

    name: str
    model: LTI
    speed: float | None
    neglects: str


def ideal_other_loop(plant: Plant2x2, i: int = 0) -> LTI:
    """Exact realisation of g_ii (1 - gamma) = det G / g_jj (channel i with h_j = 1, 0-based i).

    Requires D = 0 and C_j B_j != 0 (g_jj of relative degree one, as for every machine current
    subsystem here); raises InputError otherwise.
    """
    plant = as_plant(plant)
    if i not in (0, 1):
        raise InputError("channel", "must be 0 or 1")
    j = 1 - i
    A, B, C, D = plant.A, plant.B, plant.C, plant.D
    if np.any(D != 0.0):
        raise InputError("plant", "ideal-loop model needs D = 0")
    cj, bj = C[j : j + 1, :], B[:, j : j + 1]
    cb = float((cj @ bj)[0, 0])
    if abs(cb) <= 1e-12 * max(1.0, np.linalg.norm(cj) * np.linalg.norm(bj)):
        raise InputError("plant", f"g_{j + 1}{j + 1} must have relative degree one (C_j B_j != 0)")
    proj = np.eye(A.shape[0]) - bj @ cj / cb  # u_j = -(C_j B_j)^-1 C_j (A x + B_i u_i)
    A_c = proj @ A
    b_c = proj @ B[:, i : i + 1]
    T = scipy.linalg.null_space(cj)  # orthonormal basis of ker C_j, invariant under A_c
    return LTI(T.T @ A_c @ T, T.T @ b_c, C[i : i + 1, :] @ T, [[0.0]], name="A")


def g11_model(plant: Plant2x2, name: str) -> LTI:
    """The diagonal element g_11 of a plant as an LTI (4 states for the IM)."""
    A, b, c, d = as_plant(plant).siso(0, 0)
    return LTI(A, b, c, d, name=name)


def design_models(params: IMParams, w_r: float) -> dict[str, DesignModel]:
    """Models A-D of Amezquita-Brooks et al. sec. V-A for an IM at electrical speed w_r [rad/s]."""
    if not isinstance(params, IMParams):
        raise InputError("params", f"design models A-D need IMParams, got {type(params).__name__}")
    w_r = require_finite("w_r", w_r)
    plant = plant_from_params(params, w_r)
    plant0 = plant_from_params(params, 0.0)
    d_model = LTI([[-params.R_s / params.L_s]], [[1.0 / params.L_s]], [[1.0]], [[0.0]], name="D")
    return {
        "A": DesignModel("A", ideal_other_loop(plant, 0), w_r, NEGLECTS["A"]),
        "B": DesignModel("B", g11_model(plant, "B"), w_r, NEGLECTS["B"]),
        "C": DesignModel("C", g11_model(plant0, "C"), 0.0, NEGLECTS["C"]),
        "D": DesignModel("D", d_model, None, NEGLECTS["D"]),
    }


@dataclass(frozen=True)
class ModelError:
    """Frequency-response error of one design model against model A over a band.

    ``max_rel_error``: max |M(jw) - A(jw)| / |A(jw)|; ``max_gain_error_db`` and
    ``max_phase_error_deg``: largest absolute gain and phase differences; ``at_rad_s``: where
    the relative error is largest.
    """

    name: str
    max_rel_error: float
    max_gain_error_db: float
    max_phase_error_deg: float
    at_rad_s: float


@dataclass(frozen=True)
class ModelComparison:
    """Models A-D and their errors against A on grid ``w`` (responses stored for the figures)."""

    speed: float
    w: np.ndarray
    models: dict[str, DesignModel]
    responses: dict[str, np.ndarray]
    errors: dict[str, ModelError]


@checked(params=Instance(IMParams), w_r=REAL, w=Array(1, low=0.0))
def compare_design_models(params: IMParams, w_r: float, w) -> ModelComparison:
    """Compare the design models B, C, D with the full channel model A (Amezquita-Brooks et al.
    sec. V-A, Fig. 4) at speed w_r on the band ``w``."""
    w = check_frequency_grid(w)
    models = design_models(params, w_r)
    resp = {k: m.model.freqresp(w) for k, m in models.items()}
    ref = resp["A"]
    errors = {}
    for k, r in resp.items():
        rel = np.abs(r - ref) / np.abs(ref)
        gain = np.abs(20.0 * np.log10(np.abs(r) / np.abs(ref)))
        phase = np.abs(np.degrees(np.angle(r / ref)))
        n = int(np.argmax(rel))
        errors[k] = ModelError(k, float(rel[n]), float(gain.max()), float(phase.max()), float(w[n]))
    return ModelComparison(w_r, w, models, resp, errors)
