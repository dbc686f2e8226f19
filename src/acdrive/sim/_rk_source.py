"""One Runge-Kutta step as source text, expanded from the method's tableau
(``sim._integrators.Tableau``) in one place for every loop: numba's single loop and lockstep
loop (``NUMBA``) and the C of the native tier and of the plant export (``c_dialect``). The two
dialects differ in spelling only; the operations and their order are the tableau's, so every
tier rounds alike.

The step has the inputs held and every stage time capped at ``cap`` (the profile rule of
``sim._loop_source.advance_lines``): stage j evaluates the derivative at min(t + c_j h, cap)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from acdrive.sim._integrators import METHODS


@dataclass(frozen=True)
class Dialect:
    """How a step is spelt: ``literal(w)`` a coefficient, ``k(j)`` stage j's derivative of state
    i, ``x``/``xt`` state i of the step's start and of the stage, ``call(time, start, j)`` the
    derivative evaluation of stage j at ``time`` from the step's start state (``start``) or the
    stage state, ``capped(time)`` a stage time, ``loop``/``end`` around a statement over the
    states, ``begin`` the step's declarations, ``statement`` one statement over state i."""

    literal: Callable[[float], str]
    k: Callable[[int], str]
    x: str
    xt: str
    call: Callable[[str, bool, int], str]
    capped: Callable[[str], str]
    loop: str
    end: tuple[str, ...]
    begin: Callable[[int], list[str]]
    statement: Callable[[str], str]


def _numba_begin(stages: int) -> list[str]:
    return [f"    xt = W[{stages}]"]


#: numba's spelling: ``W`` holds the stage derivatives in rows 0..stages-1 and the stage state in
#: row ``stages``; the lockstep loop adds its lane axis to this text (``sim._loop_source``)
NUMBA = Dialect(
    literal=repr,
    k=lambda j: f"W[{j}, i]",
    x="X[i]",
    xt="xt[i]",
    call=lambda time, start, j: (
        f"    derivatives({time}, {'X' if start else 'xt'}, P, PO, Y, U, W[{j}])"
    ),
    capped=lambda time: f"min({time}, cap)",
    loop="    for i in range(N_X):",
    end=(),
    begin=_numba_begin,
    statement=lambda text: f"        {text}",
)


def c_dialect(name: str, n_x: int) -> Dialect:
    """C's spelling in the plant file of ``name`` (``sim._ccode._plant_source``): literals in the
    build's precision (``ACD_R``), stage derivatives ``k[j]`` and the stage state ``xt`` of the
    plant's state vector type, the derivative function ``<name>_derivatives``."""
    derivatives = f"{name}_derivatives"
    return Dialect(
        literal=lambda w: f"ACD_R({w!r})",
        k=lambda j: f"k[{j}].v[i]",
        x="X->v[i]",
        xt="xt.v[i]",
        call=lambda time, start, j: (
            f"    {derivatives}({time}, p, {'&X->x' if start else '&xt.x'}, in, y, &k[{j}].x);"
        ),
        capped=lambda time: f"ACD_CAPPED({time}, cap)",
        loop=f"    for (i = 0; i < {n_x}; ++i) {{",
        end=("    }",),
        begin=lambda stages: ["    int i;", f"    {name}_vector k[{stages}], xt;"],
        statement=lambda text: f"        {text};",
    )


def _capped(dialect: Dialect, node: float) -> str:
    time = "t" if node == 0.0 else "t + h" if node == 1.0 else f"t + {dialect.literal(node)} * h"
    return dialect.capped(time)


def _terms(dialect: Dialect, weights) -> list[str]:
    """The nonzero terms w_j k_j (a weight of one unwritten: 1 * k is k)."""
    return [dialect.k(j) if w == 1.0 else f"{dialect.literal(w)} * {dialect.k(j)}"
            for j, w in enumerate(weights) if w != 0.0]  # fmt: skip


def step_lines(method: str, dialect: Dialect) -> list[str]:
    """The body of one step of ``method`` (a name of ``sim._integrators.METHODS``) in
    ``dialect``."""
    m = METHODS[method]
    lines = dialect.begin(m.stages)
    for j, (node, row) in enumerate(zip(m.c, m.a, strict=True)):
        if j > 0:
            terms = [(i, w) for i, w in enumerate(row) if w != 0.0]
            if m.scaled_rows and len(terms) == 1:
                i, w = terms[0]
                scale = "h" if w == 1.0 else f"{dialect.literal(w)} * h"
                stage = f"{dialect.x} + {scale} * {dialect.k(i)}"
            else:
                stage = f"{dialect.x} + h * ({' + '.join(_terms(dialect, row))})"
            lines += [dialect.loop, dialect.statement(f"{dialect.xt} = {stage}"), *dialect.end]
        lines.append(dialect.call(_capped(dialect, node), j == 0, j))
    scale = "h" if m.divisor is None else f"h / {dialect.literal(m.divisor)}"
    update = f"{dialect.x} += {scale} * ({' + '.join(_terms(dialect, m.b))})"
    return [*lines, dialect.loop, dialect.statement(update), *dialect.end]
