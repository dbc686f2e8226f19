"""The Jacobian of a continuous part's compiled kernels at an operating point, with a bound on its
rounding error.

A continuous part (``core._parts.ContinuousPart``) is evaluated as the integrator evaluates it in
one stage: ``state_outputs(t, x, p, y)``, then ``direct_outputs(t, x, u, p, y)`` if the part has
one, then ``rhs(t, x, u, p, y, dx)``, which may read the outputs of the same evaluation. Those
compiled kernels (the functions ``part.kernels()`` hands to the code generator, fast-math as in
the integrator) are evaluated here at (x0 +- h_j e_j, u0) and (x0, u0 +- h_j e_j), and give

    A = d dx / dx,   B = d dx / du,   C = d y / dx,   D = d y / du

by central differences, in the part's own coordinates (its ``STATES``, ``INPUTS`` and
``OUTPUTS`` slots; a complex quantity is two real coordinates, real part first).

**Truncation.** The central difference of a function at most quadratic in the differenced
coordinate is exact: for f = a + b x + c x^2, (f(x + h) - f(x - h)) / 2h = b + 2 c x = f'(x) for
every h. The machine kernels are such in every coordinate (currents, fluxes and voltages enter
linearly; the speed multiplies a flux or a current; a torque is the product of two currents or a
current and a flux; the rotor phasor multiplies a voltage or a current), so the step is chosen
for rounding alone: h_j = ``relative_step`` max(|z_j|, ``scale``) with ``relative_step`` = 1 by
default, the larger the step the smaller the rounding error. A kernel that is not polynomial of
degree two at most in a coordinate (a DFIM's converter loss V_loss > 0, a saturating inductance)
has a truncation error of order h^2 f''' that this bound does not cover: give it a small
``relative_step``.

**Rounding.** With IEEE arithmetic (the fast-math flags of ``acdrive._jit`` allow neither
reassociation nor contraction) an evaluation of output i through at most n rounded operations
errs by at most gamma_n m_i, gamma_n = n u / (1 - n u), u = 2^-53, m_i the sum of the magnitudes
of the terms it adds (Higham, Accuracy and Stability of Numerical Algorithms, 2nd ed., sec. 3.1).
For a function at most quadratic in each coordinate, with J = [A B] and z = (x, u), the terms at
z0 are bounded by m_i = sum_k |J_ik z_k| + |r_i|, r = f(z0) - J z0 (for a product x y the term
is x y and J z = 2 x y); at z0 +- h_j e_j they grow by at most |J_ij| h_j + q_ij, q_ij =
|f_i(z0 + h_j e_j) + f_i(z0 - h_j e_j) - 2 f_i(z0)| / 2 the quadratic part. The difference
quotient of column j thus errs by at most gamma_n (|J_ij| + (m_i + q_ij) / h_j) through the two
evaluations, and by gamma_n kappa |J_ij| through the coefficients the kernel computes from its
parameters, kappa the relative condition number of that computation (1 for products and
quotients, (|a| + |b|) / |a - b| for a difference a - b such as a leakage inductance). The entry
bound of :meth:`KernelJacobian.bounds` is gamma_n (kappa + 1) (|J_ij| + (m_i + q_ij) / h_j), which
covers both. A model computed from the same parameters through at most n operations with the same
kappa rounds within it too, so a comparison of a model with the kernel allows twice the bound.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acdrive.core._parts import ContinuousPart

#: unit roundoff of float64
UNIT_ROUNDOFF = 2.0**-53
#: the rounded operations counted on the path of one entry (kernel and transformation): more
#: than the longest path of the machine kernels (the cage IM's di_s/dt, about 25)
OPERATIONS = 32


def gamma(n: int = OPERATIONS) -> float:
    """gamma_n = n u / (1 - n u): the relative error bound of n rounded operations."""
    return n * UNIT_ROUNDOFF / (1.0 - n * UNIT_ROUNDOFF)


@dataclass(frozen=True)
class KernelJacobian:
    """The Jacobian of one continuous part at (x0, u0) (module docstring): ``A`` (dx/x), ``B``
    (dx/u), ``C`` (y/x), ``D`` (y/u), the values ``dx`` and ``y`` there, the steps ``h_x``,
    ``h_u`` of the columns and the quadratic parts q of every entry (``curvature``, keys "A" to
    "D"). Rows and columns are the part's layout slots; :meth:`subsystem`
    picks them by name."""

    part: ContinuousPart
    x: np.ndarray
    u: np.ndarray
    dx: np.ndarray
    y: np.ndarray
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    h_x: np.ndarray
    h_u: np.ndarray
    curvature: dict

    @staticmethod
    def slots(layout, names) -> list[int]:
        """The slots of the quantities ``names`` of ``layout``, two for a complex one."""
        out = []
        for name in names:
            start = layout.slot(name)
            out += list(range(start, start + layout.var(name).width))
        return out

    def subsystem(self, states, inputs, outputs, kappa: float = 1.0, n: int = OPERATIONS):
        """(matrices, bounds, rest) of the block with the named ``states``, ``inputs`` and
        ``outputs``: ``matrices`` and ``bounds`` map "A", "B", "C", "D" to the block and its
        rounding bound (:meth:`bounds`), ``rest`` is dx - A x - B u of the block at the point
        (what the other states and inputs and any constant term contribute)."""
        every = self.bounds(kappa, n)
        rows = {"A": states, "B": states, "C": outputs, "D": outputs}
        cols = {"A": states, "B": inputs, "C": states, "D": inputs}
        matrices, bounds = {}, {}
        for k in "ABCD":
            row_layout = self.part.STATES if k in "AB" else self.part.OUTPUTS
            col_layout = self.part.STATES if k in "AC" else self.part.INPUTS
            at = np.ix_(self.slots(row_layout, rows[k]), self.slots(col_layout, cols[k]))
            matrices[k], bounds[k] = getattr(self, k)[at], every[k][at]
        x = self.x[self.slots(self.part.STATES, states)]
        u = self.u[self.slots(self.part.INPUTS, inputs)]
        rest = self.dx[self.slots(self.part.STATES, states)] - matrices["A"] @ x
        return matrices, bounds, rest - matrices["B"] @ u

    def bounds(self, kappa: float = 1.0, n: int = OPERATIONS) -> dict[str, np.ndarray]:
        """The entrywise rounding bounds of A, B, C, D (module docstring):
        gamma_n (kappa + 1) (|J_ij| + (m_i + q_ij) / h_j), m_i the term magnitude of row i."""
        g = gamma(n)
        z = np.abs(np.concatenate([self.x, self.u]))
        h = np.concatenate([self.h_x, self.h_u])
        out = {}
        for rows, value in (("AB", self.dx), ("CD", self.y)):
            J = np.hstack([getattr(self, rows[0]), getattr(self, rows[1])])
            rest = value - J @ np.concatenate([self.x, self.u])
            m = np.abs(J) @ z + np.abs(rest)
            q = np.hstack([self.curvature[rows[0]], self.curvature[rows[1]]])
            bound = g * (kappa + 1.0) * (np.abs(J) + (m[:, None] + q) / h[None, :])
            out[rows[0]], out[rows[1]] = bound[:, : self.x.size], bound[:, self.x.size :]
        return out


def _evaluate(part: ContinuousPart, kernels: dict, t: float, x, u, y, dx) -> None:
    """One evaluation of the part as the integrator's stage does it (module docstring)."""
    y[:] = 0.0
    kernels["state_outputs"](t, x, part.p, y)
    if "direct_outputs" in kernels:
        kernels["direct_outputs"](t, x, u, part.p, y)
    kernels["rhs"](t, x, u, part.p, y, dx)


