"""The constants of acdrive's sine and cosine (``sim._lane_math.sincos``), without numba: the
exported C (``sim._ccode._prelude``) writes the same numbers into its ``acd_sincos``, and a
native run imports no numba."""

from __future__ import annotations

import math

#: pi/2 = PIO2_PARTS[0] + ... + PIO2_PARTS[3] to 2e-43: the first three rounded to 27 significant
#: bits (exact products with any whole k below 2^26), the last the rest rounded to a double
#: (computed from 110 digits of pi with exact rational arithmetic; tests/test_lane_math.py
#: checks the sum and the bit counts)
PIO2_PARTS = (1.570796325802803, 9.920935739593517e-10, 5.721188709663575e-18,
              1.6446256936324258e-26)  # fmt: skip
TWO_OVER_PI = 2.0 / math.pi
#: Taylor coefficients of sin (r^3 .. r^17) and cos (r^4 .. r^18): (-1)^n / n!
SINE_TERMS = tuple((-1) ** n / math.factorial(2 * n + 1) for n in range(1, 9))
COSINE_TERMS = tuple((-1) ** n / math.factorial(2 * n) for n in range(2, 10))
#: |k| below which the whole multiple k of pi/2 converts to an integer for its quadrant
QUADRANT_LIMIT = 4.0e18
#: |x| up to which the reduction's products are exact (sim._lane_math's docstring)
EXACT_REDUCTION_LIMIT = 1e8
