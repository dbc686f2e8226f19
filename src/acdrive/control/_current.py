"""Stationary-frame current control of an AC machine as a sampled part (Amezquita-Brooks et al.).

:class:`StationaryCurrentController` runs any LTI controller K(s) (``acdrive.control._lti``: an
``LTI`` applied to both axes, a ``diagonal(k_1, k_2)`` or a full 2 x 2 ``LTIMatrix``) on the
current error in the stationary frame, as in sec. VI of the paper: e = i_ref - i_meas with
alpha = real part and beta = imaginary part, v = K e, decentralised (u_i = k_i e_i, (5)) and
without decoupling or back-EMF compensation. The controller object is the one the ICAD analysis
takes (``part.controller``; ``part.controller.diagonal_entries()`` gives the k_1, k_2 of
``acdrive.analysis.analyse``); its discretisation (``acdrive.control.discretise``, ZOH or
Tustin with optional pre-warping) is packed into the part's parameters, and the controller state
is the part's discrete state. Built-in controllers: ``acdrive.control._lti.BUILTIN`` ((20), the PI
K_P = 360, K_I = 9000, the PI family of Fig. 17, the PI of Fig. 18, the inner PI of (22)).

One sample (no computation delay, as the rest of acdrive, ``docs/design.md``):

    e_k = i_ref,k - i_meas,k                         (alpha, beta)
    v_k = C_d x_k + D_d e_k                          the unlimited command
    w_k = v_k min(1, v_max / |v_k|)                  limited along its own direction
    x_{k+1} = A_d x_k + B_d e_k + K_aw (w_k - v_k),  K_aw = gamma B_d D_d^-1

**Anti-windup: back-calculation with the gain of the conditioning technique** (Hanus, Kinnaert
and Henrotte, 1987). With ``aw_gain`` gamma = 1 the state is updated with the *realisable* error
e_r = e + D_d^-1 (w - v), the error that would have produced exactly the limited command w
(v(e_r) = w), so the state is always the one of an unsaturated controller that produced the
applied voltage: nothing winds up, and when the limit releases the loop continues from a
consistent state without the integrator's excess. While limited, the state follows
x_{k+1} = (A_d - gamma B_d D_d^-1 C_d) x_k + gamma B_d D_d^-1 w_k + (1 - gamma) B_d e_k; for
gamma = 1 this is driven by the bounded w only, and its matrix has the zeros of k_d as
eigenvalues. The construction therefore requires D_d invertible (a biproper discretisation) and
|eig(A_d - gamma B_d D_d^-1 C_d)| < 1 on the part of the state that B_d reaches (the rest keeps
the eigenvalues of A_d and is never excited) (InputError on ``aw_gain`` otherwise: a
non-minimum-phase or strictly proper controller; lower gamma or set 0). For the built-in
controllers the zeros are those of (20) and the PIs (-1000, -400, -400; -K_I/K_P), all stable.
gamma in (0, 1) is a slower tracking of the same form; gamma = 0 turns anti-windup off (the
state winds up). Chosen over conditional integration because it applies to any K(s), not only
to a PI whose integrator state is known, and it suits a magnitude (vector) limit: the correction
acts along the direction the limiter removed.

The limit v_max is the parameter ``v_max``, or, with ``v_dc_input=True``, v_dc / sqrt(2) from an
input ``v_dc`` (``plant._converter.max_voltage_magnitude``, the converter's linear SVPWM range),
read at the sample instant. A run at a sample time other than the ``T_s`` the matrices were
computed for is refused before it starts (``check_run``, an ``InputError`` naming ``<part>.T_s``).
Events: ``saturated`` (the command was limited: its magnitude lay beyond v_max by more than a
few ulps, ``_frames.beyond_limit``) and ``period_mismatch`` (a kernel-level guard for
callers that bypass the check: the run's sample time differs from ``T_s``; the output is still
computed with the stored matrices).

:class:`CurrentProgram`: a complex current (reference or test signal) from two tables.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from acdrive._frames import beyond_limit
from acdrive._jit import jit
from acdrive.control._discretise import DiscreteLTI, discretise
from acdrive.control._lti import LTI
from acdrive.control._lti_matrix import LTIMatrix
from acdrive.control._open_loop import complex_program_step
from acdrive.core._describe import layout_text
from acdrive.core._parts import SampledPart
from acdrive.core._profile import Profile
from acdrive.core._signals import Layout, cplx, real, table
from acdrive.errors import InputError
from acdrive.plant._converter import max_voltage_magnitude

#: Parameters every controller instance has, before its matrices (same slots for every order).
FIXED_PARAMS = (
    real(
        "v_max", "V", "magnitude limit of the voltage command (unless v_dc is an input)", "positive"
    ),
    real("aw_gain", "", "anti-windup tracking gain gamma (1: conditioning, 0: off)", "nonnegative",
         derived=True),  # enters K_aw only
    real("T_s", "s", "sample period the matrices were computed for", "positive", derived=True),
    real("v_dc_input", "", "1 if the limit is v_dc / sqrt(2) from the input v_dc", "flag",
         derived=True),
    real("order", "", "controller order n (number of states)", "whole", derived=True),
)
_FIXED = Layout(*FIXED_PARAMS)
_V_MAX, _T_S, _FROM_INPUT, _ORDER = (
    _FIXED.slot(n) for n in ("v_max", "T_s", "v_dc_input", "order")
)
#: first slot of the matrices (after the fixed parameters)
_MATRICES = _FIXED.fixed_size
#: parameters derived from the controller (never given directly)
DERIVED = ("T_s", "v_dc_input", "order")

_BASE_INPUTS = (
    cplx("i_ref", "A", "current reference, stationary frame (alpha = re, beta = im)"),
    cplx("i_meas", "A", "measured current, stationary frame (alpha = re, beta = im)"),
)
_V_DC_VAR = real("v_dc", "V", "DC-link voltage: the limit is v_dc / sqrt(2)")
_ALL_INPUTS = Layout(*_BASE_INPUTS, _V_DC_VAR)  # without v_dc the first slots are the same
_I_REF, _I_MEAS, _V_DC = (_ALL_INPUTS.slot(n) for n in ("i_ref", "i_meas", "v_dc"))
CONTROLLER_OUTPUTS = Layout(cplx("v_ref", "V", "voltage command, limited, stationary frame"))
_V_REF = CONTROLLER_OUTPUTS.slot("v_ref")

EVENT_SATURATED = 1
EVENT_PERIOD_MISMATCH = 2
#: relative difference between the run's sample time and T_s that raises period_mismatch
PERIOD_TOL = 1e-9
#: aw_gain above this is refused (gamma > 1 over-corrects the state)
MAX_AW_GAIN = 1.0


def _matrix_names(n: int) -> list[tuple[str, int, int]]:
    """(prefix, rows, columns) of the packed matrices, in storage order (row-major each)."""
    return [("Ad", n, n), ("Bd", n, 2), ("Cd", 2, n), ("Dd", 2, 2), ("Kaw", n, 2)]


def _params_layout(n: int) -> Layout:
    entries = [
        real(f"{name}_{i}_{j}", "", f"{name}[{i}, {j}] of the discrete controller (derived)",
             derived=True)
        for name, rows, cols in _matrix_names(n)
        for i in range(rows)
        for j in range(cols)
    ]
    return Layout(*FIXED_PARAMS, *entries)


def _states_layout(n: int) -> Layout:
    return Layout(
        *(
            real(f"x_{i}", "", f"controller state x[{i}] (units of the realisation)")
            for i in range(n)
        ),
        *(
            real(f"next_{i}", "", f"scratch: x[{i}] of the next sample (internal)")
            for i in range(n)
        ),
    )


@jit
def current_controller_step(t, T_s, u, p, s, y):
    """One sample of the module docstring's difference equation; returns the event bits.

    Explicit loops over the small matrices (row-major in ``p``, see ``_matrix_names``): no array
    is allocated. ``s[n:2n]`` holds the next state before it is copied into ``s[:n]``.
    """
    n = int(p[_ORDER])
    a = _MATRICES
    b = a + n * n
    c = b + 2 * n
    d = c + 2 * n
    k = d + 4
    e0 = u[_I_REF] - u[_I_MEAS]
    e1 = u[_I_REF + 1] - u[_I_MEAS + 1]
    v0 = p[d] * e0 + p[d + 1] * e1
    v1 = p[d + 2] * e0 + p[d + 3] * e1
    for j in range(n):
        v0 += p[c + j] * s[j]
        v1 += p[c + n + j] * s[j]
    if p[_FROM_INPUT] != 0.0:
        v_max = max_voltage_magnitude(max(u[_V_DC], 0.0))
    else:
        v_max = p[_V_MAX]
    events = 0
    w0, w1 = v0, v1
    magnitude = math.sqrt(v0 * v0 + v1 * v1)
    if beyond_limit(magnitude, v_max):
        scale = v_max / magnitude
        w0, w1 = v0 * scale, v1 * scale
        events |= EVENT_SATURATED
    dw0, dw1 = w0 - v0, w1 - v1
    for i in range(n):
        acc = p[b + 2 * i] * e0 + p[b + 2 * i + 1] * e1
        acc += p[k + 2 * i] * dw0 + p[k + 2 * i + 1] * dw1
        for j in range(n):
            acc += p[a + i * n + j] * s[j]
        s[n + i] = acc
    for i in range(n):
        s[i] = s[n + i]
    y[_V_REF], y[_V_REF + 1] = w0, w1
    if abs(T_s - p[_T_S]) > PERIOD_TOL * p[_T_S]:
        events |= EVENT_PERIOD_MISMATCH
    return events


def as_current_controller(controller) -> LTIMatrix:
    """The 2 x 2 controller of a stationary-frame current loop: an ``LTI`` k becomes
    ``LTIMatrix.diagonal(k, k)`` (the same object on both axes), a 2 x 2 ``LTIMatrix`` is kept."""
    if isinstance(controller, LTI):
        return LTIMatrix.diagonal(controller, controller, name=controller.name)
    if isinstance(controller, LTIMatrix):
        if controller.shape != (2, 2):
            p, m = controller.shape
            raise InputError(
                "controller",
                f"must be 2 x 2 (alpha, beta errors -> alpha, beta voltages), got {p} x {m}",
            )
        return controller
    raise InputError(
        "controller", f"must be an LTI or a 2 x 2 LTIMatrix, got {type(controller).__name__}"
    )


def reachable_basis(A: np.ndarray, B: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """Orthonormal basis of the reachable subspace span{B, A B, A^2 B, ...} (staircase: each new
    block A V is orthogonalised against the basis so far; directions below ``tol`` ||A|| are
    dropped)."""
    n = A.shape[0]
    scale = max(float(np.linalg.norm(A, 2)), float(np.linalg.norm(B, 2)), 1e-300)
    U, sv, _ = np.linalg.svd(B, full_matrices=False)
    basis = U[:, sv > tol * scale]
    new = basis
    while new.shape[1] and basis.shape[1] < n:
        W = A @ new
        for _ in range(2):  # re-orthogonalise once against rounding
            W = W - basis @ (basis.T @ W)
        U, sv, _ = np.linalg.svd(W, full_matrices=False)
        new = U[:, sv > tol * scale]
        basis = np.hstack([basis, new])
    return basis


def anti_windup_gain(discrete: DiscreteLTI, gamma: float, field: str) -> np.ndarray:
    """K_aw = gamma B_d D_d^-1 (module docstring), checked: D_d invertible and the conditioned
    state matrix A_d - K_aw C_d stable. ``field`` names the offending parameter."""
    n = discrete.order
    if gamma == 0.0 or n == 0:
        return np.zeros((n, 2))
    Dd = discrete.Dd
    if np.linalg.cond(Dd) > 1e12:
        raise InputError(
            field,
            "anti-windup by conditioning needs D_d invertible (a biproper controller; got "
            f"D_d = {Dd.tolist()}); set aw_gain = 0 for a strictly proper controller",
        )
    K = gamma * np.linalg.solve(Dd.T, discrete.Bd.T).T
    # A_d - K C_d = A_d + B_d F: the part of the state that B_d cannot reach (a non-minimal
    # realisation, e.g. two integrators on one input of a grid) keeps the eigenvalues of A_d and
    # is never excited, so only the reachable part must be stable
    conditioned = discrete.Ad - K @ discrete.Cd
    V = reachable_basis(discrete.Ad, discrete.Bd)
    radius = float(np.max(np.abs(np.linalg.eigvals(V.T @ conditioned @ V)), initial=0.0))
    if not radius < 1.0:
        raise InputError(
            field,
            f"the conditioned controller A_d - gamma B_d D_d^-1 C_d is not stable (max |eig| = "
            f"{radius:.6g} >= 1: zeros of k_d on or outside the unit circle); lower aw_gain or "
            "set 0",
        )
    return K


class StationaryCurrentController(SampledPart):
    """Stationary-frame current controller v = K(e) with a magnitude limit and anti-windup
    (module docstring).

    ``StationaryCurrentController(name, controller, T_s, method="tustin", prewarp=None,
    v_dc_input=False, v_max=..., aw_gain=1.0)``: ``controller`` an ``LTI`` (on both axes), a
    2 x 2 ``LTIMatrix`` or a ``DiscreteLTI`` of one (then ``T_s``, ``method`` and ``prewarp``
    come from it). ``part.controller`` is the continuous controller (its entries the very
    objects given), ``part.discrete`` its discretisation.
    """

    SOURCE = (
        "stationary-frame current controller K(z) with magnitude limit and anti-windup by "
        "conditioning (control._current; Amezquita-Brooks (20) or the PI)"
    )

    OUTPUTS = CONTROLLER_OUTPUTS
    EVENTS = ("saturated", "period_mismatch")
    PER_INSTANCE: ClassVar[dict] = {
        "PARAMS": layout_text(_FIXED) + ", then the discrete controller's matrices (set by "
        "its order; derived: give controller, T_s, method)",
        "STATES": "the discrete controller's states (as many as its order)",
        "INPUTS": layout_text(_ALL_INPUTS) + " (v_dc only with v_dc_input=True)",
    }
    #: v_max 1e12 V: no limit unless one is given
    DEFAULTS: ClassVar[dict] = {"v_max": 1e12, "aw_gain": 1.0}
    #: the parameters that set an instance's structure: its C is written for their values
    #: (``sim._ccode._kind_c.translate_part``)
    STRUCTURAL: ClassVar[tuple] = ("order", "v_dc_input")
    step = current_controller_step

    def __init__(
        self,
        name: str,
        controller,
        T_s: float | None = None,
        method: str = "tustin",
        prewarp: float | None = None,
        *,
        v_dc_input: bool = False,
        **params,
    ):
        if not isinstance(name, str) or not name.isidentifier():
            raise InputError("name", f"a part name must be an identifier, got {name!r}")
        if isinstance(controller, DiscreteLTI):
            if T_s is not None or prewarp is not None:
                raise InputError(f"{name}.T_s", "is taken from the DiscreteLTI given as controller")
            discrete = controller
            matrix = _named(name, as_current_controller, discrete.source)  # 2 x 2 or SISO
            if isinstance(discrete.source, LTI):
                discrete = _named(
                    name, discretise, matrix, discrete.T_s, discrete.method, discrete.prewarp
                )
        else:
            if T_s is None:
                raise InputError(f"{name}.T_s", "must be given (the controller's sample period)")
            matrix = _named(name, as_current_controller, controller)
            discrete = _named(name, discretise, matrix, T_s, method, prewarp)
        for key in params:
            if key in DERIVED or key.split("_")[0] in ("Ad", "Bd", "Cd", "Dd", "Kaw"):
                raise InputError(
                    f"{name}.{key}",
                    "is derived from the controller; give controller, T_s, method or prewarp",
                )
        if not isinstance(v_dc_input, bool):
            raise InputError(f"{name}.v_dc_input", "must be True or False")
        n = discrete.order
        self.controller: LTIMatrix = discrete.source
        self.discrete: DiscreteLTI = discrete
        self.v_dc_input = v_dc_input
        self.PARAMS = _params_layout(n)
        self.STATES = _states_layout(n)
        self.INPUTS = Layout(*_BASE_INPUTS, *((_V_DC_VAR,) if v_dc_input else ()))
        values = {**self.DEFAULTS, **params}
        gamma = values.get("aw_gain")
        if isinstance(gamma, (int, float)) and not isinstance(gamma, bool):
            if not 0.0 <= gamma <= MAX_AW_GAIN:
                raise InputError(f"{name}.aw_gain", f"must be between 0 and {MAX_AW_GAIN:g}")
            K = anti_windup_gain(discrete, float(gamma), f"{name}.aw_gain")
        else:
            K = np.zeros((n, 2))  # packing below names the bad value
        derived = {
            "T_s": discrete.T_s,
            "v_dc_input": 1.0 if v_dc_input else 0.0,
            "order": float(n),
        }
        for (prefix, rows, cols), M in zip(
            _matrix_names(n), (discrete.Ad, discrete.Bd, discrete.Cd, discrete.Dd, K), strict=True
        ):
            for i in range(rows):
                for j in range(cols):
                    derived[f"{prefix}_{i}_{j}"] = float(M[i, j])
        super().__init__(name, **params, **derived)

    def check_run(self, sample_time: float) -> None:
        """The run's sample time must be the one the controller was discretised for."""
        T_s = self.discrete.T_s
        if abs(sample_time - T_s) > PERIOD_TOL * T_s:
            raise InputError(
                f"{self.name}.T_s",
                f"the controller was discretised for {T_s:g} s but the run samples every "
                f"{sample_time:g} s: discretise it for the run's sample time",
            )

    def with_params(self, **changes) -> StationaryCurrentController:
        """A copy with some parameters changed: ``v_max``, ``aw_gain``, and ``controller``,
        ``T_s``, ``method``, ``prewarp`` (re-discretised; the order must stay the same, as a
        system's state slots are fixed)."""
        design = {
            "controller": self.controller,
            "T_s": self.discrete.T_s,
            "method": self.discrete.method,
            "prewarp": self.discrete.prewarp,
        }
        for key in list(changes):
            if key in design:
                design[key] = changes.pop(key)
        if "v_dc_input" in changes:
            raise InputError(f"{self.name}.v_dc_input", "changes the inputs: build a new part")
        kept = {k: v for k, v in self.values.items() if k in ("v_max", "aw_gain")}
        clone = type(self)(
            self.name,
            design["controller"],
            design["T_s"],
            design["method"],
            design["prewarp"],
            v_dc_input=self.v_dc_input,
            **{**kept, **changes},
        )
        if clone.discrete.order != self.discrete.order:
            raise InputError(
                f"{self.name}.controller",
                f"has order {clone.discrete.order}; a re-parametrised copy must keep order "
                f"{self.discrete.order}",
            )
        return clone

    def state_for(self, x) -> dict:
        """Initial-state values {x_i: ...} for a controller state vector x (e.g. bumpless
        start), for ``System.run(initial={part name: ...})``."""
        x = np.asarray(x, dtype=float).reshape(-1)
        if x.size != self.discrete.order:
            raise InputError(
                f"{self.name}.initial", f"must have {self.discrete.order} values, got {x.size}"
            )
        return {f"x_{i}": float(v) for i, v in enumerate(x)}


