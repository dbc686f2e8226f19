"""A p x m linear controller (``LTIMatrix``): a grid of SISO ``LTI`` entries (``diagonal(k_1,
k_2)`` for the decentralised controllers of Amezquita-Brooks et al., u_i = k_i e_i) or a general
MIMO state space (``ss``), with its poles and batched frequency response.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from acdrive.control._lti import LTI, to_control_ss
from acdrive.control._ss_frequency import check_frequency_grid, evaluate_ss
from acdrive.errors import InputError


def _matrix(field_name: str, value, shape: tuple[int | None, int | None]) -> np.ndarray:
    """A finite real 2-D array of the given shape (None: any size), read-only."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(field_name, "must be a real matrix") from None
    if arr.ndim != 2:
        raise InputError(field_name, f"must be a 2-D matrix, got {arr.ndim} dimension(s)")
    for axis, want in enumerate(shape):
        if want is not None and arr.shape[axis] != want:
            raise InputError(
                field_name,
                f"has shape {arr.shape[0]} x {arr.shape[1]}; "
                f"{'rows' if axis == 0 else 'columns'} must be {want}",
            )
    if not np.all(np.isfinite(arr)):
        raise InputError(field_name, "must be finite")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class LTIMatrix:
    """A real p x m continuous-time controller u = K(s) e, K(s) = C (s I - A)^-1 B + D.

    Built from SISO entries (``grid``, ``diagonal``: ``entries`` then holds the very ``LTI``
    objects, e.g. the k_1, k_2 that the ICAD analysis takes, and ``K[i, j]`` returns them) or as
    a general MIMO state space (``ss``; no entries). The realisation of a grid stacks the states
    of its entries, row by row.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    entries: tuple | None = field(default=None, repr=False)
    name: str = ""

    def __post_init__(self):
        A = _matrix("controller.A", self.A, (None, None))
        n = A.shape[0]
        if A.shape[1] != n:
            raise InputError("controller.A", f"must be square, got {A.shape[0]} x {A.shape[1]}")
        D = _matrix("controller.D", self.D, (None, None))
        p, m = D.shape
        if p == 0 or m == 0:
            raise InputError("controller.D", "needs at least one output and one input")
        object.__setattr__(self, "A", A)
        object.__setattr__(self, "B", _matrix("controller.B", self.B, (n, m)))
        object.__setattr__(self, "C", _matrix("controller.C", self.C, (p, n)))
        object.__setattr__(self, "D", D)

    # -- constructors ------------------------------------------------------------------------
    @classmethod
    def ss(cls, A, B, C, D, name: str = "") -> LTIMatrix:
        """General MIMO state space: A n x n, B n x m, C p x n, D p x m (n may be 0)."""
        D = np.atleast_2d(np.asarray(D, dtype=float))
        A = np.asarray(A, dtype=float)
        A = np.atleast_2d(A) if A.size else np.zeros((0, 0))
        n = A.shape[0]
        B = np.asarray(B, dtype=float)
        B = np.atleast_2d(B) if B.size else np.zeros((n, D.shape[1]))
        C = np.asarray(C, dtype=float)
        C = np.atleast_2d(C) if C.size else np.zeros((D.shape[0], n))
        return cls(A, B, C, D, name=name)

    @classmethod
    def from_control(cls, sys, name: str = "") -> LTIMatrix:
        """From a python-control continuous-time ``StateSpace`` or ``TransferFunction`` (any
        number of inputs and outputs)."""
        import control

        ss = control.ss(sys)
        if ss.dt not in (0, None):
            raise InputError("controller", "must be continuous-time (dt = 0)")
        return cls.ss(ss.A, ss.B, ss.C, ss.D, name=name or getattr(sys, "name", "") or "")

    def to_control(self):
        """This controller as a python-control ``StateSpace`` (continuous time)."""
        return to_control_ss(self.A, self.B, self.C, self.D, 0, self.name)

    @classmethod
    def grid(cls, rows, name: str = "") -> LTIMatrix:
        """K(s) with entries K[i][j] = ``rows[i][j]``: an ``LTI``, a number (static gain) or None
        (zero). The ``LTI`` entries are kept as they are (same objects)."""
        if not isinstance(rows, (list, tuple)) or not rows:
            raise InputError("controller", "must be a non-empty list of rows of SISO entries")
        width = None
        kept = []
        for i, row in enumerate(rows):
            if not isinstance(row, (list, tuple)) or not row:
                raise InputError(f"controller[{i}]", "must be a non-empty row of entries")
            if width is None:
                width = len(row)
            elif len(row) != width:
                raise InputError(
                    f"controller[{i}]", f"has {len(row)} entries; every row must have {width}"
                )
            out_row = []
            for j, entry in enumerate(row):
                if entry is None or isinstance(entry, LTI):
                    out_row.append(entry)
                elif isinstance(entry, (int, float)) and not isinstance(entry, bool):
                    out_row.append(None if entry == 0 else LTI.gain(entry))
                else:
                    raise InputError(
                        f"controller[{i}][{j}]",
                        f"must be an LTI, a number or None, got {type(entry).__name__}",
                    )
            kept.append(tuple(out_row))
        p, m = len(kept), width
        blocks = [(i, j, k) for i, row in enumerate(kept) for j, k in enumerate(row) if k]
        n = sum(k.order for _, _, k in blocks)
        A, B, C, D = np.zeros((n, n)), np.zeros((n, m)), np.zeros((p, n)), np.zeros((p, m))
        at = 0
        for i, j, k in blocks:
            sl = slice(at, at + k.order)
            A[sl, sl] = k.A
            B[sl, j] = k.B[:, 0]
            C[i, sl] = k.C[0, :]
            D[i, j] = k.D[0, 0]
            at += k.order
        return cls(A, B, C, D, entries=tuple(kept), name=name)

    @classmethod
    def diagonal(cls, *ks: LTI, name: str = "") -> LTIMatrix:
        """diag(k_1, ..., k_n): decentralised control u_i = k_i e_i (Amezquita-Brooks et al. (5),
        no decoupling); ``diagonal(k, k)`` applies the same controller to both axes."""
        if not ks:
            raise InputError("controller", "diagonal needs at least one entry")
        for i, k in enumerate(ks):
            if not isinstance(k, LTI):
                raise InputError(f"controller[{i}]", f"must be an LTI, got {type(k).__name__}")
        size = len(ks)
        return cls.grid(
            [[ks[i] if i == j else None for j in range(size)] for i in range(size)], name
        )

    @classmethod
    def of(cls, controller) -> LTIMatrix:
        """``controller`` as a matrix: an ``LTIMatrix`` as it is, an ``LTI`` as a 1 x 1 grid."""
        if isinstance(controller, LTIMatrix):
            return controller
        if isinstance(controller, LTI):
            return cls.grid([[controller]], name=controller.name)
        raise InputError(
            "controller", f"must be an LTI or an LTIMatrix, got {type(controller).__name__}"
        )

    # -- properties ---------------------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, int]:
        """(outputs, inputs)."""
        return self.D.shape

    @property
    def order(self) -> int:
        return self.A.shape[0]

    def __getitem__(self, index) -> LTI | None:
        """The SISO entry K[i, j] of a grid (the same object it was built from; None: zero)."""
        if self.entries is None:
            raise InputError("controller", "a general state-space matrix has no SISO entries")
        i, j = index
        return self.entries[i][j]

    @property
    def is_diagonal(self) -> bool:
        """A square grid with zero off-diagonal entries."""
        p, m = self.shape
        return (
            self.entries is not None
            and p == m
            and all(self.entries[i][j] is None for i in range(p) for j in range(m) if i != j)
        )

    def diagonal_entries(self) -> tuple[LTI, ...]:
        """(k_1, ..., k_n) of a diagonal grid (the objects ICAD's ``analyse(plant, k_1, k_2)``
        takes); a zero diagonal entry is returned as a zero gain."""
        if not self.is_diagonal:
            raise InputError("controller", "is not a diagonal grid of SISO entries")
        return tuple(
            self.entries[i][i] if self.entries[i][i] is not None else LTI.gain(0.0)
            for i in range(self.shape[0])
        )

    def poles(self) -> np.ndarray:
        return np.linalg.eigvals(self.A) if self.order else np.zeros(0, dtype=complex)

    @property
    def is_stable(self) -> bool:
        return bool(np.all(self.poles().real < 0.0))

    def evaluate(self, s) -> np.ndarray:
        """K(s) at complex points s: shape (k, p, m)."""
        return evaluate_ss(self.A, self.B, self.C, self.D, s)

    def freqresp(self, w) -> np.ndarray:
        """K(j w) on a validated frequency grid w [rad/s]: shape (k, p, m)."""
        return self.evaluate(1j * check_frequency_grid(w))
