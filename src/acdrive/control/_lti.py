"""Linear time-invariant controllers: one definition for the ICAD analysis and the simulator.

A controller is defined once, as a continuous-time state-space model, and that very object is
what both sides use: ``acdrive.analysis`` (ICAD, Amezquita-Brooks et al. (5)-(10)) evaluates its
frequency response, and ``discretise`` turns it into the difference equation that the sampled
part ``acdrive.control.StationaryCurrentController`` runs. No numbers are copied between
the two.

* :class:`LTI` (here): a real SISO k(s) = C (s I - A)^-1 B + D, built with ``tf`` (polynomials),
  ``zpk``, ``pi``, ``pi_lag``, ``gain``, ``paper_20`` or ``from_control``; ``as_lti`` accepts a
  python-control SISO model too.
* Built-in controllers of Amezquita-Brooks et al. (here, section "Built-in controllers" below):
  (20), their PI (K_P = 360, K_I = 9000), the PI family of Fig. 17, the high-integral-gain PI of
  Fig. 18 and the inner PI of (22). The ICAD reports and the simulator take them from here.
* ``LTIMatrix`` (``control._lti_matrix``): a p x m controller, a grid of SISO ``LTI`` entries or a
  general MIMO state space.
* ``discretise`` (``control._discretise``): the sampled controller by zero-order hold or Tustin.
* ``evaluate_ss`` (``control._ss_frequency``): the batched frequency-response evaluation that
  ``LTI`` and ``LTIMatrix`` use.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acdrive._arguments import Instance
from acdrive.errors import InputError, require_finite

# ---------------------------------------------------------------------------------------------
# SISO controllers


def _real_section(roots: list[complex]) -> np.ndarray:
    """Monic real polynomial coefficients (highest first) with the given 1 or 2 roots."""
    return np.real(np.poly(roots))


def _group(roots) -> list[list[complex]]:
    """Group roots into real polynomials of degree <= 2: conjugate pairs, then real pairs."""
    roots = [complex(r) for r in roots]
    reals = sorted((r.real for r in roots if abs(r.imag) <= 1e-12 * max(1.0, abs(r))), reverse=True)
    upper = [r for r in roots if r.imag > 1e-12 * max(1.0, abs(r))]
    lower = [r for r in roots if r.imag < -1e-12 * max(1.0, abs(r))]
    if len(upper) != len(lower):
        raise InputError("roots", "complex roots must come in conjugate pairs")
    groups = [[r, r.conjugate()] for r in upper]
    groups += [[reals[i], reals[i + 1]] for i in range(0, len(reals) - 1, 2)]
    if len(reals) % 2:
        groups.append([reals[-1]])
    return groups


def _canonical(num: np.ndarray, den: np.ndarray):
    """Controllable canonical realisation of num/den (den monic, deg num <= deg den)."""
    n = den.size - 1
    num = np.concatenate([np.zeros(n + 1 - num.size), num])
    d = num[0]
    r = num[1:] - d * den[1:]  # strictly proper remainder, highest power first
    A = np.zeros((n, n))
    A[0, :] = -den[1:]
    A[1:, :-1] = np.eye(n - 1)
    B = np.zeros((n, 1))
    B[0, 0] = 1.0
    C = r[None, :]
    return A, B, C, np.array([[d]])


def _series(first, second):
    """State-space of second(s) * first(s) (signal goes through ``first`` then ``second``)."""
    A1, B1, C1, D1 = first
    A2, B2, C2, D2 = second
    n1, n2 = A1.shape[0], A2.shape[0]
    A = np.block([[A1, np.zeros((n1, n2))], [B2 @ C1, A2]])
    B = np.vstack([B1, B2 @ D1])
    C = np.hstack([D2 @ C1, C2])
    return A, B, C, D2 @ D1


def _polynomial(field_name: str, coefficients) -> np.ndarray:
    """Real finite polynomial coefficients (highest power first), leading zeros removed."""
    try:
        c = np.atleast_1d(np.asarray(coefficients, dtype=float))
    except (TypeError, ValueError):
        raise InputError(field_name, "must be a sequence of real coefficients") from None
    if c.ndim != 1:
        raise InputError(field_name, "must be a 1-D sequence of coefficients, highest power first")
    if not np.all(np.isfinite(c)):
        raise InputError(field_name, "coefficients must be finite")
    nonzero = np.flatnonzero(c)
    return c[nonzero[0] :] if nonzero.size else np.zeros(0)


@dataclass(frozen=True)
class LTI:
    """A real SISO continuous-time controller k(s) = C (s I - A)^-1 B + D.

    Build it with ``tf``, ``zpk``, ``pi``, ``pi_lag``, ``gain``, ``paper_20`` or
    ``from_control``. The arrays are read-only: an ``LTI`` is shared, never copied, between the
    ICAD analysis and the simulator.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    name: str = ""

    def __post_init__(self):
        A = np.array(self.A, dtype=float)
        n = round(float(np.sqrt(A.size)))
        if n * n != A.size:
            raise InputError("controller.A", "must be square")
        A = A.reshape(n, n)
        B = np.array(self.B, dtype=float).reshape(n, 1)
        C = np.array(self.C, dtype=float).reshape(1, n)
        D = np.array(self.D, dtype=float).reshape(1, 1)
        for label, arr in (("A", A), ("B", B), ("C", C), ("D", D)):
            if not np.all(np.isfinite(arr)):
                raise InputError(f"controller.{label}", "must be finite")
            arr.setflags(write=False)
        for label, arr in (("A", A), ("B", B), ("C", C), ("D", D)):
            object.__setattr__(self, label, arr)

    # -- constructors ------------------------------------------------------------------------
    @classmethod
    def tf(cls, num, den, name: str = "") -> LTI:
        """k(s) = num(s) / den(s), coefficients highest power first; proper (deg num <= deg den).

        Realised in controllable canonical form; leading zero coefficients are ignored.
        """
        num = _polynomial("controller.num", num)
        den = _polynomial("controller.den", den)
        if den.size == 0:
            raise InputError("controller.den", "must not be the zero polynomial")
        if num.size > den.size:
            raise InputError(
                "controller.num",
                f"improper transfer function: degree of num ({num.size - 1}) exceeds degree of "
                f"den ({den.size - 1}); a realisable controller has deg num <= deg den",
            )
        if num.size == 0:
            num = np.zeros(1)
        num, den = num / den[0], den / den[0]
        if den.size == 1:
            return cls.gain(float(num[-1]), name=name)
        return cls(*_canonical(num, den), name=name)

    @classmethod
    def zpk(cls, zeros, poles, gain: float, name: str = "") -> LTI:
        """k(s) = gain * prod(s - z) / prod(s - p); proper, real (conjugate-paired) data."""
        gain = require_finite("gain", gain)
        zeros = list(np.atleast_1d(np.asarray(zeros, dtype=complex)))
        poles = list(np.atleast_1d(np.asarray(poles, dtype=complex)))
        if not all(np.isfinite(zeros)) or not all(np.isfinite(poles)):
            raise InputError("controller", "zeros and poles must be finite")
        if len(zeros) > len(poles):
            raise InputError("controller", "improper: more zeros than poles")
        # denominators: conjugate pairs and real pairs (degree 2), at most one of degree 1
        pole_groups = sorted(_group(poles), key=len, reverse=True)
        zero_groups = sorted(_group(zeros), key=len, reverse=True)
        sections = [[g, []] for g in pole_groups]
        for zg in zero_groups:  # first-fit; always succeeds for nz <= np (see grouping)
            for sec in sections:
                if len(sec[1]) + len(zg) <= len(sec[0]):
                    sec[1] = sec[1] + zg
                    break
            else:  # pragma: no cover - unreachable by the degree argument
                raise InputError("controller", "cannot realise zeros")
        ss = (np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), np.array([[gain]]))
        for pg, zg in sections:
            num = _real_section(zg) if zg else np.array([1.0])
            ss = _series(ss, _canonical(num, _real_section(pg)))
        return cls(*ss, name=name)

    @classmethod
    def pi(cls, K_P: float, K_I: float, name: str = "") -> LTI:
        """PI controller k(s) = K_P + K_I / s (state: the integral of the error)."""
        K_P = require_finite("K_P", K_P)
        K_I = require_finite("K_I", K_I)
        return cls(np.zeros((1, 1)), np.ones((1, 1)), np.array([[K_I]]), np.array([[K_P]]), name)

    @classmethod
    def pi_lag(cls, gain: float, pi_zero: float, lag_zeros, lag_poles, name: str = "") -> LTI:
        """PI x lag of Amezquita-Brooks et al. (22): gain (s + pi_zero)/s * prod(s - z)/prod(s - p)."""
        pi_zero = require_finite("pi_zero", pi_zero)
        zeros = [-pi_zero] + list(np.atleast_1d(lag_zeros))
        poles = [0.0] + list(np.atleast_1d(lag_poles))
        return cls.zpk(zeros, poles, gain, name=name)

    @classmethod
    def paper_20(cls) -> LTI:
        """Controller (20) of Amezquita-Brooks et al.: 326.5 (s+400)^2 (s+1000) / (s (s^2+100s+42500)).

        The one built-in instance (``PAPER_20``): every call returns the same object, so the ICAD
        reports and the simulator share it."""
        return PAPER_20

    @classmethod
    def gain(cls, k: float, name: str = "") -> LTI:
        """Static gain k(s) = k."""
        return cls(
            np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), [[require_finite("k", k)]], name
        )

    @classmethod
    def from_control(cls, sys, name: str = "") -> LTI:
        """From a python-control SISO continuous-time TransferFunction or StateSpace."""
        import control

        ss = control.ss(sys)
        if ss.ninputs != 1 or ss.noutputs != 1:
            raise InputError("controller", "must be SISO")
        if ss.dt not in (0, None):
            raise InputError("controller", "must be continuous-time (dt = 0)")
        return cls(ss.A, ss.B, ss.C, ss.D, name=name)

    def to_control(self):
        """This controller as a python-control ``StateSpace`` (continuous time; needs the optional
        ``control`` extra). ``control.tf(k.to_control())`` gives the transfer function."""
        return to_control_ss(self.A, self.B, self.C, self.D, 0, self.name)

    # -- properties ---------------------------------------------------------------------------
    @property
    def order(self) -> int:
        return self.A.shape[0]

    def poles(self) -> np.ndarray:
        return np.linalg.eigvals(self.A) if self.order else np.zeros(0, dtype=complex)

    def freqresp(self, w) -> np.ndarray:
        """k(j w) on a validated frequency grid w [rad/s]."""
        from acdrive.control._ss_frequency import check_frequency_grid  # numba: when used

        return self.evaluate(1j * check_frequency_grid(w))

    def evaluate(self, s) -> np.ndarray:
        """k(s) at complex points s (shape (k,))."""
        from acdrive.control._ss_frequency import evaluate_ss  # numba: when used

        return evaluate_ss(self.A, self.B, self.C, self.D, s)[:, 0, 0]

    @property
    def is_stable(self) -> bool:
        """All poles strictly in the open left half-plane."""
        return bool(np.all(self.poles().real < 0.0))

    def rhp_poles(self, tol: float = 1e-9) -> np.ndarray:
        """Poles with Re p > tol * max(1, |p|) (open right half-plane)."""
        p = self.poles()
        return p[p.real > tol * np.maximum(1.0, np.abs(p))]


