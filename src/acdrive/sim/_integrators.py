"""The explicit Runge-Kutta methods the compiled loop integrates each held-input segment with."""

from __future__ import annotations

#: Butcher's explicit seven-stage Runge-Kutta method of order six (J. C. Butcher, *Numerical
#: Methods for Ordinary Differential Equations*, the rational-coefficient example of section 32):
#: nodes c, coefficient rows a (stage i uses a[i][j] k_j, j < i) and weights b.
RK6_C = (0.0, 1 / 3, 2 / 3, 1 / 3, 1 / 2, 1 / 2, 1.0)
RK6_A = (
    (),
    (1 / 3,),
    (0.0, 2 / 3),
    (1 / 12, 1 / 3, -1 / 12),
    (-1 / 16, 9 / 8, -3 / 16, -3 / 8),
    (0.0, 9 / 8, -3 / 8, -3 / 4, 1 / 2),
    (9 / 44, -9 / 11, 63 / 44, 18 / 11, 0.0, -16 / 11),
)
RK6_B = (11 / 120, 0.0, 27 / 40, 27 / 40, -4 / 15, -4 / 15, 11 / 120)

#: Integration methods per held-input segment: name -> (order, right-hand-side evaluations per
#: step). ``rk4`` is the default (the DFIM results were established with it); ``rk6`` takes
#: 7/4 the work per step for two orders more, so one ``rk6`` step per segment replaces several
#: ``rk4`` substeps where the segments are short against the machine's time constants (the
#: switching inverter's) and rounds off fewer times. Caveat: ``rk6``'s stability region leaves
#: out the imaginary axis (an undamped rotation at h omega = 1 grows by 5e-4 per step, at 0.1 by
#: 6e-12), which RK4's includes up to h omega = 2.8; keep h omega of undamped modes small.
INTEGRATORS = {"rk4": (4, 4), "rk6": (6, 7)}
