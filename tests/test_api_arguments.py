"""The Python API keeps the command line's contract: every public function and class of
``acdrive.identify``, ``export``, ``robustness``, ``drives``, ``analysis`` and ``sweep`` refuses
``None``, a wrong type, NaN, a negative and an empty value of each of its arguments with an
``InputError`` naming that argument (the Python parameter), before any work.

Each callable states one rule per parameter (``acdrive._arguments.checked``). The test calls it
with every other required argument a placeholder its rule accepts (an instance made without
``__init__``: any work on it would fail with another error than ``InputError``) and the argument
under test misused. A rule that accepts the misuse (``None`` for an optional argument, a negative
number where the sign is free, an empty text where empty is allowed) must let the call through its
check, which is then all that runs (``check_call``).
"""

from __future__ import annotations

import importlib
import inspect
import math
import types

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from acdrive import _arguments as a
from acdrive.errors import InputError

MODULES = ("acdrive.identify", "acdrive.export", "acdrive.robustness", "acdrive.drives",
           "acdrive.analysis", "acdrive.sweep")  # fmt: skip

#: the one public class left unchecked, and why
UNCHECKED = {
    "acdrive.export.CExport": "the engine's record of generated C (acdrive.sim) to_c returns",
}


#: ``acdrive.analysis``'s ``linearize``, ``stability_map`` and ``max_stable_bandwidth`` hand every
#: argument after the study to the drive's own linearisation: the default drive's is driven too
DISPATCHED = ("linearize", "stability_map", "max_stable_bandwidth")


def _public_callables():
    from acdrive.analysis._drive_linearisation import default_linearisation

    found = []
    for module_name in MODULES:
        module = importlib.import_module(module_name)
        for name in module.__all__:
            obj = getattr(module, name)
            if callable(obj) and f"{module_name}.{name}" not in UNCHECKED:
                found.append(pytest.param(obj, id=f"{module_name}.{name}"))
    linearisation = default_linearisation()
    for name in DISPATCHED:
        found.append(pytest.param(getattr(linearisation, name), id=f"default drive's {name}"))
    return found


CALLABLES = _public_callables()


def _parameters(target) -> list[inspect.Parameter]:
    signature = inspect.signature(target)
    return [p for p in signature.parameters.values()
            if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]  # fmt: skip


def _primary(rule):
    """The rule whose shape a misused value takes (the first of an ``Either``)."""
    return _primary(rule.rules[0]) if isinstance(rule, a.Either) else rule


def _example(rule):
    """A value ``rule`` accepts."""
    rule = _primary(rule)
    if isinstance(rule, a.Anything):
        return None
    if isinstance(rule, a.Number):
        value = 1.0 if rule.low is None else rule.low + (1.0 if rule.above else 0.0)
        value = value if rule.high is None else min(value, rule.high)
        return int(value) if rule.integer else float(value)
    if isinstance(rule, a.Flag):
        return True
    if isinstance(rule, a.Text):
        return rule.choices[0] if rule.choices else "x"
    if isinstance(rule, a.FilePath):
        return "x.csv"
    if isinstance(rule, a.Function):
        return lambda *args, **kwargs: None
    if isinstance(rule, a.Attributes):
        return types.SimpleNamespace(**dict.fromkeys(rule.names))
    if isinstance(rule, a.Instance):
        kind = rule.types[0]
        return object.__new__(kind) if kind.__new__ is object.__new__ else kind.__new__(kind)
    if isinstance(rule, a.Items):
        return (_example(rule.item),)
    if isinstance(rule, a.Table):
        return {"x": 1.0 if rule.values is None else _example(rule.values)}
    if isinstance(rule, a.Array):
        ndim = rule.ndim[0] if rule.ndim else 1
        return np.full((1,) * ndim, max(1.0, rule.low or 0.0))
    raise AssertionError(f"no example for {rule!r}")


def _shaped(rule, scalar):
    """``scalar`` in the shape ``rule`` takes: an item of a sequence, a value of a table, an
    element of an array; a scalar otherwise (a wrong type for a text, an instance, ...)."""
    rule = _primary(rule)
    if isinstance(rule, a.Items):
        return (_shaped(rule.item, scalar),)
    if isinstance(rule, a.Table) and rule.values is not None:
        return {"x": _shaped(rule.values, scalar)}
    if isinstance(rule, a.Array):
        ndim = rule.ndim[0] if rule.ndim else 1
        return np.full((1,) * ndim, float(scalar))
    if isinstance(rule, a.Number) and rule.integer and math.isfinite(scalar):
        return math.floor(scalar)
    return scalar


def _empty(rule):
    rule = _primary(rule)
    if isinstance(rule, a.Items):
        return ()
    if isinstance(rule, a.Table):
        return {}
    if isinstance(rule, a.Array):
        ndim = rule.ndim[0] if rule.ndim else 1
        return np.empty((0,) * max(ndim, 1)).reshape((0,) * ndim) if ndim else np.empty(0)
    return ""


#: misuse -> (value for a rule, does the rule accept it)
MISUSES = {
    "None": (lambda rule: None, lambda rule: rule.accepts_none),
    "a wrong type": (lambda rule: object(), lambda rule: isinstance(rule, a.Anything)),
    "NaN": (lambda rule: _shaped(rule, math.nan), lambda rule: _primary(rule).accepts_nan),
    "a negative": (lambda rule: _shaped(rule, _negative(rule)),
                   lambda rule: _primary(rule).accepts_negative),  # fmt: skip
    "empty": (_empty, lambda rule: _primary(rule).accepts_empty),
}


def _leaf(rule):
    """The rule of the numbers inside ``rule`` (an item's, a table value's)."""
    rule = _primary(rule)
    while isinstance(rule, a.Items) or (isinstance(rule, a.Table) and rule.values is not None):
        rule = _primary(rule.item if isinstance(rule, a.Items) else rule.values)
    return rule


