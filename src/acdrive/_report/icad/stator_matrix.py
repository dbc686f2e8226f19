"""The stator-current matrices printed by both papers, entry by entry: Ugalde-Loo et al. (80)
and Amezquita-Brooks et al. (13) against the state-space model (Ugalde-Loo (41),
Amezquita-Brooks (1)) built with a given parameter set, each entry with a verdict to the
printed digits.

Used by the sections on the 300 W IM (``acdrive._report.icad.ugalde_im``) and on the DeLorenzo
IM (``acdrive._report.icad.delorenzo``).
"""

from __future__ import annotations

from acdrive._report import icad_targets as targets
from acdrive._report.icad.common import printed_digits
from acdrive._report.markdown import Row, fmt
from acdrive._verdicts import Verdict
from acdrive.machines._induction import IMParams, stator_current_ss


def matrix_entry_rows(
    label: str, printed: targets.PrintedIMMatrix, params: IMParams
) -> tuple[list[Row], dict[str, Verdict]]:
    """Rows of the printed matrix entries against (41) / (1) with ``params``, and each entry's
    verdict (to the printed digits) by name."""
    A, B, _, _ = stator_current_ss(params, 1.0)
    comp = {
        "a11": A[0, 0],
        "a13": A[0, 2],
        "a14_per_w": A[0, 3],
        "a31": A[2, 0],
        "a33": A[2, 2],
        "b": B[0, 0],
    }
    names = {
        "a11": "a_11 = -(L_r^2 R_s + L_m^2 R_r)/(sigma L_s L_r^2)",
        "a13": "a_13 = L_m R_r/(sigma L_s L_r^2)",
        "a14_per_w": "a_14 / w_r = L_m/(sigma L_s L_r)",
        "a31": "a_31 = L_m R_r / L_r",
        "a33": "a_33 = -R_r / L_r",
        "b": "b_11 = 1/(sigma L_s)",
    }
    rows, verdicts = [], {}
    for key, name in names.items():
        pv = targets.printed_text(getattr(printed, key))
        verdicts[key] = printed_digits(pv, comp[key])
        rows.append(
            Row(
                f"{name} ({label})",
                f"{printed.paper} {printed.where}",
                pv,
                fmt(comp[key], 5),
                str(verdicts[key]),
            )
        )
    return rows, verdicts


#: Short names of the matrix entries for sentences.
ENTRY_NAMES = {
    "a11": "a_11",
    "a13": "a_13",
    "a14_per_w": "a_14",
    "a31": "a_31",
    "a33": "a_33",
    "b": "b_11",
}


def entries_with_verdict(verdicts: dict[str, Verdict], holding: bool) -> str:
    """The short names of the entries whose verdict holds (``holding``) or fails, for a
    sentence ('none' if there are none)."""
    names = [ENTRY_NAMES[k] for k, v in verdicts.items() if v.holds == holding]
    return ", ".join(names) if names else "none"
