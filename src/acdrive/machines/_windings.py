"""What every induction machine part shares: its winding parameters and their rules.

Both the cage IM (Amezquita-Brooks et al. (1)) and the DFIM (Bodson (9)) are a stator and a rotor
winding with resistances, self inductances, a mutual inductance and a pole-pair count; only the
mutual inductance's symbol differs (L_m, M). The value rules and the cross-field rule sigma > 0
are declared here once, with the parameters (``core._signals``).
"""

from __future__ import annotations

from acdrive.core._signals import Layout, Relation, real


def leakage_factor(L_s: float, L_r: float, mutual: float) -> float:
    """sigma = 1 - mutual^2 / (L_s L_r) (Bodson, after (45); Ugalde-Loo et al. (38))."""
    return 1.0 - mutual * mutual / (L_s * L_r)


def _out_of_proportion(mutual: str):
    """The inductance a broken sigma > 0 names: a self inductance if it alone is below the
    mutual one (sigma > 0 needs one of them above it at least), else the mutual inductance."""

    def blame(L_s: float, L_r: float, L_mutual: float) -> str:
        below = [name for name, L in (("L_s", L_s), ("L_r", L_r)) if L < L_mutual]
        return below[0] if len(below) == 1 else mutual

    return blame


def winding_params(mutual: str, mutual_doc: str) -> Layout:
    """R_s, R_r, L_s, L_r, ``mutual``, n_p in this order, with the rule sigma > 0."""
    leaks = Relation(
        ("L_s", "L_r", mutual),
        f"leakage factor sigma = 1 - {mutual}^2/(L_s L_r) must be > 0",
        lambda L_s, L_r, L_mutual: leakage_factor(L_s, L_r, L_mutual) > 0.0,
        _out_of_proportion(mutual),
        c=f"1.0 - {{{mutual}}} * {{{mutual}}} / ({{L_s}} * {{L_r}}) > 0.0",
    )
    return Layout(
        real("R_s", "ohm", "stator resistance", "positive"),
        real("R_r", "ohm", "rotor resistance referred to the stator", "positive"),
        real("L_s", "H", "stator self inductance", "positive"),
        real("L_r", "H", "rotor self inductance", "positive"),
        real(mutual, "H", mutual_doc, "positive"),
        real("n_p", "", "pole pairs", "count"),
        relations=(leaks,),
    )
