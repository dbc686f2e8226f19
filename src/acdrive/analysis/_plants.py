"""2x2 linear plants for individual channel analysis: a typed state-space object and a registry.

The registry builds, for a named machine and an electrical rotor speed, the current subsystem of
that machine as a real 2-input 2-output state-space model:

- ``ugalde-im-300w``, ``delorenzo-im`` (Appendix parameters), ``delorenzo-im-13`` (parameters
  recovered from the printed matrix (13)): IM stator currents in the stationary frame,
  Ugalde-Loo et al. (41) / Amezquita-Brooks et al. (1);
- ``pmsg-2mw``: PMSG dq currents, Ugalde-Loo et al. (11);
- ``bodson-dfim``: DFIM rotor currents driven by rotor voltages in the stator-voltage-oriented
  synchronous frame, from Bodson (9)-(11) with the stator voltage set to zero (a disturbance).

All speeds are electrical rotor speeds w_r = n_p * w_m [rad/s].
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from acdrive._arguments import (
    POSITIVE,
    REAL,
    TEXT,
    Array,
    Either,
    Instance,
    Items,
    Table,
    Text,
    checked,
    optional,
)
from acdrive.errors import InputError, require_finite
from acdrive.machines import _registry as registry
from acdrive.machines._dfim import DFIMParams
from acdrive.machines._induction import (
    IMParams,
    stator_current_ss,
)
from acdrive.machines._pmsm import PMSGParams, dq_current_ss

#: Grid frequency of Bodson's experiments (60 Hz), used for the DFIM synchronous frame.
W_E_60HZ = 2.0 * math.pi * 60.0


def _real_matrix(name: str, value, shape: tuple[int | None, int | None]) -> np.ndarray:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(name, f"must be a real numeric matrix ({exc})") from None
    if arr.ndim != 2:
        raise InputError(name, f"must be a 2-D matrix, got {arr.ndim}-D")
    for axis, expected in enumerate(shape):
        if expected is not None and arr.shape[axis] != expected:
            raise InputError(name, f"has shape {arr.shape}, expected {shape}")
    if not np.all(np.isfinite(arr)):
        raise InputError(name, "must be finite (no NaN or infinity)")
    arr.setflags(write=False)
    return arr


@checked(
    A=Array(2, empty=True), B=Array(2, empty=True), C=Array(2, empty=True), D=Array(2),
    inputs=Items(TEXT), outputs=Items(TEXT), speed=optional(REAL), name=Text(empty=True),
    meta=Table(empty=True),
)
@dataclass(frozen=True)
class Plant2x2:
    """A real 2x2 linear plant x' = A x + B u, y = C x + D u (Ugalde-Loo et al. (9)).

    ``inputs`` / ``outputs`` name u_1, u_2 / y_1, y_2 (channel i pairs u_i with y_i);
    ``speed`` is the electrical rotor speed the model was built at (None for a generic plant).
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    inputs: tuple[str, str] = ("u1", "u2")
    outputs: tuple[str, str] = ("y1", "y2")
    speed: float | None = None
    name: str = ""
    meta: dict = field(default_factory=dict, compare=False, repr=False)

    def __post_init__(self):
        B = _real_matrix("B", self.B, (None, None))
        C = _real_matrix("C", self.C, (None, None))
        D = _real_matrix("D", self.D, (None, None))
        if B.shape[1] != 2 or C.shape[0] != 2 or D.shape != (2, 2):
            raise InputError(
                "plant",
                f"must have 2 inputs and 2 outputs (B n x 2, C 2 x n, D 2 x 2), got B {B.shape},"
                f" C {C.shape}, D {D.shape}",
            )
        n = B.shape[0]
        A = _real_matrix("A", self.A, (n, n)) if n else np.zeros((0, 0))
        if C.shape[1] != n:
            raise InputError("C", f"has {C.shape[1]} columns, A has {n} states")
        object.__setattr__(self, "A", A)
        object.__setattr__(self, "B", B)
        object.__setattr__(self, "C", C)
        object.__setattr__(self, "D", D)
        for label in ("inputs", "outputs"):
            names = tuple(str(v) for v in getattr(self, label))
            if len(names) != 2:
                raise InputError(label, "must name exactly two signals")
            object.__setattr__(self, label, names)
        if self.speed is not None:
            object.__setattr__(self, "speed", require_finite("speed", self.speed))

    @property
    def n_states(self) -> int:
        return self.A.shape[0]

    def poles(self) -> np.ndarray:
        """Eigenvalues of A (the open-loop poles, with any uncontrollable/unobservable modes)."""
        return np.linalg.eigvals(self.A)

    def to_control(self):
        """This plant as a python-control ``StateSpace`` (continuous time; the optional
        ``control`` extra), inputs and outputs named as here."""
        try:
            import control
        except ImportError:  # pragma: no cover - depends on the environment
            raise InputError(
                "control", "python-control is not installed (pip install 'acdrive[control]')"
            ) from None
        kwargs = {"name": self.name} if self.name else {}
        return control.ss(self.A, self.B, self.C, self.D, inputs=list(self.inputs),
                          outputs=list(self.outputs), **kwargs)  # fmt: skip

    def siso(self, i: int, j: int):
        """(A, b, c, d) of the element g_ij (0-based indices), as arrays."""
        return self.A, self.B[:, j : j + 1], self.C[i : i + 1, :], self.D[i : i + 1, j : j + 1]


#: the argument rule of a plant: a Plant2x2, its (A, B, C, D) or a python-control LTI system
PLANT = Either(
    Instance(Plant2x2),
    Items(Array(2, empty=True)),
    Instance("control:LTI"),
)