# ---------------------------------------------------------------------------------------------
# python-control conversion (shared with ``LTIMatrix`` and ``DiscreteLTI``)


def to_control_ss(A, B, C, D, dt, name: str):
    """A python-control ``StateSpace`` of (A, B, C, D) at sampling time ``dt`` (0: continuous);
    python-control is an optional dependency, so its absence is an input error naming it."""
    try:
        import control
    except ImportError:  # pragma: no cover - depends on the environment
        raise InputError(
            "control", "python-control is not installed (pip install 'acdrive[control]')"
        ) from None
    n = np.asarray(A).shape[0]
    p, m = np.asarray(D).shape
    # python-control wants (n x m) B and (p x n) C even when n = 0
    B = np.asarray(B, dtype=float).reshape(n, m)
    C = np.asarray(C, dtype=float).reshape(p, n)
    kwargs = {"name": name} if name else {}
    return control.ss(np.asarray(A, dtype=float).reshape(n, n), B, C, D, dt, **kwargs)


#: the argument rule of a controller: what ``as_lti`` takes
CONTROLLER = Instance(
    LTI, "control:LTI", what="an LTI controller or a python-control TransferFunction/StateSpace"
)


def as_lti(controller, field_name: str = "controller") -> LTI:
    """An ``LTI`` from an ``LTI`` (returned as it is) or a python-control SISO continuous-time
    ``TransferFunction`` / ``StateSpace``; anything else is an ``InputError`` naming the field."""
    if isinstance(controller, LTI):
        return controller
    try:
        import control
    except ImportError:  # pragma: no cover - depends on the environment
        control = None
    if control is not None and isinstance(controller, control.LTI):
        try:
            return LTI.from_control(controller, name=getattr(controller, "name", "") or "")
        except InputError as exc:
            raise InputError(field_name, exc.rule) from None
    raise InputError(
        field_name,
        "must be an LTI controller or a python-control TransferFunction/StateSpace, got "
        f"{type(controller).__name__}",
    )


