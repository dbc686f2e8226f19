"""What every induction machine part shares: its winding parameters and their rules.

Both the cage IM (Amezquita-Brooks et al. (1)) and the DFIM (Bodson (9)) are a stator and a rotor
winding with resistances, self inductances, a mutual inductance and a pole-pair count; only the
mutual inductance's symbol differs (L_m, M). The value rules are declared (``core._signals``); the
cross-field rule sigma > 0 is ``errors.require_leakage``, shared with ``IMParams``/``DFIMParams``.
"""

from __future__ import annotations

from acdrive.core._parts import ContinuousPart
from acdrive.core._signals import Layout, real
from acdrive.errors import require_leakage


def winding_params(mutual: str, mutual_doc: str) -> Layout:
    """R_s, R_r, L_s, L_r, ``mutual``, n_p in this order (the order of ``machines._dfim``'s
    parameter vector, whose compiled functions the DFIM part reuses)."""
    return Layout(
        real("R_s", "ohm", "stator resistance", "positive"),
        real("R_r", "ohm", "rotor resistance referred to the stator", "positive"),
        real("L_s", "H", "stator self inductance", "positive"),
        real("L_r", "H", "rotor self inductance", "positive"),
        real(mutual, "H", mutual_doc, "positive"),
        real("n_p", "", "pole pairs", "count"),
    )


class InductionWindings(ContinuousPart):
    """Base of the induction machine parts: checks sigma = 1 - mutual^2/(L_s L_r) > 0."""

    MUTUAL = ""

    def check(self):
        v = self.values
        require_leakage(f"{self.name}.{self.MUTUAL}", v["L_s"], v["L_r"], v[self.MUTUAL])
