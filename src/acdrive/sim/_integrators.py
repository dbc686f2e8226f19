"""The explicit Runge-Kutta methods the compiled loop integrates each held-input segment with, each
a Butcher tableau with the order its arithmetic is written in (``Tableau``). Every loop's step,
numba's single and lockstep loops and the C of the native tier and of the plant export, is this
tableau expanded by ``sim._rk_source``."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Tableau:
    """An explicit Runge-Kutta method: nodes ``c``, coefficient rows ``a`` (stage i evaluates the
    derivative at t + c_i h and x + h sum_j a_ij k_j, j < i) and weights ``b`` over ``divisor``
    (the step is x + h / divisor * sum_j b_j k_j; no divisor: x + h * sum_j b_j k_j).
    ``scaled_rows``: a row with one coefficient a is written x + a h k_j (the coefficient scales
    the step) rather than x + h (a k_j). Both choices fix the rounding of every stage, which is
    why they are part of the method here."""

    order: int
    c: tuple[float, ...]
    a: tuple[tuple[float, ...], ...]
    b: tuple[float, ...]
    divisor: float | None = None
    scaled_rows: bool = False

    @property
    def stages(self) -> int:
        """Right-hand-side evaluations per step."""
        return len(self.b)


#: The classical fourth-order method (Kutta 1901), written x + (h/2) k_1, x + (h/2) k_2,
#: x + h k_3 and x + h/6 (k_1 + 2 k_2 + 2 k_3 + k_4): the rounding the DFIM results were
#: established with.
RK4 = Tableau(
    order=4,
    c=(0.0, 0.5, 0.5, 1.0),
    a=((), (0.5,), (0.0, 0.5), (0.0, 0.0, 1.0)),
    b=(1.0, 2.0, 2.0, 1.0),
    divisor=6.0,
    scaled_rows=True,
)

#: Butcher's explicit seven-stage Runge-Kutta method of order six (J. C. Butcher, *Numerical
#: Methods for Ordinary Differential Equations*, the rational-coefficient example of section 32).
RK6 = Tableau(
    order=6,
    c=(0.0, 1 / 3, 2 / 3, 1 / 3, 1 / 2, 1 / 2, 1.0),
    a=(
        (),
        (1 / 3,),
        (0.0, 2 / 3),
        (1 / 12, 1 / 3, -1 / 12),
        (-1 / 16, 9 / 8, -3 / 16, -3 / 8),
        (0.0, 9 / 8, -3 / 8, -3 / 4, 1 / 2),
        (9 / 44, -9 / 11, 63 / 44, 18 / 11, 0.0, -16 / 11),
    ),
    b=(11 / 120, 0.0, 27 / 40, 27 / 40, -4 / 15, -4 / 15, 11 / 120),
)
RK6_C, RK6_A, RK6_B = RK6.c, RK6.a, RK6.b

#: The methods by name: ``rk4`` is the default (the DFIM results were established with it);
#: ``rk6`` takes 7/4 the work per step for two orders more, so one ``rk6`` step per segment
#: replaces several ``rk4`` substeps where the segments are short against the machine's time
#: constants (the switching inverter's) and rounds off fewer times. Caveat: ``rk6``'s stability
#: region leaves out the imaginary axis (an undamped rotation at h omega = 1 grows by 5e-4 per
#: step, at 0.1 by 6e-12), which RK4's includes up to h omega = 2.8; keep h omega of undamped
#: modes small.
METHODS = {"rk4": RK4, "rk6": RK6}

#: name -> (order, right-hand-side evaluations per step)
INTEGRATORS = {name: (m.order, m.stages) for name, m in METHODS.items()}