def _named(name: str, function, *args):
    """``function(*args)`` with the field of an InputError prefixed by the part name."""
    try:
        return function(*args)
    except InputError as err:
        raise InputError(f"{name}.{err.field}", err.rule) from None


CURRENT_TABLES = Layout(
    table("re", "A", "real (alpha) part of the current"),
    table("im", "A", "imaginary (beta) part of the current"),
)
CURRENT_OUTPUTS = Layout(cplx("i", "A", "current space vector, stationary frame"))


class CurrentProgram(SampledPart):
    """A complex current from two piecewise-linear tables (a current reference, or a known
    measured signal for an open-loop test); the same kernel as ``open_loop.ComplexProgram``."""

    SOURCE = "a complex current from two piecewise-linear tables (control._current)"

    PARAMS, OUTPUTS = CURRENT_TABLES, CURRENT_OUTPUTS
    DEFAULTS: ClassVar[dict] = {"re": 0.0, "im": 0.0}
    step = complex_program_step

    @classmethod
    def from_function(cls, name, function, times) -> CurrentProgram:
        """Tabulate a Python function of time (complex amperes) at ``times``."""
        times = np.asarray(times, dtype=float)
        values = np.array([complex(function(t)) for t in times])
        return cls(name, re=Profile(times, values.real), im=Profile(times, values.imag))
