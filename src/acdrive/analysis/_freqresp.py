"""Batched frequency responses from state-space data, and SISO LTI controllers.

The numerics (``evaluate_ss``: modal path with a Hessenberg fallback, see
``acdrive.control._ss_frequency``) and the controller classes now live in ``acdrive.control``
(``_lti``, ``_lti_matrix``), one layer below the analysis, so that the object the ICAD analysis
evaluates is the very one the simulator discretises and runs (``acdrive.control._current``).
They are re-exported here under their old names; ``freqresp_ss`` is the analysis-side
convenience on a validated grid.
"""

from __future__ import annotations

from acdrive.control._lti import LTI, _canonical, _group, _real_section, _series
from acdrive.control._lti_matrix import LTIMatrix
from acdrive.control._ss_frequency import (
    CANCEL_LIMIT,
    EIG_COND_LIMIT,
    _hessenberg_solve,
    _modal_sum,
    check_frequency_grid,
    evaluate_ss,
)

__all__ = [
    "CANCEL_LIMIT",
    "EIG_COND_LIMIT",
    "LTI",
    "LTIMatrix",
    "_canonical",
    "_group",
    "_hessenberg_solve",
    "_modal_sum",
    "_real_section",
    "_series",
    "check_frequency_grid",
    "evaluate_ss",
    "freqresp_ss",
]


def freqresp_ss(A, B, C, D, w):
    """G(j w) for batched state-space data on a validated grid w [rad/s]; see ``evaluate_ss``."""
    return evaluate_ss(A, B, C, D, 1j * check_frequency_grid(w))