# ---------------------------------------------------------------------------------------------
# Built-in controllers (Amezquita-Brooks et al.): the single definitions

#: Controller (20) = (22): 326.5 (s + 1000)/s * (s + 400)^2 / (s^2 + 100 s + 42500), the PI
#: (s + 1000)/s cascaded with the lag (s + 400)^2 / ((s + 50)^2 + 200^2).
PAPER_20 = LTI.pi_lag(326.5, 1000.0, [-400.0, -400.0], [-50 + 200j, -50 - 200j], name="paper-20")

#: The stationary-frame PI of sec. VI-D, K_P = 360, K_I = 9000 (crossover of (20), PM >= 45 deg),
#: applied without decoupling or back-EMF compensation (sec. VI).
PAPER_PI = LTI.pi(360.0, 9000.0, name="paper-pi")

#: The inner PI of (22): 326.5 (s + 1000)/s = K_P 326.5, K_I 326 500 (Fig. 19, 20).
PI_OF_22 = LTI.pi_lag(326.5, 1000.0, [], [], name="PI of (22)")

#: Integral gains of the PI family of Fig. 17 (sec. VII), lowest first.
FIG17_K_I = (3e3, 9e3, 3e4, 1e5, 3e5, 6e5, 9e5)
#: Their proportional gains: for each K_I, K_P such that the individual channel c_i (7) with the
#: PI on both loops crosses 0 dB at the crossover of (20) (3343.7 rad/s), DeLorenzo IM with the
#: parameters of (13) at w_r = 375 rad/s (sec. VII: "initially setting integral gain K_I and then
#: adjusting proportional gain K_P so that the desired crossover frequency is obtained"). Solved
#: by brentq (xtol 1e-9) in acdrive._report.icad.pi_comparison, which re-solves and checks them.
FIG17_K_P = (
    346.82834346910863,
    346.81905073525684,
    346.7133968461226,
    345.53752834051744,
    335.0232587104563,
    296.8008365377555,
    218.72536669274623,
)
#: The PI family of Fig. 17 (K_I rising).
FIG17_PI_FAMILY = tuple(
    LTI.pi(kp, ki, name=f"PI K_I = {ki:.0e}") for kp, ki in zip(FIG17_K_P, FIG17_K_I, strict=True)
)
#: The high-integral-gain PI of Fig. 18: the highest-gain member of the family (K_I = 9e5).
FIG18_PI = FIG17_PI_FAMILY[-1]

#: Every built-in controller by name (the same objects as the constants above).
BUILTIN = {
    "paper-20": PAPER_20,
    "paper-pi": PAPER_PI,
    "paper-22-pi": PI_OF_22,
    **{f"fig17-pi-{ki:.0e}".replace("e+0", "e"): k for ki, k in zip(FIG17_K_I, FIG17_PI_FAMILY)},
    "fig18-pi": FIG18_PI,
}


def builtin(name: str) -> LTI:
    """The built-in controller ``name`` (see ``BUILTIN``); the shared object, not a copy."""
    try:
        return BUILTIN[name]
    except (KeyError, TypeError):
        raise InputError(
            "controller", f"unknown built-in '{name}', known: {', '.join(BUILTIN)}"
        ) from None