def kernel_jacobian(part: ContinuousPart, states: dict, inputs: dict, t: float = 0.0,
                    relative_step: float = 1.0, scale: float = 1.0) -> KernelJacobian:  # fmt: skip
    """The :class:`KernelJacobian` of ``part`` at the state ``states`` and the input ``inputs``
    (name -> value, complex for a complex quantity; states not named take the part's initial
    values, every input must be named), at time ``t``; step h_j = ``relative_step``
    max(|z_j|, ``scale``) (module docstring)."""
    x0 = part.initial_state(**states)
    u0 = part.INPUTS.pack(f"{part.name} inputs", inputs)
    kernels = part.kernels()
    y = np.zeros(part.OUTPUTS.size())
    dx = np.zeros_like(x0)
    _evaluate(part, kernels, t, x0, u0, y, dx)
    dx0, y0 = dx.copy(), y.copy()

    def columns(z0, other, is_state):
        h = relative_step * np.maximum(np.abs(z0), scale)
        cols_dx, cols_y, bend_dx, bend_y = [], [], [], []
        for j in range(z0.size):
            zp, zm = z0.copy(), z0.copy()
            zp[j] += h[j]
            zm[j] -= h[j]
            step = zp[j] - zm[j]  # the step the arguments carry, rounded as they are
            values = []
            for z in (zp, zm):
                x, u = (z, other) if is_state else (other, z)
                _evaluate(part, kernels, t, x, u, y, dx)
                values.append((dx.copy(), y.copy()))
            (dx_p, y_p), (dx_m, y_m) = values
            cols_dx.append((dx_p - dx_m) / step)
            cols_y.append((y_p - y_m) / step)
            bend_dx.append(np.abs(dx_p + dx_m - 2.0 * dx0) / 2.0)
            bend_y.append(np.abs(y_p + y_m - 2.0 * y0) / 2.0)
        stack = np.column_stack
        return stack(cols_dx), stack(cols_y), h, stack(bend_dx), stack(bend_y)

    A, C, h_x, q_A, q_C = columns(x0, u0, True)
    B, D, h_u, q_B, q_D = columns(u0, x0, False)
    curvature = {"A": q_A, "B": q_B, "C": q_C, "D": q_D}
    return KernelJacobian(part, x0, u0, dx0, y0, A, B, C, D, h_x, h_u, curvature)
