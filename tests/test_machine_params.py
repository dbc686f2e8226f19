"""Machine parameters are declared once, in the machine part's PARAMS (with the shaft's J, B,
tau_c from ``plant.Shaft``): the records analysis and scenarios use are generated from that
declaration and validate by it, with the same rules and relations as the parts."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from acdrive.control._bodson import CTRL_PARAMS, SYNC_PARAMS
from acdrive.core._signals import RULES
from acdrive.errors import InputError
from acdrive.machines import (
    BODSON_DFIM,
    DELORENZO_IM,
    PMSG_2MW,
    CageInductionMachine,
    DFIMParams,
    DoublyFedMachine,
    IMParams,
    PermanentMagnetMachine,
    PMSGParams,
    machine_params,
    machine_vector,
    names,
)
from acdrive.plant import Shaft
from acdrive.plant._mechanics import SHAFT_PARAMS

#: (record, its part, part parameters that are not the machine's, a valid example)
RECORDS = [
    (DFIMParams, DoublyFedMachine, ("V_loss",), BODSON_DFIM),
    (IMParams, CageInductionMachine, (), DELORENZO_IM),
    (PMSGParams, PermanentMagnetMachine, (), PMSG_2MW),
]
IDS = ["dfim", "cage-im", "pm"]
MECHANICS = ("J", "B", "tau_c")


def _electrical(example) -> dict:
    return {
        f.name: getattr(example, f.name)
        for f in dataclasses.fields(example)
        if f.name not in MECHANICS
    }


@pytest.mark.parametrize("record, part, leave_out, example", RECORDS, ids=IDS)
def test_record_fields_are_the_parts_declaration(record, part, leave_out, example):
    """Fields, units, docs, rules and relations: the very declarations of the part and the
    shaft, in their order; defaults: the part's and the shaft's."""
    machine_vars = [v for v in part.PARAMS if v.name not in leave_out]
    shaft_vars = [SHAFT_PARAMS.var(n) for n in MECHANICS]
    fields = dataclasses.fields(record)
    assert [f.name for f in fields] == [v.name for v in machine_vars + shaft_vars]
    assert all(a is b for a, b in zip(record.DECLARED, machine_vars + shaft_vars, strict=True))
    assert record.RELATIONS is part.PARAMS.relations
    assert record.PART is part
    for f in fields:
        if f.name in part.DEFAULTS:
            assert f.default == part.DEFAULTS[f.name]
        elif f.name in ("B", "tau_c"):
            assert f.default == Shaft.DEFAULTS[f.name] == 0.0
    # the generated docstring lists each field with its unit
    for v in record.DECLARED:
        assert f"* {v.name} [{v.unit or '-'}]" in record.__doc__


@pytest.mark.parametrize("record, part, leave_out, example", RECORDS, ids=IDS)
def test_every_value_rule_names_the_field_in_record_and_part(record, part, leave_out, example):
    """Each declared rule, broken once in the record and once in the part: the same rule text,
    the field named (unprefixed in the record, ``<part>.<field>`` in the part)."""
    broken = {"positive": [0.0, -1.0], "nonnegative": [-1e-3], "count": [0, 1.5]}
    checked = 0
    for v in record.DECLARED:
        for bad in [*broken.get(v.rule, []), math.nan]:
            with pytest.raises(InputError) as exc:
                dataclasses.replace(example, **{v.name: bad})
            assert exc.value.field == v.name
            if math.isnan(bad):
                assert "finite" in exc.value.rule
            else:
                assert exc.value.rule == f"{RULES[v.rule]}, got {bad:g}"
            if v.name in MECHANICS:
                continue
            with pytest.raises(InputError) as in_part:
                part("m", **{**_electrical(example), v.name: bad})
            assert in_part.value.field == f"m.{v.name}"
            assert in_part.value.rule == exc.value.rule
            checked += 1
    assert checked >= len(part.PARAMS) - len(leave_out)


@pytest.mark.parametrize("record, part", [(DFIMParams, DoublyFedMachine), (IMParams,
                         CageInductionMachine)], ids=["dfim", "cage-im"])  # fmt: skip
def test_leakage_relation_names_sigma_and_the_fields(record, part):
    """L_s L_r <= mutual^2 (sigma <= 0): one error naming sigma, its formula and the three
    inductances with their values, in the record and the part alike."""
    example = BODSON_DFIM if record is DFIMParams else DELORENZO_IM
    mutual = "M" if record is DFIMParams else "L_m"
    L = getattr(example, mutual)
    cases = {
        "equal": ({"L_s": L, "L_r": L}, mutual),  # sigma = 0, no self inductance below
        "L_s below": ({"L_s": 0.9 * L, "L_r": 1.05 * L}, "L_s"),  # 0.945 < 1: L_s is short
        "both below": ({"L_s": 0.9 * L, "L_r": 0.9 * L}, mutual),
    }
    for changes, named in cases.values():
        with pytest.raises(InputError) as exc:
            dataclasses.replace(example, **changes)
        assert exc.value.field == named
        rule = exc.value.rule
        assert f"sigma = 1 - {mutual}^2/(L_s L_r) must be > 0" in rule
        for f in ("L_s", "L_r", mutual):
            assert f"{f} = " in rule
        values = {**_electrical(example), **changes}
        with pytest.raises(InputError) as in_part:
            part("m", **values)
        assert (in_part.value.field, in_part.value.rule) == (f"m.{named}", rule)
    # just inside the rule: a tiny leakage is accepted, and sigma is the formula's
    ok = dataclasses.replace(example, L_s=L * (1 + 1e-9), L_r=L)
    assert ok.sigma == pytest.approx(1.0 - 1.0 / (1 + 1e-9), rel=1e-6) and ok.sigma > 0


def test_pm_psi_m_zero_is_a_reluctance_machine_and_needs_saliency():
    """psi_m = 0 is a synchronous reluctance machine: accepted by the record and the part when
    L_d != L_q (its torque (8) is n_p (L_d - L_q) i_d i_q), refused (naming psi_m and the rule)
    when L_d = L_q, where no current makes torque. psi_m < 0 is refused by its own rule."""
    reluctance = dataclasses.replace(PMSG_2MW, L_q=1.6 * PMSG_2MW.L_d, psi_m=0.0)
    part = PermanentMagnetMachine.from_params("pm", reluctance)
    assert part.values["psi_m"] == 0.0
    from acdrive.machines._pmsm_part import pmsm_torque

    i_d, i_q = 3.0, 4.0
    expected = reluctance.n_p * (reluctance.L_d - reluctance.L_q) * i_d * i_q
    assert pmsm_torque(part.p, i_d, i_q) == pytest.approx(expected, rel=1e-15)
    for make in (
        lambda: dataclasses.replace(PMSG_2MW, psi_m=0.0),  # L_d = L_q in the 2 MW machine
        lambda: PermanentMagnetMachine("pm", **{**_electrical(PMSG_2MW), "psi_m": 0.0}),
    ):
        with pytest.raises(InputError) as exc:
            make()
        assert exc.value.field.endswith("psi_m")
        assert "psi_m > 0 or L_d != L_q" in exc.value.rule
    with pytest.raises(InputError, match=r"psi_m: must be >= 0"):
        dataclasses.replace(PMSG_2MW, psi_m=-0.1)


def test_pole_pairs_required_or_defaulted_alike_in_record_and_part():
    """n_p has no default for the PM machine and the DFIM (record and part), and defaults to 1
    for the cage IM in both (the two papers' IMs are 2-pole machines)."""
    pm = {k: v for k, v in _electrical(PMSG_2MW).items() if k != "n_p"}
    with pytest.raises(TypeError, match="n_p"):
        PMSGParams(**pm)
    with pytest.raises(InputError, match=r"pm\.n_p: must be given"):
        PermanentMagnetMachine("pm", **pm)
    dfim = {k: v for k, v in _electrical(BODSON_DFIM).items() if k != "n_p"}
    with pytest.raises(TypeError, match="n_p"):
        DFIMParams(**dfim, J=BODSON_DFIM.J)
    with pytest.raises(InputError, match=r"d\.n_p: must be given"):
        DoublyFedMachine("d", **dfim)
    im = {k: v for k, v in _electrical(DELORENZO_IM).items() if k != "n_p"}
    assert IMParams(**im).n_p == 1 == CageInductionMachine("im", **im).values["n_p"]
    assert isinstance(DFIMParams(**dfim, n_p=2.0, J=1.0).n_p, int)


@pytest.mark.parametrize("name", names())
def test_every_catalog_machine_gives_its_part_and_its_shaft(name):
    """``Shaft(J=params.J, ...)`` works for every built-in machine (the IMs included), and the
    part made from a record carries exactly the record's electrical values."""
    params = machine_params(name)
    shaft = Shaft("shaft", J=params.J, B=params.B, tau_c=params.tau_c)
    assert shaft.values["J"] == params.J > 0
    part = type(params).PART.from_params("m", params)
    for v in part.PARAMS:
        if hasattr(params, v.name):
            assert part.values[v.name] == getattr(params, v.name)


def test_delorenzo_inertia_is_the_one_its_scenarios_assume():
    """The DeLorenzo IM's J is the inertia the IM drive's gains are designed for
    (control.foc.J_ESTIMATE), not a new number; a record without J fails at the shaft, naming J."""
    from acdrive.control._foc import J_ESTIMATE

    assert DELORENZO_IM.J == J_ESTIMATE == machine_params("delorenzo-im-13").J
    unknown = dataclasses.replace(DELORENZO_IM, J=None)
    with pytest.raises(InputError) as exc:
        Shaft("shaft", J=unknown.J)
    assert exc.value.field == "shaft.J" and "must be given" in exc.value.rule


def test_dfim_vector_and_controller_estimates_use_the_parts_slots():
    """The compiled DFIM functions read the part's own packed vector; the controller's estimates
    take the same slots (declared first, in the part's order)."""
    p = machine_vector(BODSON_DFIM)
    assert np.array_equal(p, DoublyFedMachine.from_params("d", BODSON_DFIM).p)
    for layout in (CTRL_PARAMS, SYNC_PARAMS):
        for v in DoublyFedMachine.PARAMS:
            if v.name != "V_loss":
                assert layout.slot(v.name) == DoublyFedMachine.PARAMS.slot(v.name)
                assert layout.var(v.name).unit == v.unit and layout.var(v.name).rule == v.rule


def test_ifoc_estimates_are_the_cage_parts_declarations_with_delorenzo_defaults():
    """The IFOC's machine estimates carry the cage IM part's units and rules, and its defaults
    are the DeLorenzo machine's values (not typed again)."""
    from acdrive.control._foc import IFOC_ESTIMATES, IFOC_PARAMS, IndirectFOC

    for name in IFOC_ESTIMATES:
        declared = CageInductionMachine.PARAMS.var(name)
        assert (IFOC_PARAMS.var(name).unit, IFOC_PARAMS.var(name).rule) == (
            declared.unit,
            declared.rule,
        )
        assert IndirectFOC("ifoc").values[name] == getattr(DELORENZO_IM, name)
    with pytest.raises(InputError, match=r"ifoc\.L_r: must be > 0"):
        IndirectFOC("ifoc", L_r=-1.0)


def test_layout_relation_is_checked_on_packing_and_kept_by_extended():
    """A Relation names the blamed field with the owner and lists every field's value and unit;
    ``extended`` keeps the relation and every slot; a relation on an undeclared or complex
    quantity is refused when the layout is declared."""
    from acdrive.core._signals import Layout, Relation, cplx, real

    ordered = Relation(("lo", "hi"), "lo must be below hi", lambda lo, hi: lo < hi)
    layout = Layout(real("lo", "V", "lower"), real("hi", "V", "upper"), relations=(ordered,))
    assert list(layout.pack("box", {"lo": 1.0, "hi": 2.0})) == [1.0, 2.0]
    with pytest.raises(InputError) as exc:
        layout.pack("box", {"lo": 3.0, "hi": 2.0})
    assert exc.value.field == "box.hi"
    assert exc.value.rule == "lo must be below hi (lo = 3 V, hi = 2 V)"
    longer = layout.extended(real("x", "", "extra"))
    assert longer.relations == (ordered,)
    assert [longer.slot(n) for n in ("lo", "hi", "x")] == [0, 1, 2]
    with pytest.raises(InputError, match="box.hi"):
        longer.pack("box", {"lo": 3.0, "hi": 2.0, "x": 0.0})
    with pytest.raises(ValueError, match="not a declared real"):
        Layout(real("lo", "V", "lower"), relations=(ordered,))
    with pytest.raises(ValueError, match="not a declared real"):
        Layout(real("lo", "V", "lower"), cplx("hi", "V", "upper"), relations=(ordered,))
