"""The frequency-response kernels as ``acdrive.analysis`` offers them: ``evaluate_ss``
(``acdrive.control._ss_frequency``) and ``icad_quantities`` (``analysis._icad_frequency``) with
their arguments checked (``acdrive._arguments``). acdrive's own code calls the kernels unchecked:
its inner loops evaluate them many times, some at a pole on the axis (an infinite value is then
a result, not an input error)."""

from __future__ import annotations

from acdrive._arguments import Array, checked
from acdrive.analysis._icad_frequency import icad_quantities as _icad_quantities
from acdrive.control._ss_frequency import evaluate_ss as _evaluate_ss

#: G(s) of batched state-space data; a model without states has empty A, B, C
evaluate_ss = checked(
    A=Array(empty=True), B=Array(empty=True), C=Array(empty=True), D=Array(),
    s=Array((0, 1), complex=True),
)(_evaluate_ss)

#: the ICAD quantities of plant values G (..., 2, 2) and controller values k1, k2
icad_quantities = checked(
    G=Array(complex=True), k1=Array(complex=True), k2=Array(complex=True)
)(_icad_quantities)