def _negative(rule, magnitude: float = 1.0) -> float:
    """A negative number, within the rule's lower bound if that is negative."""
    low = getattr(_leaf(rule), "low", None)
    return max(-magnitude, low) if low is not None and low < 0 else -magnitude


def _call(target, name, value):
    """(the rules, keyword arguments: every required one a placeholder, ``name`` = ``value``)."""
    rules = a.rules_of(target)
    kwargs = {p.name: _example(rules[p.name]) for p in _parameters(target)
              if p.default is p.empty}  # fmt: skip
    kwargs[name] = value
    return rules, kwargs


def _assert_contract(target, name, value, accepted: bool, misuse: str):
    rules, kwargs = _call(target, name, value)
    if accepted:
        a.check_call(target, **kwargs)  # its check lets it through
        return
    with pytest.raises(InputError) as refused:
        target(**kwargs)
    field = refused.value.field
    assert field == name or field.startswith(f"{name}["), (
        f"{misuse} for {name!r} named {field!r}: {refused.value}"
    )
    assert refused.value.rule


@pytest.mark.parametrize("target", CALLABLES)
def test_every_argument_has_a_rule(target):
    rules = a.rules_of(target)
    assert rules is not None, "no rules: its arguments are not checked"
    assert sorted(rules) == sorted(p.name for p in _parameters(target))


@pytest.mark.parametrize("target", CALLABLES)
def test_every_misuse_of_every_argument_is_refused_by_its_name(target):
    for parameter in _parameters(target):
        rule = a.rules_of(target)[parameter.name]
        for misuse, (value_for, accepts) in MISUSES.items():
            _assert_contract(target, parameter.name, value_for(rule), accepts(rule), misuse)


#: values of no type any rule accepts (nothing callable, no number, text, sequence or array)
WRONG_TYPES = st.sampled_from([object(), {1, 2}, frozenset(), b"bytes", bytearray(b"x"),
                               range(3), Ellipsis, NotImplemented])  # fmt: skip


@pytest.mark.parametrize("target", CALLABLES)
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_drawn_misuses_are_refused_by_name(target, data):
    """The same contract for drawn values: any magnitude of negative number, NaN or infinity in
    any position, any wrong type."""
    parameters = _parameters(target)
    if not parameters:
        return
    parameter = data.draw(st.sampled_from(parameters))
    rule = a.rules_of(target)[parameter.name]
    misuse = data.draw(st.sampled_from(["None", "a wrong type", "not finite", "a negative",
                                        "empty"]))  # fmt: skip
    if misuse == "a wrong type":
        value, accepted = data.draw(WRONG_TYPES), isinstance(rule, a.Anything)
    elif misuse == "not finite":
        value = _shaped(rule, data.draw(st.sampled_from([math.nan, math.inf, -math.inf])))
        accepted = _primary(rule).accepts_nan
    elif misuse == "a negative":
        magnitude = data.draw(st.floats(min_value=1e-300, max_value=1e300))
        value = _shaped(rule, _negative(rule, magnitude))
        accepted = _primary(rule).accepts_negative
    else:
        value_for, accepts = MISUSES[misuse]
        value, accepted = value_for(rule), accepts(rule)
    _assert_contract(target, parameter.name, value, accepted, misuse)


def _sweep_spec():
    from acdrive.sweep import load_sweep

    return load_sweep("dfim-bandwidth")


#: misuses of the API found by hand, each with the argument its refusal must name
SEEN = [
    ("read_log(None)", lambda m: m.identify.read_log(None), "path"),
    ("read_log of a missing file", lambda m: m.identify.read_log("no-such-log.csv"), "path"),
    ("fit_impedance(None)", lambda m: m.identify.fit_impedance(None, 1.0, 0.0), "log"),
    ("t_circuit with an unknown split",
     lambda m: m.identify.t_circuit(m.identify.InverseGamma(1.0, 1.0, 1.0, 1.0), 2, "none"),
     "split"),
    ("builtin_bench of an unknown name", lambda m: m.identify.builtin_bench("pm", "none"), "name"),
    ("simulate(dict)", lambda m: m.drives.simulate({}), "setup"),
    ("run_scenario(None)", lambda m: m.drives.run_scenario(None), "setup"),
    ("get of an unknown kind", lambda m: m.drives.get("no-such-drive"), "kind"),
    ("paper_factors(nan)", lambda m: m.robustness.paper_factors(math.nan), "severity"),
    ("MapSpec(points=1)", lambda m: m.robustness.MapSpec(points=1), "points"),
    ("MapSpec(kind='sobol')", lambda m: m.robustness.MapSpec(kind="sobol"), "kind"),
    ("robustness_map with a negative tolerance",
     lambda m: m.robustness.robustness_map("bodson-ramp", tracking_tolerance=-1.0),
     "tracking_tolerance"),
    ("target_report('pm-foc')", lambda m: m.export.target_report("pm-foc"), "targets"),
    ("linearize at a point that is a string",
     lambda m: m.analysis.linearize(m.analysis.DriveModel(), "fast"), "point"),
    ("run_sweep to an empty folder name", lambda m: m.sweep.run_sweep(_sweep_spec(), ""), "out"),
]


@pytest.mark.parametrize(("call", "field"), [pytest.param(c, f, id=i) for i, c, f in SEEN])
def test_the_misuses_seen_are_refused_naming_the_argument(call, field):
    import acdrive.analysis
    import acdrive.drives
    import acdrive.export
    import acdrive.identify
    import acdrive.robustness
    import acdrive.sweep

    with pytest.raises(InputError) as refused:
        call(acdrive)
    assert refused.value.field == field, str(refused.value)
