"""Batched frequency responses from state-space data, and SISO LTI controllers.

The numerics (``evaluate_ss``: modal path with a Hessenberg fallback, see
``acdrive.control._ss_frequency``) and the controller classes now live in ``acdrive.control``
(``_lti``, ``_lti_matrix``), one layer below the analysis, so that the object the ICAD analysis
evaluates is the very one the simulator discretises and runs (``acdrive.control._current``).
They are re-exported here under their old names; ``freqresp_ss`` is the analysis-side
convenience on a validated grid.
"""

from __future__ import annotations

from acdrive._arguments import Array, checked
from acdrive.control._lti import LTI, _canonical, _group, _real_section, _series
from acdrive.control._lti_matrix import LTIMatrix
from acdrive.control._ss_frequency import (
    CANCEL_LIMIT,
    EIG_COND_LIMIT,
    _hessenberg_solve,
    _modal_sum,
    check_frequency_grid,
)
from acdrive.control._ss_frequency import evaluate_ss as _evaluate_ss

#: G(s) of batched state-space data (``acdrive.control._ss_frequency.evaluate_ss``), its
#: arguments checked (a model without states has empty A, B, C)
evaluate_ss = checked(
    A=Array(empty=True), B=Array(empty=True), C=Array(empty=True), D=Array(),
    s=Array((0, 1), complex=True),
)(_evaluate_ss)

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
