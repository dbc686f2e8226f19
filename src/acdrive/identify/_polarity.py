"""The current sign the inverter's voltage error follows during a standstill injection.

The inverter loses U sign(i_a) of the phase-a voltage each carrier period, the sign that of the
current at the period's sample instant (``plant._inverter``; ``identify._dc``). A compensation
needs that sign. The sign of the logged reading is wrong wherever the current lies within a few
noise deviations of zero, and near a zero crossing the dead time clamps the current there: the
inverter's polarity flips between neighbouring samples, a pattern no filtering of the noisy
reading recovers. The fitted circuit does recover it: the exact sampled model of the winding at
standstill (``identify._circuit``),

    x_{k+1} = Phi x_k + Gamma (v_k - U s_k),   i_k = C x_k,   s_k = sign(i_k),

run over the logged command v_k from rest (the settling time lets the log's own start be
forgotten), with C the sampling row of ``_circuit.sampled_admittance`` (dead time included).
Its s_k is the inverter's polarity as far as the fitted parameters are right; it carries no
sensor noise.
"""

from __future__ import annotations

import numpy as np

from acdrive.identify._circuit import _expm_2x2, standstill_state_space


def simulated_polarity(values, v: np.ndarray, hold: float, voltage_error: float,
                       dead_time: float = 0.0) -> np.ndarray:  # fmt: skip
    """s_k = sign(i_k) of the inverse-Gamma circuit ``values`` (R_s, L_sigma, R_R, L_M) fed the
    command ``v`` [V] held over periods ``hold`` [s] less ``voltage_error`` [V] times the sign
    (module docstring), from rest; the inverter's dead time ``dead_time`` [s] moves the sample
    t_d / 2 early (``_circuit.sampled_admittance``)."""
    A, B = standstill_state_space(values)
    Phi = _expm_2x2(A, hold)
    Gamma = np.linalg.solve(A, (Phi - np.eye(2)) @ B)
    C = _expm_2x2(A, -0.5 * dead_time)[0] if dead_time > 0.0 else np.array([1.0, 0.0])
    p00, p01, p10, p11 = (float(x) for x in Phi.ravel())
    g0, g1 = float(Gamma[0]), float(Gamma[1])
    c0, c1 = float(C[0]), float(C[1])
    U = float(voltage_error)
    signs = np.empty(v.size)
    x0 = x1 = 0.0
    for k, command in enumerate(v.tolist()):
        current = c0 * x0 + c1 * x1
        s = 1.0 if current > 0.0 else (-1.0 if current < 0.0 else 0.0)
        signs[k] = s
        applied = command - U * s
        x0, x1 = p00 * x0 + p01 * x1 + g0 * applied, p10 * x0 + p11 * x1 + g1 * applied
    return signs
