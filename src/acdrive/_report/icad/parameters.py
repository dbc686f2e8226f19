"""Report section 'Machine parameters': the parameters printed by both papers against
acdrive's built-in machines.

The 2 MW PMSG of Ugalde-Loo et al. sec. 3.5, the 300 W IM of Ugalde-Loo et al. sec. 4.5 and the
DeLorenzo IM of the Amezquita-Brooks et al. Appendix (printed as P = 2 poles, i.e. n_p = 1),
plus the parameter set acdrive derives from Amezquita-Brooks et al. matrix (13)
(``delorenzo-im-13``, discussed in ``acdrive._report.icad.delorenzo``).
"""

from __future__ import annotations

from acdrive._report import icad_targets as targets
from acdrive._report.icad.common import EXACT_REL_TOL, within_rel
from acdrive._report.markdown import Row, Section, fmt
from acdrive.machines._induction import DELORENZO_IM, DELORENZO_IM_13, UGALDE_IM_300W
from acdrive.machines._pmsm import PMSG_2MW


def section_parameters() -> Section:
    """Printed machine parameters against acdrive's built-in machines."""
    s = Section("Machine parameters")
    s.text = (
        "The built-in machines of `acdrive.analysis._plants` against the printed parameters. "
        "seed 002 prints P = 2 poles, i.e. n_p = 1."
    )
    for label, printed, params in (
        ("pmsg-2mw", targets.PMSG_2MW_PRINTED, PMSG_2MW),
        ("ugalde-im-300w", targets.UGALDE_IM_PRINTED, UGALDE_IM_300W),
        ("delorenzo-im", targets.DELORENZO_APPENDIX_PRINTED, DELORENZO_IM),
    ):
        for key, pv in printed.items():
            if key == "f":
                continue
            attr = "n_p" if key == "P" else key
            value = getattr(params, attr)
            expected = pv.value / 2 if key == "P" else pv.value
            note = ("P/2 = n_p: " if key == "P" else "") + str(
                within_rel(value, expected, EXACT_REL_TOL)
            )
            if pv.text:
                note = (note + "; " if note else "") + pv.text
            s.rows.append(
                Row(
                    f"{label}: {key}",
                    f"{pv.paper} {pv.where}",
                    f"{fmt(pv.value, 6)} {pv.unit}",
                    fmt(value, 6),
                    note,
                )
            )
    s.rows.append(
        Row(
            "delorenzo-im-13",
            "derived from (13)",
            "-",
            ", ".join(
                f"{k} = {fmt(getattr(DELORENZO_IM_13, k), 5)}"
                for k in ("R_s", "R_r", "L_s", "L_r", "L_m")
            ),
            "see the seed 002 section",
        )
    )
    return s