@checked(obj=PLANT, speed=optional(REAL))
def as_plant(obj, speed: float | None = None) -> Plant2x2:
    """Coerce a Plant2x2, an (A, B, C, D) tuple or a python-control StateSpace to Plant2x2."""
    if isinstance(obj, Plant2x2):
        return obj
    if isinstance(obj, (tuple, list)) and len(obj) == 4:
        return Plant2x2(*obj, speed=speed)
    try:  # python-control is an optional extra
        import control
    except ImportError:  # pragma: no cover - depends on the environment
        control = None
    if control is not None and isinstance(obj, control.LTI):
        if not isinstance(obj, control.StateSpace):
            obj = control.ss(obj)
        if obj.dt not in (0, None):
            raise InputError("plant", "must be continuous-time (dt = 0)")
        return Plant2x2(obj.A, obj.B, obj.C, obj.D, speed=speed)
    raise InputError(
        "plant",
        f"must be a Plant2x2, an (A, B, C, D) tuple or a StateSpace, got {type(obj).__name__}",
    )


def dfim_rotor_current_ss(p: DFIMParams, w_r: float, w_e: float = W_E_60HZ):
    """Real (A, B, C, D) of the DFIM rotor-current subsystem, from Bodson (9)-(11).

    Complex model in the synchronous frame rotating at w_e (stator-voltage oriented):
    L d/dt (i_S, i_R) = (v_S, v_R) - Z (i_S, i_R), L = [[L_S, M], [M, L_R]],
    Z = [[R_S + j w_e L_S, j w_e M], [j (w_e - w_r) M, R_R + j (w_e - w_r) L_R]] with w_r = n_P w
    the electrical rotor speed. Input: v_R = v_Rd + j v_Rq (v_S = 0, a disturbance);
    output: i_R. Real states (Re i_S, Im i_S, Re i_R, Im i_R).
    """
    w_r = require_finite("w_r", w_r)
    w_e = require_finite("w_e", w_e)
    w_slip = w_e - w_r
    L = np.array([[p.L_s, p.M], [p.M, p.L_r]])
    Z = np.array(
        [
            [p.R_s + 1j * w_e * p.L_s, 1j * w_e * p.M],
            [1j * w_slip * p.M, p.R_r + 1j * w_slip * p.L_r],
        ]
    )
    L_inv = np.linalg.inv(L)
    A_c = -L_inv @ Z
    B_c = L_inv[:, 1:2]
    C_c = np.array([[0.0, 1.0]])
    return _complex_to_real(A_c), _complex_to_real(B_c), _complex_to_real(C_c), np.zeros((2, 2))


def _complex_to_real(M: np.ndarray) -> np.ndarray:
    """Real form of a complex matrix acting on (Re, Im) pairs: a + jb -> [[a, -b], [b, a]]."""
    J = np.array([[0.0, -1.0], [1.0, 0.0]])
    return np.kron(M.real, np.eye(2)) + np.kron(M.imag, J)


#: Built-in machines by CLI name (one registry: ``acdrive.machines._registry``).
MACHINES = registry.MACHINES
machine_params = registry.machine_params


@checked(
    params=Instance(IMParams, PMSGParams, DFIMParams), speed=REAL, w_e=POSITIVE,
    name=Text(empty=True),
)
def plant_from_params(params, speed: float, *, w_e: float = W_E_60HZ, name: str = "") -> Plant2x2:
    """Current-subsystem plant of a machine given by its parameters, at electrical speed ``speed``.

    IMParams -> stator currents (stationary frame); PMSGParams -> dq currents;
    DFIMParams -> rotor currents (synchronous frame at ``w_e``).
    """
    speed = require_finite("speed", speed)
    if isinstance(params, IMParams):
        return Plant2x2(
            *stator_current_ss(params, speed),
            inputs=("v_alpha_s", "v_beta_s"),
            outputs=("i_alpha_s", "i_beta_s"),
            speed=speed,
            name=name,
        )
    if isinstance(params, PMSGParams):
        return Plant2x2(
            *dq_current_ss(params, speed),
            inputs=("v_d", "v_q"),
            outputs=("i_d", "i_q"),
            speed=speed,
            name=name,
        )
    if isinstance(params, DFIMParams):
        return Plant2x2(
            *dfim_rotor_current_ss(params, speed, w_e),
            inputs=("v_Rd", "v_Rq"),
            outputs=("i_Rd", "i_Rq"),
            speed=speed,
            name=name,
            meta={"w_e": w_e},
        )
    raise InputError("params", f"unsupported machine parameters {type(params).__name__}")


@checked(machine=TEXT, speed=REAL, w_e=POSITIVE)
def plant_for(machine: str, speed: float, *, w_e: float = W_E_60HZ) -> Plant2x2:
    """Current-subsystem plant of a built-in machine (see ``MACHINES``) at electrical speed."""
    return plant_from_params(machine_params(machine), speed, w_e=w_e, name=machine)


@checked(machine=TEXT, speeds=Array((0, 1)), w_e=POSITIVE)
def plants_for(machine: str, speeds, *, w_e: float = W_E_60HZ) -> list[Plant2x2]:
    """``plant_for`` over a sequence of speeds (NaN or empty -> InputError)."""
    speeds = np.atleast_1d(np.asarray(speeds, dtype=float))
    if speeds.size == 0:
        raise InputError("speeds", "must not be empty")
    if not np.all(np.isfinite(speeds)):
        raise InputError("speeds", "must be finite (no NaN or infinity)")
    return [plant_for(machine, float(w), w_e=w_e) for w in speeds]
